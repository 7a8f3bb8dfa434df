//! A study's points: the swept values, where each point's outputs go, and their evaluation
//! on the solver pool in a fixed order.

use super::*;

/// The swept values of each parameter: `n` evenly spaced from min, the last exactly max.
pub(super) fn sweep_values(params: &[Param], n: usize) -> Vec<Vec<f64>> {
    params
        .iter()
        .map(|p| {
            (0..n)
                .map(|k| {
                    if k + 1 == n {
                        p.max
                    } else {
                        p.min + (p.max - p.min) * (k as f64) / ((n - 1) as f64)
                    }
                })
                .collect()
        })
        .collect()
}

/// The study's points in response order: the base, each parameter's curve of `n`, each of
/// the `grids` pair grids of n × n, then per parameter its `nx` energy proportions and its
/// four central-difference points.
pub(super) fn study_slots(params: &[Param], grids: usize, n: usize, nx: usize) -> Vec<Slot> {
    let mut slots = vec![Slot::Base];
    for i in 0..params.len() {
        slots.extend((0..n).map(|k| Slot::Curve(i, k)));
    }
    for g in 0..grids {
        for yi in 0..n {
            slots.extend((0..n).map(|xi| Slot::Grid(g, yi, xi)));
        }
    }
    for (i, p) in params.iter().enumerate() {
        slots.extend(
            (0..nx)
                .filter(|&k| p.proportion_defined[k])
                .map(|k| Slot::Proportion(i, k)),
        );
        if p.fd.is_some() {
            slots.extend((0..4).map(|j| Slot::Difference(i, j)));
        }
    }
    slots
}

impl StudyPlan {
    /// Number of points: the base (point 0) and the items (1 ..).
    #[must_use]
    pub fn points(&self) -> u64 {
        self.slots.len() as u64
    }

    /// The resolved request (the response's `inputs`).
    #[must_use]
    pub fn inputs(&self) -> StudyRequest {
        let mut req = self.req.clone();
        req.base = self.base_resolved.clone();
        req
    }

    /// The swept values of point `index`: (parameter index, value) of each.
    pub(super) fn sets(&self, index: usize) -> Vec<(usize, f64)> {
        let (params, values) = (&self.params, &self.values);
        match self.slots[index] {
            Slot::Base => Vec::new(),
            Slot::Curve(i, k) => vec![(i, values[i][k])],
            Slot::Grid(g, yi, xi) => {
                let (a, b) = self.pairs[g];
                vec![(a, values[a][xi]), (b, values[b][yi])]
            }
            Slot::Proportion(i, k) => vec![(i, self.req.x_values[k] * params[i].max)],
            Slot::Difference(i, j) => vec![(i, params[i].fd.map_or(0.0, |f| f[j]))],
        }
    }

    /// A point's error names the swept parameter (of `sets`) that set the field, else the
    /// base's field.
    pub(super) fn blame_point(&self, e: ApiError, sets: &[(usize, f64)]) -> ApiError {
        let params = &self.params;
        e.rename_fields(|f| {
            params
                .iter()
                .enumerate()
                .position(|(i, p)| p.pointer == f && sets.iter().any(|(s, _)| *s == i))
                .map_or_else(|| format!("/base{f}"), |i| format!("/parameters/{i}"))
        })
    }

    /// Every curve and grid point must be a valid column request (the range ends, energy
    /// proportions and central-difference points are checked with their parameter): the first
    /// point, in point order, that the request's own validation refuses is refused as such.
    pub(super) fn check_points(&self, config: &Config) -> Result<(), ApiError> {
        let sent = &self.req.base;
        match (0..self.slots.len())
            .into_par_iter()
            .filter(|&k| matches!(self.slots[k], Slot::Curve(..) | Slot::Grid(..)))
            .find_map_first(|k| {
                let sets = self.sets(k);
                let fields: Vec<(SweptField, f64)> = sets
                    .iter()
                    .map(|&(i, x)| (self.params[i].field, x))
                    .collect();
                resolve_point(config, sent, &fields)
                    .err()
                    .map(|e| self.blame_point(e, &sets))
            }) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// Solves point `index`: the listed outputs and then the energy ratio.
    pub fn eval(
        &self,
        _config: &Config,
        index: usize,
        control: &Control,
    ) -> Result<Vec<f64>, ApiError> {
        control.check()?;
        let sets = self.sets(index);
        let swept: Vec<(calc::study::Parameter, f64)> = sets
            .iter()
            .map(|&(i, x)| (self.params[i].field.parameter(), x))
            .collect();
        let case = self.base.point(&swept);
        let report = Column::solve(&case, control).map_err(|e| {
            let e = ApiError::from(e).with_capacity_velocity(case.impact.velocity);
            let e = match case.end_time {
                Some(t) => e.with_step_field("/end_time_s", t),
                None => e,
            };
            self.blame_point(e, &sets)
        })?;
        let out = extract(&report.result, &self.reads)?;
        control.add_done(1);
        Ok(out)
    }

    /// The response from the outputs of every point, in point order.
    pub fn finish(self, results: Vec<Vec<f64>>) -> Result<StudyResponse, ApiError> {
        if results.len() != self.slots.len() {
            return Err(ApiError::internal(format!(
                "{} study results for {} points",
                results.len(),
                self.slots.len()
            )));
        }
        finish_study(self, results)
    }
}
