//! The cell walk: a uniform grid of square cells over a plan rectangle (origin and cell size
//! in m), the cell holding a point and the cells a straight horizontal path crosses, in order,
//! with the time window (s) it spends in each. Both floors with facets use it, the grid for its
//! own cells and the triangle mesh for its buckets.

use super::{Facet, FlightEnd};

/// A cell index or count as f64, exact (below 2⁵³): through i64, one cvtsi2sd on x86-64,
/// where a usize takes the unsigned conversion's longer sequence.
#[inline(always)]
#[allow(clippy::cast_possible_wrap, clippy::cast_precision_loss)]
pub(super) fn fl(k: usize) -> f64 {
    k as i64 as f64
}

/// Uniform cell grid over a rectangle, used to walk a straight horizontal line cell by cell.
#[derive(Debug, Clone, Copy)]
pub(super) struct CellGrid {
    pub(super) x0: f64,
    pub(super) y0: f64,
    pub(super) d: f64,
    pub(super) ncx: usize,
    pub(super) ncy: usize,
}

impl CellGrid {
    pub(super) fn x_max(&self) -> f64 {
        self.x0 + self.ncx as f64 * self.d
    }
    pub(super) fn y_max(&self) -> f64 {
        self.y0 + self.ncy as f64 * self.d
    }

    /// Cell index along one axis for coordinate u (in cells) moving with rate r, or None outside.
    #[inline]
    pub(super) fn axis_cell(u: f64, r: f64, n: usize) -> Option<usize> {
        // points a rounding error outside the extent count as on its boundary
        let u = if u < 0.0 && u > -1e-9 {
            0.0
        } else if u > fl(n) && u < fl(n) + 1e-9 {
            fl(n)
        } else {
            u
        };
        if !(u >= 0.0 && u <= fl(n)) {
            return None;
        }
        // u ≥ 0 here, so truncation is the floor (and avoids a libm call on baseline x86-64);
        // one conversion, through i64 (a single cvttsd2si; u ≤ n < 2⁶³ is exact)
        let mut c = u as i64 as usize;
        if fl(c) == u && r < 0.0 {
            // on a cell boundary moving back: the cell before it (none before the first)
            c = c.checked_sub(1)?;
        }
        if c >= n {
            // on the far boundary: inside only when moving back in (or not moving)
            if r > 0.0 {
                return None;
            }
            c = n - 1;
        }
        Some(c)
    }

    /// The cell (ci, cj) and those of its neighbours whose shared boundary (edge or corner) the
    /// straight path (x, y) + (vx, vy) t over [t0, t1] comes within `tol` of, m: a path running
    /// along a grid line is in both cells at once as far as rounding can tell, and the instant it
    /// crosses the line is then ill-conditioned, so both cells' facets are candidates. Returned
    /// as the offsets along x and along y (the cell itself first, then −1, then +1); the cells
    /// are visited row by row, (ci + ox, cj + oy) for oy in the y offsets, ox in the x offsets.
    #[inline]
    pub(super) fn near_cells(
        &self,
        ci: usize,
        cj: usize,
        (x, y, vx, vy): (f64, f64, f64, f64),
        t0: f64,
        t1: f64,
        tol: f64,
    ) -> (&'static [isize], &'static [isize]) {
        let span = |u: f64, r: f64| {
            let (a, b) = (u + r * t0, u + r * t1.min(1e300));
            (a.min(b), a.max(b))
        };
        let (xa, xb) = span(x, vx);
        let (ya, yb) = span(y, vy);
        let lo_x = self.x0 + fl(ci) * self.d;
        let lo_y = self.y0 + fl(cj) * self.d;
        let dx: &'static [isize] = match (
            ci > 0 && xa <= lo_x + tol,
            ci + 1 < self.ncx && xb >= lo_x + self.d - tol,
        ) {
            (true, true) => &[0, -1, 1],
            (true, false) => &[0, -1],
            (false, true) => &[0, 1],
            _ => &[0],
        };
        let dy: &'static [isize] = match (
            cj > 0 && ya <= lo_y + tol,
            cj + 1 < self.ncy && yb >= lo_y + self.d - tol,
        ) {
            (true, true) => &[0, -1, 1],
            (true, false) => &[0, -1],
            (false, true) => &[0, 1],
            _ => &[0],
        };
        (dx, dy)
    }

    /// Walks the cells crossed by (x, y) + (vx, vy) t for t in [0, t_max]; `visit(ci, cj, t0, t1)`
    /// returns a hit inside the cell's time window or None to go on.
    pub(super) fn walk(
        &self,
        x: f64,
        y: f64,
        vx: f64,
        vy: f64,
        t_max: f64,
        mut visit: impl FnMut(usize, usize, f64, f64) -> Option<(f64, Facet)>,
    ) -> FlightEnd {
        let ux = (x - self.x0) / self.d;
        let uy = (y - self.y0) / self.d;
        let rx = vx / self.d;
        let ry = vy / self.d;
        let (Some(mut ci), Some(mut cj)) = (
            Self::axis_cell(ux, rx, self.ncx),
            Self::axis_cell(uy, ry, self.ncy),
        ) else {
            return FlightEnd::Leaves { t: 0.0 };
        };
        let mut t0 = 0.0_f64;
        loop {
            let tx = if rx > 0.0 {
                (fl(ci + 1) - ux) / rx
            } else if rx < 0.0 {
                (fl(ci) - ux) / rx
            } else {
                f64::INFINITY
            };
            let ty = if ry > 0.0 {
                (fl(cj + 1) - uy) / ry
            } else if ry < 0.0 {
                (fl(cj) - uy) / ry
            } else {
                f64::INFINITY
            };
            let t1 = tx.min(ty).max(t0);
            if let Some((t, f)) = visit(ci, cj, t0, t1.min(t_max)) {
                return FlightEnd::Hit { t, facet: f };
            }
            if t1 >= t_max {
                return FlightEnd::Clear;
            }
            // step to the next cell (both axes when the line passes a corner)
            if tx <= ty {
                if rx > 0.0 {
                    ci += 1;
                    if ci >= self.ncx {
                        return FlightEnd::Leaves { t: t1 };
                    }
                } else {
                    if ci == 0 {
                        return FlightEnd::Leaves { t: t1 };
                    }
                    ci -= 1;
                }
            }
            if ty <= tx {
                if ry > 0.0 {
                    cj += 1;
                    if cj >= self.ncy {
                        return FlightEnd::Leaves { t: t1 };
                    }
                } else {
                    if cj == 0 {
                        return FlightEnd::Leaves { t: t1 };
                    }
                    cj -= 1;
                }
            }
            t0 = t1;
        }
    }
}
