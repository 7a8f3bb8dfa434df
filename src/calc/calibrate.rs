//! `/v1/calibrate`: back-analysis of a migration ensemble's parameters from field observations.
//!
//! A search over a box of 1 to 3 parameters (restitution, friction, the rigid block's damping)
//! for the values whose seeded ensemble reproduces the observed runouts, stopping points or
//! horizontal runouts (and, optionally, what collectors saw) best: a grid of `points`^d over the
//! box, then `refinements` grids over a box shrunk by 2/(points − 1) around the best so far.
//! Every evaluation runs the same runs with the same streams (common random numbers: run i of
//! release k draws from the stream of run k·runs + i of the seed), so the objective changes with
//! the parameters only, and the bytes depend on nothing but the case.
//!
//! Objectives: the two-sample Kolmogorov–Smirnov distance sup |F_obs − F_sim| (stop points: the
//! mean of the along-dip and across distances), or the quantile loss: the mean over p = 0.05,
//! 0.10, …, 0.95 of |Q_sim(p) − Q_obs(p)| (type-7 quantiles) divided by the observed spread
//! Q_obs(0.95) − Q_obs(0.05). Observed collectors add one term per observed array; the
//! objective is the mean of the terms.

use std::sync::Arc;

use crate::physics::material::Rock;
use crate::physics::migration::{
    self, Crossings, Distribution, Line, Method, MigrationCase, MonteCarlo, Release, RunSummary,
};
use crate::physics::stats::percentile_sorted;
use crate::physics::{Control, PhysicsError};

use super::{Report, Stage, Warning};

/// A parameter that calibration can move.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Parameter {
    /// The normal restitution e_n (lumped mass): the centre of the ensemble's e_n distribution
    /// (its width kept) and the face's e_n.
    RestitutionNormal,
    /// The tangential restitution e_t (lumped mass): as e_n.
    RestitutionTangential,
    /// The Coulomb friction μ of the lumped mass: the centre of the drawn μ (its width kept),
    /// or the face's μ for every run when μ is not drawn.
    FrictionCoefficient,
    /// The contact dashpot's critical damping ratio β (rigid block): the centre of the drawn β,
    /// or β for every run.
    CriticalDampingRatio,
    /// The Coulomb friction μ of the rigid block, as [`Parameter::FrictionCoefficient`].
    RigidBlockFrictionCoefficient,
}

impl Parameter {
    /// Every parameter.
    pub const ALL: [Parameter; 5] = [
        Parameter::RestitutionNormal,
        Parameter::RestitutionTangential,
        Parameter::FrictionCoefficient,
        Parameter::CriticalDampingRatio,
        Parameter::RigidBlockFrictionCoefficient,
    ];

    /// The parameter's name on the wire.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Parameter::RestitutionNormal => "restitution_normal",
            Parameter::RestitutionTangential => "restitution_tangential",
            Parameter::FrictionCoefficient => "friction_coefficient",
            Parameter::CriticalDampingRatio => "critical_damping_ratio",
            Parameter::RigidBlockFrictionCoefficient => "rigid_block_friction_coefficient",
        }
    }

    /// The method the parameter belongs to.
    #[must_use]
    pub const fn method(self) -> Method {
        match self {
            Parameter::RestitutionNormal
            | Parameter::RestitutionTangential
            | Parameter::FrictionCoefficient => Method::LumpedMass,
            Parameter::CriticalDampingRatio | Parameter::RigidBlockFrictionCoefficient => {
                Method::RigidBlock
            }
        }
    }

    /// The distribution the parameter moves in `mc` (None: the parameter is not drawn).
    fn distribution(self, case: &MigrationCase, mc: &MonteCarlo) -> Option<Distribution> {
        match self {
            Parameter::RestitutionNormal => Some(mc.restitution_normal),
            Parameter::RestitutionTangential => Some(mc.restitution_tangential),
            Parameter::FrictionCoefficient | Parameter::RigidBlockFrictionCoefficient => {
                mc.friction_coefficient
            }
            Parameter::CriticalDampingRatio => case.rigid_block.critical_damping_ratio_distribution,
        }
    }

    /// The parameter's value in `case`: the centre of its distribution when drawn, else the
    /// face's (or the rigid block's) value.
    #[must_use]
    pub fn base_value(self, case: &MigrationCase) -> f64 {
        if let Some(d) = case
            .monte_carlo
            .as_ref()
            .and_then(|mc| self.distribution(case, mc))
        {
            return centre(&d);
        }
        match self {
            Parameter::RestitutionNormal => case.face.restitution_normal,
            Parameter::RestitutionTangential => case.face.restitution_tangential,
            Parameter::FrictionCoefficient | Parameter::RigidBlockFrictionCoefficient => {
                case.face.friction_coefficient
            }
            Parameter::CriticalDampingRatio => case.rigid_block.critical_damping_ratio,
        }
    }

    /// Writes value `v` into `work`, a copy of `base`: the face's (or rigid block's) value, and
    /// the base's distribution moved to centre `v` (its width kept).
    fn apply(self, base: &MigrationCase, work: &mut MigrationCase, v: f64) {
        let moved = base
            .monte_carlo
            .as_ref()
            .and_then(|mc| self.distribution(base, mc))
            .map(|d| recentre(&d, v));
        match self {
            Parameter::RestitutionNormal => {
                work.face.restitution_normal = v;
                if let (Some(mc), Some(d)) = (work.monte_carlo.as_mut(), moved) {
                    mc.restitution_normal = d;
                }
            }
            Parameter::RestitutionTangential => {
                work.face.restitution_tangential = v;
                if let (Some(mc), Some(d)) = (work.monte_carlo.as_mut(), moved) {
                    mc.restitution_tangential = d;
                }
            }
            Parameter::FrictionCoefficient | Parameter::RigidBlockFrictionCoefficient => {
                work.face.friction_coefficient = v;
                if let (Some(mc), Some(d)) = (work.monte_carlo.as_mut(), moved) {
                    mc.friction_coefficient = Some(d);
                }
            }
            Parameter::CriticalDampingRatio => {
                work.rigid_block.critical_damping_ratio = v;
                if moved.is_some() {
                    work.rigid_block.critical_damping_ratio_distribution = moved;
                }
            }
        }
    }
}

/// The centre of a distribution: the midpoint of a uniform, the (parent) mean of a normal.
#[must_use]
pub fn centre(d: &Distribution) -> f64 {
    match *d {
        Distribution::Uniform { min, max } => 0.5 * (min + max),
        Distribution::Normal { mean, .. } | Distribution::TruncatedNormal { mean, .. } => mean,
    }
}

/// `d` moved so that its centre is `v`, its width (and a truncated normal's window around the
/// mean) kept.
#[must_use]
pub fn recentre(d: &Distribution, v: f64) -> Distribution {
    let shift = v - centre(d);
    match *d {
        Distribution::Uniform { min, max } => Distribution::Uniform {
            min: min + shift,
            max: max + shift,
        },
        Distribution::Normal { std, .. } => Distribution::Normal { mean: v, std },
        Distribution::TruncatedNormal { std, min, max, .. } => Distribution::TruncatedNormal {
            mean: v,
            std,
            min: min + shift,
            max: max + shift,
        },
    }
}

/// A parameter and the box it is searched in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    /// The parameter.
    pub parameter: Parameter,
    /// Lower end of the box.
    pub min: f64,
    /// Upper end of the box (above `min`).
    pub max: f64,
}

/// The observed quantity: one value per observed run.
#[derive(Debug, Clone, PartialEq)]
pub enum Observed {
    /// Runouts (stop along-dip position minus the release's, in the face's mean plane), m.
    Runout(Vec<f64>),
    /// Stopping points [along_dip, across] in the face's frame, m.
    StopPoints(Vec<[f64; 2]>),
    /// Horizontal distances from the release point to the stop point, m.
    HorizontalRunout(Vec<f64>),
}

impl Observed {
    /// The number of observed runs.
    #[must_use]
    pub fn len(&self) -> usize {
        match self {
            Observed::Runout(v) | Observed::HorizontalRunout(v) => v.len(),
            Observed::StopPoints(v) => v.len(),
        }
    }

    /// True when nothing was observed.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// What a collector line across the whole face saw in the field.
#[derive(Debug, Clone, PartialEq)]
pub struct CollectorObservation {
    /// Along-dip position of the line in the face's mean plane, m.
    pub along_dip: f64,
    /// Speeds of the rocks that passed it, m/s (empty: not observed).
    pub speed: Vec<f64>,
    /// Heights of the rocks' lowest points above the floor where they passed it, m (empty: not
    /// observed).
    pub passing_height: Vec<f64>,
}

/// The distance between observed and computed distributions that the search minimises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Objective {
    /// The two-sample Kolmogorov–Smirnov distance.
    #[default]
    Ks,
    /// The mean absolute difference of the quantiles p05…p95 over the observed spread.
    QuantileLoss,
}

/// The grid search.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Search {
    /// Grid points per parameter and round (at least 3).
    pub points: u32,
    /// Rounds after the first grid, each over a box shrunk by 2/(points − 1) around the best.
    pub refinements: u32,
}

/// A calibration: the base ensemble, the observed runs and the parameters' boxes.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationCase {
    /// The base migration case, with its Monte Carlo ensemble (`monte_carlo` is Some).
    pub base: MigrationCase,
    /// One release (and rock) per observed run (empty: the base's release and rock for all).
    pub releases: Vec<(Release, Rock)>,
    /// The observed quantity.
    pub observed: Observed,
    /// Observed collectors (lines across the whole face).
    pub collectors: Vec<CollectorObservation>,
    /// The parameters searched, 1 to 3, distinct, each applicable to the base's method.
    pub parameters: Vec<Bounds>,
    /// The objective.
    pub objective: Objective,
    /// The grid search.
    pub search: Search,
}

impl CalibrationCase {
    /// Runs of one evaluation: the ensemble's runs × the releases (1 without releases).
    #[must_use]
    pub fn runs_per_evaluation(&self) -> u64 {
        let runs = self.base.monte_carlo.map_or(0, |mc| mc.runs);
        runs.saturating_mul(self.releases.len().max(1) as u64)
    }

    /// The most evaluations the search can make: the base's values, points^d per round
    /// (1 + refinements rounds) and two per parameter for the sensitivity.
    #[must_use]
    pub fn max_evaluations(&self) -> u64 {
        max_evaluations(self.search, self.parameters.len())
    }
}

/// The most evaluations of a search of `d` parameters: 1 + points^d (1 + refinements) + 2d.
#[must_use]
pub fn max_evaluations(search: Search, d: usize) -> u64 {
    let grid = u64::from(search.points).saturating_pow(u32::try_from(d).unwrap_or(u32::MAX));
    grid.saturating_mul(1 + u64::from(search.refinements))
        .saturating_add(1 + 2 * d as u64)
}

/// Why a point was evaluated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EvaluationStage {
    /// The base's own values.
    Base,
    /// A grid point of round `k` (0: the first grid over the whole box).
    Grid(u32),
    /// A neighbour of the best for the sensitivity.
    Sensitivity,
}

/// One point tried.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    /// Why it was tried.
    pub stage: EvaluationStage,
    /// The parameters' values, in the order of [`CalibrationCase::parameters`].
    pub values: Vec<f64>,
    /// The objective there.
    pub objective: f64,
}

/// A neighbour of the best along one parameter: its value and the objective there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Neighbour {
    /// The parameter's value.
    pub value: f64,
    /// The objective.
    pub objective: f64,
}

/// The objective around the best along one parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sensitivity {
    /// The final grid step of the parameter.
    pub step: f64,
    /// The best minus one step (None: below the box).
    pub low: Option<Neighbour>,
    /// The best plus one step (None: above the box).
    pub high: Option<Neighbour>,
    /// Finite-difference slope of the objective per unit of the parameter: central between the
    /// neighbours, one-sided with the best where one is outside the box.
    pub slope: Option<f64>,
}

/// One observed quantity beside its computed distributions (what the page plots).
#[derive(Debug, Clone, PartialEq)]
pub struct FigureSeries {
    /// The quantity's name (`runout_m`, `stop_along_dip_m`, `collectors/0/speed_m_s`, …).
    pub quantity: String,
    /// The probabilities of the quantiles, 0.01…0.99.
    pub probabilities: Vec<f64>,
    /// Observed quantiles (type 7).
    pub observed_quantiles: Vec<f64>,
    /// Computed quantiles at the best.
    pub best_quantiles: Vec<f64>,
    /// Computed quantiles at the base's values.
    pub base_quantiles: Vec<f64>,
    /// Observed ECDF points [x, F(x)].
    pub observed_ecdf: Vec<[f64; 2]>,
    /// Computed ECDF points at the best (at most [`ECDF_POINTS`]).
    pub best_ecdf: Vec<[f64; 2]>,
    /// Computed ECDF points at the base's values (at most [`ECDF_POINTS`]).
    pub base_ecdf: Vec<[f64; 2]>,
    /// The term of the objective at the best.
    pub best_term: f64,
    /// The term of the objective at the base's values.
    pub base_term: f64,
}

/// Largest number of points of an ECDF in the figure (the observed one, at most the observation
/// limit, is given whole).
pub const ECDF_POINTS: usize = 200;

/// What a calibration found.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationResult {
    /// The best values, in the order of the parameters.
    pub best: Vec<f64>,
    /// The objective at the best.
    pub best_objective: f64,
    /// The base's own values.
    pub base: Vec<f64>,
    /// The objective at the base's values.
    pub base_objective: f64,
    /// Every point tried, in order.
    pub evaluations: Vec<Evaluation>,
    /// Per parameter, the objective one final grid step either side of the best.
    pub sensitivity: Vec<Sensitivity>,
    /// Observed and computed distributions at the best and at the base.
    pub figure: Vec<FigureSeries>,
    /// Runs of one evaluation (runs × releases).
    pub runs_per_evaluation: u64,
}

/// A failed calibration: the physics error, and the release whose runs raised it (None: the
/// base's).
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationError {
    /// The release item at fault, when the runs of one release raised the error.
    pub release: Option<usize>,
    /// The error.
    pub error: PhysicsError,
}

impl From<PhysicsError> for CalibrationError {
    fn from(error: PhysicsError) -> Self {
        Self {
            release: None,
            error,
        }
    }
}

/// The calibration calculation.
#[derive(Debug, Clone, Copy)]
pub struct Calibration;

impl super::Calculation for Calibration {
    type Case = CalibrationCase;
    type Result = CalibrationResult;
    type Error = CalibrationError;

    fn solve(
        case: &CalibrationCase,
        control: &Control,
    ) -> Result<Report<CalibrationResult>, CalibrationError> {
        solve(case, control)
    }
}

/// The computed sample of each term, sorted.
type Samples = Vec<Vec<f64>>;

/// The evaluator: the base, the floor built once, the case to run and the lines' order.
struct Evaluator<'a> {
    case: &'a CalibrationCase,
    floor: Arc<migration::Floor>,
    work: MigrationCase,
    /// For each observed collector, the index of its line in `work.lines`.
    line_of: Vec<usize>,
    /// The observed samples of the terms, sorted.
    observed: Samples,
    /// Observed spread per term (quantile loss).
    spread: Vec<f64>,
}

/// The probabilities of the quantile loss: 0.05, 0.10, …, 0.95.
fn loss_probabilities() -> impl Iterator<Item = f64> {
    (1..=19).map(|k| f64::from(k) / 20.0)
}

impl<'a> Evaluator<'a> {
    fn new(case: &'a CalibrationCase) -> Result<Self, CalibrationError> {
        let mut work = case.base.clone();
        // the observed collectors become recording lines, sorted along the dip as physics needs
        let mut order: Vec<usize> = (0..case.collectors.len()).collect();
        order.sort_by(|&a, &b| {
            case.collectors[a]
                .along_dip
                .total_cmp(&case.collectors[b].along_dip)
        });
        let mut line_of = vec![0; case.collectors.len()];
        work.lines = order
            .iter()
            .enumerate()
            .map(|(l, &c)| {
                line_of[c] = l;
                Line {
                    along_dip: case.collectors[c].along_dip,
                    across: None,
                    barrier: None,
                }
            })
            .collect();
        let floor = migration::build_floor(&work)?;
        let mut observed: Samples = match &case.observed {
            Observed::Runout(v) | Observed::HorizontalRunout(v) => vec![v.clone()],
            Observed::StopPoints(p) => vec![
                p.iter().map(|q| q[0]).collect(),
                p.iter().map(|q| q[1]).collect(),
            ],
        };
        for c in &case.collectors {
            for v in [&c.speed, &c.passing_height] {
                if !v.is_empty() {
                    observed.push(v.clone());
                }
            }
        }
        for o in &mut observed {
            o.sort_by(f64::total_cmp);
        }
        let spread = observed
            .iter()
            .map(|o| percentile_sorted(o, 0.95) - percentile_sorted(o, 0.05))
            .collect();
        Ok(Self {
            case,
            floor,
            work,
            line_of,
            observed,
            spread,
        })
    }

    /// Names of the terms, in the order of the samples.
    fn quantities(&self) -> Vec<String> {
        let mut names: Vec<String> = match &self.case.observed {
            Observed::Runout(_) => vec!["runout_m".into()],
            Observed::HorizontalRunout(_) => vec!["horizontal_runout_m".into()],
            Observed::StopPoints(_) => vec!["stop_along_dip_m".into(), "stop_across_m".into()],
        };
        for (i, c) in self.case.collectors.iter().enumerate() {
            if !c.speed.is_empty() {
                names.push(format!("collectors/{i}/speed_m_s"));
            }
            if !c.passing_height.is_empty() {
                names.push(format!("collectors/{i}/passing_height_m"));
            }
        }
        names
    }

    /// The computed samples at `values` (sorted), running every release's runs.
    fn samples(&mut self, values: &[f64], control: &Control) -> Result<Samples, CalibrationError> {
        let case = self.case;
        for (b, &v) in case.parameters.iter().zip(values) {
            b.parameter.apply(&case.base, &mut self.work, v);
        }
        let mc = self
            .work
            .monte_carlo
            .ok_or_else(|| PhysicsError::Numerical("a calibration needs an ensemble".into()))?;
        let releases = case.releases.len().max(1);
        let mut out: Samples = vec![Vec::new(); self.observed.len()];
        let chunk = match case.base.method {
            Method::LumpedMass => 256,
            Method::RigidBlock => 8,
        };
        for k in 0..releases {
            if let Some((release, rock)) = case.releases.get(k) {
                self.work.release = *release;
                self.work.rock = rock.clone();
            }
            let start = k as u64 * mc.runs;
            let (work, floor) = (&self.work, &self.floor);
            let runs: Vec<(RunSummary, Crossings)> =
                migration::run_in_chunks(start..start + mc.runs, chunk, control, |i| {
                    migration::ensemble_run(work, floor, &mc, i, None, control).map(|r| (r.0, r.2))
                })
                .map_err(|error: PhysicsError| CalibrationError {
                    release: (!case.releases.is_empty()).then_some(k),
                    error,
                })?;
            for (s, crossings) in &runs {
                let mut t = 0;
                match &case.observed {
                    Observed::Runout(_) => {
                        out[0].push(s.runout);
                        t = 1;
                    }
                    Observed::HorizontalRunout(_) => {
                        out[0].push(horizontal_runout(s, floor));
                        t = 1;
                    }
                    Observed::StopPoints(_) => {
                        out[0].push(s.stop_along_dip);
                        out[1].push(s.stop_across);
                        t += 2;
                    }
                }
                for (c, &l) in case.collectors.iter().zip(&self.line_of) {
                    let x = crossings.get(l).copied().flatten();
                    if !c.speed.is_empty() {
                        if let Some(x) = x {
                            out[t].push(x.speed);
                        }
                        t += 1;
                    }
                    if !c.passing_height.is_empty() {
                        if let Some(x) = x {
                            out[t].push(x.passing_height);
                        }
                        t += 1;
                    }
                }
            }
        }
        for o in &mut out {
            if o.is_empty() {
                // no run reached the line: nothing passed it, at speed and height 0
                o.push(0.0);
            }
            o.sort_by(f64::total_cmp);
        }
        Ok(out)
    }

    /// The terms of the objective for computed samples `sim`.
    fn terms(&self, sim: &Samples) -> Vec<f64> {
        self.observed
            .iter()
            .zip(sim)
            .zip(&self.spread)
            .map(|((o, s), &spread)| match self.case.objective {
                Objective::Ks => ks_distance(o, s),
                Objective::QuantileLoss => quantile_loss(o, s, spread),
            })
            .collect()
    }

    /// The objective from its terms: the observed quantity's (stop points: the mean of its two),
    /// then one per observed collector array, averaged.
    fn objective(&self, terms: &[f64]) -> f64 {
        let first = match self.case.observed {
            Observed::StopPoints(_) => 2,
            _ => 1,
        };
        let head = terms[..first].iter().sum::<f64>() / first as f64;
        let rest = &terms[first..];
        (head + rest.iter().sum::<f64>()) / (1 + rest.len()) as f64
    }
}

/// The horizontal distance from the release point to the stop point of run `s` on `floor`, m:
/// both points placed on the floor in plan ([`migration::Floor::plan_x`] of their along-dip and
/// across positions; on the plane the along-dip runout × cos θ), then their plan distance.
#[must_use]
pub(crate) fn horizontal_runout(s: &RunSummary, floor: &migration::Floor) -> f64 {
    let dx = floor.plan_x(s.stop_along_dip, s.stop_across)
        - floor.plan_x(s.release_along_dip, s.release_across);
    dx.hypot(s.stop_across - s.release_across)
}

/// The two-sample Kolmogorov–Smirnov distance sup_x |F_a(x) − F_b(x)| of two sorted samples (1
/// when one is empty and the other not, 0 when both are).
#[must_use]
pub fn ks_distance(a: &[f64], b: &[f64]) -> f64 {
    match (a.is_empty(), b.is_empty()) {
        (true, true) => return 0.0,
        (true, false) | (false, true) => return 1.0,
        _ => {}
    }
    let (n, m) = (a.len() as f64, b.len() as f64);
    let (mut i, mut j, mut d) = (0usize, 0usize, 0.0f64);
    while i < a.len() && j < b.len() {
        // step both ECDFs past the next value (ties together)
        let x = a[i].min(b[j]);
        while i < a.len() && a[i] <= x {
            i += 1;
        }
        while j < b.len() && b[j] <= x {
            j += 1;
        }
        d = d.max((i as f64 / n - j as f64 / m).abs());
    }
    d
}

/// The mean over p = 0.05, 0.10, …, 0.95 of |Q_b(p) − Q_a(p)| (type 7) divided by `spread`
/// (the observed p95 − p05; 1 in the quantity's unit where that is 0).
#[must_use]
pub fn quantile_loss(observed: &[f64], computed: &[f64], spread: f64) -> f64 {
    let scale = if spread > 0.0 { spread } else { 1.0 };
    let sum: f64 = loss_probabilities()
        .map(|p| (percentile_sorted(computed, p) - percentile_sorted(observed, p)).abs())
        .sum();
    sum / 19.0 / scale
}

/// Two-sample KS critical value at the 5 % level for samples of n and m (asymptotic:
/// 1.358 √((n + m)/(n m))).
#[must_use]
pub fn ks_critical_5(n: usize, m: usize) -> f64 {
    let (n, m) = (n as f64, m as f64);
    1.358 * ((n + m) / (n * m)).sqrt()
}

/// The values of the grid of `round` over the box [lo, hi], first parameter slowest.
fn grid(lo: &[f64], hi: &[f64], points: u32) -> Vec<Vec<f64>> {
    let d = lo.len();
    let p = points as usize;
    let axis = |j: usize, i: usize| -> f64 {
        if i + 1 == p {
            hi[j]
        } else {
            lo[j] + (hi[j] - lo[j]) * i as f64 / (p - 1) as f64
        }
    };
    let total = p.pow(d as u32);
    (0..total)
        .map(|mut n| {
            let mut idx = vec![0; d];
            for j in (0..d).rev() {
                idx[j] = n % p;
                n /= p;
            }
            (0..d).map(|j| axis(j, idx[j])).collect()
        })
        .collect()
}

/// Quantiles at 0.01…0.99 of a sorted sample.
fn quantiles(sorted: &[f64]) -> Vec<f64> {
    (1..=99)
        .map(|k| percentile_sorted(sorted, f64::from(k) / 100.0))
        .collect()
}

/// The ECDF points [x_(i), i/n] of a sorted sample, at most `max` of them (equally spaced ranks,
/// the last always kept).
fn ecdf(sorted: &[f64], max: usize) -> Vec<[f64; 2]> {
    let n = sorted.len();
    if n == 0 {
        return Vec::new();
    }
    let k = n.min(max.max(1));
    (1..=k)
        .map(|j| {
            let rank = (j * n).div_ceil(k); // 1-based, k = n gives every rank
            [sorted[rank - 1], rank as f64 / n as f64]
        })
        .collect()
}

/// Runs the calibration (see the module documentation).
///
/// # Errors
/// The first physics error of a run (with the release at fault), `Cancelled`/`TimedOut` from
/// the control, or the pace refusal of [`Control::check_pace`].
pub fn solve(
    case: &CalibrationCase,
    control: &Control,
) -> Result<Report<CalibrationResult>, CalibrationError> {
    let d = case.parameters.len();
    let mut ev = Evaluator::new(case)?;
    control.set_total(
        case.max_evaluations()
            .saturating_mul(case.runs_per_evaluation()),
    );
    let mut evaluations: Vec<Evaluation> = Vec::new();
    // the objective of every point run, by the bits of its values (a point met again is not run)
    let mut cache: std::collections::HashMap<Vec<u64>, f64> = std::collections::HashMap::new();
    let key = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();

    let base: Vec<f64> = case
        .parameters
        .iter()
        .map(|b| b.parameter.base_value(&case.base))
        .collect();
    let base_samples = ev.samples(&base, control)?;
    let base_terms = ev.terms(&base_samples);
    let base_objective = ev.objective(&base_terms);
    evaluations.push(Evaluation {
        stage: EvaluationStage::Base,
        values: base.clone(),
        objective: base_objective,
    });
    cache.insert(key(&base), base_objective);

    let mins: Vec<f64> = case.parameters.iter().map(|b| b.min).collect();
    let maxs: Vec<f64> = case.parameters.iter().map(|b| b.max).collect();
    let (mut lo, mut hi) = (mins.clone(), maxs.clone());
    // the best grid point so far, its objective and its samples
    let mut best: Option<(Vec<f64>, f64, Samples, Vec<f64>)> = None;
    let points = case.search.points.max(3);
    for round in 0..=case.search.refinements {
        for values in grid(&lo, &hi, points) {
            let k = key(&values);
            let known = cache.get(&k).copied();
            let (objective, fresh) = match known {
                Some(o) => (o, None),
                None => {
                    let s = ev.samples(&values, control)?;
                    let t = ev.terms(&s);
                    let o = ev.objective(&t);
                    cache.insert(k, o);
                    evaluations.push(Evaluation {
                        stage: EvaluationStage::Grid(round),
                        values: values.clone(),
                        objective: o,
                    });
                    (o, Some((s, t)))
                }
            };
            if best.as_ref().is_none_or(|b| objective < b.1) {
                let (s, t) = match fresh {
                    Some(st) => st,
                    // a point met before (the base's values): its samples again
                    None => {
                        let s = ev.samples(&values, control)?;
                        let t = ev.terms(&s);
                        (s, t)
                    }
                };
                best = Some((values, objective, s, t));
            }
        }
        if round < case.search.refinements
            && let Some((b, ..)) = &best
        {
            for j in 0..d {
                let width = (hi[j] - lo[j]) * 2.0 / f64::from(points - 1);
                let mut l = (b[j] - 0.5 * width).max(mins[j]);
                let mut h = l + width;
                if h > maxs[j] {
                    h = maxs[j];
                    l = (h - width).max(mins[j]);
                }
                lo[j] = l;
                hi[j] = h;
            }
        }
    }
    let (best, best_objective, best_samples, best_terms) =
        best.ok_or_else(|| PhysicsError::Numerical("the search evaluated no point".into()))?;

    let mut sensitivity = Vec::with_capacity(d);
    for j in 0..d {
        let step = (hi[j] - lo[j]) / f64::from(points - 1);
        let mut side = |v: f64| -> Result<Option<Neighbour>, CalibrationError> {
            if !(mins[j]..=maxs[j]).contains(&v) || step <= 0.0 {
                return Ok(None);
            }
            let mut values = best.clone();
            values[j] = v;
            let k = key(&values);
            let objective = match cache.get(&k) {
                Some(&o) => o,
                None => {
                    let s = ev.samples(&values, control)?;
                    let o = ev.objective(&ev.terms(&s));
                    cache.insert(k, o);
                    evaluations.push(Evaluation {
                        stage: EvaluationStage::Sensitivity,
                        values,
                        objective: o,
                    });
                    o
                }
            };
            Ok(Some(Neighbour {
                value: v,
                objective,
            }))
        };
        let low = side(best[j] - step)?;
        let high = side(best[j] + step)?;
        let at_best = Neighbour {
            value: best[j],
            objective: best_objective,
        };
        let slope = match (low, high) {
            (Some(a), Some(b)) => Some((b.objective - a.objective) / (b.value - a.value)),
            (Some(a), None) => Some((at_best.objective - a.objective) / (at_best.value - a.value)),
            (None, Some(b)) => Some((b.objective - at_best.objective) / (b.value - at_best.value)),
            (None, None) => None,
        };
        sensitivity.push(Sensitivity {
            step,
            low,
            high,
            slope,
        });
    }

    let names = ev.quantities();
    let figure = names
        .into_iter()
        .enumerate()
        .map(|(t, quantity)| FigureSeries {
            quantity,
            probabilities: (1..=99).map(|k| f64::from(k) / 100.0).collect(),
            observed_quantiles: quantiles(&ev.observed[t]),
            best_quantiles: quantiles(&best_samples[t]),
            base_quantiles: quantiles(&base_samples[t]),
            observed_ecdf: ecdf(&ev.observed[t], usize::MAX),
            best_ecdf: ecdf(&best_samples[t], ECDF_POINTS),
            base_ecdf: ecdf(&base_samples[t], ECDF_POINTS),
            best_term: best_terms[t],
            base_term: base_terms[t],
        })
        .collect::<Vec<_>>();

    let warnings = warnings(case, &ev, &best, &sensitivity, &figure, &best_samples);
    let plan = vec![Stage::ran(
        "calibration",
        format!(
            "{} evaluations of {} runs each (common random numbers), {} objective",
            evaluations.len(),
            case.runs_per_evaluation(),
            match case.objective {
                Objective::Ks => "Kolmogorov–Smirnov",
                Objective::QuantileLoss => "quantile loss",
            }
        ),
    )];
    Ok(Report {
        result: CalibrationResult {
            best,
            best_objective,
            base,
            base_objective,
            evaluations,
            sensitivity,
            figure,
            runs_per_evaluation: case.runs_per_evaluation(),
        },
        plan,
        warnings,
    })
}

/// The named warnings of a calibration.
fn warnings(
    case: &CalibrationCase,
    ev: &Evaluator<'_>,
    best: &[f64],
    sensitivity: &[Sensitivity],
    figure: &[FigureSeries],
    best_samples: &Samples,
) -> Vec<Warning> {
    let mut w = Vec::new();
    for (b, &v) in case.parameters.iter().zip(best) {
        if v <= b.min || v >= b.max {
            w.push(Warning {
                code: "best_on_bound",
                message: format!(
                    "the best {} = {v} is on the bound of its box [{}, {}]: the objective may \
                     fall further outside it; widen the box on that side",
                    b.parameter.name(),
                    b.min,
                    b.max
                ),
            });
        }
    }
    for (b, s) in case.parameters.iter().zip(sensitivity) {
        let flat = [s.low, s.high]
            .iter()
            .flatten()
            .all(|n| n.objective == figure_objective(ev, figure));
        if flat && (s.low.is_some() || s.high.is_some()) {
            w.push(Warning {
                code: "parameter_insensitive",
                message: format!(
                    "the objective does not change one grid step either side of the best {}: \
                     the observations do not constrain it there",
                    b.parameter.name()
                ),
            });
        }
    }
    for (t, f) in figure.iter().enumerate() {
        if case.objective == Objective::QuantileLoss && ev.spread[t] <= 0.0 {
            w.push(Warning {
                code: "observed_without_spread",
                message: format!(
                    "the observed {} have no spread (p95 = p05): the quantile loss is taken in \
                     the quantity's own unit",
                    f.quantity
                ),
            });
        }
        if f.quantity.starts_with("collectors/") && best_samples[t] == [0.0] {
            w.push(Warning {
                code: "collector_not_reached",
                message: format!(
                    "at the best values no computed run reached the line of {}: its computed \
                     sample is 0 (nothing passed)",
                    f.quantity
                ),
            });
        }
        if case.objective == Objective::Ks {
            let c = ks_critical_5(ev.observed[t].len(), best_samples[t].len());
            if f.best_term > c {
                w.push(Warning {
                    code: "fit_rejected",
                    message: format!(
                        "at the best values the Kolmogorov–Smirnov distance of {} ({:.4}) is \
                         above its 5 % critical value {c:.4}: the observations are unlikely \
                         under the calibrated model (another parameter, a wider box or another \
                         method may be needed)",
                        f.quantity, f.best_term
                    ),
                });
            }
        }
    }
    w
}

/// The objective at the best, recomputed from the figure's terms.
fn figure_objective(ev: &Evaluator<'_>, figure: &[FigureSeries]) -> f64 {
    let terms: Vec<f64> = figure.iter().map(|f| f.best_term).collect();
    ev.objective(&terms)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// sup |F_a − F_b| by evaluating both ECDFs at every sample point (O((n + m)²)).
    fn ks_direct(a: &[f64], b: &[f64]) -> f64 {
        let f = |s: &[f64], x: f64| s.iter().filter(|&&v| v <= x).count() as f64 / s.len() as f64;
        a.iter()
            .chain(b)
            .map(|&x| (f(a, x) - f(b, x)).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn ks_distance_is_the_direct_count() {
        let mut rng = migration::monte_carlo::run_stream(7, 0);
        for n in [1usize, 2, 5, 17, 40] {
            for m in [1usize, 3, 8, 33] {
                // rounded values so that ties within and across samples occur
                let mut a: Vec<f64> = (0..n)
                    .map(|_| (migration::monte_carlo::uniform01(&mut rng) * 10.0).round())
                    .collect();
                let mut b: Vec<f64> = (0..m)
                    .map(|_| (migration::monte_carlo::uniform01(&mut rng) * 12.0).round())
                    .collect();
                a.sort_by(f64::total_cmp);
                b.sort_by(f64::total_cmp);
                let d = ks_distance(&a, &b);
                assert!((d - ks_direct(&a, &b)).abs() < 1e-15, "{n} {m}");
                assert_eq!(d, ks_distance(&b, &a));
            }
        }
        assert_eq!(ks_distance(&[1.0, 2.0], &[3.0, 4.0]), 1.0);
        assert_eq!(ks_distance(&[1.0, 2.0], &[1.0, 2.0]), 0.0);
    }

    #[test]
    fn quantile_loss_of_a_shift_is_the_shift_over_the_spread() {
        let a: Vec<f64> = (0..101).map(f64::from).collect();
        let b: Vec<f64> = a.iter().map(|x| x + 9.0).collect();
        // p05…p95 of 0..100 are 5…95: spread 90; a shift of 9 is 0.1 of it at every p
        assert!((quantile_loss(&a, &b, 90.0) - 0.1).abs() < 1e-12);
        assert_eq!(quantile_loss(&a, &a, 90.0), 0.0);
    }

    #[test]
    fn recentring_keeps_the_width() {
        let Distribution::Uniform { min, max } =
            recentre(&Distribution::Uniform { min: 0.2, max: 0.4 }, 0.5)
        else {
            panic!("kind changed")
        };
        assert!((min - 0.4).abs() < 1e-15 && (max - 0.6).abs() < 1e-15);
        let t = recentre(
            &Distribution::TruncatedNormal {
                mean: 0.2,
                std: 0.02,
                min: 0.1,
                max: 0.5,
            },
            0.3,
        );
        match t {
            Distribution::TruncatedNormal {
                mean,
                std,
                min,
                max,
            } => {
                assert_eq!((mean, std), (0.3, 0.02));
                assert!((min - 0.2).abs() < 1e-15 && (max - 0.6).abs() < 1e-15);
            }
            _ => panic!("kind changed"),
        }
    }

    #[test]
    fn the_grid_spans_the_box_and_refines_by_two_steps() {
        let g = grid(&[0.0, 1.0], &[1.0, 2.0], 3);
        assert_eq!(g.len(), 9);
        assert_eq!(g[0], vec![0.0, 1.0]);
        assert_eq!(g[1], vec![0.0, 1.5]);
        assert_eq!(g[8], vec![1.0, 2.0]);
        assert_eq!(
            max_evaluations(
                Search {
                    points: 5,
                    refinements: 3
                },
                2
            ),
            1 + 25 * 4 + 4
        );
    }

    /// A small lumped-mass calibration of μ on a 30° face.
    fn small_case() -> CalibrationCase {
        let mut base = MigrationCase::default();
        base.face.dip_deg = 30.0;
        base.face.length = 2000.0;
        base.face.friction_coefficient = 0.75;
        base.monte_carlo = Some(MonteCarlo {
            runs: 40,
            ..MonteCarlo::default()
        });
        CalibrationCase {
            base,
            releases: Vec::new(),
            observed: Observed::Runout(vec![8.0, 10.0, 12.0, 14.0]),
            collectors: Vec::new(),
            parameters: vec![Bounds {
                parameter: Parameter::FrictionCoefficient,
                min: 0.6,
                max: 0.9,
            }],
            objective: Objective::Ks,
            search: Search {
                points: 4,
                refinements: 2,
            },
        }
    }

    #[test]
    fn progress_counts_the_runs_made_of_the_most_the_search_can_make() {
        let case = small_case();
        let control = Control::unlimited();
        let r = solve(&case, &control).unwrap().result;
        let (done, total) = control.progress();
        // 1 + 4 × 3 + 2 evaluations at most, of 40 runs; the points met again are not run
        assert_eq!(total, 15 * 40);
        assert_eq!(done, r.evaluations.len() as u64 * 40);
        assert!(
            r.evaluations.len() < 15,
            "{} evaluations",
            r.evaluations.len()
        );
    }

    #[test]
    fn a_cancelled_calibration_stops_with_the_cancellation() {
        let control = Control::unlimited();
        control.cancel();
        let e = solve(&small_case(), &control).unwrap_err();
        assert_eq!(e.error, PhysicsError::Cancelled);
        assert_eq!(control.progress().0, 0, "no run was made");
    }

    #[test]
    fn ecdf_keeps_the_last_point_and_at_most_max() {
        let s: Vec<f64> = (0..1000).map(f64::from).collect();
        let e = ecdf(&s, 200);
        assert_eq!(e.len(), 200);
        assert_eq!(e[199], [999.0, 1.0]);
        assert_eq!(e[0], [4.0, 0.005]);
        assert_eq!(ecdf(&[3.0, 1.0_f64.max(3.0)], 200).len(), 2);
    }
}
