//! A planar facet of a floor: its plane z = z_r + b_x (x − x_r) + b_y (y − y_r) (heights in m,
//! slopes dimensionless) with its unit normal, the plane through three corners and the
//! point-in-triangle test in plan (m).

use nalgebra::Vector3;

/// A planar facet z = z_r + b_x (x − x_r) + b_y (y − y_r), heights in m, with its unit normal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FacetPlane {
    xr: f64,
    yr: f64,
    zr: f64,
    pub(super) bx: f64,
    pub(super) by: f64,
    n: Vector3<f64>,
}

impl FacetPlane {
    pub(super) fn new(xr: f64, yr: f64, zr: f64, bx: f64, by: f64) -> Self {
        let k = 1.0 / (1.0 + bx * bx + by * by).sqrt();
        FacetPlane {
            xr,
            yr,
            zr,
            bx,
            by,
            n: Vector3::new(-bx * k, -by * k, k),
        }
    }

    /// Height of the facet's plane at (x, y), m.
    #[inline]
    pub(crate) fn z(&self, x: f64, y: f64) -> f64 {
        self.zr + self.bx * (x - self.xr) + self.by * (y - self.yr)
    }

    /// Unit normal pointing up (n_z > 0).
    pub(crate) fn normal(&self) -> Vector3<f64> {
        self.n
    }

    /// Vertical height of p above the plane, m.
    #[inline]
    pub(crate) fn height(&self, p: &Vector3<f64>) -> f64 {
        p.z - self.z(p.x, p.y)
    }

    /// Rate of change of the vertical height for velocity v, m/s.
    #[inline]
    pub(crate) fn height_rate(&self, v: &Vector3<f64>) -> f64 {
        v.z - self.bx * v.x - self.by * v.y
    }

    /// Unit vector in the plane whose horizontal part points along +x (the local down-dip).
    pub(crate) fn down_dip(&self) -> Vector3<f64> {
        Vector3::new(1.0, 0.0, self.bx).normalize()
    }
}

/// Whether (x, y) lies in the counter-clockwise plan triangle `c` or within `tol` of it, m.
#[inline]
pub(crate) fn inside_tri(c: &[[f64; 2]; 3], x: f64, y: f64, tol: f64) -> bool {
    (0..3).all(|k| {
        let a = c[k];
        let b = c[(k + 1) % 3];
        let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
        // axis-parallel edges (every edge of a grid cell but its diagonal) need no square root
        let len = if ey == 0.0 {
            ex.abs()
        } else if ex == 0.0 {
            ey.abs()
        } else {
            (ex * ex + ey * ey).sqrt()
        };
        // outward normal of a ccw edge is (ey, −ex)
        (ey * (x - a[0]) - ex * (y - a[1])) <= tol * len
    })
}

/// The plane through the three corners `c` (plan, m) at heights `z` (m).
pub(super) fn plane_of(c: &[[f64; 2]; 3], z: &[f64; 3]) -> FacetPlane {
    let (ax, ay) = (c[1][0] - c[0][0], c[1][1] - c[0][1]);
    let (bx, by) = (c[2][0] - c[0][0], c[2][1] - c[0][1]);
    let (az, bz) = (z[1] - z[0], z[2] - z[0]);
    let det = ax * by - ay * bx;
    FacetPlane::new(
        c[0][0],
        c[0][1],
        z[0],
        (az * by - bz * ay) / det,
        (ax * bz - bx * az) / det,
    )
}
