//! The floor's triangles under a plan box (corners in m, floor-wide vertex ids), for the
//! contacts of a rigid block.

use nalgebra::Vector3;

use super::walk::CellGrid;
use super::{Facet, Floor, FloorKind};

/// A floor triangle with its vertex ids (unique per floor) and corners, for block contacts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FloorTriangle {
    /// The facet.
    pub(crate) facet: Facet,
    /// Floor-wide ids of the three corners.
    pub(crate) ids: [u32; 3],
    /// Corners [x, y, z], m, counter-clockwise seen from above.
    pub(crate) corners: [Vector3<f64>; 3],
}

impl Floor {
    /// Appends to `out` the triangles whose plan bounding boxes may overlap the plan box
    /// [x_min, x_max, y_min, y_max] (each once; nothing for the plane).
    pub(crate) fn triangles_in(&self, b: [f64; 4], out: &mut Vec<FloorTriangle>) {
        let range = |c: &CellGrid, lo: f64, hi: f64, d0: f64, n: usize| -> Option<(usize, usize)> {
            let a = ((lo - d0) / c.d).floor();
            let z = ((hi - d0) / c.d).floor();
            if z < 0.0 || a >= n as f64 {
                return None;
            }
            Some((a.max(0.0) as usize, (z as usize).min(n - 1)))
        };
        match &self.kind {
            FloorKind::Plane(_) => {}
            FloorKind::Grid(g) => {
                let c = &g.cells;
                let (Some((j0, j1)), Some((i0, i1))) = (
                    range(c, b[0], b[1], c.x0, c.ncx),
                    range(c, b[2], b[3], c.y0, c.ncy),
                ) else {
                    return;
                };
                for i in i0..=i1 {
                    for j in j0..=j1 {
                        for half in 0..2 {
                            let f = g.facet(j, i, half);
                            if g.holes.get(f as usize).copied().unwrap_or(false) {
                                continue;
                            }
                            let (cs, zs) = g.corners_at(f, i, j);
                            let id = |di: usize, dj: usize| ((i + di) * g.nx + j + dj) as u32;
                            let ids = if half == 0 {
                                [id(0, 0), id(0, 1), id(1, 1)]
                            } else {
                                [id(0, 0), id(1, 1), id(1, 0)]
                            };
                            out.push(FloorTriangle {
                                facet: f,
                                ids,
                                corners: [0, 1, 2].map(|k| Vector3::new(cs[k][0], cs[k][1], zs[k])),
                            });
                        }
                    }
                }
            }
            FloorKind::Mesh(m) => {
                let c = &m.cells;
                let (Some((j0, j1)), Some((i0, i1))) = (
                    range(c, b[0], b[1], c.x0, c.ncx),
                    range(c, b[2], b[3], c.y0, c.ncy),
                ) else {
                    return;
                };
                let start = out.len();
                for i in i0..=i1 {
                    for j in j0..=j1 {
                        for &f in m.bucket(j, i) {
                            if m.holes.get(f as usize).copied().unwrap_or(false) {
                                continue;
                            }
                            let t = m.tris[f as usize];
                            out.push(FloorTriangle {
                                facet: f,
                                ids: t,
                                corners: t.map(|k| {
                                    let q = m.xyz[k as usize];
                                    Vector3::new(q[0], q[1], q[2])
                                }),
                            });
                        }
                    }
                }
                out[start..].sort_by_key(|t| t.facet);
                let mut tail = out.split_off(start);
                tail.dedup_by_key(|t| t.facet);
                out.extend(tail);
            }
        }
    }
}
