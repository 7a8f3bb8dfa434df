//! Along a run: the impact speed at a support and the first reach of a column along a closed-form
//! piece, the arrival of the nominal run, and the trajectory sampled from the closed forms.

use nalgebra::Vector3;

use super::lumped_mass::{self, Phase, RunOut};
use super::release::{Prepared, roll_radius};
use super::terrain::{Floor, MeanPlane};
use super::{Arrival, MigrationCase, SupportStop, Trajectory};
use crate::physics::error::{Param, PhysicsError, PhysicsResult};
use crate::physics::numeric::polynomial::first_root_nonpositive;

/// Impact speed at a support, m/s: spanning, the down-dip velocity; a column, the velocity in the
/// mean plane towards its axis (positive when approaching).
pub(crate) fn support_impact_speed(
    mean: &MeanPlane,
    stop: &SupportStop,
    p: &Vector3<f64>,
    v: &Vector3<f64>,
) -> f64 {
    let vu = v.dot(&mean.dip_dir());
    match stop.across {
        None => vu,
        Some(y) => {
            let (du, dw) = (stop.along_dip - mean.along(p), y - p.y);
            let d = du.hypot(dw);
            if d > 0.0 {
                (vu * du + v.y * dw) / d
            } else {
                vu.hypot(v.y)
            }
        }
    }
}

/// First time τ in [0, dt] at which a piece p(τ) = p + v τ + ½ a τ² reaches one of the columns
/// (distance in the mean plane from its axis ≤ its reach), and that column's index.
pub(crate) fn first_column_reach(
    mean: &MeanPlane,
    supports: &[SupportStop],
    p: &Vector3<f64>,
    v: &Vector3<f64>,
    a: &Vector3<f64>,
    dt: f64,
) -> Option<(f64, usize)> {
    let dip = mean.dip_dir();
    let (u0, vu, au) = (mean.along(p), v.dot(&dip), a.dot(&dip));
    let mut best: Option<(f64, usize)> = None;
    for (k, s) in supports.iter().enumerate() {
        let Some(y) = s.across else { continue };
        let (cu, cw) = (u0 - s.along_dip, p.y - y);
        let (bu, bw) = (vu, v.y);
        let (qu, qw) = (0.5 * au, 0.5 * a.y);
        let horizon = best.map_or(dt, |b| b.0);
        // quick rejection: the piece cannot come within reach before `horizon`
        let near =
            cu.hypot(cw) - (bu.hypot(bw) * horizon + qu.hypot(qw) * horizon * horizon) - s.reach;
        if near > 1e-9 * (1.0 + cu.hypot(cw)) {
            continue;
        }
        // |C + B τ + Q τ²|² − R², a quartic in τ (ascending coefficients)
        let r2 = s.reach * s.reach;
        let c = [
            cu * cu + cw * cw - r2,
            2.0 * (bu * cu + bw * cw),
            bu * bu + bw * bw + 2.0 * (qu * cu + qw * cw),
            2.0 * (qu * bu + qw * bw),
            qu * qu + qw * qw,
        ];
        if let Some(t) = first_root_nonpositive(&c, horizon)
            && best.is_none_or(|b| t < b.0)
        {
            best = Some((t, k));
        }
    }
    best
}

/// The components of `v` as an array (the wire form of a vector).
pub(super) fn xyz(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

pub(crate) fn height_above_floor(floor: &Floor, p: &Vector3<f64>, v: &Vector3<f64>) -> f64 {
    floor.locate(p.x, p.y, v.x, v.y).map_or(0.0, |f| {
        let pl = floor.facet_plane(f);
        pl.height(p) * pl.normal().z
    })
}

pub(super) fn arrival_of(case: &MigrationCase, pr: &Prepared, out: &RunOut) -> Arrival {
    let m = pr.mass;
    let mean = pr.floor.mean;
    let ke = 0.5 * m * out.v.norm_squared() + m * out.e_rot;
    let on_floor = matches!(out.phase, Phase::Slide | Phase::Roll | Phase::Stopped);
    Arrival {
        phase: out.phase,
        stop_reason: out.reason,
        time: out.t,
        speed: robust_norm(&out.v),
        along_dip_velocity: out.v.dot(&mean.dip_dir()),
        normal_velocity: out.v.dot(&mean.normal()),
        along_dip: mean.along(&out.p),
        normal_offset: if on_floor {
            0.0
        } else {
            height_above_floor(&pr.floor, &out.p, &out.v)
        },
        position: xyz(&out.p),
        angular_speed: robust_norm(&out.omega),
        kinetic_energy: ke,
        rotational_energy: m * out.e_rot,
        support: out.support,
        impact_speed: out
            .support
            .map(|k| support_impact_speed(&mean, &case.supports[k], &out.p, &out.v)),
    }
}

/// Euclidean norm without underflow of the squares: a speed of 1e-163 m/s (a subnormal face
/// length) is reported as such, not as 0.
pub(super) fn robust_norm(v: &Vector3<f64>) -> f64 {
    let m = v.amax();
    if m == 0.0 || !m.is_finite() {
        return v.norm();
    }
    m * (v / m).norm()
}

pub(super) fn sample_trajectory(
    case: &MigrationCase,
    pr: &Prepared,
    out: &RunOut,
    segs: &[lumped_mass::Segment],
) -> PhysicsResult<Trajectory> {
    let dt = case.output.sample_interval;
    let t_end = out.t;
    let n_grid = (t_end / dt).floor();
    let n = n_grid + 1.0 + if n_grid * dt < t_end { 1.0 } else { 0.0 };
    if n.is_nan() || n > case.output.max_samples as f64 {
        return Err(PhysicsError::invalid(
            Param::TrajectorySampleInterval,
            dt,
            format!(
                "the trajectory of {t_end:.6} s would need {n} samples, more than the limit {}",
                case.output.max_samples
            ),
        ));
    }
    let n = n as usize;
    let m = pr.mass;
    let g = pr.g;
    let mean = pr.floor.mean;
    let mut tr = Trajectory::default();
    let mut k = 0usize;
    for i in 0..n {
        let t = if i + 1 == n { t_end } else { i as f64 * dt };
        while k + 1 < segs.len() && segs[k].t0 + segs[k].dt < t {
            k += 1;
        }
        let (p, v, diss, rot, omega, on_floor) = match segs.get(k) {
            Some(s) => {
                let tau = (t - s.t0).clamp(0.0, s.dt);
                let p = s.p0 + s.v0 * tau + s.a * (0.5 * tau * tau);
                let v = s.v0 + s.a * tau;
                let diss = s.diss0 + s.fric.dot(&(p - s.p0));
                let (rot, om) = match s.rolling {
                    Some(nrm) => (
                        0.2 * v.norm_squared(),
                        nrm.cross(&v) / roll_radius(&case.rock),
                    ),
                    None => s.spin,
                };
                (p, v, diss, rot, om, s.on_floor)
            }
            None => (
                out.p,
                out.v,
                out.e_imp + out.e_fric + out.e_trans + out.e_barrier,
                out.e_rot,
                out.omega,
                true,
            ),
        };
        let (p, v, diss, rot, omega) = if i + 1 == n {
            (
                out.p,
                out.v,
                out.e_imp + out.e_fric + out.e_trans + out.e_barrier,
                out.e_rot,
                out.omega,
            )
        } else {
            (p, v, diss, rot, omega)
        };
        let on_floor = if i + 1 == n {
            matches!(out.phase, Phase::Slide | Phase::Roll | Phase::Stopped)
        } else {
            on_floor
        };
        tr.time.push(t);
        tr.position.push(xyz(&p));
        tr.along_dip.push(mean.along(&p));
        // invariant: every sample lies on or above the floor, in flight and on the ground (the
        // solver checks events and piece ends; a piece between them is checked here)
        lumped_mass::check_above_floor(&pr.floor, &p, t)?;
        tr.height.push(if on_floor {
            0.0
        } else {
            height_above_floor(&pr.floor, &p, &v)
        });
        tr.velocity.push(xyz(&v));
        tr.speed.push(robust_norm(&v));
        tr.angular_velocity.push(xyz(&omega));
        tr.kinetic_energy.push(m * (0.5 * v.norm_squared() + rot));
        tr.rotational_energy.push(m * rot);
        tr.potential_energy.push(m * g * (p.z - pr.z_end));
        tr.dissipated_energy.push(m * diss);
    }
    Ok(tr)
}

#[cfg(test)]
mod support_stop_tests {
    //! The column stop: the first time a quadratic piece comes within reach of a column's axis in
    //! the mean plane. Expectation: at the time found the distance equals the reach (to rounding),
    //! and no earlier time of the piece is within reach; without a time, no time of the piece is.
    use super::*;
    use proptest::prelude::*;

    fn dist(mean: &MeanPlane, s: &SupportStop, p: &Vector3<f64>) -> f64 {
        (mean.along(p) - s.along_dip).hypot(p.y - s.across.unwrap())
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]
        #[test]
        fn the_first_reach_of_a_column_is_the_first_crossing(
            dip in 5.0f64..80.0,
            x in 0.0f64..50.0, y in -3.0f64..3.0, h in 0.0f64..5.0,
            vx in -20.0f64..20.0, vy in -5.0f64..5.0, vz in -20.0f64..20.0,
            flight in any::<bool>(),
            sc in 0.0f64..80.0, yc in -3.0f64..3.0, reach in 0.005f64..3.0,
            dt in 1e-6f64..5.0,
        ) {
            let floor = Floor::plane(dip.to_radians());
            let mean = floor.mean;
            let p = Vector3::new(x, y, -x * mean.sin / mean.cos + h);
            let v = Vector3::new(vx, vy, vz);
            let a = if flight { Vector3::new(0.0, 0.0, -9.81) } else { mean.dip_dir() * 3.0 };
            let s = SupportStop { along_dip: sc, across: Some(yc), reach };
            let at = |t: f64| p + v * t + a * (0.5 * t * t);
            let found = first_column_reach(&mean, &[s], &p, &v, &a, dt);
            let scale = 1e-9 * (1.0 + reach + (v.norm() + a.norm() * dt) * dt + sc.abs());
            let end = match found {
                Some((t, k)) => {
                    prop_assert_eq!(k, 0);
                    prop_assert!((0.0..=dt).contains(&t));
                    let d = dist(&mean, &s, &at(t));
                    prop_assert!(d <= reach + scale, "distance {} at t {} > reach {}", d, t, reach);
                    if t > 0.0 {
                        prop_assert!(dist(&mean, &s, &p) > reach - scale);
                    }
                    t
                }
                None => dt,
            };
            // before the time found (nothing to sample when reached at once)
            for i in (0..400).filter(|_| end > 0.0) {
                let t = end * f64::from(i) / 400.0;
                let d = dist(&mean, &s, &at(t));
                prop_assert!(d > reach - scale, "within reach at t {} (d {}) before {}", t, d, end);
            }
        }
    }
}
