//! The rigid block among column supports: columns far from every path change no bit of any
//! run; a settled slide skipped in closed form stops at the column or spanning support it
//! crosses, where the closed-form slide reaches it and at its speed; an ensemble on the paper's
//! face with its 62 columns gives the same bytes on 1 and 2 solver threads.

mod common;

use common::post;
use gangue::physics::Control;
use gangue::physics::migration::{
    Distribution, Method, MigrationCase, MigrationResult, MonteCarlo, StopReason, SupportStop, run,
};
use serde_json::json;

fn solve(c: &MigrationCase) -> MigrationResult {
    run(c, &Control::unlimited()).unwrap()
}

/// The rigid block on the default 45°, 120 m plane, released 3.27 m above its top, with an
/// ensemble of 6 runs (μ and β drawn), events, trajectory and per-run summaries.
fn dropped_ensemble() -> MigrationCase {
    let mut c = MigrationCase {
        method: Method::RigidBlock,
        monte_carlo: Some(MonteCarlo {
            runs: 6,
            seed: 11,
            friction_coefficient: Some(Distribution::Uniform {
                min: 0.15,
                max: 0.3,
            }),
            ..MonteCarlo::default()
        }),
        ..MigrationCase::default()
    };
    c.output.events = true;
    c.output.trajectory = true;
    c.output.runs_csv = true;
    c
}

#[test]
fn columns_far_from_every_path_change_no_bit_of_any_run() {
    for (drop, across) in [(3.27, 0.0), (0.0, 0.0), (3.27, 0.6)] {
        let mut bare = dropped_ensemble();
        bare.release.drop_height = drop;
        bare.release.across = across;
        let mut far = bare.clone();
        // 30 columns: 15 beyond the lower end (the runout ends there), 15 along the whole face
        // 25 m to either side
        far.supports = (0..30)
            .map(|k| {
                let k = f64::from(k);
                if k < 15.0 {
                    SupportStop {
                        along_dip: 122.0 + 1.5 * k,
                        across: Some(0.0),
                        reach: 0.7,
                    }
                } else {
                    SupportStop {
                        along_dip: 8.0 * (k - 15.0),
                        across: Some(if k % 2.0 == 0.0 { 25.0 } else { -25.0 }),
                        reach: 0.7,
                    }
                }
            })
            .collect();
        let (a, b) = (solve(&bare), solve(&far));
        // the runs slide (the closed-form skips are taken) to the lower end
        assert_eq!(a.arrival.stop_reason, StopReason::LowerEnd);
        let runs = a.runs.as_ref().unwrap();
        assert!(
            runs.iter().all(|r| r.stop_reason == StopReason::LowerEnd),
            "{runs:?}"
        );
        assert_eq!(
            format!("{a:?}"),
            format!("{b:?}"),
            "drop {drop} m, across {across} m"
        );
    }
}

/// The settled slide from rest on the 45° plane: a = g (sin θ − μ cos θ), so the centre
/// (starting at along-dip s₀) passes s at the speed √(2a(s − s₀)).
#[test]
fn a_skipped_slide_stops_at_the_support_it_crosses_where_the_closed_form_does() {
    let (g, mu) = (9.81, 0.2);
    let th = 45f64.to_radians();
    let a = g * (th.sin() - mu * th.cos());
    let mut base = MigrationCase {
        method: Method::RigidBlock,
        ..MigrationCase::default()
    };
    base.release.drop_height = 0.0;
    base.release.along_dip = 5.0;
    base.output.events = false;
    let free = solve(&base);
    let dt = free.rigid_block.as_ref().unwrap().time_step;
    let s0 = 5.0;
    let reach = 0.6;
    // (along-dip of the support, across of its column or None, along-dip where it is reached)
    let du = (reach * reach - 0.35f64 * 0.35).sqrt();
    for (sc, yc, s_hit) in [
        (60.0, Some(0.0), 60.0 - reach),
        (97.3, Some(0.35), 97.3 - du),
        (41.0, Some(-0.35), 41.0 - du),
        (73.0, None, 73.0),
    ] {
        let mut c = base.clone();
        c.supports = vec![
            // a column beside the path (never reached) and the one crossed
            SupportStop {
                along_dip: sc - 10.0,
                across: Some(1.5),
                reach,
            },
            SupportStop {
                along_dip: sc,
                across: yc,
                reach,
            },
        ];
        let r = solve(&c);
        let arr = &r.arrival;
        assert_eq!(arr.stop_reason, StopReason::Support, "support at {sc} m");
        assert_eq!(arr.support, Some(1));
        let t = (2.0 * (s_hit - s0) / a).sqrt();
        let v = a * t;
        // reached within the step's travel, at the closed form's speed (the DEM slide's
        // accuracy, physics.md §C.3: 2e-3)
        let along = arr.along_dip;
        assert!(
            (along - s_hit).abs() <= 2.0 * v * dt + 1e-3 * s_hit,
            "support at {sc} m: reached at {along} m, closed form {s_hit} m"
        );
        assert!(
            (arr.speed - v).abs() <= 2e-3 * v,
            "support at {sc} m: speed {} m/s, closed form {v} m/s",
            arr.speed
        );
        // the impact speed the strike uses: towards the axis (all of it on a spanning
        // support)
        let expect = match yc {
            Some(y) => v * (sc - s_hit) / (((sc - s_hit).powi(2) + y * y).sqrt()),
            None => v,
        };
        let got = arr.impact_speed.unwrap();
        assert!(
            (got - expect).abs() <= 2e-3 * expect,
            "support at {sc} m: impact speed {got} m/s, closed form {expect} m/s"
        );
        // the slide was skipped in closed form, not stepped: far fewer steps than its time
        let steps = r.rigid_block.as_ref().unwrap().steps;
        assert!(
            (steps as f64) < 0.2 * arr.time / dt,
            "support at {sc} m: {steps} steps for {} s at {dt} s",
            arr.time
        );
    }
}

#[tokio::test]
async fn the_paper_face_with_its_62_columns_gives_the_same_bytes_on_1_and_2_threads() {
    let one = gangue::app(gangue::config::Config {
        solver_threads: Some(1),
        ..Default::default()
    });
    let two = gangue::app(gangue::config::Config {
        solver_threads: Some(2),
        ..Default::default()
    });
    // 130 runs: three chunks of runs, so both threads take some
    let body = json!({
        "method": "rigid_block",
        "support_rows": {"lowest_along_dip_m": 118.5, "spacing_m": 1.5, "count": 62,
                         "across_m": [0.9]},
        "monte_carlo": {"runs": 130, "seed": 3,
                        "release_across_m": {"distribution": "uniform", "min": -1.5, "max": 1.5}},
        "release_zones": "table1",
        "migration_output": {"runs_csv": true},
    });
    let a = post(&one, "/v1/scene", &body).await;
    let b = post(&two, "/v1/scene", &body).await;
    assert_eq!(a.status, 200, "{}", String::from_utf8_lossy(&a.body));
    assert_eq!(a.body, b.body, "same bytes with 1 and 2 threads");
    // some runs reach a column, some pass between them to the lower end
    let v = a.json();
    let o = &v["statistics"]["outcomes"];
    let (support, lower) = (
        o["support"].as_f64().unwrap(),
        o["lower_end"].as_f64().unwrap(),
    );
    assert!(support > 0.05 && lower > 0.05, "{o}");
}
