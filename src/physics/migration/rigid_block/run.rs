//! One run of the block: release, the leapfrog step with its contact forces, flights in closed
//! form, episodes (impacts, ground phases), stops, samples and the energy books.

use super::*;
use crate::physics::migration::Release;
use crate::physics::migration::maps::CellTrack;

impl Model<'_> {
    /// Runs the block from its release to its stop with the friction coefficient `mu` and
    /// the critical damping ratio `beta`; `record`: (sample interval s, most samples) of the
    /// trajectory; `events`: keep the event log; `control`: polled for cancellation.
    #[cfg(test)]
    pub(super) fn simulate(
        &self,
        mu: f64,
        beta: f64,
        record: Option<(f64, usize)>,
        events: bool,
        control: Option<&Control>,
    ) -> PhysicsResult<RunOut> {
        let draws = Draws {
            mu,
            beta,
            start: None,
        };
        self.simulate_tracked(draws, None, record, events, None, control)
    }

    /// The block's state at the release `rel` (a drawn velocity or orientation) on the model's
    /// release point (see [`start_state`]).
    pub(super) fn start_of(&self, rel: &Release) -> State {
        let rel = Release {
            drop_height: self.drop,
            ..*rel
        };
        start_state(
            &self.shape,
            &rel,
            &self.floor_pt,
            &self.floor_normal_at_release,
            &self.floor_down_dip_at_release,
            self.static_overlap,
        )
    }

    /// (kₙ, kₛ) of the floor at the contact point p (m), N/m: its material's on a floor of
    /// several materials.
    pub(super) fn stiffness_at(&self, p: &Vector3<f64>) -> (f64, f64) {
        match self.zones {
            None => (self.kn, self.ks),
            Some(z) => {
                let b = &z.material_at(p.x, p.y).block;
                (b.normal_stiffness, b.shear_stiffness)
            }
        }
    }

    /// (μ, β) of a contact at p (m) in the run of `cfg`: its material's on a floor of several
    /// materials.
    pub(super) fn draws_at(&self, cfg: &RunSettings<'_>, p: &Vector3<f64>) -> (f64, f64) {
        match (self.zones, cfg.zone) {
            (Some(z), Some(d)) => d[z.material_index(p.x, p.y)],
            _ => (cfg.mu, cfg.beta),
        }
    }

    /// [`Self::simulate`], following the centre's path on a map's cells when `track` is given:
    /// its state at every step, and closed-form flights and settled slides sampled at most half
    /// a cell apart (see `maps`); on a floor of several materials `zone` gives each material's
    /// (μ, β) in this run.
    pub(super) fn simulate_tracked(
        &self,
        draws: Draws,
        zone: Option<&[(f64, f64)]>,
        record: Option<(f64, usize)>,
        events: bool,
        mut track: Option<&mut CellTrack<'_>>,
        control: Option<&Control>,
    ) -> PhysicsResult<RunOut> {
        let cfg = RunSettings {
            zone,
            mu: draws.mu,
            beta: draws.beta,
            end_t: self.end_time.unwrap_or(f64::INFINITY),
            has_columns: !self.columns.is_empty(),
            plane_normal: match &self.floor.kind {
                FloorKind::Plane(pl) => Some(pl.normal()),
                _ => None,
            },
            log_events: events,
        };
        let (mut run, e_start) = self.release(record, draws.start.as_ref());
        let mut prev: Option<State> = None;
        let reason = loop {
            if let Some(t) = track.as_deref_mut() {
                self.track_state(t, &mut prev, &run.st);
            }
            if let Some(reason) = self.stop_before_step(&mut run, &cfg)? {
                break reason;
            }
            match self.try_flight(&mut run, &cfg)? {
                Flight::Stopped(reason) => break reason,
                Flight::Flew => continue,
                Flight::Grounded => {}
            }
            self.check_budget(&run, control)?;
            let Some(step) = self.leapfrog_step(&mut run, &cfg)? else {
                // a vertex is off the floor below its level: the block leaves the floor
                break StopReason::LeftFloor;
            };
            let in_contact = !run.contacts.is_empty();
            self.book_episode(&mut run, &step, in_contact, events);
            if !in_contact && run.first_impact_done {
                run.max_bounce = run.max_bounce.max(self.height_of_centre(&run.st.c));
            }
            if let Some(reason) = self.reach_in_step(&mut run, step.h, &cfg) {
                break reason;
            }
            if self.at_rest(&mut run, in_contact) {
                break StopReason::AtRest;
            }
            self.skip_settled_slide(&mut run, &step.forces, &cfg);
        };
        if let Some(t) = track {
            self.track_state(t, &mut prev, &run.st);
        }
        self.finish(run, reason, e_start, &cfg)
    }

    /// The path from the previous tracked state `prev` to `st`: one step is a chord; a longer
    /// advance (a closed-form flight or settled slide) is the constant-acceleration piece
    /// between the two states, sampled by the track.
    fn track_state(&self, track: &mut CellTrack<'_>, prev: &mut Option<State>, st: &State) {
        let (kt, kr, _) = self.energy(st);
        if let Some(p) = prev.as_ref()
            && st.t - p.t > 1.5 * self.dt
        {
            let dt = st.t - p.t;
            let a = (st.c - p.c - p.v * dt) * (2.0 / (dt * dt));
            let m = self.m;
            track.piece(&p.c, &p.v, &a, dt, &|v| 0.5 * m * v.norm_squared() + kr);
        }
        track.point(&st.c, st.v.norm(), kt + kr);
        *prev = Some(*st);
    }

    /// The run at release, with the energy at the start (J): a block released on the floor
    /// has its contacts closed already (with unloaded shear springs) and the acceleration of
    /// their elastic forces.
    pub(super) fn release(
        &self,
        record: Option<(f64, usize)>,
        start: Option<&State>,
    ) -> (Run, f64) {
        let mut st = start.copied().unwrap_or(State {
            t: 0.0,
            c: self.c0,
            v: self.v0,
            q: self.q0,
            w: self.w0,
        });
        let mut springs = Vec::new();
        let mut contacts = Vec::new();
        let mut tris = Vec::new();
        let mut acc = Vector3::new(0.0, 0.0, -self.g);
        let r = self.rot(&st.q);
        self.contacts(&st.c, &r, &mut tris, &mut contacts);
        if self.on_floor_at_start || !self.floor.is_single_facet() {
            // placed on the facet under the release point (and lifted from there by the drop);
            // on a rough floor the relief around it may reach deeper into the block than the
            // rest overlap: lift the block onto it. (A drop smaller than the relief beside the
            // release point started the block inside it: a 1.85 m cube dropped 0.22 m beside a
            // 0.5 m step started 0.3 m inside the step, and its springs threw the 15.7 t block
            // off at 9.4 m/s.)
            let nf = self.floor_normal_at_release;
            for _ in 0..8 {
                let deepest = contacts.iter().map(|g| g.u).fold(0.0, f64::max);
                let excess = deepest - self.static_overlap;
                if excess <= 1e-12 * (1.0 + self.shape.r_max) {
                    break;
                }
                st.c += nf * (excess / nf.z.max(0.1) * 1.0001);
                self.contacts(&st.c, &r, &mut tris, &mut contacts);
            }
        }
        let onsets = contacts
            .iter()
            .map(|g| Onset {
                feature: g.feature,
                offset: 0.0,
                carried: g.u,
                rr: g.p - st.c,
                n: g.n,
            })
            .collect();
        let stored = contacts
            .iter()
            .map(|g| self.normal_energy(g.u, self.stiffness_at(&g.p).0))
            .sum::<f64>();
        for gk in &contacts {
            let (kn, ks) = self.stiffness_at(&gk.p);
            let f_el = match self.hertz {
                None => kn * gk.u,
                Some(hz) => hz.k * gk.u * gk.u.sqrt(),
            };
            acc += gk.n * (f_el / self.m);
            springs.push(Spring {
                key: gk.key,
                fs: Vector3::zeros(),
                ks,
                rr: gk.p - st.c,
                n: gk.n,
                u: gk.u,
            });
        }
        let (k0, r0, p0) = self.energy(&st);
        let e_start = k0 + r0 + p0 + stored;
        let ke_start = k0 + r0;
        let on_floor = self.on_floor_at_start;
        let episode = on_floor.then(|| Episode {
            t0: 0.0,
            speed_before: st.v.norm(),
            diss_before: 0.0,
            peak: 0.0,
            p: st.c,
            ground: true,
            impact: false,
            last_speed: st.v.norm(),
            last_p: st.c,
            last_diss: 0.0,
            last_t: 0.0,
        });
        let run = Run {
            st,
            springs,
            new_springs: Vec::new(),
            contacts,
            onsets,
            new_onsets: Vec::new(),
            tris,
            damping: 0.0,
            friction: 0.0,
            stored,
            acc,
            ang_acc: Vector3::zeros(),
            rec: record.map(|(interval, max)| Recorder {
                interval,
                next: 0.0,
                max,
                tr: Trajectory::default(),
            }),
            events: Vec::new(),
            impacts: 0,
            slide_start: on_floor.then(|| self.mean.along(&st.c)),
            max_bounce: 0.0,
            steps: 0,
            max_overlap: 0.0,
            had_contact: on_floor,
            last_contact_t: if on_floor { 0.0 } else { f64::NEG_INFINITY },
            episode,
            first_impact_done: false,
            still_since: None,
            quiet_window: None,
            slip_max: 0.0,
            prev_along: self.mean.along(&st.c),
            support: None,
            steady_since: None,
            patch_wait: None,
            column_clear: None,
            half_step: None,
            drift_h: 0.0,
            off_floor: false,
            e_start,
            ke_start,
            next_line: super::super::lines::first_reachable(&self.lines, self.mean.along(&st.c)),
            crossings: vec![None; self.lines.len()],
            barrier: 0.0,
        };
        (run, e_start)
    }

    /// Before a step: records the trajectory sample due; stops at the end time or off the
    /// floor's extent; closes an episode whose contact ended more than the gap ago.
    pub(super) fn stop_before_step(
        &self,
        run: &mut Run,
        cfg: &RunSettings,
    ) -> PhysicsResult<Option<StopReason>> {
        if let Some(r) = run.rec.as_mut()
            && run.st.t >= r.next
        {
            let diss = run.damping + run.friction + run.barrier;
            let s = self.synced(&run.st, run.half_step, &run.acc, &run.ang_acc);
            self.sample(r, &s, diss, run.stored)?;
            while r.next <= run.st.t {
                r.next += r.interval;
            }
        }
        if run.st.t >= cfg.end_t * (1.0 - 1e-12) {
            return Ok(Some(StopReason::EndTime));
        }
        if !matches!(self.floor.kind, FloorKind::Plane(_))
            && self
                .floor
                .locate(run.st.c.x, run.st.c.y, 0.0, 0.0)
                .is_none()
        {
            return Ok(Some(StopReason::LeftFloor));
        }
        if run.springs.is_empty()
            && run.st.t - run.last_contact_t > self.gap
            && let Some(ep) = run.episode.take()
        {
            self.close_episode(ep, true, &mut run.events, cfg.log_events);
        }
        Ok(None)
    }

    /// Free flight in closed form, when the block has been off the floor for longer than the
    /// gap and stays clear of it for more than two steps: the parabola to the floor's
    /// approach, a column, the lower end or the end time, with the bounce's apex and the
    /// trajectory samples inside it.
    pub(super) fn try_flight(&self, run: &mut Run, cfg: &RunSettings) -> PhysicsResult<Flight> {
        let dt = self.dt;
        if !(run.springs.is_empty() && run.st.t - run.last_contact_t > self.gap.max(dt)) {
            return Ok(Flight::Grounded);
        }
        let st = run.st;
        let margin = 2.0 * (st.v.norm() + st.w.norm() * self.shape.r_max + self.g * dt) * dt
            + 1e-9 * self.shape.r_max;
        let Some(tau) = self
            .clear_time(&st.c, &st.v, margin, cfg.end_t - st.t)
            .filter(|&tau| tau > 2.0 * dt)
        else {
            return Ok(Flight::Grounded);
        };
        // the flight starts from the velocities at the state's own time
        let st = self.synced(&st, run.half_step, &run.acc, &run.ang_acc);
        run.half_step = None;
        // off the floor, nothing stored: the account must close here
        self.check_energy(
            &st,
            0.0,
            run.damping + run.friction + run.barrier,
            (run.e_start, run.ke_start),
        )?;
        let t_target = st.t + tau;
        let gravity = Vector3::new(0.0, 0.0, -self.g);
        // lower end inside the flight?
        let cross = self.along_cross(&st, tau);
        // a column reached inside the flight ends it there
        let column = if cfg.has_columns {
            self.columns.first_reach(
                &self.mean,
                &self.supports,
                Piece::new(&st.c, &st.v, &gravity, cross.unwrap_or(tau)),
                0.0,
            )
        } else {
            None
        };
        let cross = if column.is_some() { None } else { cross };
        let mut t_stop = column.map(|c| st.t + c.0).or(cross.map(|tc| st.t + tc));
        // a barrier that acts inside the flight ends it there (collectors only record)
        let barrier = if self.lines.is_empty() {
            None
        } else {
            self.lines_in_flight(run, &st, t_stop.unwrap_or(t_target) - st.t)
        };
        if let Some((sx, ..)) = &barrier {
            t_stop = Some(sx.t);
        }
        let t_final = t_stop.unwrap_or(t_target);
        if run.first_impact_done {
            run.max_bounce = run.max_bounce.max(self.apex_height(&st, t_final));
        }
        // samples inside the flight
        while let Some(r) = run.rec.as_mut()
            && r.next < t_final
        {
            let s = self.fly(&st, r.next - st.t);
            self.sample(r, &s, run.damping + run.friction + run.barrier, run.stored)?;
            r.next += r.interval;
        }
        run.st = self.fly(&st, t_final - st.t);
        run.drift_h = 0.0;
        run.acc = gravity;
        run.ang_acc = Vector3::zeros();
        if let Some((sx, action, f)) = barrier {
            run.st = sx;
            if action == LineAction::Stopped {
                return Ok(Flight::Stopped(StopReason::Barrier));
            }
            self.break_through(run, f, cfg.log_events);
            run.prev_along = self.mean.along(&run.st.c);
            return Ok(Flight::Flew);
        }
        if let Some((_, k)) = column {
            run.support = Some(k);
            return Ok(Flight::Stopped(StopReason::Support));
        }
        if t_stop.is_some() {
            return Ok(Flight::Stopped(StopReason::LowerEnd));
        }
        if let Some(te) = self.end_time
            && t_target >= te * (1.0 - 1e-12)
        {
            run.st.t = te;
            return Ok(Flight::Flew);
        }
        run.prev_along = self.mean.along(&run.st.c);
        Ok(Flight::Flew)
    }

    /// Height of the centre above its resting height (m) at the apex of the flight from `st`
    /// that ends at `t_final` (s): the highest point along the mean plane's normal.
    pub(super) fn apex_height(&self, st: &State, t_final: f64) -> f64 {
        let nrm = self.mean.normal();
        let (b, a) = (nrm.dot(&st.v), -self.g * nrm.z);
        let ta = if a < 0.0 {
            (-b / a).clamp(0.0, t_final - st.t)
        } else {
            0.0
        };
        let ca = st.c + st.v * ta + Vector3::new(0.0, 0.0, -0.5 * self.g * ta * ta);
        self.height_of_centre(&ca)
    }

    /// Invariant: energy is never created. At the state `st` (velocities at its own time) with
    /// `stored` J in the springs and `lost` J dissipated so far, KE + PE + stored + lost may
    /// exceed the energy at release `e_start` by the scheme's error only: at most
    /// [`ENERGY_TOLERANCE_LINEAR`] (linear law) or [`ENERGY_TOLERANCE_HERTZ`] (Hertz) of the
    /// energy in play, m g (|Δs| + |Δz| + drop + ten static overlaps and shear displacements) +
    /// ½ m v₀² (Δs along the dip and Δz down from the release), plus half the stored energy
    /// (mid-contact the leapfrog's shadow energy differs from the true one by O(ωΔt) of it).
    /// Beyond that the state is impossible: a numerical failure, never an answer.
    pub(super) fn check_energy(
        &self,
        st: &State,
        stored: f64,
        lost: f64,
        (e_start, ke_start): (f64, f64),
    ) -> PhysicsResult<()> {
        let (kt, kr, pe) = self.energy(st);
        let excess = kt + kr + pe + stored + lost - e_start;
        let scale = self.energy_scale(st, ke_start);
        let tol = match self.hertz {
            None => ENERGY_TOLERANCE_LINEAR,
            Some(_) => ENERGY_TOLERANCE_HERTZ,
        };
        if excess > tol * scale + 0.5 * stored || !excess.is_finite() {
            return Err(PhysicsError::Numerical(format!(
                "rigid block: {excess:.6e} J of energy created by t = {:.6} s (allowed \
                 {:.3e} J of {scale:.6e} J in play): invariant violated",
                st.t,
                tol * scale + 0.5 * stored
            )));
        }
        Ok(())
    }

    /// The energy in play at the state `st` (J): the energy in play at release and m g times
    /// the travel since (along the dip and down).
    pub(super) fn energy_scale(&self, st: &State, ke_start: f64) -> f64 {
        let travel =
            (self.mean.along(&st.c) - self.mean.along(&self.c0)).abs() + (st.c.z - self.c0.z).abs();
        self.energy_in_play + ke_start + self.m * self.g * travel
    }

    /// Refuses a run past its step budget; polls the control every 4096 steps.
    pub(super) fn check_budget(&self, run: &Run, control: Option<&Control>) -> PhysicsResult<()> {
        if run.steps as f64 >= self.max_steps {
            return Err(PhysicsError::TooManySteps {
                estimated: run.steps as f64,
                limit: self.max_steps,
            });
        }
        if run.steps & 0xFFF == 0
            && let Some(c) = control
        {
            c.check()?;
        }
        Ok(())
    }

    /// One leapfrog step of Δt (shortened to end exactly at the end time): the contact forces
    /// at x(t), the local damping, then Newton–Euler; refuses a non-finite state.
    /// None, without stepping, when a block vertex is off the floor below its level at x(t):
    /// the block leaves the floor there, in the state the step started from (its springs
    /// brought to it).
    pub(super) fn leapfrog_step(
        &self,
        run: &mut Run,
        cfg: &RunSettings,
    ) -> PhysicsResult<Option<Step>> {
        let dt = self.dt;
        let h = if cfg.end_t - run.st.t < dt * (1.0 + 1e-9) {
            cfg.end_t - run.st.t
        } else {
            dt
        };
        let r = self.rot(&run.st.q);
        // stepping from a state with its velocities at its own time (release, end of a
        // flight): put them half a step back, where the leapfrog keeps them
        if run.half_step.is_none() {
            run.st.v -= run.acc * (0.5 * h);
            run.st.w -= r.transpose() * run.ang_acc * (0.5 * h);
        }
        let w_world = r * run.st.w;
        let diss_before = run.damping + run.friction;
        let mut forces = self.contact_forces(run, &r, &w_world, h, cfg);
        if run.off_floor && self.stop_off_floor {
            // the springs have seen the drift to x(t); the velocities lag by half a step
            run.drift_h = 0.0;
            run.half_step.get_or_insert(h);
            return Ok(None);
        }
        self.local_damping(&mut forces, &run.st.v, &w_world);
        let speed_before = run.st.v.norm();
        self.newton_euler(run, &r, &forces, h);
        let st = &run.st;
        if !st.c.iter().chain(st.v.iter()).all(|x| x.is_finite()) {
            return Err(PhysicsError::Numerical(format!(
                "the block's state became non-finite at t = {:.6} s",
                st.t
            )));
        }
        Ok(Some(Step {
            h,
            speed_before,
            diss_before,
            forces,
        }))
    }

    /// The forces at x(t) with the half-step velocities (ω in the world frame `w_world`):
    /// gravity and, per contact, the normal spring–dashpot and the capped shear spring. Books
    /// the shear springs' work (those of opened contacts too), the elastic energy stored, the
    /// deepest overlap and the fastest slip.
    pub(super) fn contact_forces(
        &self,
        run: &mut Run,
        r: &Matrix3<f64>,
        w_world: &Vector3<f64>,
        h: f64,
        cfg: &RunSettings,
    ) -> Forces {
        run.off_floor = self.contacts(&run.st.c, r, &mut run.tris, &mut run.contacts);
        self.onset_offsets(run, w_world, h);
        // the velocities at x(t), predicted from the half step with the last accelerations
        let v_t = run.st.v + run.acc * (0.5 * h);
        let w_t = w_world + run.ang_acc * (0.5 * h);
        let mut fo = Forces {
            force: Vector3::new(0.0, 0.0, -self.m * self.g),
            moment: Vector3::zeros(),
            normal_total: 0.0,
            damping_force: Vector3::zeros(),
            damping_moment: Vector3::zeros(),
            slip_force: Vector3::zeros(),
            slipping: 0,
        };
        run.new_springs.clear();
        // the centre at the last force evaluation
        let c_prev = run.st.c - run.st.v * run.drift_h;
        run.stored = 0.0;
        run.slip_max = 0.0;
        for gk in &run.contacts {
            let rr = gk.p - run.st.c;
            let vrel = run.st.v + w_world.cross(&rr);
            let vn = gk.n.dot(&vrel);
            let vt = vrel - gk.n * vn;
            run.slip_max = run.slip_max.max(vt.norm());
            let old = run.springs.iter().find(|s| s.key == gk.key);
            let (mu, beta) = self.draws_at(cfg, &gk.p);
            let motion = StepMotion {
                v_t: &v_t,
                w_t: &w_t,
                h,
            };
            let nf = self.normal_force(gk, &rr, motion, old.is_none(), beta);
            let (f_el, fnm, ks) = (nf.elastic, nf.total, nf.shear_stiffness);
            // dashpot work (and the clipped spring's share)
            let fd = gk.n * (fnm - f_el);
            fo.damping_force += fd;
            fo.damping_moment += rr.cross(&fd);
            fo.normal_total += nf.at_position;
            // the spring follows the contact point's drift since the last step
            let d = vt * run.drift_h;
            let (fs, es_new, slipping, work) = shear_spring(&gk.n, old, &d, ks, mu * f_el);
            fo.slipping += usize::from(slipping);
            if slipping {
                fo.slip_force += fs;
            }
            run.friction += work;
            run.stored += self.normal_energy(gk.u, nf.normal_stiffness) + es_new;
            // a contact whose nearest floor feature switched during the drift
            let kink = old.map_or_else(Vector3::zeros, |o| {
                crease_kink_force(o, gk, &(c_prev + o.rr), f_el)
            });
            run.new_springs.push(Spring {
                key: gk.key,
                fs,
                ks,
                rr,
                n: gk.n,
                u: gk.u,
            });
            let fc = gk.n * fnm + fs + kink;
            fo.force += fc;
            fo.moment += rr.cross(&fc);
        }
        // springs of contacts that opened release their shear energy over the drift
        for sp in &run.springs {
            if !run.new_springs.iter().any(|s| s.key == sp.key) {
                run.friction += self.opened_spring_work(sp, &run.st, w_world, run.drift_h);
            }
        }
        std::mem::swap(&mut run.springs, &mut run.new_springs);
        fo
    }

    /// Onset offsets, after 3DEC's incremental normal law (a contact's force grows from zero
    /// with the approach after it forms): a pair of features that first touches deeper than
    /// twice the approach of the last drift (the velocities of that drift at the contact
    /// point, over the longer of it and the step `h`, s; a block vertex: deeper than the rest
    /// overlap plus that, as a face settles on a facet) is a floor peak or crease met while
    /// the block already touched through another feature. Its spring carries only that much;
    /// the rest of the overlap is the contact's offset, kept while the pair stays closed and
    /// lowered to the overlap whenever the overlap falls below it. So a feature switching on
    /// inside the block creates at most the elastic energy of its approach, never that of its
    /// depth (nor of the rest overlap: a crease under a block resting on the relief, switching
    /// on and off as the block rocks, would create that at every switch), and the offset never
    /// adds any. Records the deepest geometric overlap; `w_world`:
    /// ω, world frame.
    pub(super) fn onset_offsets(&self, run: &mut Run, w_world: &Vector3<f64>, h: f64) {
        let span = run.drift_h.max(h);
        let slack = 1e-12 * (1.0 + self.shape.r_max);
        run.new_onsets.clear();
        if self.shape.sphere_radius.is_some() {
            // a sphere's touches are continuous in depth as they pass from a facet's face to
            // its edges and corners (which change their feature): no offsets
            for gk in &run.contacts {
                run.max_overlap = run.max_overlap.max(gk.u);
            }
            return;
        }
        // pairs still closed, and whether any carries an offset: without a pair switched off
        // and an offset to take its energy there is nothing to hand over
        let (mut kept, mut any_offset) = (0usize, false);
        for gk in &mut run.contacts {
            run.max_overlap = run.max_overlap.max(gk.u);
            let offset = match run.onsets.iter().find(|o| o.feature == gk.feature) {
                Some(o) => {
                    kept += 1;
                    o.offset.min(gk.u)
                }
                None => {
                    let vrel = run.st.v + w_world.cross(&(gk.p - run.st.c));
                    let approach = (-gk.n.dot(&vrel)).max(0.0) * span;
                    // a block vertex may land at the rest overlap (a face settling on a
                    // facet); a floor peak or crease is born unloaded
                    let rest = if gk.feature >> 62 == 0 {
                        self.static_overlap
                    } else {
                        0.0
                    };
                    (gk.u - 2.0 * approach - rest - slack).max(0.0)
                }
            };
            gk.u -= offset;
            any_offset |= offset > 0.0;
            run.new_onsets.push(Onset {
                feature: gk.feature,
                offset,
                carried: gk.u,
                rr: gk.p - run.st.c,
                n: gk.n,
            });
        }
        if any_offset && kept < run.onsets.len() {
            self.hand_over_switched_off(run, w_world);
        }
        std::mem::swap(&mut run.onsets, &mut run.new_onsets);
    }

    /// A pair that switched off while still compressed (its overlap carried at the last force
    /// evaluation, less the approach undone over the drift since, is positive) took its
    /// spring's energy with it. The contacts that carry onset offsets hold overlap their
    /// springs do not count: that energy is handed to them, their offsets lowered (largest
    /// first) until their springs hold it, as far as their offsets go. Only energy just lost is
    /// handed on, so none is created; what finds no offset stays lost (the account's residual).
    pub(super) fn hand_over_switched_off(&self, run: &mut Run, w_world: &Vector3<f64>) {
        let mut lost = 0.0;
        for o in &run.onsets {
            if run.new_onsets.iter().any(|x| x.feature == o.feature) {
                continue;
            }
            let vrel = run.st.v + w_world.cross(&o.rr);
            let u = o.carried + o.n.dot(&vrel) * -run.drift_h;
            if u > 0.0 {
                lost += self.normal_energy(u, self.stiffness_at(&(run.st.c + o.rr)).0);
            }
        }
        if lost <= 0.0 {
            return;
        }
        let mut order: Vec<usize> = (0..run.new_onsets.len())
            .filter(|&k| run.new_onsets[k].offset > 0.0)
            .collect();
        order.sort_by(|&a, &b| {
            run.new_onsets[b]
                .offset
                .total_cmp(&run.new_onsets[a].offset)
        });
        for k in order {
            if lost <= 0.0 {
                break;
            }
            let kn = self.stiffness_at(&(run.st.c + run.new_onsets[k].rr)).0;
            let on = &mut run.new_onsets[k];
            let held = self.normal_energy(on.carried, kn);
            let wanted = self.overlap_holding(held + lost, kn);
            let du = (wanted - on.carried).min(on.offset).max(0.0);
            on.carried += du;
            on.offset = if du >= on.offset { 0.0 } else { on.offset - du };
            lost -= self.normal_energy(on.carried, kn) - held;
            if let Some(gk) = run.contacts.iter_mut().find(|g| g.feature == on.feature) {
                gk.u = on.carried;
            }
        }
    }

    /// The overlap (m) whose normal spring (of stiffness `kn`, N/m, linear law) holds the
    /// elastic energy `e` (J).
    pub(super) fn overlap_holding(&self, e: f64, kn: f64) -> f64 {
        match self.hertz {
            None => (2.0 * e / kn).sqrt(),
            Some(h) => (e / (0.4 * h.k)).powf(0.4),
        }
    }

    /// Normal force of the contact `gk` (arm `rr` from the centre, m) over the step `motion`,
    /// the dashpot taking the velocity at x(t) from it; `fresh`: a contact that has just
    /// closed, whose dashpot impulse is corrected for the time since its touch; `beta`: the
    /// critical damping ratio there.
    pub(super) fn normal_force(
        &self,
        gk: &Geo,
        rr: &Vector3<f64>,
        motion: StepMotion<'_>,
        fresh: bool,
        beta: f64,
    ) -> NormalForce {
        let StepMotion { v_t, w_t, h } = motion;
        let (kn, ks) = self.stiffness_at(&gk.p);
        let (f_el, kt, ks) = match self.hertz {
            None => (kn * gk.u, kn, ks),
            Some(hz) => {
                let kt = hz.kt * gk.u.sqrt();
                (hz.k * gk.u * gk.u.sqrt(), kt, kt * hz.shear_ratio)
            }
        };
        let cn = 2.0 * beta * (self.m * kt).sqrt();
        // the dashpot takes the velocity at x(t), predicted from the half step with the last
        // acceleration (second order; the lagged half-step velocity alone would err by
        // O(β ω Δt) in the restitution)
        let vn_t = gk.n.dot(&(v_t + w_t.cross(rr)));
        // A contact that has just closed touched U/|vₙ| ago, not half a step ago as the step's
        // impulse assumes: correct the dashpot impulse by c(U − |vₙ|Δt/2) (else the
        // restitution errs by O(Δt) with the random phase of the touch). Only for a fresh
        // touch (U within the step's approach), never for a contact that appears deep (a new
        // floor feature under a block already in contact).
        let touch = fresh && vn_t < 0.0 && gk.u <= -1.5 * vn_t * h;
        let onset = if touch {
            cn * (gk.u / h + 0.5 * vn_t)
        } else {
            0.0
        };
        // The force itself: that impulse spread over the step is no force the contact ever
        // carried (up to 1.5 c vₙ). A fresh touch's force is the dashpot's at the touch, c₀|vₙ|
        // (c₀ the dashpot at zero overlap: 0 for Hertz); the velocity predicted at x(t) has
        // not yet seen the contact's own deceleration since the touch, so the force there
        // would be too high by O(k vₙ Δt).
        let at_position = if touch {
            let c0 = match self.hertz {
                None => cn,
                Some(_) => 0.0,
            };
            -c0 * vn_t
        } else {
            (f_el - cn * vn_t).max(0.0)
        };
        NormalForce {
            elastic: f_el,
            total: (f_el - cn * vn_t + onset).max(0.0),
            shear_stiffness: ks,
            normal_stiffness: kn,
            at_position,
        }
    }

    /// Local damping: each component of the force and of the moment (world frame) loses α
    /// times its size against the sign of its velocity `v` (of ω `w_world`); booked with the
    /// dashpots.
    pub(super) fn local_damping(&self, fo: &mut Forces, v: &Vector3<f64>, w_world: &Vector3<f64>) {
        if self.alpha > 0.0 {
            for i in 0..3 {
                let d = self.alpha * fo.force[i].abs() * v[i].signum();
                if v[i] != 0.0 {
                    fo.force[i] -= d;
                    fo.damping_force[i] -= d;
                }
                let dm = self.alpha * fo.moment[i].abs() * w_world[i].signum();
                if w_world[i] != 0.0 {
                    fo.moment[i] -= dm;
                    fo.damping_moment[i] -= dm;
                }
            }
        }
    }

    /// Newton–Euler over h (s) under the forces `fo` (orientation `r`): the half-step
    /// velocity, Euler's equations in the body frame (implicit midpoint for an anisotropic
    /// block), the dashpots' work with the step's mean velocities, then position and turn.
    pub(super) fn newton_euler(&self, run: &mut Run, r: &Matrix3<f64>, fo: &Forces, h: f64) {
        let m = self.m;
        let st = &mut run.st;
        let v_old = st.v;
        run.acc = fo.force / m;
        st.v += fo.force * (h / m);
        let torque_body = r.transpose() * fo.moment;
        let i = self.inertia;
        let w0 = st.w;
        let mut w1 = w0 + (torque_body - w0.cross(&w0.component_mul(&i))).component_div(&i) * h;
        if !self.isotropic {
            for _ in 0..3 {
                let wm = (w0 + w1) * 0.5;
                w1 = w0 + (torque_body - wm.cross(&wm.component_mul(&i))).component_div(&i) * h;
            }
        }
        run.ang_acc = r * ((w1 - w0) / h);
        st.w = w1;
        // Dissipation is booked with the step's mean velocities, the ones whose product
        // with a force gives the leapfrog's kinetic-energy change.
        let v_bar = (v_old + st.v) * 0.5;
        let w_bar = r * ((w0 + w1) * 0.5);
        run.damping -= (v_bar.dot(&fo.damping_force) + w_bar.dot(&fo.damping_moment)) * h;
        st.c += st.v * h;
        run.drift_h = h;
        st.q = UnitQuaternion::new_normalize(
            (st.q * UnitQuaternion::from_scaled_axis(st.w * h)).into_inner(),
        );
        st.t += h;
        run.steps += 1;
        run.half_step = Some(h);
    }

    /// Contact episodes after a step: contact after more than the gap is a new impact (the
    /// last episode closed); an episode that lasts five contact times becomes a ground phase
    /// (its impact reported then, with the speed and loss up to then, and a `slide_start`
    /// event; the first one is the run's slide start); one whose contact stays open for the gap
    /// is over.
    pub(super) fn book_episode(&self, run: &mut Run, step: &Step, in_contact: bool, events: bool) {
        let t = run.st.t;
        if !in_contact {
            // the step in which the contacts opened: the shear springs release their energy
            // over its drift, part of the contact's loss
            if let Some(ep) = run.episode.as_mut()
                && (t - step.h - ep.last_t).abs() < 0.5 * step.h
            {
                ep.last_diss = run.damping + run.friction;
            }
            if let Some(ep) = run.episode
                && t - run.last_contact_t > self.gap
            {
                run.episode = None;
                self.close_episode(ep, true, &mut run.events, events);
            }
            return;
        }
        if !run.had_contact || t - run.last_contact_t > self.gap {
            // a new impact (the previous episode, if any, is closed here)
            if let Some(ep) = run.episode.take() {
                self.close_episode(ep, true, &mut run.events, events);
            }
            run.impacts += 1;
            run.first_impact_done = true;
            run.episode = Some(Episode {
                t0: t - step.h,
                speed_before: step.speed_before,
                // the impact's first step dissipates too (its dashpot's onset most)
                diss_before: step.diss_before,
                peak: 0.0,
                p: run.st.c,
                ground: false,
                impact: true,
                last_speed: run.st.v.norm(),
                last_p: run.st.c,
                last_diss: run.damping + run.friction,
                last_t: t,
            });
        }
        run.had_contact = true;
        run.last_contact_t = t;
        let Some(ep) = run.episode.as_mut() else {
            return;
        };
        ep.peak = ep.peak.max(step.forces.normal_total);
        ep.last_speed = run.st.v.norm();
        ep.last_p = run.st.c;
        ep.last_diss = run.damping + run.friction;
        ep.last_t = t;
        let became_ground = !ep.ground && t - ep.t0 > 5.0 * self.t_contact;
        if !became_ground {
            return;
        }
        ep.ground = true;
        if run.slide_start.is_none() {
            run.slide_start = Some(self.mean.along(&run.st.c));
        }
        if events {
            let speed = run.st.v.norm();
            // the impact that became the ground phase, reported as it becomes it (not when
            // the ground phase ends, seconds of sliding later)
            run.events.push(self.event(
                ep.t0,
                EventKind::Impact,
                &ep.p,
                EventChange {
                    before: ep.speed_before,
                    after: speed,
                    lost: run.damping + run.friction - ep.diss_before,
                    peak: Some(ep.peak),
                },
            ));
            ep.impact = false;
            run.events.push(self.event(
                t,
                EventKind::SlideStart,
                &run.st.c,
                EventChange {
                    before: speed,
                    after: speed,
                    lost: 0.0,
                    peak: None,
                },
            ));
        }
    }

    /// A column reached inside the step h (s; the centre moved by v h along a line) or the
    /// lower end passed: the block put back to where it happened.
    pub(super) fn reach_in_step(
        &self,
        run: &mut Run,
        h: f64,
        cfg: &RunSettings,
    ) -> Option<StopReason> {
        let dt = self.dt;
        let st = &mut run.st;
        if cfg.has_columns {
            let c_prev = st.c - st.v * h;
            // the drift is a segment: with both its ends within the clearance of the last
            // checked point, it is all farther than every column's reach
            let (u, u_prev) = (self.mean.along(&st.c), self.mean.along(&c_prev));
            let within = |(u0, y0, d): (f64, f64, f64), uu: f64, yy: f64| {
                (uu - u0) * (uu - u0) + (yy - y0) * (yy - y0) < d * d
            };
            let clear = run
                .column_clear
                .is_some_and(|cl| within(cl, u, st.c.y) && within(cl, u_prev, c_prev.y));
            if clear {
                // nothing to test
            } else if let Some((tc, k)) = self.columns.first_reach(
                &self.mean,
                &self.supports,
                Piece::new(&c_prev, &st.v, &Vector3::zeros(), h),
                0.0,
            ) {
                st.t -= h - tc;
                st.c = c_prev + st.v * tc;
                run.drift_h = tc;
                run.support = Some(k);
                return Some(StopReason::Support);
            } else {
                run.column_clear = self
                    .columns
                    .clearance(&self.supports, u, st.c.y)
                    .map(|d| (u, st.c.y, d));
            }
        }
        // lines are reached before the lower end (a barrier stands in front of its support)
        if !self.lines.is_empty()
            && let Some(reason) = self.lines_in_step(run, cfg)
        {
            return Some(reason);
        }
        let st = &mut run.st;
        let along = self.mean.along(&st.c);
        if along >= self.length {
            let frac = if along > run.prev_along {
                (along - self.length) / (along - run.prev_along)
            } else {
                0.0
            };
            st.t -= frac * dt;
            st.c -= st.v * (frac * dt);
            run.drift_h -= frac * dt;
            return Some(StopReason::LowerEnd);
        }
        run.prev_along = along;
        None
    }

    /// At rest: in contact, slower than REST_SPEED_M_S (centre and farthest point) for
    /// REST_TIME_S; or, over REST_TIME_S of unbroken contact, centre and farthest point moved
    /// less than REST_SPEED_M_S·REST_TIME_S (a block held by its stuck shear springs may keep
    /// an elastic vibration that no dashpot damps, its speeds above the threshold while it
    /// goes nowhere).
    pub(super) fn at_rest(&self, run: &mut Run, in_contact: bool) -> bool {
        let st = &run.st;
        let still = st.v.norm() < REST_SPEED_M_S
            && st.w.norm() * self.shape.r_max < REST_SPEED_M_S
            && in_contact;
        if still {
            let since = *run.still_since.get_or_insert(st.t);
            if st.t - since >= REST_TIME_S {
                return true;
            }
        } else {
            run.still_since = None;
        }
        if !in_contact {
            run.quiet_window = None;
            return false;
        }
        let (t0, c0, q0) = *run.quiet_window.get_or_insert((st.t, st.c, st.q));
        if st.t - t0 >= REST_TIME_S {
            let reach = REST_SPEED_M_S * REST_TIME_S;
            if (st.c - c0).norm() < reach && q0.angle_to(&st.q) * self.shape.r_max < reach {
                return true;
            }
            run.quiet_window = Some((st.t, st.c, st.q));
        }
        false
    }

    /// The run's report: the velocities brought to the end time and the springs to the end
    /// position (second order), the last episode closed, the phase and the stop event.
    pub(super) fn finish(
        &self,
        mut run: Run,
        reason: StopReason,
        e_start: f64,
        cfg: &RunSettings,
    ) -> PhysicsResult<RunOut> {
        let lagged = run.st;
        let mut st = self.synced(&run.st, run.half_step, &run.acc, &run.ang_acc);
        // the springs at the end position: the normal ones from its overlaps, the shear ones
        // carried over the last drift (the slip on it booked)
        let in_contact = !run.springs.is_empty();
        if in_contact {
            let (stored, slip) = self.stored_at_end(&mut run, &lagged, &st, cfg, None);
            run.stored = stored;
            run.friction += slip;
        }
        let mut barrier_event = None;
        if reason == StopReason::Barrier {
            // the barrier takes the kinetic energy the block brought to it (its crossing's)
            let (kt, kr, _) = self.energy(&st);
            run.barrier += kt + kr;
            barrier_event = cfg.log_events.then(|| {
                let before = st.v.norm();
                self.event(
                    st.t,
                    EventKind::Barrier,
                    &st.c,
                    EventChange {
                        before,
                        after: 0.0,
                        lost: kt + kr,
                        peak: None,
                    },
                )
            });
            st.v = Vector3::zeros();
            st.w = Vector3::zeros();
        }
        let lost = run.damping + run.friction + run.barrier;
        self.check_energy(&st, run.stored, lost, (e_start, run.ke_start))?;
        if let Some(ep) = run.episode.take()
            && ep.impact
        {
            self.close_episode(ep, false, &mut run.events, cfg.log_events);
        }
        run.events.extend(barrier_event);
        let reason = match (reason, self.span_support) {
            (StopReason::LowerEnd, Some(k)) => {
                run.support = Some(k);
                StopReason::Support
            }
            (r, _) => r,
        };
        let stopped = matches!(reason, StopReason::AtRest | StopReason::Barrier);
        let phase = match reason {
            _ if stopped => Phase::Stopped,
            _ if !in_contact => Phase::Flight,
            _ if run.slip_max < 1e-3 * st.v.norm() => Phase::Roll,
            _ => Phase::Slide,
        };
        let stop_along = stopped.then(|| self.mean.along(&st.c));
        if cfg.log_events && stopped {
            run.events.push(self.event(
                st.t,
                EventKind::Stop,
                &st.c,
                EventChange {
                    before: st.v.norm(),
                    after: 0.0,
                    lost: 0.0,
                    peak: None,
                },
            ));
        }
        if let Some(r) = run.rec.as_mut()
            && r.tr.time.last().is_none_or(|&t| t < st.t)
        {
            self.sample(r, &st, lost, run.stored)?;
        }
        Ok(RunOut {
            st,
            reason,
            phase,
            impacts: run.impacts,
            slide_start: run.slide_start,
            stop_along,
            max_bounce: run.max_bounce,
            damping: run.damping,
            friction: run.friction,
            stored: run.stored,
            e_start,
            ke_start: run.ke_start,
            steps: run.steps,
            max_overlap: run.max_overlap,
            events: run.events,
            trajectory: run.rec.map(|r| r.tr),
            support: run.support,
            barrier: run.barrier,
            crossings: run.crossings,
        })
    }

    /// Work the shear spring `sp` of a contact that opened dissipates over the drift `h` (s)
    /// with the block's velocities in `st` (ω in the world frame `w_world`): its force falls to
    /// zero along it (see [`shear_work`]).
    pub(super) fn opened_spring_work(
        &self,
        sp: &Spring,
        st: &State,
        w_world: &Vector3<f64>,
        h: f64,
    ) -> f64 {
        let vrel = st.v + w_world.cross(&sp.rr);
        let vt = vrel - sp.n * sp.n.dot(&vrel);
        shear_work(&sp.fs, sp.energy(), &Vector3::zeros(), 0.0, &(vt * h))
    }

    /// Elastic energy held in the contacts at the end state `end` (J), and the shear work
    /// dissipated on the way there: the springs as the last step left them are carried over
    /// the drift `h` (s) since with the velocities of `lagged` (the leapfrog's half-step ones),
    /// rotated into the end's tangent planes and capped at μ times the end's elastic force; a
    /// spring whose contact is no longer closed releases its energy. With `carried`, the
    /// carried springs of the pairs still closed are pushed there (a pair new at the end has
    /// none: its next force evaluation sees it as a fresh touch).
    pub(super) fn stored_at_end(
        &self,
        run: &mut Run,
        lagged: &State,
        end: &State,
        cfg: &RunSettings<'_>,
        mut carried: Option<&mut Vec<Spring>>,
    ) -> (f64, f64) {
        let Run {
            springs,
            onsets,
            drift_h: h,
            tris,
            contacts: geos,
            ..
        } = run;
        let h = *h;
        let r = self.rot(&end.q);
        self.contacts(&end.c, &r, tris, geos);
        let w_world = r * lagged.w;
        let (mut stored, mut friction) = (0.0, 0.0);
        for gk in geos.iter_mut() {
            // the offsets as the last step left them (a pair new at the end: unloaded; a
            // sphere has none, see [`Model::onset_offsets`])
            if self.shape.sphere_radius.is_none() {
                gk.u -= onsets
                    .iter()
                    .find(|o| o.feature == gk.feature)
                    .map_or(gk.u, |o| o.offset.min(gk.u));
            }
            let k = self.stiffness_at(&gk.p);
            stored += self.normal_energy(gk.u, k.0);
            let Some(old) = springs.iter().find(|s| s.key == gk.key) else {
                continue;
            };
            let rr = gk.p - end.c;
            let vrel = lagged.v + w_world.cross(&rr);
            let vt = vrel - gk.n * gk.n.dot(&vrel);
            let (f_el, ks) = self.elastic_and_shear(gk.u, k);
            let mu = self.draws_at(cfg, &gk.p).0;
            let mag = old.fs.norm();
            let pr = old.fs - gk.n * gk.n.dot(&old.fs);
            let pn = pr.norm();
            let fs_old = if pn > 0.0 { pr * (mag / pn) } else { pr };
            let d = vt * h;
            let mut fs = fs_old - d * ks;
            let cap = mu * f_el;
            let fs_n = fs.norm();
            if fs_n > cap {
                fs *= if fs_n > 0.0 { cap / fs_n } else { 0.0 };
            }
            let es_new = if ks > 0.0 {
                fs.norm_squared() / (2.0 * ks)
            } else {
                0.0
            };
            stored += es_new;
            friction += shear_work(&fs_old, old.energy(), &fs, es_new, &d);
            if let Some(out) = carried.as_deref_mut() {
                out.push(Spring {
                    key: gk.key,
                    fs,
                    ks,
                    rr,
                    n: gk.n,
                    u: gk.u,
                });
            }
        }
        for sp in springs {
            if !geos.iter().any(|g| g.key == sp.key) {
                friction += self.opened_spring_work(sp, lagged, &w_world, h);
            }
        }
        (stored, friction)
    }

    /// Elastic normal force (N) and shear stiffness (N/m) of a contact of overlap `u` (m) on
    /// a floor of stiffnesses `(kn, ks)` (N/m, linear law).
    pub(super) fn elastic_and_shear(&self, u: f64, (kn, ks): (f64, f64)) -> (f64, f64) {
        match self.hertz {
            None => (kn * u, ks),
            Some(hz) => (hz.k * u * u.sqrt(), hz.kt * u.sqrt() * hz.shear_ratio),
        }
    }

    /// Elastic energy (J) of a normal spring of overlap `u` (m), stiffness `kn` (N/m, linear
    /// law).
    pub(super) fn normal_energy(&self, u: f64, kn: f64) -> f64 {
        match self.hertz {
            None => 0.5 * kn * u * u,
            Some(h) => 0.4 * h.k * u * u * u.sqrt(),
        }
    }

    /// The state with its velocities brought to its time: the leapfrog's velocities lag the
    /// positions by half a step h, so v + a h/2 and ω + α h/2 with the last step's
    /// accelerations (world frame; error O(h²)). Without a pending half step, the state itself.
    pub(super) fn synced(
        &self,
        st: &State,
        half_step: Option<f64>,
        acc: &Vector3<f64>,
        wacc_world: &Vector3<f64>,
    ) -> State {
        let Some(h) = half_step else { return *st };
        let r = self.rot(&st.q);
        State {
            v: st.v + acc * (0.5 * h),
            w: st.w + r.transpose() * wacc_world * (0.5 * h),
            ..*st
        }
    }

    /// Free flight over τ: the parabola and the torque-free rotation.
    pub(super) fn fly(&self, st: &State, tau: f64) -> State {
        let (q, w) = self.free_rotation(st.q, st.w, tau);
        let gv = Vector3::new(0.0, 0.0, -self.g);
        State {
            t: st.t + tau,
            c: st.c + st.v * tau + gv * (0.5 * tau * tau),
            v: st.v + gv * tau,
            q,
            w,
        }
    }

    /// First time in (0, τ] at which the centre's along-dip position reaches the face length.
    pub(super) fn along_cross(&self, st: &State, tau: f64) -> Option<f64> {
        self.along_reach(st, self.length, tau)
    }

    /// First time in [0, τ] at which the centre's along-dip position in free flight from `st`
    /// reaches `target` (m).
    pub(super) fn along_reach(&self, st: &State, target: f64, tau: f64) -> Option<f64> {
        let d = self.mean.dip_dir();
        let s0 = self.mean.along(&st.c) - target;
        let b = d.dot(&st.v);
        let a = -self.g * d.z; // d²s/dt² = g sin θ
        super::super::terrain::outward_root(s0, b, a).filter(|&t| t <= tau)
    }

    pub(super) fn event(
        &self,
        t: f64,
        kind: EventKind,
        p: &Vector3<f64>,
        change: EventChange,
    ) -> Event {
        let EventChange {
            before,
            after,
            lost,
            peak,
        } = change;
        Event {
            time: t,
            kind,
            position: v3(p),
            along_dip: self.mean.along(p),
            speed_before: before,
            speed_after: after,
            energy_lost: lost,
            peak_contact_force: peak,
            zone: None,
        }
    }

    /// Reports an episode's impact (speed after = at its last contact) and, when a ground
    /// phase ends by separation, the take-off.
    pub(super) fn close_episode(
        &self,
        ep: Episode,
        separated: bool,
        evs: &mut Vec<Event>,
        events: bool,
    ) {
        if !events {
            return;
        }
        if ep.impact {
            evs.push(self.event(
                ep.t0,
                EventKind::Impact,
                &ep.p,
                EventChange {
                    before: ep.speed_before,
                    after: ep.last_speed,
                    lost: ep.last_diss - ep.diss_before,
                    peak: Some(ep.peak),
                },
            ));
        }
        if ep.ground && separated {
            evs.push(self.event(
                ep.last_t,
                EventKind::TakeOff,
                &ep.last_p,
                EventChange {
                    before: ep.last_speed,
                    after: ep.last_speed,
                    lost: 0.0,
                    peak: None,
                },
            ));
        }
    }

    pub(super) fn sample(
        &self,
        r: &mut Recorder,
        st: &State,
        diss: f64,
        _stored: f64,
    ) -> PhysicsResult<()> {
        if r.tr.time.len() >= r.max {
            return Err(PhysicsError::invalid(
                Param::TrajectorySampleInterval,
                r.interval,
                format!("the trajectory would need more than {} samples", r.max),
            ));
        }
        let (kt, kr, pe) = self.energy(st);
        let w = st.q * st.w;
        let tr = &mut r.tr;
        tr.time.push(st.t);
        tr.position.push(v3(&st.c));
        tr.along_dip.push(self.mean.along(&st.c));
        tr.height.push(self.height_of_centre(&st.c).max(0.0));
        tr.velocity.push(v3(&st.v));
        tr.speed.push(st.v.norm());
        tr.angular_velocity.push(v3(&w));
        tr.orientation.push([st.q.w, st.q.i, st.q.j, st.q.k]);
        tr.kinetic_energy.push(kt + kr);
        tr.rotational_energy.push(kr);
        tr.potential_energy.push(pe);
        tr.dissipated_energy.push(diss);
        Ok(())
    }
}

/// The block's motion over one step as a contact's normal force reads it (see
/// [`Model::normal_force`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct StepMotion<'a> {
    /// Velocity of the centre predicted at x(t) (world frame), m/s.
    pub(super) v_t: &'a Vector3<f64>,
    /// Angular velocity predicted at x(t) (world frame), rad/s.
    pub(super) w_t: &'a Vector3<f64>,
    /// The step h, s.
    pub(super) h: f64,
}

/// The normal force of one contact over one step (see [`Model::normal_force`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct NormalForce {
    /// Elastic force of the spring, N.
    pub(super) elastic: f64,
    /// Spring–dashpot force applied over the step (≥ 0, a fresh touch's dashpot impulse
    /// corrected for the time since the touch), N.
    pub(super) total: f64,
    /// Shear stiffness at the overlap, N/m.
    pub(super) shear_stiffness: f64,
    /// Normal stiffness kₙ of the floor there (linear law), N/m.
    pub(super) normal_stiffness: f64,
    /// The force the contact carries at the step's position (≥ 0; a fresh touch: at the
    /// touch), N: what its peak is made of.
    pub(super) at_position: f64,
}

/// The force (N) that makes up for a switch of a contact's nearest floor feature inside the
/// last drift. Its overlap is the distance to the floor's surface (see
/// [`Model::depth_below_surface`]), the smaller of its distances to two facets' planes
/// across a convex crease (or to two faces of the block for a floor peak): continuous, but
/// its gradient, the normal, jumps where the two are equal. The leapfrog applies each step's
/// force over the half drifts either side of its position, so the old normal `old.n` and the
/// new one `gk.n` share the drift at its midpoint instead of at the switch: a work error of
/// up to half a drift's (F_old − F_new)·Δx, O(Δt), of either sign. Locating the switch on
/// the drift (the two planes' distances, linear along it, equal at the fraction φ) and adding
/// (F_old − F_new)(φ − ½) to this step's force gives the work the force did along the drift,
/// to O(Δt²). `p_prev`: the contact point at the last evaluation (its arm from the centre
/// then added to the centre then), m; `f_el`: the elastic force, N. Zero unless the old
/// feature was the nearer at the start of the drift and the new one at its end.
fn crease_kink_force(old: &Spring, gk: &Geo, p_prev: &Vector3<f64>, f_el: f64) -> Vector3<f64> {
    let (na, nb) = (old.n, gk.n);
    if na.dot(&nb) >= 1.0 - 1e-12 {
        return Vector3::zeros();
    }
    let dp = gk.p - p_prev;
    // distance to the old plane less that to the new, at the drift's start and end
    let g0 = old.u - gk.u - nb.dot(&dp);
    let g1 = old.u - na.dot(&dp) - gk.u;
    if !(g0 < 0.0 && g1 > 0.0) {
        return Vector3::zeros();
    }
    let phi = g0 / (g0 - g1);
    (na - nb) * (f_el * (phi - 0.5))
}
