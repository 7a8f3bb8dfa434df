//! One integration pass over the window ([`run_pass`]): the walk from the first touch through
//! contact phases (Dormand–Prince, or the exponential integrator on heavily damped columns) and
//! flight phases (the exact propagator), the terminal events (separation, re-contact) located
//! and redone exactly, the non-terminal ones (maxima of approach, extrema of w_mid and of the
//! curvatures) and the history samples processed per step, and the energy balances closed at
//! the end.

#![allow(clippy::needless_range_loop)] // index loops over several parallel arrays

use nalgebra::{DMatrix, DVector};

use super::estimate::CONTACT_MAX_STEP_FRACTION;
use super::flight::{FlightContext, FreeFlight, Sink, Tracked, free_flight};
use super::modal::{ModalFlight, ModalFunctionals, modal_free_flight};
use super::system::{Functionals, ROCK_DISPLACEMENT, ROCK_VELOCITY, System, apply};
use super::{
    ContactIntegrator, CoupledInput, CoupledResult, FlightPropagator, capacity_exceeded,
    contact_energy, exponential, extremum_slot,
};
use crate::physics::contact::ForceLaw;
use crate::physics::control::Control;
use crate::physics::error::{PhysicsError, PhysicsResult};
use crate::physics::numeric::ode::{Dopri5, OdeError, find_roots};

/// One integration over the window with relative tolerance `tol`, the column's modal states and
/// energies controlled on the energy scale `energy_scale` (J): absolute tolerances
/// tol·√(2E/Kᵢ) for wᵢ, tol·√(2E/Mᵢᵢ) for ẇᵢ and tol·E for the dissipated energy and the work.
pub(super) fn run_pass(
    input: &CoupledInput,
    control: &Control,
    tol: f64,
    energy_scale: f64,
    contact: ContactIntegrator,
    flight: FlightPropagator,
) -> PhysicsResult<CoupledResult> {
    let (sys, mass, minv) = System::new(input)?;
    let n = sys.n;
    let layout = sys.layout;
    let dim = layout.len();
    let v = input.velocity;
    let atol = sys.absolute_tolerances(input, &mass, tol, energy_scale);
    let t_end = input.end_time;
    let mut st = Dopri5::new(tol, atol.clone(), (input.time_scale * 1e-3).min(t_end));
    st.max_step = input.time_scale * CONTACT_MAX_STEP_FRACTION;
    // A damping rate that would bound the explicit contact steps hands the contact phases to
    // the exponential integrator (its step set by the contact force alone).
    let damping_rate = (0..n)
        .map(|i| minv[(i, i)] * sys.c[i])
        .fold(0.0f64, f64::max);
    let mut exp_contact = (contact == ContactIntegrator::Auto
        && exponential::exponential_contact_pays(damping_rate, input.time_scale))
    .then(|| {
        exponential::ExpStepper::new(
            &sys,
            &minv,
            tol,
            atol,
            (input.time_scale * 1e-3).min(t_end),
            input.time_scale * CONTACT_MAX_STEP_FRACTION,
            input.time_scale,
        )
    });

    let fs = sys.functionals();
    let pass = Pass {
        input,
        sys: &sys,
        mass: &mass,
        fs: &fs,
    };

    let column_energy = |y: &[f64]| sys.column_energy(&mass, y);
    let mut walk = Walk::new(v, t_end, tol, dim);
    let samples = &input.sample_times;
    let record = |res: &mut CoupledResult, ts: f64, ys: &[f64], in_contact: bool| {
        pass.record(res, ts, ys, in_contact)
    };
    while walk.next_sample < samples.len() && samples[walk.next_sample] <= 0.0 {
        record(&mut walk.res, samples[walk.next_sample], &walk.y, true);
        walk.next_sample += 1;
    }

    let omega_max = highest_angular_frequency(&sys, &mass);
    let mut free: Option<FreeFlight> = None;
    let mut modal: Option<Option<(ModalFlight, ModalFunctionals)>> = None;
    // φ(½)ᵀK⁻¹φ(½), m²/J: |w_mid| ≤ √(2·E_col·reach) for a column holding energy E_col
    // (Cauchy–Schwarz in the norm of K, and E_col ≥ ½wᵀKw).
    let reach: f64 = (0..n).map(|j| sys.phi[j] * sys.phi[j] / sys.k[j]).sum();
    let amplitude_bound = |yy: &[f64]| {
        let (kin, strain) = column_energy(yy);
        (2.0 * (kin + strain) * reach).sqrt()
    };
    // The exact propagator steps at 1/8 of the shortest period whatever the damping (a heavily
    // damped column has its propagator built by doubling and its in-step states exactly).
    let exact_flight = omega_max > 0.0;
    while walk.t < t_end {
        if !walk.in_contact && exact_flight {
            // the modal flight where its decomposition is accurate, else the dense one
            let modal = match flight {
                FlightPropagator::Auto => modal
                    .get_or_insert_with(|| modal_flight(&sys, &mass, &minv, &fs, omega_max))
                    .as_ref(),
                _ => None,
            };
            let cx = FlightContext {
                sys: &sys,
                t_end,
                samples,
                record: &record,
                control,
                max_steps: input.max_steps,
                amplitude_bound: &amplitude_bound,
            };
            let out = Sink {
                res: &mut walk.res,
                next_sample: &mut walk.next_sample,
            };
            let (recontact, t_new) = if let Some((mf, fl)) = modal {
                modal_free_flight(mf, fl, cx, &mut walk.y, walk.t, out, &mut st)?
            } else {
                let ff =
                    free.get_or_insert_with(|| FreeFlight::new(&minv, &sys.k, &sys.c, omega_max));
                let tracked = Tracked {
                    apply: &apply,
                    values: [&fs.wmid, &fs.c0, &fs.cm],
                    rates: [&fs.wmid_rate, &fs.c0_rate, &fs.cm_rate],
                };
                free_flight(ff, cx, &tracked, &mut walk.y, walk.t, out, &mut st)?
            };
            walk.t = t_new;
            if recontact {
                walk.switch(&pass, &mut st, t_new);
            }
            continue;
        }
        if let (true, Some(es)) = (walk.in_contact, exp_contact.as_mut()) {
            exponential_contact_phase(es, &pass, &mut walk, &mut st, control)?;
            continue;
        }
        explicit_step(&pass, &mut walk, &mut st, control)?;
    }
    // Samples at exactly the end (rounding).
    for &ts in &samples[walk.next_sample..] {
        record(&mut walk.res, ts, &walk.y, walk.in_contact);
    }
    walk.next_sample = samples.len();
    let mut res = walk.res;
    close_balances(
        input,
        &sys,
        &mass,
        &walk.y,
        walk.in_contact,
        walk.first_separated,
        &mut res,
    );
    res.steps = st.steps;
    res.rejected_steps = st.rejected;
    Ok(res)
}

/// The highest angular frequency of the column's modes, rad/s (0 without modes).
fn highest_angular_frequency(sys: &System, mass: &DMatrix<f64>) -> f64 {
    2.0 * std::f64::consts::PI
        * crate::physics::beam::generalized_frequencies(
            mass,
            &DMatrix::from_diagonal(&DVector::from_column_slice(&sys.k)),
        )
        .last()
        .copied()
        .unwrap_or(0.0)
}

/// The modal free flight of the column and the functionals it reports, in modal coordinates;
/// None where the decomposition would lose accuracy (the dense flight is used then).
fn modal_flight(
    sys: &System,
    mass: &DMatrix<f64>,
    minv: &DMatrix<f64>,
    fs: &Functionals,
    omega_max: f64,
) -> Option<(ModalFlight, ModalFunctionals)> {
    let layout = sys.layout;
    let mass_diag: Vec<f64> = (0..sys.n).map(|j| mass[(j, j)]).collect();
    ModalFlight::new(minv, &sys.k, &sys.c, &mass_diag, omega_max).map(|mf| {
        let fl = ModalFunctionals {
            delta: mf.functional(layout, &fs.delta),
            values: [&fs.wmid, &fs.c0, &fs.cm].map(|f| mf.functional(layout, f)),
            rates: [&fs.wmid_rate, &fs.c0_rate, &fs.cm_rate].map(|f| mf.functional(layout, f)),
        };
        (mf, fl)
    })
}

/// One contact phase by the exponential integrator `es`, up to separation (the walk switched
/// to flight) or the end of the window; its steps counted into `st`.
fn exponential_contact_phase(
    es: &mut exponential::ExpStepper,
    pass: &Pass<'_>,
    walk: &mut Walk,
    st: &mut Dopri5,
    control: &Control,
) -> PhysicsResult<()> {
    let (steps, rejected) = (es.steps, es.rejected);
    let (separated, t_new) = exponential::exponential_contact(
        es,
        pass,
        &mut walk.y,
        walk.t,
        Sink {
            res: &mut walk.res,
            next_sample: &mut walk.next_sample,
        },
        control,
        st.steps,
    )?;
    st.steps += es.steps - steps;
    st.rejected += es.rejected - rejected;
    walk.t = t_new;
    if separated {
        walk.separate_first(pass, t_new);
        walk.in_contact = false;
        pass.sys.in_contact.set(false);
        st.reset();
    }
    Ok(())
}

/// The mutable state of one pass's walk over the window: the state vector and its two scratch
/// copies, the time (s), the results so far, the next history sample, the phase, whether the
/// first contact has ended and the number of phase switches.
pub(super) struct Walk {
    pub(super) y: Vec<f64>,
    pub(super) ysave: Vec<f64>,
    pub(super) ytmp: Vec<f64>,
    pub(super) t: f64,
    pub(super) res: CoupledResult,
    pub(super) next_sample: usize,
    pub(super) in_contact: bool,
    pub(super) first_separated: bool,
    pub(super) switches: u64,
}

impl Walk {
    /// The start: the rock at speed `v` (m/s) touching the column at rest, in contact.
    pub(super) fn new(v: f64, t_end: f64, tol: f64, dim: usize) -> Self {
        let mut y = vec![0.0; dim];
        y[ROCK_VELOCITY] = v;
        Walk {
            y,
            ysave: vec![0.0; dim],
            ytmp: vec![0.0; dim],
            t: 0.0,
            res: CoupledResult::at_start(v, t_end, tol),
            next_sample: 0,
            in_contact: true,
            first_separated: false,
            switches: 0,
        }
    }

    /// Books the end of the first contact at `te` (s), once: its duration, the rebound
    /// velocity and the column's energy then.
    pub(super) fn separate_first(&mut self, pass: &Pass<'_>, te: f64) {
        if !self.first_separated {
            self.first_separated = true;
            self.res.first_contact_duration = Some(te);
            self.res.rebound_velocity = self.y[ROCK_VELOCITY];
            let (kin, strain) = pass.sys.column_energy(pass.mass, &self.y);
            self.res.column_energy_after_contact = kin + strain;
        }
    }

    /// Switches between contact and flight at the current state, an event at `te` (s): a
    /// separation or a re-contact; counts the contacts and restarts the explicit integrator.
    pub(super) fn switch(&mut self, pass: &Pass<'_>, st: &mut Dopri5, te: f64) {
        if self.in_contact {
            self.separate_first(pass, te);
        } else {
            self.res.contact_count += 1;
        }
        self.in_contact = !self.in_contact;
        pass.sys.in_contact.set(self.in_contact);
        st.reset();
        st.h = st.h.max(pass.input.time_scale * 1e-6);
    }
}

/// One explicit Dormand–Prince step in contact or in flight (without the exact propagator).
/// A separation or re-contact inside the step is located on the dense output, the step redone
/// from its start to the event exactly, and the phase switched; otherwise the step's events and
/// samples are processed and the capacity of the contact law checked.
pub(super) fn explicit_step(
    pass: &Pass<'_>,
    w: &mut Walk,
    st: &mut Dopri5,
    control: &Control,
) -> PhysicsResult<()> {
    let (input, sys) = (pass.input, pass.sys);
    let f_delta = &pass.fs.delta;
    let t_end = input.end_time;
    if st.steps % 1000 == 999 {
        control.check()?;
    }
    if st.steps >= input.max_steps {
        return Err(PhysicsError::TooManySteps {
            estimated: st.steps as f64 * t_end / w.t.max(f64::MIN_POSITIVE),
            limit: input.max_steps as f64,
        });
    }
    w.ysave.copy_from_slice(&w.y);
    let t_save = w.t;
    let in_contact = w.in_contact;
    let t1 = st
        .step(sys, w.t, &mut w.y, t_end)
        .map_err(|e| pass.map_ode(e, in_contact, sys.delta(&w.y)))?;
    // Terminal event: separation (δ ↓ 0) in contact, re-contact (δ ↑ 0) in flight.
    let cd = st.functional(f_delta);
    let gd = |th: f64| Dopri5::eval_functional(&cd, th);
    let dir = if in_contact { -1 } else { 1 };
    let hit = find_roots(
        gd,
        apply(f_delta, &w.ysave),
        apply(f_delta, &w.y),
        dir,
        4,
        true,
    );
    let (t0, h) = st.last_step();
    // An event must move time forward (a grazing δ ≈ 0 at the very start of a step would
    // otherwise switch back and forth without progress).
    let event = hit
        .first()
        .map(|&th| t0 + th * h)
        .filter(|&te| te > t_save + 1e-13 * h.max(t_save.abs() * 1e-3));
    if let Some(te) = event {
        w.switches += 1;
        if w.switches.is_multiple_of(64) {
            control.check()?;
        }
        if w.switches > input.max_steps {
            return Err(PhysicsError::TooManySteps {
                estimated: w.switches as f64 * t_end / t_save.max(f64::MIN_POSITIVE),
                limit: input.max_steps as f64,
            });
        }
        redo_to_event(pass, w, st, t_save, te)?;
        w.switch(pass, st, te);
        return Ok(());
    }
    pass.process(
        st,
        Sink {
            res: &mut w.res,
            next_sample: &mut w.next_sample,
        },
        &w.ysave,
        &w.y,
        in_contact,
        &mut w.ytmp,
    )?;
    if in_contact
        && let Some(cap) = input.law.deformation_capacity()
        && sys.delta(&w.y) >= cap
    {
        return Err(capacity_exceeded(input));
    }
    w.t = t1;
    Ok(())
}

/// Integrates again from the start of a step (state `ysave` at `t_save`, s) to the event at
/// `te` (s) exactly, processing the events and samples of each piece.
pub(super) fn redo_to_event(
    pass: &Pass<'_>,
    w: &mut Walk,
    st: &mut Dopri5,
    t_save: f64,
    te: f64,
) -> PhysicsResult<()> {
    let sys = pass.sys;
    let in_contact = w.in_contact;
    w.y.copy_from_slice(&w.ysave);
    w.t = t_save;
    st.reset();
    st.h = (te - t_save).max(f64::MIN_POSITIVE);
    let mut scratch = vec![0.0; w.y.len()];
    while w.t < te {
        w.ytmp.copy_from_slice(&w.y);
        w.t = st
            .step(sys, w.t, &mut w.y, te)
            .map_err(|e| pass.map_ode(e, in_contact, sys.delta(&w.y)))?;
        pass.process(
            st,
            Sink {
                res: &mut w.res,
                next_sample: &mut w.next_sample,
            },
            &w.ytmp,
            &w.y,
            in_contact,
            &mut scratch,
        )?;
    }
    Ok(())
}

/// What the contact integration of one pass shares: the input, the system, its mass matrix
/// and the linear functionals of the state.
pub(super) struct Pass<'a> {
    pub(super) input: &'a CoupledInput,
    pub(super) sys: &'a System,
    pub(super) mass: &'a DMatrix<f64>,
    pub(super) fs: &'a Functionals,
}

impl Pass<'_> {
    /// Records a history sample from state ys at time ts (s).
    pub(super) fn record(&self, res: &mut CoupledResult, ts: f64, ys: &[f64], in_contact: bool) {
        let (input, layout) = (self.input, self.sys.layout);
        let (kin, strain) = self.sys.column_energy(self.mass, ys);
        let d = self.sys.delta(ys);
        let (p, ec) = if in_contact {
            (
                input.law.force(d).unwrap_or(0.0),
                contact_energy(&input.law, d).unwrap_or(0.0),
            )
        } else {
            (0.0, 0.0)
        };
        let h = &mut res.history;
        h.time.push(ts);
        h.midpoint_displacement.push(apply(&self.fs.wmid, ys));
        h.kinetic_energy.push(kin);
        h.strain_energy.push(strain);
        h.dissipated_energy.push(ys[layout.dissipated()]);
        h.rock_displacement.push(ys[ROCK_DISPLACEMENT]);
        h.rock_kinetic_energy
            .push(0.5 * input.rock_mass * ys[ROCK_VELOCITY] * ys[ROCK_VELOCITY]);
        h.contact_force.push(p);
        h.contact_energy.push(ec);
    }

    /// Non-terminal events (maxima of approach in contact, extrema of w_mid and of the
    /// curvatures) and history samples over the last accepted step from y0 to y1, up to θ = 1.
    pub(super) fn process(
        &self,
        st: &Dopri5,
        out: Sink<'_>,
        y0: &[f64],
        y1: &[f64],
        in_contact: bool,
        ytmp: &mut [f64],
    ) -> PhysicsResult<()> {
        let Sink { res, next_sample } = out;
        let fs = self.fs;
        let samples = &self.input.sample_times;
        let (t0, h) = st.last_step();
        let sub = 4;
        if in_contact {
            let cr = st.functional(&fs.delta_rate);
            let cd = st.functional(&fs.delta);
            let g = |th: f64| Dopri5::eval_functional(&cr, th);
            let (r0, r1) = (apply(&fs.delta_rate, y0), apply(&fs.delta_rate, y1));
            for th in find_roots(g, r0, r1, -1, sub, false) {
                let d = Dopri5::eval_functional(&cd, th);
                if d > res.max_contact_deformation {
                    res.max_contact_deformation = d;
                    res.max_force = self
                        .input
                        .law
                        .force(d)
                        .ok_or_else(|| capacity_exceeded(self.input))?;
                }
            }
        }
        for (rate, val, slot) in [
            (&fs.wmid_rate, &fs.wmid, 0usize),
            (&fs.c0_rate, &fs.c0, 1),
            (&fs.cm_rate, &fs.cm, 2),
        ] {
            let cr = st.functional(rate);
            let g = |th: f64| Dopri5::eval_functional(&cr, th);
            let mut best = apply(val, y1).abs();
            let roots = find_roots(g, apply(rate, y0), apply(rate, y1), 0, sub, false);
            if !roots.is_empty() {
                let cv = st.functional(val);
                for th in roots {
                    best = best.max(Dopri5::eval_functional(&cv, th).abs());
                }
            }
            let target = extremum_slot(res, slot);
            *target = target.max(best);
        }
        while *next_sample < samples.len() && samples[*next_sample] <= t0 + h {
            let ts = samples[*next_sample];
            st.dense_state(ts, ytmp);
            if ts >= t0 + h {
                ytmp.copy_from_slice(y1);
            }
            self.record(res, ts, ytmp, in_contact);
            *next_sample += 1;
        }
        Ok(())
    }

    /// The error of a failed integrator step. A step-size underflow is the capacity only when
    /// the approach δ (m) is close to δ_cap (the log law's force is unbounded there); anywhere
    /// else it is a numerical failure, never reported as a capacity with an energy parameter
    /// that contradicts it.
    pub(super) fn map_ode(&self, e: OdeError, in_contact: bool, delta: f64) -> PhysicsError {
        let law = self.input.law;
        let near_cap = law
            .deformation_capacity()
            .is_some_and(|cap| delta >= 0.9 * cap);
        match (e, law) {
            (OdeError::StepTooSmall { .. }, ForceLaw::Log { .. }) if in_contact && near_cap => {
                capacity_exceeded(self.input)
            }
            (OdeError::StepTooSmall { t }, _) => {
                PhysicsError::Numerical(format!("step size underflow at t = {t:e} s"))
            }
        }
    }
}

/// The end-of-window results and the energy balances of a pass ending in state y: the column
/// and rock energies, the contact energy (when `in_contact`), the rebound values when no
/// separation happened, the rock's balance relative to its initial kinetic energy and the
/// column's E_col + D = W relative to the transferred energy.
pub(super) fn close_balances(
    input: &CoupledInput,
    sys: &System,
    mass: &DMatrix<f64>,
    y: &[f64],
    in_contact: bool,
    first_separated: bool,
    res: &mut CoupledResult,
) {
    let layout = sys.layout;
    let ke0 = 0.5 * input.rock_mass * input.velocity * input.velocity;
    let (kin, strain) = sys.column_energy(mass, y);
    res.column_energy_end = kin + strain;
    res.rock_velocity_end = y[ROCK_VELOCITY];
    res.damping_energy = y[layout.dissipated()];
    res.contact_energy_end = if in_contact {
        contact_energy(&input.law, sys.delta(y)).unwrap_or(0.0)
    } else {
        0.0
    };
    if !first_separated {
        res.rebound_velocity = y[ROCK_VELOCITY];
        res.column_energy_after_contact = kin + strain;
    }
    let total = 0.5 * input.rock_mass * y[ROCK_VELOCITY] * y[ROCK_VELOCITY]
        + res.contact_energy_end
        + res.column_energy_end
        + res.damping_energy;
    res.energy_residual = ((total - ke0) / ke0).abs();
    // The column's own balance: energy + dissipated = work done on it by the contact force.
    let work = y[layout.work()];
    let column_total = res.column_energy_end + res.damping_energy;
    res.column_energy_scale = work
        .abs()
        .max(column_total)
        .max(res.column_energy_after_contact);
    res.column_energy_residual = if res.column_energy_scale > 0.0 {
        ((column_total - work) / res.column_energy_scale).abs()
    } else {
        0.0
    };
    res.estimated_error = res.energy_residual.max(res.column_energy_residual);
}
