//! Column dynamics after an impact (api.md `POST /v1/column`): the paper's decoupled single-mode
//! free vibration, or the coupled rock–contact–beam model (physics.md §B).

use super::beam::{
    FirstMode, Galerkin, ModalSample, ModeIntegrals, ModeShapes, SingleMode, UniformColumns,
};
use super::contact::{ForceLaw, ImpactDetail, ImpactResult, force_law, solve_impact};
use super::control::Control;
use super::coupled::{CoupledInput, solve_coupled};
use super::error::{Param, PhysicsError, PhysicsResult};
use super::material::{Damping, ImpactCase, Section};
use super::validity;

/// Which column model to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ColumnModel {
    /// The paper's method: mode 1 released from w_mid(0) = δmax (physics.md §B.5).
    #[default]
    Decoupled,
    /// Rock + contact law + n exact modes (physics.md §B.7).
    Coupled,
}

/// Which history the caller wants.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum HistoryRequest {
    /// No history (the default).
    #[default]
    None,
    /// Samples at these times, s (each ≥ 0; coupled: each ≤ the end time).
    Times(Vec<f64>),
    /// Evenly spaced samples over [0, duration].
    Uniform {
        /// Duration, s; coupled: `None` means the whole window (decoupled requires it).
        duration: Option<f64>,
        /// Number of samples ≥ 2; `None`: ⌈40·f₁·duration⌉ + 1, capped by `max_samples`.
        samples: Option<usize>,
    },
}

/// A `/v1/column` calculation.
#[derive(Debug, Clone, PartialEq)]
pub struct ColumnCase {
    /// The impact (speed, rock, column, contact model).
    pub impact: ImpactCase,
    /// Decoupled (default) or coupled.
    pub model: ColumnModel,
    /// Number of modes: decoupled 1 only; coupled 1…50; `None`: 1 (decoupled) or 3 (coupled).
    pub modes: Option<usize>,
    /// Mode-1 shapes (decoupled; coupled accepts only `Exact`).
    pub mode_shapes: ModeShapes,
    /// Include the rotary inertia J₀ = ρ_s I (default true).
    pub rotary_inertia: bool,
    /// Initial midpoint displacement, m (decoupled only); `None`: δmax of the impact.
    pub initial_midpoint_displacement: Option<f64>,
    /// End of the coupled window, s; `None`: 50 × the rigid contact duration.
    pub end_time: Option<f64>,
    /// History request.
    pub output: HistoryRequest,
    /// Largest number of history samples allowed (the service's limit).
    pub max_samples: usize,
    /// Relative tolerance of the coupled integrator (default 1e-9).
    pub tolerance: f64,
    /// Largest number of integrator steps (coupled; default 2e6).
    pub max_steps: u64,
}

impl Default for ColumnCase {
    fn default() -> Self {
        Self {
            impact: ImpactCase::default(),
            model: ColumnModel::Decoupled,
            modes: None,
            mode_shapes: ModeShapes::Exact,
            rotary_inertia: true,
            initial_midpoint_displacement: None,
            end_time: None,
            output: HistoryRequest::None,
            max_samples: 100_000,
            tolerance: 1e-9,
            max_steps: 2_000_000,
        }
    }
}

/// A named warning attached to a result (defined with the validity checks).
pub use super::validity::Warning;

/// Largest bending stress σ = E_s·(D₁/2)·max|w″|, Pa.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BendingStress {
    /// At the clamps, Pa.
    pub clamp: f64,
    /// At the midpoint, Pa.
    pub midpoint: f64,
}

/// Column histories: equal-length arrays, SI units.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ColumnHistory {
    /// Times, s.
    pub time: Vec<f64>,
    /// Midpoint deflection, m.
    pub midpoint_displacement: Vec<f64>,
    /// Column kinetic energy, J.
    pub kinetic_energy: Vec<f64>,
    /// Column strain energy, J.
    pub strain_energy: Vec<f64>,
    /// Energy dissipated by the column's damping (∫Cẇ²dt, computed in its own right), J.
    pub dissipated_energy: Vec<f64>,
    /// Coupled only: the rock and the contact.
    pub rock: Option<RockHistory>,
}

/// Coupled-only history columns.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RockHistory {
    /// Rock displacement towards the column, m.
    pub rock_displacement: Vec<f64>,
    /// Rock kinetic energy, J.
    pub rock_kinetic_energy: Vec<f64>,
    /// Contact force, N.
    pub contact_force: Vec<f64>,
    /// Energy stored in the contact ∫P dδ, J.
    pub contact_energy: Vec<f64>,
}

/// Decoupled-only results (physics.md §B.5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DecoupledDetail {
    /// δmax of the rigid-column impact, m.
    pub max_deformation: f64,
    /// Pmax of the rigid-column impact, N.
    pub max_force: f64,
    /// w₁(0) = w_mid(0)/φ(½), m.
    pub initial_modal_displacement: f64,
    /// U₀ = ½K₁w₁(0)², J.
    pub absorbed_energy: f64,
    /// U₀ / rock kinetic energy.
    pub energy_ratio: f64,
}

/// Coupled-only results (physics.md §B.7).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoupledDetail {
    /// Largest contact force over all maxima of approach, N.
    pub max_force: f64,
    /// Largest approach over all maxima of approach, m.
    pub max_contact_deformation: f64,
    /// max |w_mid| over the window, m.
    pub max_midpoint_displacement: f64,
    /// Number of contacts.
    pub contact_count: u32,
    /// Duration of the first contact, s; `None` if it lasts past the end of the window.
    pub first_contact_duration: Option<f64>,
    /// Rock velocity at the first separation (positive towards the column), m/s.
    pub rebound_velocity: f64,
    /// Column energy at the first separation, J.
    pub column_energy_after_contact: f64,
    /// That over the rock's kinetic energy.
    pub energy_ratio: f64,
    /// Rock velocity at the end, m/s.
    pub rock_velocity_end: f64,
    /// Column energy at the end, J.
    pub column_energy_end: f64,
    /// Energy dissipated by the column's damping over the window, J.
    pub damping_energy: f64,
    /// End of the window, s.
    pub end_time: f64,
    /// Accepted integrator steps.
    pub steps: u64,
    /// Rejected integrator steps.
    pub rejected_steps: u64,
    /// Relative tolerance of the integrator.
    pub tolerance: f64,
    /// Energy-balance error at the end relative to the rock's kinetic energy.
    pub estimated_error: f64,
}

/// Model-specific part of a [`ColumnResult`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ColumnDetail {
    /// Decoupled model.
    Decoupled(DecoupledDetail),
    /// Coupled model.
    Coupled(CoupledDetail),
}

/// Everything `/v1/column` reports.
#[derive(Debug, Clone, PartialEq)]
pub struct ColumnResult {
    /// Undamped natural frequencies, Hz (decoupled: mode 1 only).
    pub natural_frequencies_hz: Vec<f64>,
    /// Damping ratios ζᵢ = Cᵢᵢ/(2√(KᵢᵢMᵢᵢ)).
    pub damping_ratios: Vec<f64>,
    /// Damping coefficient c as used, N·s/m².
    pub damping_coefficient: f64,
    /// Modal mass M₁, kg.
    pub modal_mass: f64,
    /// Modal stiffness K₁, N/m.
    pub modal_stiffness: f64,
    /// Modal damping C₁, N·s/m.
    pub modal_damping: f64,
    /// φ₁(½).
    pub midpoint_mode_value: f64,
    /// Mode-1 integrals (paper: the printed constants).
    pub mode_integrals: ModeIntegrals,
    /// Envelope decay rate of mode 1, 1/s.
    pub decay_rate: f64,
    /// Time to 1 % amplitude, s; `None` when there is no damping (infinite).
    pub decay_time_1pct: Option<f64>,
    /// Section properties.
    pub section: Section,
    /// K_mid = K₁/φ₁(½)², N/m.
    pub midpoint_stiffness: f64,
    /// M_mid = M₁/φ₁(½)², kg.
    pub midpoint_mass: f64,
    /// Rock kinetic energy ½mv², J.
    pub kinetic_energy: f64,
    /// Largest bending stresses, Pa.
    pub max_bending_stress: BendingStress,
    /// Largest stress / yield stress.
    pub stress_utilisation: f64,
    /// History, when asked.
    pub history: Option<ColumnHistory>,
    /// Model-specific results.
    pub detail: ColumnDetail,
    /// Warnings (code, message).
    pub warnings: Vec<Warning>,
}

/// The contact law of a solved impact (k = P_cap/δ_cap, P_ref = e·P_cap; Hertz κ).
#[must_use]
pub fn force_law_of(impact: &ImpactResult) -> ForceLaw {
    match &impact.detail {
        ImpactDetail::Line(l) => {
            ForceLaw::log_from_capacity(l.force_capacity, l.deformation_capacity)
        }
        ImpactDetail::Hertz(h) => ForceLaw::Hertz { kappa: h.stiffness },
    }
}

/// Smallest rock kinetic energy the column models accept, J: below it the energies, their
/// tolerances (1e-9 of it and less) and squares leave the normal range of double precision.
pub const MIN_KINETIC_ENERGY: f64 = 1e-280;

/// Shortest coupled window, s: 1 ns, far below any contact duration the models resolve (µs–s)
/// and far above the range where step sizes underflow.
pub const MIN_END_TIME: f64 = 1e-9;

/// Longest default coupled window (50 × the rigid contact duration), s: the largest end_time_s.
pub const MAX_DEFAULT_END_TIME: f64 = 1e3;

/// Solves `/v1/column`: the impact (contact module), then the decoupled or coupled column model.
///
/// # Examples
/// ```
/// use gangue::physics::{Control, column::{solve_column, ColumnCase, ColumnDetail}};
/// let r = solve_column(&ColumnCase::default(), &Control::unlimited()).unwrap();
/// let ColumnDetail::Decoupled(d) = r.detail else { panic!() };
/// assert!((d.energy_ratio - 1.4712097663375543).abs() < 1e-9); // P07
/// ```
///
/// # Special cases
/// * No damping (c = 0 or ζ₁ = 0): `decay_time_1pct` is `None` with the warning `no_damping`.
/// * The paper's c = 1 N·s/m²: warning `paper_damping`; a decoupled energy ratio above 1:
///   warning `energy_ratio_above_one`; a coupled first contact still open at the end of the
///   window: warning `contact_not_ended` (first-contact quantities then at the end).
///
/// # Errors
/// * `CapacityExceeded` from the impact, or when the coupled approach reaches δ_cap;
/// * `InvalidInput` for option combinations api.md rejects (see [`solve_column_with_impact`]);
/// * `TooManySteps`, `Cancelled`, `TimedOut` from the coupled integration.
///
/// # References
/// physics.md §B.5–§B.7; api.md `POST /v1/column`.
pub fn solve_column(case: &ColumnCase, control: &Control) -> PhysicsResult<ColumnResult> {
    let impact = solve_impact(&case.impact)?;
    solve_column_solved(case, &impact, control)
}

/// Solves `/v1/column` for its impact already solved (`impact` = [`solve_impact`] of
/// `case.impact`, the law taken from the case as [`solve_column`] does): the same bytes as
/// [`solve_column`] without solving the impact again (the scene's strike solves it once for
/// both stages).
///
/// # Errors
/// As [`solve_column_with_impact`].
pub fn solve_column_solved(
    case: &ColumnCase,
    impact: &ImpactResult,
    control: &Control,
) -> PhysicsResult<ColumnResult> {
    solve_inner(case, impact, force_law(&case.impact)?, control)
}

fn check_times(times: &[f64], limit: Option<f64>) -> PhysicsResult<()> {
    for (i, &t) in times.iter().enumerate() {
        if !(t >= 0.0 && t.is_finite()) {
            return Err(PhysicsError::invalid(
                Param::HistoryTime(i),
                t,
                "history times must lie in [0, 1e6] s",
            ));
        }
        if let Some(end) = limit
            && t > end
        {
            return Err(PhysicsError::invalid(
                Param::HistoryTime(i),
                t,
                format!("coupled history times must lie in [0, the end time = {end:e}] s"),
            ));
        }
    }
    Ok(())
}

/// Sample times of a history request given the lowest frequency f₁ (Hz) and, for coupled,
/// the window end (s).
fn sample_times(
    req: &HistoryRequest,
    f1: f64,
    window: Option<f64>,
    max_samples: usize,
) -> PhysicsResult<Option<Grid>> {
    match req {
        HistoryRequest::None => Ok(None),
        HistoryRequest::Times(t) => {
            if t.len() > max_samples {
                return Err(PhysicsError::invalid(
                    Param::HistoryTimes,
                    t.len() as f64,
                    format!("at most {max_samples} history times"),
                ));
            }
            check_times(t, window)?;
            Ok(Some(Grid::Times(t.clone())))
        }
        HistoryRequest::Uniform { duration, samples } => {
            let d = match (duration, window) {
                (Some(d), _) => *d,
                (None, Some(w)) => w,
                (None, None) => {
                    return Err(PhysicsError::invalid(
                        Param::HistoryDuration,
                        0.0,
                        "the decoupled history needs a duration in (0, 1e6] s",
                    ));
                }
            };
            if !(d > 0.0 && d.is_finite()) {
                return Err(PhysicsError::invalid(
                    Param::HistoryDuration,
                    d,
                    "the history's duration must lie in (0, 1e6] s",
                ));
            }
            if let Some(w) = window
                && d > w
            {
                return Err(PhysicsError::invalid(
                    Param::HistoryDuration,
                    d,
                    format!("a coupled history's duration must not exceed the end time = {w:e} s"),
                ));
            }
            let n = match samples {
                Some(n) => {
                    if *n < 2 || *n > max_samples {
                        return Err(PhysicsError::invalid(
                            Param::HistorySamples,
                            *n as f64,
                            format!("samples must lie in [2, {max_samples}]"),
                        ));
                    }
                    *n
                }
                None => {
                    let want = (40.0 * f1 * d).ceil() + 1.0;
                    let cap = max_samples.max(2) as f64;
                    (if want.is_finite() { want.min(cap) } else { cap }).max(2.0) as usize
                }
            };
            Ok(Some(Grid::Uniform(d, n)))
        }
    }
}

/// Sample times: a list, or n evenly spaced over [0, d] (the last exactly d).
enum Grid {
    Times(Vec<f64>),
    Uniform(f64, usize),
}

impl Grid {
    fn times(self) -> Vec<f64> {
        match self {
            Grid::Times(t) => t,
            Grid::Uniform(d, n) => {
                let step = d / (n - 1) as f64;
                (0..n)
                    .map(|k| if k + 1 == n { d } else { k as f64 * step })
                    .collect()
            }
        }
    }
}

fn stress_of(case: &ImpactCase, curvature_clamp: f64, curvature_mid: f64) -> BendingStress {
    let f = case.column.elastic_modulus * case.column.outer_diameter / 2.0;
    BendingStress {
        clamp: f * curvature_clamp,
        midpoint: f * curvature_mid,
    }
}

/// Solves `/v1/column` for a given impact, its contact law taken from the impact
/// ([`force_law_of`]; for tests that set the impact themselves).
///
/// # Errors
/// `InvalidInput` for: decoupled with more than one mode ([`Param::GalerkinModes`]) or an
/// `end_time` ([`Param::CoupledWindow`]); coupled with non-exact shapes ([`Param::ModeShapes`]),
/// with an initial displacement ([`Param::InitialMidpointDisplacement`]) or with modes outside
/// [1, 50]; history times or durations out of range ([`Param::HistoryTime`] and the like). Otherwise as [`solve_column`].
///
/// # References
/// physics.md §B.5–§B.7.
pub fn solve_column_with_impact(
    case: &ColumnCase,
    impact: &ImpactResult,
    control: &Control,
) -> PhysicsResult<ColumnResult> {
    solve_inner(case, impact, force_law_of(impact), control)
}

fn solve_inner(
    case: &ColumnCase,
    impact: &ImpactResult,
    law: ForceLaw,
    control: &Control,
) -> PhysicsResult<ColumnResult> {
    let col = &case.impact.column;
    let single = SingleMode::new(col, case.mode_shapes, case.rotary_inertia)?;
    let ke = impact.kinetic_energy;
    let dmax = impact.max_deformation();
    if !(ke >= MIN_KINETIC_ENERGY && dmax >= f64::MIN_POSITIVE) {
        return Err(PhysicsError::invalid(
            Param::ImpactVelocity,
            case.impact.velocity,
            format!(
                "the impact energy ½mv² = {ke:e} J (maximum approach {dmax:e} m) is below what \
                 double precision resolves in the column energies ({MIN_KINETIC_ENERGY:e} J): \
                 give a larger velocity"
            ),
        ));
    }
    let mut warnings = Vec::new();
    if let Damping::Coefficient(c) = col.damping
        && c == 1.0
    {
        warnings.push(Warning {
            code: "paper_damping",
            message: "c = 1 N·s/m² (the paper's value) gives a decay to 1 % in minutes, not the \
                      0.6 s the paper reports; give damping_ratio (e.g. 0.02) for realistic damping"
                .into(),
        });
    }
    let mut result = match case.model {
        ColumnModel::Decoupled => decoupled(case, impact, &single, ke, warnings),
        ColumnModel::Coupled => coupled(case, impact, law, &single, ke, warnings, control),
    }?;
    result
        .warnings
        .extend(validity_warnings(case, impact, &result));
    Ok(result)
}

/// The validity warnings of a column result ([`super::validity`]): the contact's pressure and
/// approach at the largest contact force of the model run (the rigid-column maxima for the
/// decoupled model; for the coupled model the largest over all maxima of approach), and the
/// stress utilisation.
fn validity_warnings(
    case: &ColumnCase,
    impact: &ImpactResult,
    result: &ColumnResult,
) -> Vec<Warning> {
    let (force, approach) = match &result.detail {
        ColumnDetail::Decoupled(d) => (d.max_force, d.max_deformation),
        ColumnDetail::Coupled(c) => (c.max_force, c.max_contact_deformation),
    };
    let column = &case.impact.column;
    let mut out = validity::contact_warnings(
        validity::contact_pressure_at(impact, force),
        approach,
        column.yield_stress,
        column.contact_radius,
    );
    out.extend(validity::stress_warning(result.stress_utilisation));
    out
}

/// What the decoupled and the coupled column share in their result, before assembly.
struct ResultParts<'a> {
    /// The single-mode (mode 1) quantities.
    single: &'a SingleMode,
    /// Kinetic energy of the rock at impact, J.
    ke: f64,
    /// Largest bending stresses at the clamp and the midpoint, Pa.
    stress: BendingStress,
    /// The column's yield stress, Pa.
    yield_stress: f64,
    /// Natural frequencies of the modes used, Hz.
    frequencies: Vec<f64>,
    /// Damping ratios of the modes used.
    damping_ratios: Vec<f64>,
    /// The history, when asked for.
    history: Option<ColumnHistory>,
    /// The model's own quantities.
    detail: ColumnDetail,
    /// Warnings so far.
    warnings: Vec<Warning>,
}

fn assemble_result(parts: ResultParts<'_>) -> PhysicsResult<ColumnResult> {
    let ResultParts {
        single,
        ke,
        stress,
        yield_stress,
        frequencies,
        damping_ratios,
        history,
        detail,
        mut warnings,
    } = parts;
    let utilisation = stress.clamp.max(stress.midpoint) / yield_stress;
    if !utilisation.is_finite() {
        return Err(PhysicsError::invalid(
            Param::ColumnYieldStress,
            yield_stress,
            format!(
                "the stress utilisation (largest bending stress {:e} Pa / yield stress) overflows \
                 double precision: the yield stress is too small to compare with",
                stress.clamp.max(stress.midpoint)
            ),
        ));
    }
    let fv = single.free_vibration(1.0);
    let decay = fv.decay_time(0.01);
    if decay.is_none() {
        warnings.push(if fv.damping > 0.0 {
            Warning {
                code: "decay_time_unrepresentable",
                message: format!(
                    "the damping (decay rate {:e} 1/s) is so light that the decay time exceeds \
                     the range of double precision: the decay time to 1 % is left undefined (null)",
                    fv.decay_rate()
                ),
            }
        } else {
            Warning {
                code: "no_damping",
                message: "without damping the vibration never decays: the decay time to 1 % is left undefined (null)"
                    .into(),
            }
        });
    }
    let first: &FirstMode = &single.first;
    Ok(ColumnResult {
        natural_frequencies_hz: frequencies,
        damping_ratios,
        damping_coefficient: single.damping_coefficient,
        modal_mass: single.mass,
        modal_stiffness: single.stiffness,
        modal_damping: single.damping,
        midpoint_mode_value: first.midpoint_value,
        mode_integrals: first.integrals,
        decay_rate: fv.decay_rate(),
        decay_time_1pct: decay,
        section: single.section,
        midpoint_stiffness: single.midpoint_stiffness,
        midpoint_mass: single.midpoint_mass,
        kinetic_energy: ke,
        max_bending_stress: stress,
        stress_utilisation: utilisation,
        history,
        detail,
        warnings,
    })
}

/// The rule that the decoupled model has one mode: the message when `modes` breaks it.
///
/// # Errors
/// The rule's message when `modes` is not 1.
pub fn decoupled_modes_rule(modes: usize) -> Result<(), &'static str> {
    if modes == 1 {
        Ok(())
    } else {
        Err("the decoupled model uses mode 1 only (modes = 1)")
    }
}

/// The rule that only the coupled model has a time window: the message when one is given to the
/// decoupled model.
///
/// # Errors
/// The rule's message when `end_time` is given.
pub fn decoupled_window_rule(end_time: Option<f64>) -> Result<(), &'static str> {
    match end_time {
        None => Ok(()),
        Some(_) => Err("applies to the coupled model only"),
    }
}

fn decoupled(
    case: &ColumnCase,
    impact: &ImpactResult,
    single: &SingleMode,
    ke: f64,
    mut warnings: Vec<Warning>,
) -> PhysicsResult<ColumnResult> {
    if let Some(n) = case.modes {
        decoupled_modes_rule(n)
            .map_err(|m| PhysicsError::invalid(Param::GalerkinModes, n as f64, m))?;
    }
    decoupled_window_rule(case.end_time).map_err(|m| {
        PhysicsError::invalid(Param::CoupledWindow, case.end_time.unwrap_or(f64::NAN), m)
    })?;
    let (dmax, pmax) = (impact.max_deformation(), impact.max_force());
    let w_mid0 = match case.initial_midpoint_displacement {
        Some(w) => {
            if !(w > 0.0 && w <= 1.0) {
                return Err(PhysicsError::invalid(
                    Param::InitialMidpointDisplacement,
                    w,
                    "the initial midpoint displacement must lie in (0, 1] m",
                ));
            }
            w
        }
        None => dmax,
    };
    let phi = single.first.midpoint_value;
    let w0 = w_mid0 / phi;
    let fv = single.free_vibration(w0);
    let u0 = fv.initial_energy();
    let ratio = u0 / ke;
    if ratio > 1.0 {
        warnings.push(Warning {
            code: "energy_ratio_above_one",
            message: format!(
                "the decoupled approach stores {ratio:.4} times the rock's kinetic energy in the \
                 column (energy is not conserved); use the coupled model for energy transfer"
            ),
        });
    }
    let f1 = fv.omega_n / (2.0 * std::f64::consts::PI);
    let history = sample_times(&case.output, f1, None, case.max_samples)?.map(|grid| {
        let n = match &grid {
            Grid::Uniform(_, n) => *n,
            Grid::Times(t) => t.len(),
        };
        let mut h = ColumnHistory {
            time: Vec::with_capacity(n),
            midpoint_displacement: Vec::with_capacity(n),
            kinetic_energy: Vec::with_capacity(n),
            strain_energy: Vec::with_capacity(n),
            dissipated_energy: Vec::with_capacity(n),
            rock: None,
        };
        match grid {
            Grid::Uniform(d, n) => fv.extend_uniform(
                d,
                n,
                phi,
                UniformColumns {
                    time: &mut h.time,
                    displacement: &mut h.midpoint_displacement,
                    kinetic: &mut h.kinetic_energy,
                    strain: &mut h.strain_energy,
                    dissipated: &mut h.dissipated_energy,
                },
            ),
            Grid::Times(t) => t.iter().for_each(|&t| {
                let s: ModalSample = fv.sample(t);
                h.time.push(s.time);
                h.midpoint_displacement.push(phi * s.displacement);
                h.kinetic_energy.push(s.kinetic);
                h.strain_energy.push(s.strain);
                h.dissipated_energy.push(s.dissipated);
            }),
        }
        h
    });
    let l = case.impact.column.length;
    let mode = &single.first.mode;
    let stress = stress_of(
        &case.impact,
        (w0 * mode.curvature(0.0) / (l * l)).abs(),
        (w0 * mode.curvature(0.5) / (l * l)).abs(),
    );
    assemble_result(ResultParts {
        single,
        ke,
        stress,
        yield_stress: case.impact.column.yield_stress,
        frequencies: vec![f1],
        damping_ratios: vec![fv.zeta],
        history,
        detail: ColumnDetail::Decoupled(DecoupledDetail {
            max_deformation: dmax,
            max_force: pmax,
            initial_modal_displacement: w0,
            absorbed_energy: u0,
            energy_ratio: ratio,
        }),
        warnings,
    })
}

fn coupled(
    case: &ColumnCase,
    impact: &ImpactResult,
    law: ForceLaw,
    single: &SingleMode,
    ke: f64,
    mut warnings: Vec<Warning>,
    control: &Control,
) -> PhysicsResult<ColumnResult> {
    if case.mode_shapes != ModeShapes::Exact {
        return Err(PhysicsError::invalid(
            Param::ModeShapes,
            0.0,
            "the coupled model uses exact mode shapes only",
        ));
    }
    if let Some(w) = case.initial_midpoint_displacement {
        return Err(PhysicsError::invalid(
            Param::InitialMidpointDisplacement,
            w,
            "an initial midpoint displacement applies to the decoupled model only",
        ));
    }
    let n = case.modes.unwrap_or(3);
    let col = &case.impact.column;
    let galerkin = Galerkin::new(col, n, single.damping_coefficient, case.rotary_inertia)?;
    let freqs = galerkin.natural_frequencies();
    let ratios = galerkin.damping_ratios();
    let tc = impact.contact_duration;
    let end_time = match case.end_time {
        Some(t) if !(t >= MIN_END_TIME && t.is_finite()) => {
            return Err(PhysicsError::invalid(
                Param::CoupledWindow,
                t,
                "the end time must lie in [1e-9, 1e3] s",
            ));
        }
        Some(t) => t,
        None if 50.0 * tc <= MAX_DEFAULT_END_TIME => 50.0 * tc,
        None => {
            return Err(PhysicsError::invalid(
                Param::CoupledWindow,
                50.0 * tc,
                format!(
                    "the default window, 50 × the rigid contact duration = {:e} s, exceeds \
                     {MAX_DEFAULT_END_TIME:e} s (the contact law barely resists this impact): \
                     give an end time in [1e-9, 1e3] s",
                    50.0 * tc
                ),
            ));
        }
    };
    let mut times =
        sample_times(&case.output, freqs[0], Some(end_time), case.max_samples)?.map(Grid::times);
    // The integrator wants ascending times; remember the caller's order.
    let order: Option<Vec<usize>> = times.as_mut().map(|t| {
        let mut idx: Vec<usize> = (0..t.len()).collect();
        idx.sort_by(|&a, &b| t[a].total_cmp(&t[b]));
        let sorted: Vec<f64> = idx.iter().map(|&i| t[i]).collect();
        *t = sorted;
        idx
    });
    let dmax = impact.max_deformation();
    let v = case.impact.velocity;
    let input = CoupledInput {
        rock_mass: impact.mass,
        velocity: v,
        law,
        galerkin,
        column_length: col.length,
        end_time,
        time_scale: tc.min(end_time).max(f64::MIN_POSITIVE),
        displacement_scale: dmax,
        tolerance: case.tolerance,
        sample_times: times.clone().unwrap_or_default(),
        max_steps: case.max_steps,
    };
    let r = solve_coupled(&input, control)?;
    if r.estimated_error > super::coupled::ACCURACY_TARGET {
        warnings.push(Warning {
            code: "integrator_error_above_target",
            message: format!(
                "the integrator's estimated error {:.1e} (energy balances of the rock and of the \
                 column, after {} passes down to tolerance {:.0e}) exceeds the target {:.0e}: \
                 treat the energies as approximate",
                r.estimated_error,
                r.passes,
                r.tolerance,
                super::coupled::ACCURACY_TARGET
            ),
        });
    }
    if r.first_contact_duration.is_none() {
        warnings.push(Warning {
            code: "contact_not_ended",
            message: "the rock is still in contact at the end of the window: the first-contact \
                      quantities are those at the end; increase the end time"
                .into(),
        });
    }
    let history = order.map(|idx| {
        let h = &r.history;
        let mut out = ColumnHistory::default();
        let mut rock = RockHistory::default();
        let mut inverse = vec![0usize; idx.len()];
        for (k, &i) in idx.iter().enumerate() {
            inverse[i] = k;
        }
        for &k in &inverse {
            out.time.push(h.time[k]);
            out.midpoint_displacement.push(h.midpoint_displacement[k]);
            out.kinetic_energy.push(h.kinetic_energy[k]);
            out.strain_energy.push(h.strain_energy[k]);
            out.dissipated_energy.push(h.dissipated_energy[k]);
            rock.rock_displacement.push(h.rock_displacement[k]);
            rock.rock_kinetic_energy.push(h.rock_kinetic_energy[k]);
            rock.contact_force.push(h.contact_force[k]);
            rock.contact_energy.push(h.contact_energy[k]);
        }
        out.rock = Some(rock);
        out
    });
    let stress = stress_of(
        &case.impact,
        r.max_curvature_clamp,
        r.max_curvature_midpoint,
    );
    assemble_result(ResultParts {
        single,
        ke,
        stress,
        yield_stress: col.yield_stress,
        frequencies: freqs,
        damping_ratios: ratios,
        history,
        detail: ColumnDetail::Coupled(CoupledDetail {
            max_force: r.max_force,
            max_contact_deformation: r.max_contact_deformation,
            max_midpoint_displacement: r.max_midpoint_displacement,
            contact_count: r.contact_count,
            first_contact_duration: r.first_contact_duration,
            rebound_velocity: r.rebound_velocity,
            column_energy_after_contact: r.column_energy_after_contact,
            energy_ratio: r.column_energy_after_contact / ke,
            rock_velocity_end: r.rock_velocity_end,
            column_energy_end: r.column_energy_end,
            damping_energy: r.damping_energy,
            end_time,
            steps: r.steps,
            rejected_steps: r.rejected_steps,
            tolerance: r.tolerance,
            estimated_error: r.estimated_error,
        }),
        warnings,
    })
}

#[cfg(test)]
#[allow(clippy::field_reassign_with_default)] // cases read as "the default, except …"
mod tests {
    use super::*;
    use crate::physics::contact::force_law;

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    #[test]
    fn decoupled_default_matches_the_verification_case() {
        // api_column / analytic_column: energy ratio 1.4712097663375543 (U₀/KE), c = 1 warned.
        let r = solve_column(&ColumnCase::default(), &Control::unlimited()).unwrap();
        let ColumnDetail::Decoupled(d) = &r.detail else {
            panic!("decoupled expected")
        };
        assert!(rel(d.energy_ratio, 1.471_209_766_337_554_3) < 1e-9);
        let codes: Vec<&str> = r.warnings.iter().map(|w| w.code).collect();
        assert!(codes.contains(&"paper_damping"), "{codes:?}");
        // 221.9 % of the yield stress: the validity warning is attached.
        assert!(r.stress_utilisation > 1.0);
        assert!(codes.contains(&"stress_utilisation_above_one"), "{codes:?}");
    }

    #[test]
    fn the_law_of_a_solved_impact_is_the_law_of_its_case() {
        let case = ImpactCase::default();
        let impact = solve_impact(&case).unwrap();
        let (ForceLaw::Log { k: k1, p_ref: p1 }, ForceLaw::Log { k: k2, p_ref: p2 }) =
            (force_law_of(&impact), force_law(&case).unwrap())
        else {
            panic!("log laws expected")
        };
        assert!(rel(k1, k2) < 1e-14 && rel(p1, p2) < 1e-14);
    }

    #[test]
    fn coupled_run_past_the_step_limit_is_refused_before_integrating() {
        // An expired deadline stops any integration at its first check (TimedOut); the estimate
        // refuses first, so the answer is TooManySteps with an estimate above the limit.
        let mut case = ColumnCase::default();
        case.model = ColumnModel::Coupled;
        case.modes = Some(50);
        case.impact.column.inner_diameter = 0.2499;
        case.impact.column.length = 0.3;
        case.end_time = Some(10.0);
        let expired = Control::with_deadline(Some(std::time::Instant::now()));
        match solve_column(&case, &expired) {
            Err(PhysicsError::TooManySteps { estimated, limit }) => {
                assert!(estimated > limit, "{estimated} ≤ {limit}");
            }
            other => panic!("expected TooManySteps, got {other:?}"),
        }
    }

    #[test]
    fn history_times_are_checked_against_the_window() {
        assert!(check_times(&[0.0, 1e-3], Some(1e-2)).is_ok());
        assert!(check_times(&[0.0, 2e-2], Some(1e-2)).is_err());
        assert!(check_times(&[-1e-9], None).is_err());
        let grid = sample_times(
            &HistoryRequest::Uniform {
                duration: Some(0.01),
                samples: Some(11),
            },
            100.0,
            None,
            1000,
        )
        .unwrap()
        .unwrap()
        .times();
        assert_eq!(grid.len(), 11);
        assert_eq!(grid[0], 0.0);
        assert!(rel(grid[10], 0.01) < 1e-15);
    }
}
