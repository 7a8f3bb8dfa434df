//! The first strike of a free flight on a floor: the parabola p + v t + ½ (0, 0, −g) t²
//! (positions in m, velocities in m/s, g in m/s², times in s) against each candidate facet's
//! plane, the candidates found by the cell walk along the flight's straight plan-view path
//! (or, above a coplanar patch, its plane alone).

use nalgebra::Vector3;

use super::walk::fl;

use super::facet::{FacetPlane, inside_tri};
use super::{Facet, Floor, FloorKind};

/// Descending root of h0 + b t − ½ g t² (the larger root), or None when the parabola stays below.
#[inline]
pub(super) fn descent_root(h0: f64, b: f64, g: f64) -> Option<f64> {
    let d = b * b + 2.0 * g * h0;
    if d < 0.0 {
        return None;
    }
    let s = d.sqrt();
    if b >= 0.0 {
        Some((b + s) / g)
    } else if s - b > 0.0 {
        Some(2.0 * h0 / (s - b))
    } else {
        Some(0.0)
    }
}

/// Result of a flight query.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum FlightEnd {
    /// The parabola strikes facet `facet` after `t` s.
    Hit {
        /// Time of flight, s.
        t: f64,
        /// Struck facet.
        facet: Facet,
    },
    /// The horizontal path leaves the floor's extent after `t` s without a hit.
    Leaves {
        /// Time of flight, s.
        t: f64,
    },
    /// No hit within the time asked for.
    Clear,
}

/// Rounding allowance, m, of a start point's height against a facet's plane: a few ulps of
/// p's coordinates (m), far below the invariant's 1e-9 tolerance.
#[inline]
pub(crate) fn start_rounding(p: &Vector3<f64>) -> f64 {
    1e-12 * (1.0 + p.x.abs().max(p.y.abs()).max(p.z.abs()))
}

/// The strike of the parabola p + v t + ½ (0, 0, −g) t² (m, m/s, m/s²) on the plane `pl`: its
/// time, s, and whether it is a strike at the start (`h_round`, m: [`start_rounding`] of p), or
/// None when the parabola does not strike it.
#[inline]
fn strike_root(
    pl: &FacetPlane,
    p: &Vector3<f64>,
    v: &Vector3<f64>,
    g: f64,
    h_round: f64,
) -> Option<(f64, bool)> {
    let h0 = pl.height(p);
    let b = pl.height_rate(v);
    let r = descent_root(h0, b, g)?;
    // a strike: the height decreases through zero (not a graze at the start)
    let slope = b - g * r;
    // A start on the plane (to rounding) not moving away from it is a strike now, if the
    // motion goes on over the facet (checked a little ahead, see `ahead`): a rock at rest
    // on a facet grazes it at t = 0 (h = −g t²/2), and a start a rounding error below
    // the plane, sinking further, has its root h0/|b| in the past, which is long for a
    // slow rock (a rock bounced off a node at 6 mm/s into a steeper facet 9e-16 m below
    // the node's height had its root 3.6e-12 s back: refused as past, it fell through).
    if slope >= -1e-12 * (1.0 + b.abs()) {
        return (h0.abs() <= h_round && b <= 1e-12).then_some((0.0, true));
    }
    if r < -1e-12 && h0 >= -h_round {
        return Some((0.0, true));
    }
    Some((r, false))
}

/// First strike within t ≤ `t_max` (s) of the parabola p + v t + ½ (0, 0, −g) t² on the plane
/// floor `pl` (one facet, 0, without holes): [`Floor::flight`] on a plane.
#[inline]
pub(crate) fn plane_flight(
    pl: &FacetPlane,
    p: &Vector3<f64>,
    v: &Vector3<f64>,
    g: f64,
    t_max: f64,
) -> FlightEnd {
    match strike_root(pl, p, v, g, start_rounding(p)) {
        Some((t, _)) if t <= t_max => FlightEnd::Hit { t, facet: 0 },
        _ => FlightEnd::Clear,
    }
}

impl Floor {
    /// First strike of the parabola p + v t + ½ (0, 0, −g) t² on the floor within t ≤ t_max.
    /// A strike on a hole's facet (its height filled in from the data around it) is a landing
    /// in the hole: the rock leaves the floor there ([`FlightEnd::Leaves`]); a flight passing
    /// over a hole above that surface goes on.
    pub(crate) fn flight(
        &self,
        p: &Vector3<f64>,
        v: &Vector3<f64>,
        g: f64,
        t_max: f64,
    ) -> FlightEnd {
        match self.flight_any(p, v, g, t_max) {
            FlightEnd::Hit { t, facet } if self.is_hole(facet) => FlightEnd::Leaves { t },
            e => e,
        }
    }

    fn flight_any(&self, p: &Vector3<f64>, v: &Vector3<f64>, g: f64, t_max: f64) -> FlightEnd {
        // rounding of the start point's height against a facet's plane (a few ulps of its
        // coordinates), far below the invariant's 1e-9 tolerance
        let h_round = start_rounding(p);
        let root = |pl: &FacetPlane| strike_root(pl, p, v, g, h_round);
        // where a strike at the start is tested against a facet: a step of 1e-6 of a cell
        // along the horizontal motion (on the start point itself when there is none), so that a
        // rock leaving a facet across its edge does not strike it again
        let ahead = |d: f64| -> (f64, f64) {
            // the direction only (a step of 1e-6 of a cell): a sum and a square root, not the
            // library's hypot; a speed whose square underflows counts as none
            let hv = (v.x * v.x + v.y * v.y).sqrt();
            if hv > 0.0 {
                (p.x + 1e-6 * d * v.x / hv, p.y + 1e-6 * d * v.y / hv)
            } else {
                (p.x, p.y)
            }
        };
        match &self.kind {
            FloorKind::Plane(pl) => plane_flight(pl, p, v, g, t_max),
            // In each cell of the walk, the candidates are its facets and those of the cells
            // whose boundary the path runs within `near` of; a root counts when its point lies in
            // the facet (closed, with a rounding tolerance), not in the past and not after the cell's
            // window. A root before the window is a strike all the same (the window's start is formed
            // from a crossing time that is ill-conditioned when the path runs along a line), so
            // no strike can fall between two cells' windows.
            FloorKind::Grid(gr) => {
                if let Some(hit) = gr.patch_flight(p, v, g, t_max) {
                    return hit;
                }
                let tol = 1e-9 * gr.cells.d;
                let (inv_d, t_cells) = (1.0 / gr.cells.d, 1e-9);
                let near = 1e-6 * gr.cells.d;
                let path = (p.x, p.y, v.x, v.y);
                gr.cells.walk(p.x, p.y, v.x, v.y, t_max, |ci, cj, t0, t1| {
                    let mut best: Option<(f64, Facet)> = None;
                    let (dx, dy) = gr.cells.near_cells(ci, cj, path, t0, t1, near);
                    for (ni, nj) in dy.iter().flat_map(|&oy| {
                        dx.iter().map(move |&ox| {
                            (ci.wrapping_add_signed(ox), cj.wrapping_add_signed(oy))
                        })
                    }) {
                        for half in 0..2 {
                            let f = gr.facet(ni, nj, half);
                            let pl = gr.plane(f);
                            if let Some((r, now)) = root(&pl)
                                && r >= -1e-12
                                && r <= t1 + 1e-12 * (1.0 + t1)
                                && best.is_none_or(|b| r < b.0)
                            {
                                let (qx, qy) = if now {
                                    ahead(gr.cells.d)
                                } else {
                                    (p.x + v.x * r, p.y + v.y * r)
                                };
                                let gq = (
                                    (qx - gr.cells.x0) * inv_d - fl(ni),
                                    (qy - gr.cells.y0) * inv_d - fl(nj),
                                );
                                let te = (t_cells, gr.clear_margin(qx, qy, t_cells));
                                if gr.near_facet(f, (ni, nj), (qx, qy), gq, tol, te) {
                                    best = Some((r.max(0.0), f));
                                }
                            }
                        }
                    }
                    best
                })
            }
            FloorKind::Mesh(m) => {
                let tol = 1e-9 * m.cells.d;
                let near = 1e-6 * m.cells.d;
                let path = (p.x, p.y, v.x, v.y);
                m.cells.walk(p.x, p.y, v.x, v.y, t_max, |ci, cj, t0, t1| {
                    let mut best: Option<(f64, Facet)> = None;
                    let (dx, dy) = m.cells.near_cells(ci, cj, path, t0, t1, near);
                    for (ni, nj) in dy.iter().flat_map(|&oy| {
                        dx.iter().map(move |&ox| {
                            (ci.wrapping_add_signed(ox), cj.wrapping_add_signed(oy))
                        })
                    }) {
                        for &f in m.bucket(ni, nj) {
                            let pl = m.plane(f);
                            if let Some((r, now)) = root(&pl)
                                && r >= -1e-12
                                && r <= t1 + 1e-12 * (1.0 + t1)
                                && best.is_none_or(|b| r < b.0)
                            {
                                let (qx, qy) = if now {
                                    ahead(m.cells.d)
                                } else {
                                    (p.x + v.x * r, p.y + v.y * r)
                                };
                                if inside_tri(&m.corners(f).0, qx, qy, tol) {
                                    best = Some((r.max(0.0), f));
                                }
                            }
                        }
                    }
                    best
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn descent_root_is_the_flight_time() {
        // from the floor with vertical height rate b: 2b/g
        let r = descent_root(0.0, 3.0, 9.81).unwrap();
        assert!((r - 6.0 / 9.81).abs() < 1e-15);
        // dropped from h at rest: √(2h/g)
        let r = descent_root(3.27, 0.0, 9.81).unwrap();
        assert!((r - (2.0 * 3.27 / 9.81_f64).sqrt()).abs() < 1e-15);
        assert!(descent_root(-1.0, -1.0, 9.81).is_none());
    }

    #[test]
    fn a_slow_flight_starting_a_rounding_error_below_a_facet_strikes_it_at_once() {
        // the grid z = −x; the start 1e-15 m (rounding) below it, sinking 0.25 mm/s relative
        // to it: the root lies 4e-12 s in the past, a strike now, not a fall through the floor
        let h = vec![vec![0.0, -1.0, -2.0]; 3];
        let f = Floor::grid(0.7, [0.0, 0.0], 1.0, &h).unwrap();
        let p = Vector3::new(1.3, 0.6, -1.3 - 1e-15);
        let v = Vector3::new(0.0, 0.0, -2.5e-4);
        match f.flight(&p, &v, 9.81, 1.0) {
            FlightEnd::Hit { t, .. } => assert_eq!(t, 0.0),
            e => panic!("{e:?}"),
        }
        // clearly below (1e-6 m) is not a rounding error: no strike from underneath
        let p = Vector3::new(1.3, 0.6, -1.3 - 1e-6);
        assert!(!matches!(
            f.flight(&p, &v, 9.81, 1.0),
            FlightEnd::Hit { .. }
        ));
    }

    #[test]
    fn a_rock_at_rest_on_a_facet_strikes_it_at_once_and_one_leaving_it_does_not() {
        // a convex grid: z = −x up to x = 1, then z = 1 − 2x
        let h = vec![vec![0.0, -1.0, -3.0]; 3];
        let f = Floor::grid(0.7, [0.0, 0.0], 1.0, &h).unwrap();
        // at rest exactly on the floor (a graze at t = 0): a strike now, not a fall through it
        let p = Vector3::new(0.4, 0.3, -0.4);
        match f.flight(&p, &Vector3::zeros(), 9.81, 1.0) {
            FlightEnd::Hit { t, .. } => assert_eq!(t, 0.0),
            e => panic!("{e:?}"),
        }
        // taking off at the convex edge x = 1 along the upper facet: no strike on it at t = 0,
        // the landing is on the steeper facet beyond
        let p = Vector3::new(1.0, 0.3, -1.0);
        let v = Vector3::new(1.0, 0.0, -1.0);
        match f.flight(&p, &v, 9.81, 10.0) {
            FlightEnd::Hit { t, .. } => assert!(t > 0.05, "{t}"),
            e => panic!("{e:?}"),
        }
    }
}
