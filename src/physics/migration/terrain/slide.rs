//! The exit of a slide from a facet: the planar motion p + v t + ½ a t² (positions in m,
//! velocities in m/s, accelerations in m/s², times in s) leaves a triangle at the first
//! outward crossing of one of its edges, the smallest outward root of a quadratic per edge.

use nalgebra::Vector3;

use super::{Facet, Floor, FloorKind, NONE};

impl Floor {
    /// First exit of the planar motion p + v t + ½ a t² from facet f through one of its edges
    /// within t ≤ t_max: the time, the facet across that edge (None: off the floor) and the
    /// edge's end points in plan.
    #[inline]
    pub(crate) fn slide_exit(
        &self,
        f: Facet,
        p: &Vector3<f64>,
        v: &Vector3<f64>,
        a: &Vector3<f64>,
        t_max: f64,
    ) -> Option<(f64, Option<Facet>, [[f64; 2]; 2])> {
        let (corners, ij) = match &self.kind {
            FloorKind::Plane(_) => return None,
            FloorKind::Grid(g) => {
                let (i, j) = g.cell_of(f);
                (g.corners_at(f, i, j).0, (i, j))
            }
            FloorKind::Mesh(m) => (m.corners(f).0, (0, 0)),
        };
        let mut best: Option<(f64, usize)> = None;
        for k in 0..3 {
            let e0 = corners[k];
            let e1 = corners[(k + 1) % 3];
            let (sx, sy) = (e1[1] - e0[1], -(e1[0] - e0[0]));
            let f0 = sx * (p.x - e0[0]) + sy * (p.y - e0[1]);
            let f1 = sx * v.x + sy * v.y;
            let f2 = sx * a.x + sy * a.y;
            if let Some(t) = outward_root(f0, f1, f2)
                && t <= t_max
                && best.is_none_or(|b| t < b.0)
            {
                best = Some((t, k));
            }
        }
        best.map(|(t, k)| {
            let next = match &self.kind {
                FloorKind::Grid(g) => g.neighbor_at(f, ij.0, ij.1, k),
                FloorKind::Mesh(m) => {
                    let n = m.nbr[f as usize][k];
                    (n != NONE).then_some(n)
                }
                FloorKind::Plane(_) => None,
            };
            // a removed facet across the edge is no floor
            let next = next.filter(|&n| !self.is_hole(n));
            (t, next, [corners[k], corners[(k + 1) % 3]])
        })
    }
}

/// Smallest t ≥ 0 where f0 + f1 t + ½ f2 t² reaches 0 while increasing (leaving the half-plane
/// f ≤ 0); t = 0 when already on or past the line and moving out.
#[inline]
pub(crate) fn outward_root(f0: f64, f1: f64, f2: f64) -> Option<f64> {
    if f0 >= 0.0 && (f1 > 0.0 || (f1 == 0.0 && f2 > 0.0)) {
        return Some(0.0);
    }
    if f1 <= 0.0 && f2 <= 0.0 {
        // never increasing for t > 0: no outward crossing (saves the square root)
        return None;
    }
    if f2 == 0.0 {
        return (f1 > 0.0).then(|| (-f0 / f1).max(0.0));
    }
    let disc = f1 * f1 - 2.0 * f2 * f0;
    if disc < 0.0 {
        // never on the line: past it (f0 > 0) it stays past it, i.e. it is out from the start
        // (moving inwards a moment, then turned back out before reaching the line)
        return (f0 >= 0.0).then_some(0.0);
    }
    let s = disc.sqrt();
    let q = -(f1 + f1.signum() * s);
    let mut roots = [f64::NAN; 2];
    if q != 0.0 {
        roots = [q / f2, 2.0 * f0 / q];
    } else if f0 == 0.0 {
        roots = [0.0, 0.0];
    }
    roots
        .into_iter()
        .filter(|&r| r > 0.0 && f1 + f2 * r > 0.0)
        .fold(None, |acc: Option<f64>, r| {
            Some(acc.map_or(r, |b| b.min(r)))
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outward_root_of_a_point_past_the_line_turning_back_out_is_zero() {
        // a rock a rounding step past an edge, moving inwards a moment, accelerated outwards:
        // it never reaches the line again, so it has left at t = 0 (was: no exit, and the rock
        // slid on the facet's plane beyond the facet, below the floor)
        assert_eq!(outward_root(9e-17, -5.4e-9, 2.78), Some(0.0));
        assert_eq!(outward_root(1.0, -1.0, 1.0), Some(0.0));
        // past the line, coming in and out again: f = 1 − t + 0.2 t² leaves at (1 + √0.2)/0.4
        let t = outward_root(1.0, -1.0, 0.4).unwrap();
        assert!((t - (1.0 + 0.2f64.sqrt()) / 0.4).abs() < 1e-12, "{t}");
    }

    #[test]
    fn outward_root_picks_the_leaving_crossing() {
        // f = −1 + 0 t + ½·2 t²: leaves at t = 1
        assert!((outward_root(-1.0, 0.0, 2.0).unwrap() - 1.0).abs() < 1e-15);
        // moving in and decelerating back out: f = −t + ½ t² … roots 0 (entering) and 2
        assert!((outward_root(0.0, -1.0, 1.0).unwrap() - 2.0).abs() < 1e-15);
        // moving in for ever
        assert!(outward_root(-1.0, -1.0, 0.0).is_none());
    }
}
