//! Floors of the face: the analytic plane, a regular height grid and a Delaunay-triangulated
//! contour set, with the queries the energy tracking method needs.
//!
//! Every floor is a height field z = h(x, y) made of planar facets (the plane is one facet). The
//! horizontal projection of a free-flight parabola is a straight line, so a flight's first hit is
//! found by walking the cells of a uniform grid along that line (cost ∝ path length, not floor
//! size) and, in each cell, taking the descending root of the quadratic height above each
//! candidate facet. A slide on one facet has constant acceleration, so its exit through an edge is
//! the smallest outward root of a quadratic per edge.
//!
//! References: physics.md §C.2 ("On a triangulated floor …"), api.md `POST /v1/migration` (floors).
//!
//! Files: `facet.rs` (a facet's plane and the point-in-triangle test), `walk.rs` (the cell
//! walk along a straight plan-view path), `grid.rs` (the regular height grid and its holes),
//! `patches.rs` (the grid's coplanar patches), `mesh.rs` (the triangulated floor and contours),
//! `map.rs` (floors given in map coordinates), `locate.rs` (point queries), `flight.rs` (the
//! first strike of a flight), `slide.rs` (a slide's exit from a facet), `triangles.rs` (the
//! triangles under a box, for block contacts), `zones.rs` (floors of several materials: the
//! material under a point and the boundaries a slide piece is cut at); this file holds [`Floor`], its kinds, its mean
//! plane and the accessors common to all kinds.

mod facet;
mod flight;
mod grid;
mod locate;
mod map;
mod mesh;
mod patches;
mod slide;
mod triangles;
mod walk;
mod zones;

use nalgebra::Vector3;

pub(crate) use self::facet::{FacetPlane, inside_tri};
pub(crate) use self::flight::{FlightEnd, plane_flight, start_rounding};
use self::grid::GridFloor;
pub use self::grid::{GRID_BYTES_PER_POINT, grid_bytes};
pub use self::map::MapFrame;
use self::mesh::MeshFloor;
pub use self::mesh::{CONTOUR_BYTES_PER_POINT, ContourLine, contour_points};
pub(crate) use self::slide::outward_root;
pub(crate) use self::triangles::FloorTriangle;
pub use self::zones::{
    BlockContact, MAX_CODE_CELLS, MAX_MATERIALS, MAX_POLYGON_VERTICES, MAX_POLYGONS, Material,
    ZonePolygon, ZoneShape, Zones, ZonesSpec, self_intersection,
};
pub(crate) use self::zones::{RunZones, per_run_values};

/// Identifier of one planar facet of a floor (the plane floor has the single facet 0).
pub(crate) type Facet = u32;

/// Largest number of facets whose planes a floor keeps precomputed (64 bytes each); larger
/// floors set each plane up when it is needed.
const MAX_TABLED_FACETS: usize = 1 << 20;

/// The face's mean plane (dip θ) used for `along_dip_m` and the potential-energy zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct MeanPlane {
    /// x of the upper end, m.
    pub(crate) x0: f64,
    /// Height of the mean plane at x₀, m.
    pub(crate) z_ref: f64,
    /// cos θ.
    pub(crate) cos: f64,
    /// sin θ.
    pub(crate) sin: f64,
}

impl MeanPlane {
    /// Distance along dip of the foot of the perpendicular from p to the mean plane, m.
    pub(crate) fn along(&self, p: &Vector3<f64>) -> f64 {
        (p.x - self.x0) * self.cos - (p.z - self.z_ref) * self.sin
    }

    /// Unit down-dip vector of the mean plane.
    pub(crate) fn dip_dir(&self) -> Vector3<f64> {
        Vector3::new(self.cos, 0.0, -self.sin)
    }

    /// Unit outward normal of the mean plane.
    pub(crate) fn normal(&self) -> Vector3<f64> {
        Vector3::new(self.sin, 0.0, self.cos)
    }

    /// Height of the mean plane where `along_dip` = s, m.
    pub(crate) fn z_at(&self, s: f64) -> f64 {
        self.z_ref - s * self.sin
    }
}

const NONE: u32 = u32::MAX;

/// A floor of the face.
#[derive(Debug, Clone)]
pub(crate) enum FloorKind {
    /// The plane z = −x tan θ.
    Plane(FacetPlane),
    /// A regular height grid.
    Grid(GridFloor),
    /// Delaunay-triangulated contours.
    Mesh(MeshFloor),
}

/// A floor with its mean plane.
#[derive(Debug, Clone)]
pub(crate) struct Floor {
    /// The facets.
    pub(crate) kind: FloorKind,
    /// Mean plane for `along_dip_m` and the energy zero.
    pub(crate) mean: MeanPlane,
}

impl Floor {
    /// The plane z = −x tan θ.
    pub(crate) fn plane(dip: f64) -> Self {
        let (sin, cos) = dip.sin_cos();
        Floor {
            kind: FloorKind::Plane(FacetPlane::new(0.0, 0.0, 0.0, -sin / cos, 0.0)),
            mean: MeanPlane {
                x0: 0.0,
                z_ref: 0.0,
                cos,
                sin,
            },
        }
    }

    /// The facet's plane.
    #[inline(always)]
    pub(crate) fn facet_plane(&self, f: Facet) -> FacetPlane {
        match &self.kind {
            FloorKind::Plane(p) => *p,
            FloorKind::Grid(g) => g.plane(f),
            FloorKind::Mesh(m) => m.plane(f),
        }
    }

    /// True for the plane, a floor of one facet: the floor's surface at any point is that
    /// facet's plane.
    #[inline]
    pub(crate) fn is_single_facet(&self) -> bool {
        matches!(self.kind, FloorKind::Plane(_))
    }

    /// The face x, m, of the floor point at across position `y` whose foot on the mean plane
    /// lies `along` m down the dip (for a rock at rest, the plan point where it lies): on the
    /// plane the mean plane's own point x₀ + along cos θ; on a grid
    /// or mesh the root of along(x, y, z_floor(x, y)) = along, by bisection over the floor's
    /// extent (over a hole, and outside the extent, the mean plane's own point stands in).
    #[must_use]
    pub(crate) fn plan_x(&self, along: f64, y: f64) -> f64 {
        let m = self.mean;
        let on_mean = m.x0 + along * m.cos;
        if matches!(self.kind, FloorKind::Plane(_)) {
            return on_mean;
        }
        let ext = self.extent();
        let along_at = |x: f64| {
            self.locate(x, y, 0.0, 0.0).map_or_else(
                || along - (on_mean - x) * m.cos,
                |f| m.along(&Vector3::new(x, y, self.facet_plane(f).z(x, y))),
            )
        };
        let (mut lo, mut hi) = (ext[0], ext[1]);
        if along_at(lo) >= along {
            return lo.min(on_mean);
        }
        if along_at(hi) <= along {
            return hi.max(on_mean);
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if along_at(mid) < along {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// Plan extent [x_min, x_max, y_min, y_max] (infinite for the plane), m.
    pub(crate) fn extent(&self) -> [f64; 4] {
        match &self.kind {
            FloorKind::Plane(_) => [
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
            ],
            FloorKind::Grid(GridFloor { cells, .. }) => {
                [cells.x0, cells.x_max(), cells.y0, cells.y_max()]
            }
            FloorKind::Mesh(m) => m.bbox,
        }
    }

    /// Plan corners [x, y] (m, counter-clockwise) and heights z (m) of facet f; None for the
    /// plane, which has no corners.
    pub(crate) fn facet_corners(&self, f: Facet) -> Option<([[f64; 2]; 3], [f64; 3])> {
        match &self.kind {
            FloorKind::Plane(_) => None,
            FloorKind::Grid(g) => Some(g.corners(f)),
            FloorKind::Mesh(m) => Some(m.corners(f)),
        }
    }

    /// Length scale of the floor's facets (grid spacing or bucket cell), m; 1 for the plane.
    pub(crate) fn cell_size(&self) -> f64 {
        match &self.kind {
            FloorKind::Plane(_) => 1.0,
            FloorKind::Grid(g) => g.cells.d,
            FloorKind::Mesh(m) => m.cells.d,
        }
    }
}
