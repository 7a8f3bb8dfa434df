//! A study's answer from its points' outputs: curves, grids, sensitivity measures and
//! orderings, energy proportions, the paper comparison.

use super::*;

/// The outputs `reads` (each with its name) of a point's result.
pub(super) fn extract(
    r: &crate::physics::column::ColumnResult,
    reads: &[(String, Output)],
) -> Result<Vec<f64>, ApiError> {
    reads
        .iter()
        .map(|(name, o)| {
            o.of(r)
                .filter(|x| x.is_finite())
                .ok_or_else(|| ApiError::internal(format!("study output {name} missing")))
        })
        .collect()
}

pub(super) fn ordering_names(groups: &[Vec<usize>], params: &[Param]) -> Vec<String> {
    groups
        .iter()
        .map(|g| {
            g.iter()
                .map(|&i| params[i].name.as_str())
                .collect::<Vec<_>>()
                .join("=")
        })
        .collect()
}

/// Each point's outputs, placed where the response lists them.
pub(super) struct Assembled {
    /// The base point's outputs, then its energy ratio.
    pub(super) base: Vec<f64>,
    /// The curves: [parameter][output][point].
    pub(super) curves: Vec<Vec<Vec<f64>>>,
    /// The pair grids: [pair][output][y point][x point].
    pub(super) grids: Vec<Vec<Vec<Vec<f64>>>>,
    /// The energy ratio at each x·max: [parameter][x] (`None` where x·max is not a valid
    /// column request).
    pub(super) proportions: Vec<Vec<Option<f64>>>,
    /// The four central-difference points' outputs: [parameter][output].
    pub(super) differences: Vec<Vec<[f64; 4]>>,
}

/// Places the outputs `results` of the points `slots` (`no` outputs then the energy ratio
/// each) for `np` parameters of `n` points, `n_pairs` pair grids and `nx` x values.
pub(super) fn assemble(
    slots: &[Slot],
    results: Vec<Vec<f64>>,
    no: usize,
    np: usize,
    n: usize,
    n_pairs: usize,
    nx: usize,
) -> Assembled {
    let ie = no; // index of energy_ratio in each result
    let mut y = Assembled {
        base: Vec::new(),
        curves: vec![vec![vec![0.0; n]; no]; np],
        grids: vec![vec![vec![vec![0.0; n]; n]; no]; n_pairs],
        proportions: vec![vec![None; nx]; np],
        differences: vec![vec![[0.0; 4]; no]; np],
    };
    for (slot, r) in slots.iter().zip(results) {
        match *slot {
            Slot::Base => y.base = r,
            Slot::Curve(i, k) => (0..no).for_each(|o| y.curves[i][o][k] = r[o]),
            Slot::Grid(g, yi, xi) => (0..no).for_each(|o| y.grids[g][o][yi][xi] = r[o]),
            Slot::Proportion(i, k) => y.proportions[i][k] = Some(r[ie]),
            Slot::Difference(i, j) => (0..no).for_each(|o| y.differences[i][o][j] = r[o]),
        }
    }
    y
}

/// The response of a checked study `plan` from the outputs `results` of its points.
pub(super) fn finish_study(
    plan: StudyPlan,
    results: Vec<Vec<f64>>,
) -> Result<StudyResponse, ApiError> {
    let StudyPlan {
        mut req,
        base_resolved,
        coupled,
        outputs,
        reads,
        params,
        values,
        pairs,
        slots,
        mut warnings,
        ..
    } = plan;
    let n = req.points as usize;
    let np = params.len();
    let no = outputs.len();
    let ie = no; // index of energy_ratio in each result
    let y = assemble(&slots, results, no, np, n, pairs.len(), req.x_values.len());
    let curves = OrderedMap(
        params
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let mut m = vec![("values".to_string(), values[i].clone())];
                m.extend(
                    outputs
                        .iter()
                        .enumerate()
                        .map(|(o, name)| (name.clone(), y.curves[i][o].clone())),
                );
                (p.name.clone(), OrderedMap(m))
            })
            .collect(),
    );
    let grids = (req.grid == StudyGrid::Pairs).then(|| {
        pairs
            .iter()
            .enumerate()
            .map(|(g, &(a, b))| StudyGridDto {
                x: params[a].name.clone(),
                y: params[b].name.clone(),
                x_values: values[a].clone(),
                y_values: values[b].clone(),
                outputs: OrderedMap(
                    outputs
                        .iter()
                        .enumerate()
                        .map(|(o, name)| (name.clone(), y.grids[g][o].clone()))
                        .collect(),
                ),
            })
            .collect()
    });
    let ranks: Vec<usize> = params.iter().map(|p| p.rank).collect();
    let mut sensitivity = Vec::new();
    let mut groups_by_output = Vec::new();
    for (o, name) in outputs.iter().enumerate() {
        let (dto, groups) = output_sensitivity(o, name, &params, &ranks, &y, n, &mut warnings);
        sensitivity.push((name.clone(), dto));
        groups_by_output.push((reads[o].1, groups));
    }
    let prop_groups: Vec<Vec<Vec<usize>>> = (0..req.x_values.len())
        .map(|k| {
            let m: Vec<Option<f64>> = (0..np).map(|i| y.proportions[i][k]).collect();
            order_groups(&m, &ranks, TIE_REL)
        })
        .collect();
    let energy_proportion = EnergyProportionDto {
        model: if coupled { "coupled" } else { "decoupled" }.into(),
        x: req.x_values.clone(),
        curves: OrderedMap(
            params
                .iter()
                .enumerate()
                .map(|(i, p)| (p.name.clone(), y.proportions[i].clone()))
                .collect(),
        ),
        orderings: prop_groups
            .iter()
            .map(|g| ordering_names(g, &params))
            .collect(),
    };
    let swept: Vec<(calc::study::Parameter, f64, f64)> = params
        .iter()
        .map(|p| (p.field.parameter(), p.min, p.max))
        .collect();
    let paper_comparison: Vec<PaperComparisonDto> = calc::study::compare_with_paper(
        &swept,
        req.base.contact.effective_modulus == ModulusDto::TwoBody,
        coupled,
        &groups_by_output,
        &req.x_values,
        &prop_groups,
        y.base[ie],
    )
    .into_iter()
    .map(|c| PaperComparisonDto {
        item: c.item,
        paper: c.paper,
        ours: c.ours,
        reproduced: c.reproduced,
        note: c.note,
    })
    .collect();
    if paper_comparison.is_empty() {
        warnings.push(Warning::new(
            "no_paper_comparison",
            "paper_comparison is empty: it needs the paper's four parameters with the paper's ranges (physics.md §D.1)",
        ));
    }
    let analytic: Vec<&str> = params
        .iter()
        .filter(|p| p.analytic.is_some())
        .map(|p| p.name.as_str())
        .collect();
    let mut meta = Meta::new(plan_of(&calc::study::plan(
        &analytic,
        slots.len(),
        coupled,
        pairs.len(),
        n,
    )));
    meta.warnings = warnings;
    req.base = base_resolved;
    Ok(StudyResponse {
        curves,
        grids,
        sensitivity: OrderedMap(sensitivity),
        energy_proportion,
        paper_comparison,
        warnings: meta.warnings,
        plan: meta.plan,
        inputs: req,
        model_version: meta.model_version,
    })
}

/// The sensitivity of output `o` (`name`) to each parameter: its measures (a warning for
/// each that is undefined) and its three orderings (span over base, ratio, elasticity).
pub(super) fn output_sensitivity(
    o: usize,
    name: &str,
    params: &[Param],
    ranks: &[usize],
    y: &Assembled,
    n: usize,
    warnings: &mut Vec<Warning>,
) -> (OutputSensitivityDto, [Vec<Vec<usize>>; 3]) {
    let y0 = y.base[o];
    let mut any_numeric = false;
    let measures: Vec<MeasuresDto> = params
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let (low, high) = (y.curves[i][o][0], y.curves[i][o][n - 1]);
            let analytic = p.analytic.and_then(|e| match name {
                "max_deformation_m" => Some(e.max_deformation),
                "max_force_n" => Some(e.max_force),
                "absorbed_energy_j" => Some(e.absorbed_energy),
                "energy_ratio" => Some(e.energy_ratio),
                _ => None,
            });
            let elasticity = analytic.or_else(|| {
                any_numeric = true;
                match (p.base, p.fd) {
                    (Some(b), Some(x)) => richardson_elasticity(b, y0, x, y.differences[i][o]),
                    _ => None,
                }
            });
            MeasuresDto {
                low,
                high,
                span_over_base: span_over_base(low, high, y0),
                ratio: ratio(low, high),
                elasticity,
            }
        })
        .collect();
    for (p, m) in params.iter().zip(&measures) {
        for (what, v) in [
            ("span_over_base", m.span_over_base),
            ("ratio", m.ratio),
            ("elasticity", m.elasticity),
        ] {
            if v.is_none() && !(what == "elasticity" && p.fd.is_none() && p.analytic.is_none()) {
                warnings.push(Warning::new(
                    "measure_undefined",
                    format!(
                        "{name}, {}: {what} is null (zero base output, or outputs of opposite sign or zero at the range ends); left out of the ordering",
                        p.name
                    ),
                ));
            }
        }
    }
    let by = |f: fn(&MeasuresDto) -> Option<f64>, tol: f64| {
        order_groups(&measures.iter().map(f).collect::<Vec<_>>(), ranks, tol)
    };
    let g_span = by(|m| m.span_over_base, TIE_REL);
    let g_ratio = by(|m| m.ratio, TIE_REL);
    let g_el = by(
        |m| m.elasticity,
        if any_numeric {
            TIE_REL_NUMERIC
        } else {
            TIE_REL
        },
    );
    let dto = OutputSensitivityDto {
        base: y0,
        parameters: OrderedMap(
            params
                .iter()
                .zip(&measures)
                .map(|(p, m)| (p.name.clone(), *m))
                .collect(),
        ),
        ordering: OrderingDto {
            span_over_base: ordering_names(&g_span, params),
            ratio: ordering_names(&g_ratio, params),
            elasticity: ordering_names(&g_el, params),
        },
    };
    (dto, [g_span, g_ratio, g_el])
}
