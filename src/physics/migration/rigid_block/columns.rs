//! The column supports a run can reach, indexed by their along-dip position: a piece of motion
//! (a step's drift, a flight, a skipped settled slide) tests only the columns standing within
//! reach of the along-dip interval it sweeps, so the columns far from the block cost a binary
//! search, not a test each.

use super::super::terrain::MeanPlane;
use super::super::{SupportStop, first_column_reach};
use nalgebra::Vector3;

/// The column supports of a scene (those with an across position), sorted by along-dip position.
#[derive(Debug, Clone, Default)]
pub(super) struct Columns {
    /// Index into the supports of each column, in along-dip order (ties in index order).
    order: Vec<usize>,
    /// Along-dip position of each column of `order`, m (ascending).
    along: Vec<f64>,
    /// Largest reach of a column, m.
    reach_max: f64,
}

/// A piece of the centre's path, p + v τ + ½ a τ² for τ in [0, `dt`] (s, or any parameter
/// the velocity and acceleration are per): where [`Columns::first_reach`] looks for a column.
#[derive(Debug, Clone, Copy)]
pub(super) struct Piece<'a> {
    /// Position at τ = 0, m.
    pub(super) p: &'a Vector3<f64>,
    /// Velocity, m per unit of τ.
    pub(super) v: &'a Vector3<f64>,
    /// Acceleration, m per unit of τ².
    pub(super) a: &'a Vector3<f64>,
    /// End of the piece, in units of τ.
    pub(super) dt: f64,
}

impl<'a> Piece<'a> {
    /// The piece p + v τ + ½ a τ², τ in [0, `dt`].
    pub(super) fn new(
        p: &'a Vector3<f64>,
        v: &'a Vector3<f64>,
        a: &'a Vector3<f64>,
        dt: f64,
    ) -> Self {
        Self { p, v, a, dt }
    }
}

/// How far along the dip (m, beyond the largest reach) [`Columns::clearance`] looks for the
/// nearest column: the most a clearance can be.
const CLEARANCE_SEARCH_M: f64 = 3.0;

/// Candidates in index order that fit on the stack (a window of more is sorted on the heap).
const STACK_CANDIDATES: usize = 16;

impl Columns {
    /// The index of the columns among `supports` (spanning supports are left out: the run's
    /// length ends at them).
    pub(super) fn new(supports: &[SupportStop]) -> Self {
        let mut order: Vec<usize> = (0..supports.len())
            .filter(|&k| supports[k].across.is_some())
            .collect();
        order.sort_by(|&a, &b| {
            supports[a]
                .along_dip
                .total_cmp(&supports[b].along_dip)
                .then(a.cmp(&b))
        });
        let along = order.iter().map(|&k| supports[k].along_dip).collect();
        let reach_max = order.iter().map(|&k| supports[k].reach).fold(0.0, f64::max);
        Self {
            order,
            along,
            reach_max,
        }
    }

    /// True when the scene has no column.
    pub(super) fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// The distance (m) from the point (along-dip `u`, across `y`) of the mean plane to the
    /// nearest column's reach, less a rounding margin, at most [`CLEARANCE_SEARCH_M`]; None
    /// when not positive. Only the columns within that search distance of `u` along the dip
    /// (and the largest reach) are measured: any other is farther.
    pub(super) fn clearance(&self, supports: &[SupportStop], u: f64, y: f64) -> Option<f64> {
        let w = CLEARANCE_SEARCH_M + self.reach_max;
        let lo = self.along.partition_point(|&s| s < u - w);
        let hi = self.along.partition_point(|&s| s <= u + w);
        let mut d = CLEARANCE_SEARCH_M;
        for &k in &self.order[lo..hi] {
            let s = &supports[k];
            let yc = s.across.unwrap_or(y);
            d = d.min((u - s.along_dip).hypot(y - yc) - s.reach);
        }
        let d = d - 1e-9 * (1.0 + u.abs() + y.abs() + self.reach_max);
        (d > 0.0).then_some(d)
    }

    /// The first column reached by the centre's piece p + v τ + ½ a τ², τ in [0, `dt`] (s or
    /// any parameter), each column's reach widened by `margin` (m): its τ and its index into
    /// `supports`. The same answer, bit for bit, as [`first_column_reach`] over every support
    /// (with `margin` 0): the columns are tested in index order with the horizon shrinking to
    /// the earliest reach found, but only those whose along-dip position lies within the reach
    /// of the along-dip interval the piece sweeps (|Δs| ≤ |v·d| τ + ½|a·d| τ², padded); the
    /// others are the ones that function rejects before solving.
    pub(super) fn first_reach(
        &self,
        mean: &MeanPlane,
        supports: &[SupportStop],
        piece: Piece<'_>,
        margin: f64,
    ) -> Option<(f64, usize)> {
        let Piece { p, v, a, dt } = piece;
        if self.order.is_empty() || dt.is_nan() || dt <= 0.0 {
            return None;
        }
        let dip = mean.dip_dir();
        let u0 = mean.along(p);
        let sweep = v.dot(&dip).abs() * dt + 0.5 * a.dot(&dip).abs() * dt * dt;
        let pad = sweep + self.reach_max + margin + 1e-6 * (1.0 + u0.abs() + sweep);
        let lo = self.along.partition_point(|&s| s < u0 - pad);
        let hi = self.along.partition_point(|&s| s <= u0 + pad);
        if lo >= hi {
            return None;
        }
        let window = &self.order[lo..hi];
        let mut stack = [0usize; STACK_CANDIDATES];
        let mut heap = Vec::new();
        let ks: &mut [usize] = if window.len() <= STACK_CANDIDATES {
            let s = &mut stack[..window.len()];
            s.copy_from_slice(window);
            s
        } else {
            heap.extend_from_slice(window);
            &mut heap
        };
        ks.sort_unstable();
        let mut best: Option<(f64, usize)> = None;
        for &k in ks.iter() {
            let horizon = best.map_or(dt, |b| b.0);
            let s = SupportStop {
                reach: supports[k].reach + margin,
                ..supports[k]
            };
            if let Some((t, _)) =
                first_column_reach(mean, std::slice::from_ref(&s), p, v, a, horizon)
                && best.is_none_or(|b| t < b.0)
            {
                best = Some((t, k));
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    //! The index gives the answer of the test of every support, bit for bit.
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn indexed_reach_is_the_full_test_bit_for_bit() {
        let th = 45f64.to_radians();
        let mean = MeanPlane {
            x0: 0.0,
            z_ref: 0.0,
            cos: th.cos(),
            sin: th.sin(),
        };
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        // the paper's rows (62 columns 1.5 m apart), a spanning support and two columns at
        // one position, in a shuffled order
        let mut supports: Vec<SupportStop> = (0..62)
            .map(|k| SupportStop {
                along_dip: 118.5 - 1.5 * f64::from(k),
                across: Some(0.9),
                reach: 0.55,
            })
            .collect();
        supports.push(SupportStop {
            along_dip: 60.0,
            across: None,
            reach: 0.55,
        });
        supports.push(SupportStop {
            along_dip: 60.0,
            across: Some(-0.9),
            reach: 0.7,
        });
        supports.swap(3, 40);
        supports.swap(10, 63);
        let cols = Columns::new(&supports);
        let (mut hits, mut checked) = (0, 0);
        for _ in 0..20_000 {
            let s: f64 = rng.random_range(20.0..125.0);
            let y: f64 = rng.random_range(-2.0..2.0);
            let h: f64 = rng.random_range(0.0..1.0);
            let p = mean.dip_dir() * s + Vector3::new(0.0, y, 0.0) + mean.normal() * h;
            let scale = if rng.random_bool(0.5) { 0.05 } else { 10.0 };
            let v = Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ) * scale;
            let a = if rng.random_bool(0.5) {
                Vector3::zeros()
            } else {
                Vector3::new(0.0, 0.0, -9.81)
            };
            let dt = if rng.random_bool(0.5) {
                1e-4
            } else {
                rng.random_range(0.0..3.0)
            };
            let full = first_column_reach(&mean, &supports, &p, &v, &a, dt);
            let indexed = cols.first_reach(&mean, &supports, Piece::new(&p, &v, &a, dt), 0.0);
            assert_eq!(
                full.map(|(t, k)| (t.to_bits(), k)),
                indexed.map(|(t, k)| (t.to_bits(), k)),
                "p {p:?} v {v:?} a {a:?} dt {dt}"
            );
            hits += usize::from(full.is_some());
            checked += 1;
        }
        // both outcomes are exercised
        assert!(hits > 1000 && checked - hits > 1000, "{hits} of {checked}");
        // the clearance: no column's reach nearer, and the nearest one that near
        let mut clear = 0;
        for _ in 0..20_000 {
            let u: f64 = rng.random_range(0.0..140.0);
            let y: f64 = rng.random_range(-3.0..3.0);
            let nearest = supports
                .iter()
                .filter_map(|s| s.across.map(|yc| (u - s.along_dip).hypot(y - yc) - s.reach))
                .fold(f64::INFINITY, f64::min);
            match cols.clearance(&supports, u, y) {
                Some(d) => {
                    clear += 1;
                    assert!(d > 0.0 && d < nearest, "u {u} y {y}: {d} against {nearest}");
                    assert!(
                        d > nearest.min(CLEARANCE_SEARCH_M) - 1e-6,
                        "u {u} y {y}: {d} against {nearest}"
                    );
                }
                None => assert!(nearest < 1e-6, "u {u} y {y}: none against {nearest}"),
            }
        }
        assert!(clear > 10_000, "{clear}");
    }
}
