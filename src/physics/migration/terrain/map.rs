//! Floors given in map coordinates (easting, northing, m; azimuth in degrees): the map frame,
//! the rigid transform of a grid's or contours' points into the face frame, and the mean plane
//! placed through the floor's height at the map origin.

use super::grid::GridFloor;
use super::mesh::{ContourLine, MeshFloor};
use super::{Facet, Floor, FloorKind, NONE};
use crate::physics::error::{Param, PhysicsError, PhysicsResult};

/// Placement of a floor given in map coordinates (easting E, northing N, m) on the face: the
/// face's origin is at `origin` and its x axis (down the dip) points at azimuth
/// `dip_direction_deg` (clockwise from north); y is x turned 90° anticlockwise seen from above.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapFrame {
    /// Map coordinates [E, N] of the face's origin, m.
    pub origin: [f64; 2],
    /// Azimuth of the face's down-dip x axis, degrees clockwise from north, in [0, 360).
    pub dip_direction_deg: f64,
}

impl MapFrame {
    /// Face coordinates [x, y] (m) of the map point [E, N] (m).
    #[must_use]
    pub fn to_face(&self, p: [f64; 2]) -> [f64; 2] {
        let (de, dn) = (p[0] - self.origin[0], p[1] - self.origin[1]);
        if self.dip_direction_deg == 90.0 {
            return [de, dn];
        }
        let (s, c) = self.dip_direction_deg.to_radians().sin_cos();
        [de * s + dn * c, dn * s - de * c]
    }

    /// Map coordinates [E, N] (m) of the face point [x, y] (m): the inverse of [`Self::to_face`].
    #[must_use]
    pub fn to_map(&self, p: [f64; 2]) -> [f64; 2] {
        if self.dip_direction_deg == 90.0 {
            return [p[0] + self.origin[0], p[1] + self.origin[1]];
        }
        let (s, c) = self.dip_direction_deg.to_radians().sin_cos();
        [
            p[0] * s - p[1] * c + self.origin[0],
            p[0] * c + p[1] * s + self.origin[1],
        ]
    }
}

impl GridFloor {
    /// The same triangles (ids, corners, neighbours, holes) as a mesh, its nodes moved from map
    /// coordinates relative to the map origin into the face frame.
    fn to_mesh(&self, map: &MapFrame) -> MeshFloor {
        let ny = self.cells.ncy + 1;
        let rel = MapFrame {
            origin: [0.0, 0.0],
            dip_direction_deg: map.dip_direction_deg,
        };
        let mut xyz = Vec::with_capacity(self.nx * ny);
        for i in 0..ny {
            for j in 0..self.nx {
                let p = rel.to_face([
                    self.cells.x0 + j as f64 * self.cells.d,
                    self.cells.y0 + i as f64 * self.cells.d,
                ]);
                xyz.push([p[0], p[1], self.z[i * self.nx + j]]);
            }
        }
        let n_facets = 2 * self.cells.ncx * self.cells.ncy;
        let mut tris = Vec::with_capacity(n_facets);
        let mut nbr = Vec::with_capacity(n_facets);
        for f in 0..n_facets as Facet {
            let (i, j) = self.cell_of(f);
            let id = |di: usize, dj: usize| ((i + di) * self.nx + j + dj) as u32;
            tris.push(if f & 1 == 0 {
                [id(0, 0), id(0, 1), id(1, 1)]
            } else {
                [id(0, 0), id(1, 1), id(1, 0)]
            });
            nbr.push([0, 1, 2].map(|k| self.neighbor_at(f, i, j, k).unwrap_or(NONE)));
        }
        MeshFloor::new(xyz, tris, nbr, self.holes.clone())
    }
}

impl Floor {
    /// A grid given in map coordinates (origin (E₀, N₀) of the grid, spacing, heights with NaN
    /// for nodes without data) placed in the face frame of `map`: a rigid transform of its nodes.
    /// A dip direction of exactly 90° (east) keeps it a grid; any other turns it into a
    /// triangle mesh with the same triangles. The mean plane passes through the floor's height
    /// at the map origin, where `along_dip` is 0.
    pub(crate) fn grid_in_map(
        dip: f64,
        origin: [f64; 2],
        spacing: f64,
        heights: &[Vec<f64>],
        map: &MapFrame,
    ) -> PhysicsResult<Self> {
        let rel = [origin[0] - map.origin[0], origin[1] - map.origin[1]];
        let mut floor = Floor::grid(dip, rel, spacing, heights)?;
        if map.dip_direction_deg != 90.0 {
            let FloorKind::Grid(g) = &floor.kind else {
                unreachable!("Floor::grid builds a grid")
            };
            floor.kind = FloorKind::Mesh(g.to_mesh(map));
        }
        floor.place_mean_at_origin()?;
        Ok(floor)
    }

    /// Contours given in map coordinates placed in the face frame of `map` (a rigid transform
    /// of their points, then [`Floor::contours`]); the mean plane passes through the floor's
    /// height at the map origin.
    pub(crate) fn contours_in_map(
        dip: f64,
        lines: &[ContourLine],
        resolution: f64,
        map: &MapFrame,
    ) -> PhysicsResult<Self> {
        let moved: Vec<ContourLine> = lines
            .iter()
            .map(|l| ContourLine {
                elevation: l.elevation,
                points: l.points.iter().map(|p| map.to_face(*p)).collect(),
            })
            .collect();
        let mut floor = Floor::contours(dip, &moved, resolution)?;
        floor.place_mean_at_origin()?;
        Ok(floor)
    }

    /// Puts `along_dip` = 0 at (0, 0), the mean plane through the floor's height there.
    fn place_mean_at_origin(&mut self) -> PhysicsResult<()> {
        let z = self.height_at(0.0, 0.0).ok_or_else(|| {
            PhysicsError::invalid(
                Param::FloorMapOrigin,
                0.0,
                "the map origin is not on the floor (outside it or over a hole): the along-dip \
                 distance is measured from the floor's height there",
            )
        })?;
        self.mean.x0 = 0.0;
        self.mean.z_ref = z;
        Ok(())
    }
}
