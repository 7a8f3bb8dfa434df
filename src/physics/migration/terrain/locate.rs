//! Point queries on a floor, positions in m: the facet under a point (holes excepted or not),
//! the floor's height there, the highest plane near it, and the level off the floor (over a
//! hole or beyond a grid's extent).

use super::facet::inside_tri;
use super::grid::GridFloor;
use super::walk::{CellGrid, fl};
use super::{Facet, Floor, FloorKind};

impl Floor {
    /// Height of the floor under (x, y), m, or None off the floor.
    #[inline]
    pub(crate) fn height_at(&self, x: f64, y: f64) -> Option<f64> {
        match &self.kind {
            FloorKind::Plane(p) => return Some(p.z(x, y)),
            // the grid's facet under (x, y) as `locate` finds it, in one pass
            FloorKind::Grid(g) => {
                let f = Self::grid_facet(g, x, y, 0.0, 0.0)?;
                return (!g.holes.get(f as usize).copied().unwrap_or(false))
                    .then(|| g.plane_z(f, x, y));
            }
            FloorKind::Mesh(_) => {}
        }
        self.locate(x, y, 0.0, 0.0)
            .map(|f| self.facet_plane(f).z(x, y))
    }

    /// Highest plane, m, at (x, y) among the facets (holes excepted) whose closed triangle comes
    /// within `tol` m of it in plan; None when there is none. At a node or on an edge this is
    /// the highest of the planes meeting there: a point at that height is on or above every
    /// facet a flight from it can strike, so none is missed from underneath.
    #[inline]
    pub(crate) fn top_height_near(&self, x: f64, y: f64, tol: f64) -> Option<f64> {
        match &self.kind {
            FloorKind::Plane(p) => Some(p.z(x, y)),
            _ => self.top_height_near_facets(x, y, tol),
        }
    }

    /// [`Floor::top_height_near`] on a floor of several facets (a grid or a mesh).
    fn top_height_near_facets(&self, x: f64, y: f64, tol: f64) -> Option<f64> {
        let mut top: Option<f64> = None;
        let mut take = |f: Facet, c: &[[f64; 2]; 3]| {
            if !self.is_hole(f) && inside_tri(c, x, y, tol) {
                let z = self.facet_plane(f).z(x, y);
                top = Some(top.map_or(z, |t: f64| t.max(z)));
            }
        };
        match &self.kind {
            FloorKind::Plane(p) => return Some(p.z(x, y)),
            FloorKind::Grid(g) => return g.top_height_near(x, y, tol),
            FloorKind::Mesh(m) => {
                let c = &m.cells;
                let ci = CellGrid::axis_cell((x - c.x0) / c.d, 0.0, c.ncx)?;
                let cj = CellGrid::axis_cell((y - c.y0) / c.d, 0.0, c.ncy)?;
                for &f in m.bucket(ci, cj) {
                    take(f, &m.corners(f).0);
                }
            }
        }
        top
    }

    /// Whether facet f was removed (a corner without data): not part of the floor.
    #[inline]
    pub(crate) fn is_hole(&self, f: Facet) -> bool {
        let holes = match &self.kind {
            FloorKind::Plane(_) => return false,
            FloorKind::Grid(g) => &g.holes,
            FloorKind::Mesh(m) => &m.holes,
        };
        holes.get(f as usize).copied().unwrap_or(false)
    }

    /// The facet under (x, y), preferring the one the direction (dx, dy) moves into; None off
    /// the floor or over a hole.
    #[inline]
    pub(crate) fn locate(&self, x: f64, y: f64, dx: f64, dy: f64) -> Option<Facet> {
        self.locate_any(x, y, dx, dy).filter(|&f| !self.is_hole(f))
    }

    /// The facet (hole or not) under (x, y), preferring the one (dx, dy) moves into.
    fn locate_any(&self, x: f64, y: f64, dx: f64, dy: f64) -> Option<Facet> {
        match &self.kind {
            FloorKind::Plane(_) => Some(0),
            FloorKind::Grid(g) => Self::grid_facet(g, x, y, dx, dy),
            FloorKind::Mesh(m) => {
                let c = &m.cells;
                let ci = CellGrid::axis_cell((x - c.x0) / c.d, dx, c.ncx)?;
                let cj = CellGrid::axis_cell((y - c.y0) / c.d, dy, c.ncy)?;
                let eps = 1e-9 * c.d;
                let n = (dx * dx + dy * dy).sqrt();
                let (qx, qy) = if n > 0.0 {
                    (x + eps * dx / n, y + eps * dy / n)
                } else {
                    (x, y)
                };
                let cand = m.bucket(ci, cj);
                for tol in [0.0, 1e-9 * c.d] {
                    for &f in cand {
                        if inside_tri(&m.corners(f).0, qx, qy, tol) {
                            return Some(f);
                        }
                    }
                }
                for &f in cand {
                    if inside_tri(&m.corners(f).0, x, y, 1e-9 * c.d) {
                        return Some(f);
                    }
                }
                None
            }
        }
    }

    /// The grid's facet (hole or not) under (x, y), preferring the one (dx, dy) moves into.
    #[inline]
    fn grid_facet(g: &GridFloor, x: f64, y: f64, dx: f64, dy: f64) -> Option<Facet> {
        let c = &g.cells;
        let ux = (x - c.x0) / c.d;
        let uy = (y - c.y0) / c.d;
        let ci = CellGrid::axis_cell(ux, dx, c.ncx)?;
        let cj = CellGrid::axis_cell(uy, dy, c.ncy)?;
        let (fx, fy) = (ux - fl(ci), uy - fl(cj));
        let half = if fx > fy || (fx == fy && dx > dy) {
            0
        } else {
            1
        };
        Some(g.facet(ci, cj, half))
    }

    /// Height (m) of the floor's level at a point (x, y) off the floor: over a hole, its facet's
    /// height filled in from the data around it (the surface a flight lands in the hole on);
    /// beyond a grid's extent, the plane of the facet at the nearest point of the extent,
    /// continued; None on the floor, and beyond a contour floor's extent.
    pub(crate) fn level_off_floor(&self, x: f64, y: f64) -> Option<f64> {
        if self.locate(x, y, 0.0, 0.0).is_some() {
            return None;
        }
        if let Some(f) = self.locate_any(x, y, 0.0, 0.0) {
            return Some(self.facet_plane(f).z(x, y));
        }
        let FloorKind::Grid(g) = &self.kind else {
            return None;
        };
        let c = &g.cells;
        let (xc, yc) = (x.clamp(c.x0, c.x_max()), y.clamp(c.y0, c.y_max()));
        let f = self.locate_any(xc, yc, 0.0, 0.0)?;
        Some(self.facet_plane(f).z(x, y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_top_plane_near_a_valley_line_is_the_floor_beside_it() {
        // a V-shaped valley along x = 1: z = 1 − x, then z = x − 1
        let h = vec![vec![1.0, 0.0, 1.0]; 3];
        let f = Floor::grid(0.5, [0.0, 0.0], 1.0, &h).unwrap();
        // 1e-10 m past the valley line: the floor there is the rising facet's plane (+1e-10);
        // the facet left behind, extended, is 1e-10 below it
        let top = f.top_height_near(1.0 + 1e-10, 0.5, 2e-9).unwrap();
        assert!((top - 1e-10).abs() < 1e-16, "{top}");
        assert_eq!(f.height_at(1.0 + 1e-10, 0.5), Some(top));
        // away from every edge only the facet's own plane counts
        assert_eq!(f.top_height_near(0.5, 0.25, 2e-9), Some(0.5));
        // off the floor: none
        assert_eq!(f.top_height_near(-1.0, 0.5, 2e-9), None);
    }
}
