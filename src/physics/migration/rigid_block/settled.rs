//! The settled slide on a flat patch: detected, and its steps taken in closed form (the
//! leapfrog's own travel, friction work and energy) instead of one by one.

use super::*;

impl Model<'_> {
    /// A settled slide on the plane, or on a flat patch of a mesh floor, skipped in closed
    /// form: N leapfrog steps under the constant force `fo`, exactly, with the dashpots' and
    /// the slip's work over them.
    pub(super) fn skip_settled_slide(&self, run: &mut Run, fo: &Forces, cfg: &RunSettings) {
        let dt = self.dt;
        let Some((v_t, a_t)) = self.settled_slide(run, fo, cfg) else {
            return;
        };
        let mut n_skip = self.steady_steps(
            &run.st,
            &v_t,
            &a_t,
            cfg.end_t,
            run.rec.as_ref().map(|r| r.next),
            self.skip_end(run),
        );
        if n_skip < 8 {
            return;
        }
        // never past a column: the skip ends two steps before the first step whose drift would
        // reach one, and the steps from there find the reach as they do everywhere
        if cfg.has_columns {
            match self.steps_before_column(&run.st, n_skip, &v_t, &a_t) {
                Some(n) if n >= 8 => n_skip = n,
                Some(_) => return,
                None => {}
            }
        }
        // on a mesh floor, only as far as the footprint stays on the flat patch
        if cfg.plane_normal.is_none() {
            match self.steps_on_patch(run, n_skip, &v_t, &a_t) {
                Some(n) => n_skip = n,
                None => return,
            }
        }
        // never into the floor: on a mesh floor the skipped path is checked against the floor
        // itself (a check independent of the patch search), shortened until no vertex along
        // it goes deeper than the contacts it starts with
        if cfg.plane_normal.is_none() {
            while n_skip >= 8 && !self.skip_stays_out(run, n_skip, &v_t, &a_t) {
                n_skip /= 2;
            }
            if n_skip < 8 {
                return;
            }
        }
        // the rest checks decide at the steps the stepped run would take them
        let window;
        (n_skip, window) = self.rest_checks_in_skip(run, n_skip, &v_t, &a_t);
        if n_skip < 8 {
            return;
        }
        let nf = n_skip as f64;
        // the skipped piece ends before the slide's stop (the velocity never turns) and its
        // slip takes energy: a piece that would not is stepped
        let v_end = v_t + a_t * (nf * dt);
        let drifts = v_t * (nf * dt) + a_t * (0.5 * dt * dt * nf * (nf - 1.0));
        if v_end.dot(&v_t) <= 0.0 || drifts.dot(&fo.slip_force) > 0.0 {
            return;
        }
        run.quiet_window = window;
        if !self.lines.is_empty() {
            self.lines_in_skip(run, n_skip, &v_t, &a_t);
        }
        // N leapfrog steps under the constant force, exactly: v ← v + N a h,
        // x ← x + N h v + a h² N(N+1)/2; the damping with the steps' mean velocities (their
        // kinetic-energy change), the slip over the drifts the springs see (one behind)
        let path = v_t * (nf * dt) + a_t * (0.5 * dt * dt * nf * nf);
        run.damping -= path.dot(&fo.damping_force);
        run.friction -= drifts.dot(&fo.slip_force);
        let st = &mut run.st;
        st.c += v_t * (nf * dt) + a_t * (0.5 * dt * dt * nf * (nf + 1.0));
        st.v += a_t * (nf * dt);
        st.t += nf * dt;
        run.acc = a_t;
        run.half_step = Some(dt);
        run.last_contact_t = st.t;
        if let Some(ep) = run.episode.as_mut() {
            ep.last_speed = st.v.norm();
            ep.last_p = st.c;
            ep.last_diss = run.damping + run.friction;
            ep.last_t = st.t;
        }
        run.prev_along = self.mean.along(&st.c);
    }

    /// Steps of `n_skip` a settled slide (velocity `v_t`, acceleration `a_t`) may skip so that
    /// the rest checks ([`Model::at_rest`]) decide as in the stepped run: the skip ends two
    /// steps before the speed falls below the rest speed, before the step at which a started
    /// rest timer would reach its time, and before a step at which the quiet window would be
    /// judged with the block slow enough to be found quiet (or too near a step boundary to
    /// tell). A window judged inside the skip with the block faster than that fails, and is
    /// re-anchored where and when the stepped run re-anchors it: returns the steps and the
    /// window after them.
    fn rest_checks_in_skip(
        &self,
        run: &Run,
        n_skip: u64,
        v_t: &Vector3<f64>,
        a_t: &Vector3<f64>,
    ) -> (u64, Option<QuietWindow>) {
        let dt = self.dt;
        let t = run.st.t;
        let mut n = n_skip as f64;
        let vs = v_t.norm();
        let a_s = a_t.dot(v_t) / vs;
        match run.still_since {
            Some(since) => n = n.min(((since + REST_TIME_S - t) / dt).ceil() - 2.0),
            None if a_s < 0.0 => {
                n = n.min(((vs - REST_SPEED_M_S) / (-a_s * dt)).floor() - 2.0);
            }
            None => {}
        }
        let mut window = run.quiet_window;
        if let Some((mut t0, mut c0, q0)) = window {
            let at = |k: f64| run.st.c + v_t * (k * dt) + a_t * (0.5 * dt * dt * k * (k + 1.0));
            loop {
                let x = (t0 + REST_TIME_S - t) / dt;
                let k = x.ceil().max(1.0);
                if k > n {
                    break;
                }
                let speed = (v_t + a_t * (k * dt)).norm();
                if speed < 2.0 * REST_SPEED_M_S || (x - x.round()).abs() < 1e-6 {
                    n = n.min(k - 2.0);
                    break;
                }
                t0 = t + k * dt;
                c0 = at(k);
            }
            window = Some((t0, c0, q0));
        }
        (if n > 0.0 { n as u64 } else { 0 }, window)
    }

    /// Steps a settled slide from `st` (velocity `v_t`, acceleration `a_t`) may skip of `n_skip`
    /// before a column: None when none of the steps' drifts comes within a column's reach, else
    /// the whole steps before the first that might, less two (0 when fewer). After k steps the
    /// centre is at c + v Δt k + a Δt² k(k + 1)/2, the parabola c + (v Δt + a Δt²/2) k +
    /// (a Δt²/2) k² in k; the steps' drifts are its chords, which stray from it by at most
    /// |a| Δt²/8, so the columns' reach is widened by |a| Δt² (and rounding) for the test.
    fn steps_before_column(
        &self,
        st: &State,
        n_skip: u64,
        v_t: &Vector3<f64>,
        a_t: &Vector3<f64>,
    ) -> Option<u64> {
        let dt = self.dt;
        let vk = v_t * dt + a_t * (0.5 * dt * dt);
        let ak = a_t * (dt * dt);
        let margin = ak.norm() + 1e-9 * (1.0 + self.shape.r_max);
        let (k_hit, _) = self.columns.first_reach(
            &self.mean,
            &self.supports,
            Piece::new(&st.c, &vk, &ak, n_skip as f64),
            margin,
        )?;
        let n = k_hit.floor() - 2.0;
        Some(if n > 0.0 { (n as u64).min(n_skip) } else { 0 })
    }

    /// Whether the block, translated along the skipped path of `n_skip` steps (velocity `v_t`,
    /// acceleration `a_t`, no rotation), keeps every vertex out of the floor beyond the deepest
    /// overlap its contacts carry now (twice that, plus rounding), at 16 points of the path and
    /// its end, measured along the normal of the facet under each vertex; a vertex off the
    /// floor fails too.
    fn skip_stays_out(
        &self,
        run: &Run,
        n_skip: u64,
        v_t: &Vector3<f64>,
        a_t: &Vector3<f64>,
    ) -> bool {
        let dt = self.dt;
        let r = self.rot(&run.st.q);
        let u_max = run.contacts.iter().map(|g| g.u).fold(0.0f64, f64::max);
        let tol = 2.0 * u_max + 1e-9 * (1.0 + self.shape.r_max);
        let nf = n_skip as f64;
        (1..=16).all(|k| {
            let m = nf * f64::from(k) / 16.0;
            let c = run.st.c + v_t * (m * dt) + a_t * (0.5 * dt * dt * m * (m + 1.0));
            self.shape.vertices.iter().all(|b| {
                let p = c + r * b;
                self.floor.locate(p.x, p.y, 0.0, 0.0).is_some_and(|f| {
                    let pl = self.floor.facet_plane(f);
                    (pl.z(p.x, p.y) - p.z) * pl.normal().z <= tol
                })
            })
        })
    }

    /// The tangential velocity and acceleration (m/s, m/s²) of a slide settled for two
    /// contact times: every contact (three or more) slipping on one plane (the floor's, or a
    /// flat patch's with vertex–face contacts only), no local damping, no normal motion, no
    /// spin, and the acceleration along the velocity, all within
    /// STEADY_TOLERANCE.
    pub(super) fn settled_slide(
        &self,
        run: &mut Run,
        fo: &Forces,
        cfg: &RunSettings,
    ) -> Option<(Vector3<f64>, Vector3<f64>)> {
        let contacts = &run.contacts;
        let one_plane = if self.skip_slides
            && self.alpha == 0.0
            && contacts.len() >= 3
            && fo.slipping == contacts.len()
        {
            cfg.plane_normal.or_else(|| {
                let n = contacts[0].n;
                contacts
                    .iter()
                    .all(|g| g.key < (1 << 62) && g.n.dot(&n) >= 1.0 - 1e-12)
                    .then_some(n)
            })
        } else {
            None
        };
        let Some(nrm) = one_plane else {
            run.steady_since = None;
            return None;
        };
        let st = &run.st;
        let acc = fo.force / self.m;
        let a_t = acc - nrm * nrm.dot(&acc);
        let v_t = st.v - nrm * nrm.dot(&st.v);
        let vs = v_t.norm();
        let tol_a = STEADY_TOLERANCE * self.g;
        // a slide: the slip force opposes the velocity (friction takes energy, never gives
        // it), and the acceleration along the velocity is at most gravity's there (no contact
        // pushes the block on); a block moving up the slope with its springs still capped the
        // way they held it sliding down (just past the stop of a decelerating slide) is not
        // one, and skipped so it would rise with friction driving it
        let e = v_t / vs.max(f64::MIN_POSITIVE);
        let slip = fo.slip_force.norm();
        let g_along = -self.g * e.z;
        let settled = vs > 0.0
            && (slip == 0.0 || fo.slip_force.dot(&e) < 0.0)
            && a_t.dot(&e) <= g_along + tol_a
            && nrm.dot(&acc).abs() <= tol_a
            && nrm.dot(&st.v).abs() <= STEADY_TOLERANCE * vs.max(1.0)
            && run.ang_acc.norm() * self.shape.r_max <= tol_a
            && st.w.norm() * self.shape.r_max <= STEADY_TOLERANCE * vs.max(1.0)
            && (a_t - v_t * (a_t.dot(&v_t) / (vs * vs))).norm() <= tol_a;
        if !settled {
            run.steady_since = None;
            return None;
        }
        let since = *run.steady_since.get_or_insert(st.t);
        if st.t - since < 2.0 * self.t_contact {
            return None;
        }
        Some((v_t, a_t))
    }

    /// How many of `n_skip` steps a settled slide (`v_t`, `a_t`) on a mesh floor may skip
    /// with its footprint on the flat patch: None (and wait until the centre has moved on)
    /// when fewer than eight.
    pub(super) fn steps_on_patch(
        &self,
        run: &mut Run,
        n_skip: u64,
        v_t: &Vector3<f64>,
        a_t: &Vector3<f64>,
    ) -> Option<u64> {
        let dt = self.dt;
        if run
            .patch_wait
            .is_some_and(|(c, d)| (run.st.c - c).norm() < d)
        {
            return None;
        }
        run.patch_wait = None;
        let e = v_t / v_t.norm();
        let (b, c2) = (e.dot(v_t) * dt, 0.5 * e.dot(a_t) * dt * dt);
        let nf = n_skip as f64;
        let want = b * nf + c2 * nf * (nf + 1.0);
        let r = self.rot(&run.st.q);
        let (on_patch, wait) =
            self.flat_patch_run(&run.st.c, &r, &run.contacts, &e, want, &mut run.tris);
        if on_patch < want {
            let n_patch = steps_to_travel(b, c2, on_patch).floor() - 2.0;
            let n = if n_patch > 0.0 {
                n_skip.min(n_patch as u64)
            } else {
                0
            };
            if n < 8 {
                run.patch_wait = Some((run.st.c, wait));
                return None;
            }
            return Some(n);
        }
        Some(n_skip)
    }

    /// Whole time steps a settled slide on the plane may skip from `st` (velocity `v_t` and
    /// constant acceleration `a_t` in the plane): it stops two steps short of the end time and
    /// of the along-dip position `end_along` (m: the lower end, or a barrier's line before
    /// it), lands on the next trajectory sample, and takes at most 90 % of the steps left
    /// before a decelerating slide would stop.
    pub(super) fn steady_steps(
        &self,
        st: &State,
        v_t: &Vector3<f64>,
        a_t: &Vector3<f64>,
        end_t: f64,
        next_sample: Option<f64>,
        end_along: f64,
    ) -> u64 {
        let dt = self.dt;
        let mut n = f64::INFINITY;
        if end_t.is_finite() {
            n = n.min(((end_t - st.t) / dt).floor() - 2.0);
        }
        if let Some(tn) = next_sample {
            n = n.min(((tn - st.t) / dt).ceil().max(0.0));
        }
        let vs = v_t.norm();
        let a_s = a_t.dot(v_t) / vs;
        if a_s < 0.0 {
            n = n.min((0.9 * vs / (-a_s * dt)).floor());
        }
        // along(N) = s₀ + b N + c N (N + 1) reaches the face length
        let d = self.mean.dip_dir();
        let s0 = self.mean.along(&st.c) - end_along;
        let b = d.dot(v_t) * dt;
        let c = 0.5 * d.dot(a_t) * dt * dt;
        n = n.min(steps_to_travel(b, c, -s0).floor() - 2.0);
        if n.is_finite() && n > 0.0 {
            n as u64
        } else {
            0
        }
    }

    /// How far (m, at most `limit`) the block at (c, R), sliding settled on the flat patch of a
    /// mesh floor that carries its vertex–face contacts `geos`, may translate along the unit
    /// vector `e` (in the patch) while the stepped run would see the same contacts: every floor
    /// triangle whose plan box meets the block's plan box (padded by 1 % of r_max) anywhere
    /// along the way lies in the contact facet's plane, and every contact vertex and the centre
    /// stay over such a triangle (no hole, not off the floor). Also returns how far the centre
    /// should move before asking again when the patch ends sooner (past that edge of the patch).
    ///
    /// The footprint is swept in chunks of its own size; a non-coplanar triangle limits the run
    /// where the moving box first meets its plan box, a gap in the cover where the first point
    /// leaves the union of the coplanar triangles along its path.
    pub(super) fn flat_patch_run(
        &self,
        c: &Vector3<f64>,
        r: &Matrix3<f64>,
        geos: &[Geo],
        e: &Vector3<f64>,
        limit: f64,
        tris: &mut Vec<FloorTriangle>,
    ) -> (f64, f64) {
        let sh = &self.shape;
        let fl = self.floor;
        // the contact plane: the facet under the first contact vertex
        let p0 = c + r * sh.vertices[geos[0].key as usize];
        let Some(fr) = fl.locate(p0.x, p0.y, 0.0, 0.0) else {
            return (0.0, 0.0);
        };
        let pl = fl.facet_plane(fr);
        let n = pl.normal();
        let coplanar = |t: &FloorTriangle| {
            let tn = (t.corners[1] - t.corners[0])
                .cross(&(t.corners[2] - t.corners[0]))
                .normalize();
            tn.dot(&n) >= 1.0 - 1e-12
                && t.corners
                    .iter()
                    .all(|x| (pl.height(x) * n.z).abs() <= 1e-12 * (1.0 + sh.r_max + x.norm()))
        };
        let margin = 0.01 * sh.r_max;
        let (mut bx0, mut bx1, mut by0, mut by1) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        let (mut lo_e, mut hi_e) = (f64::INFINITY, f64::NEG_INFINITY);
        for b in &sh.vertices {
            let p = c + r * b;
            bx0 = bx0.min(p.x - margin);
            bx1 = bx1.max(p.x + margin);
            by0 = by0.min(p.y - margin);
            by1 = by1.max(p.y + margin);
            lo_e = lo_e.min(e.dot(&(p - c)));
            hi_e = hi_e.max(e.dot(&(p - c)));
        }
        // the points that must stay over the patch: the contact vertices and the centre
        let mut pts: Vec<[f64; 2]> = geos
            .iter()
            .map(|g| {
                let p = c + r * sh.vertices[g.key as usize];
                [p.x, p.y]
            })
            .collect();
        pts.push([c.x, c.y]);
        let (ex, ey) = (e.x, e.y);
        let chunk = (bx1 - bx0).max(by1 - by0).max(fl.cell_size());
        let eps = 1e-9 * (1.0 + sh.r_max);
        let mut run = limit;
        let mut cover: Vec<[f64; 2]> = Vec::new();
        let mut sa = 0.0f64;
        while sa < run {
            let sb = (sa + chunk).min(run);
            let bx = [bx0 + (sa * ex).min(sb * ex), bx1 + (sa * ex).max(sb * ex)];
            let by = [by0 + (sa * ey).min(sb * ey), by1 + (sa * ey).max(sb * ey)];
            tris.clear();
            fl.triangles_in([bx[0], bx[1], by[0], by[1]], tris);
            // a triangle off the patch: where the moving box first meets its plan box
            for t in tris.iter().filter(|t| !coplanar(t)) {
                let (mut s_in, mut s_out) = (0.0f64, f64::INFINITY);
                for (lo, hi, d, k) in [(bx0, bx1, ex, 0), (by0, by1, ey, 1)] {
                    let t_lo = t.corners.iter().map(|x| x[k]).fold(f64::INFINITY, f64::min);
                    let t_hi = t
                        .corners
                        .iter()
                        .map(|x| x[k])
                        .fold(f64::NEG_INFINITY, f64::max);
                    if d == 0.0 {
                        if hi < t_lo || lo > t_hi {
                            s_in = f64::INFINITY;
                        }
                    } else {
                        let (a, b) = ((t_lo - hi) / d, (t_hi - lo) / d);
                        s_in = s_in.max(a.min(b));
                        s_out = s_out.min(a.max(b));
                    }
                }
                if s_in <= s_out {
                    run = run.min(s_in);
                }
            }
            // each point's path over [sa, sb] covered by the patch's triangles
            let sb = sb.min(run);
            for q in &pts {
                cover.clear();
                for t in tris.iter().filter(|t| coplanar(t)) {
                    let (mut lo, mut hi) = (sa, sb);
                    for k in 0..3 {
                        let (a, b) = (t.corners[k], t.corners[(k + 1) % 3]);
                        let (dx, dy) = (b.x - a.x, b.y - a.y);
                        // outward (dy, −dx) of a counter-clockwise edge: g(s) ≤ 0 inside
                        let g0 = dy * (q[0] - a.x) - dx * (q[1] - a.y);
                        let g1 = dy * ex - dx * ey;
                        let tol = eps * (dx * dx + dy * dy).sqrt();
                        if g1 == 0.0 {
                            if g0 > tol {
                                hi = f64::NEG_INFINITY;
                            }
                        } else if g1 > 0.0 {
                            hi = hi.min((tol - g0) / g1);
                        } else {
                            lo = lo.max((tol - g0) / g1);
                        }
                    }
                    if lo <= hi {
                        cover.push([lo, hi]);
                    }
                }
                cover.sort_by(|x, y| x[0].total_cmp(&y[0]));
                let mut reach = sa;
                for iv in &cover {
                    if iv[0] > reach + eps {
                        break;
                    }
                    reach = reach.max(iv[1]);
                }
                if reach < sb {
                    run = run.min(reach);
                }
            }
            sa = sb;
        }
        let run = run.max(0.0);
        (run, run + (hi_e - lo_e) + 2.0 * margin)
    }
}
