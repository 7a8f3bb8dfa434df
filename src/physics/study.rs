//! Parameter studies (physics.md §D): sensitivity measures of an output to a parameter, their
//! orderings with the tie rule, central-difference elasticities with one Richardson step, and
//! the analytic elasticities of the decoupled log-law and Hertz impacts (§D.2).
//!
//! The sweep itself (which request is solved at which point) belongs to the caller: here are
//! only the numbers made from the points.

use super::contact::{ImpactDetail, effective_modulus, impact_maxima};
use super::error::PhysicsResult;
use super::material::{ContactLaw, ImpactCase, ModulusConvention, RockShape};

/// Relative tie tolerance of orderings of closed-form measures (api.md: 1e-9).
pub const TIE_REL: f64 = 1e-9;
/// Relative tie tolerance of orderings of numerically differentiated elasticities (1e-6).
pub const TIE_REL_NUMERIC: f64 = 1e-6;
/// Relative step of central differences: h = 1e-4·|p| (api.md).
pub const FD_REL_STEP: f64 = 1e-4;

/// `span_over_base` = |y(p_hi) − y(p_lo)| / |y(base)|; `None` when y(base) is 0.
#[must_use]
pub fn span_over_base(low: f64, high: f64, base: f64) -> Option<f64> {
    (base != 0.0).then(|| (high - low).abs() / base.abs())
}

/// `ratio` = max/min of |y(p_hi)| and |y(p_lo)| (≥ 1); `None` when one is 0 or they differ in
/// sign (the ratio of magnitudes would not measure a change of the output then).
#[must_use]
pub fn ratio(low: f64, high: f64) -> Option<f64> {
    if low == 0.0 || high == 0.0 || (low < 0.0) != (high < 0.0) {
        return None;
    }
    let (a, b) = (low.abs(), high.abs());
    Some(a.max(b) / a.min(b))
}

/// The four points of a central difference with one Richardson step at `p`: p − h, p + h,
/// p − h/2, p + h/2 with h = 1e-4·|p|. `None` when p is 0 (no relative step).
#[must_use]
pub fn richardson_points(p: f64) -> Option<[f64; 4]> {
    let h = FD_REL_STEP * p.abs();
    (h > 0.0 && h.is_finite()).then_some([p - h, p + h, p - 0.5 * h, p + 0.5 * h])
}

/// Elasticity d ln y/d ln p at `p` from y at the [`richardson_points`]: D(h) and D(h/2) are
/// central differences over the points actually used, (4D(h/2) − D(h))/3 removes the h² term,
/// and the result is p·D/y0. `None` when y0 is 0.
///
/// # Examples
/// ```
/// use gangue::physics::study::{richardson_points, richardson_elasticity};
/// let p = 2.0;
/// let x = richardson_points(p).unwrap();
/// let y = x.map(|x: f64| x.powf(2.5));
/// let e = richardson_elasticity(p, p.powf(2.5), x, y).unwrap();
/// assert!((e - 2.5).abs() < 1e-9);
/// ```
///
/// # References
/// L. F. Richardson (1911), Phil. Trans. R. Soc. A 210, 307–357; api.md `POST /v1/study`.
#[must_use]
pub fn richardson_elasticity(p: f64, y0: f64, x: [f64; 4], y: [f64; 4]) -> Option<f64> {
    if y0 == 0.0 {
        return None;
    }
    let d1 = (y[1] - y[0]) / (x[1] - x[0]);
    let d2 = (y[3] - y[2]) / (x[3] - x[2]);
    let d = (4.0 * d2 - d1) / 3.0;
    Some(p * d / y0)
}

/// Groups of indices ordered by |measure|, largest first: going down the sorted list, a value
/// within `rel_tol` (relative) of its group's largest joins that group. Inside a group, and
/// between exactly equal values, indices follow `rank` (smaller first). `None` measures are left
/// out.
///
/// # Examples
/// ```
/// use gangue::physics::study::{order_groups, TIE_REL};
/// let g = order_groups(&[Some(0.5), Some(2.0), Some(-0.5), None], &[0, 1, 2, 3], TIE_REL);
/// assert_eq!(g, vec![vec![1], vec![0, 2]]);
/// ```
#[must_use]
pub fn order_groups(measures: &[Option<f64>], rank: &[usize], rel_tol: f64) -> Vec<Vec<usize>> {
    let mut idx: Vec<usize> = (0..measures.len())
        .filter(|&i| measures[i].is_some_and(f64::is_finite))
        .collect();
    let mag = |i: usize| measures[i].map_or(0.0, f64::abs);
    idx.sort_by(|&a, &b| mag(b).total_cmp(&mag(a)).then(rank[a].cmp(&rank[b])));
    let mut groups: Vec<(f64, Vec<usize>)> = Vec::new();
    for i in idx {
        match groups.last_mut() {
            Some((top, g)) if *top - mag(i) <= rel_tol * *top => g.push(i),
            _ => groups.push((mag(i), vec![i])),
        }
    }
    groups
        .into_iter()
        .map(|(_, mut g)| {
            g.sort_by_key(|&i| rank[i]);
            g
        })
        .collect()
}

/// A parameter with an analytic elasticity (§D.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImpactParameter {
    /// Impact speed v.
    Velocity,
    /// Cube side L (also the contact length of the line laws).
    SideLength,
    /// Rock density ρ.
    Density,
    /// Rock Young's modulus E.
    RockModulus,
}

/// Elasticities d ln y/d ln p of the decoupled model's outputs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpactElasticities {
    /// Of δmax.
    pub max_deformation: f64,
    /// Of Pmax.
    pub max_force: f64,
    /// Of the absorbed energy U₀ = ½K₁(δmax/φ₁(½))² (2·e_δ).
    pub absorbed_energy: f64,
    /// Of the energy ratio U₀/(½mv²).
    pub energy_ratio: f64,
}

/// Analytic elasticities of the rigid-column impact maxima and of the decoupled absorbed energy
/// and energy ratio to v, L, ρ or E, for a cube (physics.md §D.2). The caller must make sure
/// that nothing else moves with the parameter (for `hertz_point`, the corner radius must not
/// follow L; the initial midpoint displacement must be δmax).
///
/// With du/d ln G = −(1 + u)/u and s_E = ∂ln E*/∂ln E (1 for the paper's E*, E*(1 − ν²)/E for
/// the two-body E*):
/// e_P = ∂ln P_ref + ((1 + u)/(2u))·∂ln G, e_δ = e_P − ((1 + u)/(u(2 + u)))·∂ln G − ∂ln k,
/// e_U = 2e_δ, e_ratio = 2e_δ − ∂ln(½mv²). Hertz: e_δ = (2/5)(∂ln(mv²) − s_E[p = E]),
/// e_P = s_E[p = E] + (3/2)e_δ.
///
/// Returns `Ok(None)` for a rock that is not a cube.
///
/// # Errors
/// As [`impact_maxima`] (capacity exceeded, invalid input).
///
/// # Special cases
/// At the branch point (u → 0) the log-law elasticities diverge like 1/u: G = 1 exactly gives
/// infinite values, which the caller must treat as undefined.
///
/// # References
/// physics.md §D.2 (matches a 50-digit central difference to 1e-20).
pub fn impact_elasticities(
    case: &ImpactCase,
    p: ImpactParameter,
) -> PhysicsResult<Option<ImpactElasticities>> {
    if !matches!(case.rock.shape, RockShape::Cube) {
        return Ok(None);
    }
    let detail = impact_maxima(case)?;
    let es = effective_modulus(&case.rock, &case.column, case.contact.modulus);
    let s_e = match case.contact.modulus {
        ModulusConvention::Paper => 1.0,
        ModulusConvention::TwoBody => {
            es * (1.0 - case.rock.poisson_ratio * case.rock.poisson_ratio)
                / case.rock.elastic_modulus
        }
    };
    let (v, l, rho, e) = match p {
        ImpactParameter::Velocity => (1.0, 0.0, 0.0, 0.0),
        ImpactParameter::SideLength => (0.0, 1.0, 0.0, 0.0),
        ImpactParameter::Density => (0.0, 0.0, 1.0, 0.0),
        ImpactParameter::RockModulus => (0.0, 0.0, 0.0, 1.0),
    };
    // ∂ln(½mv²) with m = ρL³.
    let d_ke = 2.0 * v + 3.0 * l + rho;
    let (e_d, e_p) = match (&detail, case.contact.law) {
        (ImpactDetail::Line(li), law) => {
            let u = li.u;
            let d_pref = match law {
                ContactLaw::Paper => 3.0 * l + s_e * e,
                _ => l + s_e * e,
            };
            let d_k = l + s_e * e;
            let d_g = 2.0 * v + rho + 4.0 * l + s_e * e - 2.0 * d_pref;
            let e_p = d_pref + (1.0 + u) / (2.0 * u) * d_g;
            let e_d = e_p - (1.0 + u) / (u * (2.0 + u)) * d_g - d_k;
            (e_d, e_p)
        }
        (ImpactDetail::Hertz(_), _) => {
            let e_d = 0.4 * (d_ke - s_e * e);
            (e_d, s_e * e + 1.5 * e_d)
        }
    };
    Ok(Some(ImpactElasticities {
        max_deformation: e_d,
        max_force: e_p,
        absorbed_energy: 2.0 * e_d,
        energy_ratio: 2.0 * e_d - d_ke,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_join_within_tolerance_of_the_group_top() {
        // 1.0, 1.0 − 5e-10 (joins), 1.0 − 1.5e-9 (does not: compared with the top, not the last).
        let m = [Some(1.0 - 1.5e-9), Some(1.0), Some(1.0 - 5e-10)];
        assert_eq!(
            order_groups(&m, &[0, 1, 2], TIE_REL),
            vec![vec![1, 2], vec![0]]
        );
        // Inside a group the canonical rank decides, not the size.
        let m = [Some(0.3), Some(0.3 * (1.0 + 1e-12))];
        assert_eq!(order_groups(&m, &[0, 1], TIE_REL), vec![vec![0, 1]]);
        assert_eq!(order_groups(&m, &[1, 0], TIE_REL), vec![vec![1, 0]]);
    }

    #[test]
    fn measures_of_degenerate_outputs_are_none() {
        assert_eq!(span_over_base(1.0, 2.0, 0.0), None);
        assert_eq!(ratio(-1.0, 2.0), None);
        assert_eq!(ratio(0.0, 2.0), None);
        assert_eq!(ratio(-1.0, -3.0), Some(3.0));
        assert_eq!(richardson_points(0.0), None);
    }

    /// Richardson removes the h² term: a quartic's elasticity is exact to rounding.
    #[test]
    fn richardson_is_fourth_order() {
        let f = |x: f64| 3.0 + x * x * x * x - 2.0 * x;
        let p = 1.7;
        let x = richardson_points(p).unwrap();
        let y = x.map(f);
        let exact = p * (4.0 * p * p * p - 2.0) / f(p);
        let e = richardson_elasticity(p, f(p), x, y).unwrap();
        assert!((e - exact).abs() < 1e-10, "{e} vs {exact}");
    }
}
