//! Per-cell maps of an ensemble (`output.maps` of `/v1/migration`, `migration_output.maps` of
//! `/v1/scene`): against the closed form of a slide on a plane, against an independent
//! recomputation from the per-run data, with the rigid block, in a scene (runs end at their
//! support), the limits (422 naming the pointer), thread-count invariance, the answer without
//! maps unchanged, a migration's maps through shards (the bytes of one request) and the
//! refusal of a scene's maps in a sharded computation.

mod common;

use common::gangue_cli as gangue;
use common::{assert_problem, post};
use serde_json::{Value, json};

const G: f64 = 9.81;

/// A plane face of 20 m at 45°, a rock released on the floor (no drop: a slide from rest, no
/// impact, no draw of restitution), `runs` runs, maps of 10 × 5 cells (2 m along the dip,
/// 0.4 m across: the path y = 0 runs inside the middle column).
fn slide(runs: u64, friction: Option<Value>) -> Value {
    let mut mc = json!({"runs": runs, "seed": 3});
    if let Some(f) = friction {
        mc["friction_coefficient"] = f;
    }
    json!({
        "face": {"length_m": 20, "dip_deg": 45, "friction_coefficient": 0.2},
        "release": {"drop_height_m": 0},
        "monte_carlo": mc,
        "output": {"runs_csv": true, "maps": {
            "cells_along_dip": 10, "cells_across": 5, "across_min_m": -1, "across_max_m": 1
        }}
    })
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// Type-7 percentile of sorted values (R's default).
fn type7(sorted: &[f64], p: f64) -> f64 {
    let h = (sorted.len() - 1) as f64 * p;
    let lo = h.floor() as usize;
    if lo + 1 >= sorted.len() {
        return sorted[sorted.len() - 1];
    }
    sorted[lo] + (h - lo as f64) * (sorted[lo + 1] - sorted[lo])
}

#[tokio::test]
async fn a_slide_on_a_plane_passes_every_cell_of_its_column_at_the_closed_form_speed() {
    let app = common::app();
    let r = post(&app, "/v1/migration", &slide(7, None)).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    let m = &b["maps"];
    assert_eq!(m["runs"], 7);
    assert_eq!(f(&m["cell_along_dip_m"]), 2.0);
    assert!((f(&m["cell_across_m"]) - 0.4).abs() < 1e-15);
    assert_eq!(b["inputs"]["output"]["maps"]["along_dip_max_m"], 20.0);
    let mass = f(&b["mass_kg"]);
    let th = 45f64.to_radians();
    let a = G * (th.sin() - 0.2 * th.cos());
    for i in 0..10 {
        for j in 0..5 {
            let k = i * 5 + j;
            if j != 2 {
                // beside the path: nobody passed
                assert_eq!(m["passages"][k], 0, "cell ({i}, {j})");
                assert!(m["speed_mean_m_s"][k].is_null());
                assert!(m["kinetic_energy_p95_j"][k].is_null());
                continue;
            }
            assert_eq!(m["passages"][k], 7, "cell ({i}, {j})");
            // the largest speed in the cell is the exit speed √(2 a s) at its lower edge
            let v = (2.0 * a * 2.0 * (i + 1) as f64).sqrt();
            for key in ["speed_mean_m_s", "speed_p95_m_s"] {
                let got = f(&m[key][k]);
                assert!((got - v).abs() < 1e-3 * v, "{key} ({i}, {j}): {got} vs {v}");
            }
            let e = 0.5 * mass * v * v;
            for key in ["kinetic_energy_mean_j", "kinetic_energy_p95_j"] {
                let got = f(&m[key][k]);
                assert!((got - e).abs() < 2e-3 * e, "{key} ({i}, {j}): {got} vs {e}");
            }
        }
    }
    // the last cell holds the arrival itself
    let arrival = f(&b["statistics"]["speed_m_s"]["max"]);
    assert!((f(&m["speed_p95_m_s"][9 * 5 + 2]) - arrival).abs() < 1e-12 * arrival);
}

#[tokio::test]
async fn per_cell_mean_and_p95_are_those_of_the_runs_recomputed_from_their_arrivals() {
    // μ drawn per run: each run slides from rest with its own a = g (sin θ − μ cos θ), which its
    // arrival speed gives back (v² = 2 a L); its largest speed in row i is √(2 a s_{i+1})
    let app = common::app();
    let body = slide(
        60,
        Some(json!({"distribution": "uniform", "min": 0.1, "max": 0.6})),
    );
    let r = post(&app, "/v1/migration", &body).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    let m = &b["maps"];
    let mass = f(&b["mass_kg"]);
    let csv = b["runs_csv"].as_str().unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 60);
    let accel: Vec<f64> = rows
        .iter()
        .map(|c| {
            assert_eq!(c[7], "lower_end");
            let v: f64 = c[2].parse().unwrap();
            v * v / (2.0 * 20.0)
        })
        .collect();
    for i in 0..10 {
        let k = i * 5 + 2;
        assert_eq!(m["passages"][k], 60);
        let s = 2.0 * (i + 1) as f64;
        let speeds: Vec<f64> = accel.iter().map(|a| (2.0 * a * s).sqrt()).collect();
        let mean = speeds.iter().sum::<f64>() / 60.0;
        let mut sorted = speeds.clone();
        sorted.sort_by(f64::total_cmp);
        let p95 = type7(&sorted, 0.95);
        let energies: Vec<f64> = speeds.iter().map(|v| 0.5 * mass * v * v).collect();
        let e_mean = energies.iter().sum::<f64>() / 60.0;
        let mut e_sorted = energies.clone();
        e_sorted.sort_by(f64::total_cmp);
        let e_p95 = type7(&e_sorted, 0.95);
        for (key, want, tol) in [
            ("speed_mean_m_s", mean, 1e-3),
            ("speed_p95_m_s", p95, 1e-3),
            ("kinetic_energy_mean_j", e_mean, 2e-3),
            ("kinetic_energy_p95_j", e_p95, 2e-3),
        ] {
            let got = f(&m[key][k]);
            assert!(
                (got - want).abs() < tol * want,
                "{key} row {i}: {got} vs {want}"
            );
        }
    }
}

#[tokio::test]
async fn rigid_block_maps_follow_every_run_down_to_its_arrival() {
    let app = common::app();
    let body = json!({
        "method": "rigid_block",
        "face": {"length_m": 4},
        "release": {"drop_height_m": 0.2},
        "monte_carlo": {"runs": 4, "seed": 1, "friction_coefficient": {"distribution": "uniform", "min": 0.2, "max": 0.4}},
        "output": {"runs_csv": true, "maps": {
            "cells_along_dip": 8, "cells_across": 4, "across_min_m": -1, "across_max_m": 1
        }}
    });
    let r = post(&app, "/v1/migration", &body).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    let m = &b["maps"];
    assert_eq!(f(&b["statistics"]["reached_fraction"]), 1.0);
    let passages = |i: usize| -> u64 {
        (0..4)
            .map(|j| m["passages"][i * 4 + j].as_u64().unwrap())
            .sum()
    };
    // a run whose path runs from the top row to the lower end crosses every row
    for i in 0..8 {
        assert!(passages(i) >= 4, "row {i}: {}", passages(i));
    }
    for k in 0..32 {
        let n = m["passages"][k].as_u64().unwrap();
        assert!(n <= 4);
        assert_eq!(n == 0, m["speed_mean_m_s"][k].is_null());
        if n > 0 {
            let (mean, p95) = (f(&m["speed_mean_m_s"][k]), f(&m["speed_p95_m_s"][k]));
            assert!(mean >= 0.0 && p95 >= 0.0);
            let (em, ep) = (
                f(&m["kinetic_energy_mean_j"][k]),
                f(&m["kinetic_energy_p95_j"][k]),
            );
            // a run's largest energy is at least its translational ½ m v² at its largest speed
            assert!(ep >= 0.5 * f(&b["mass_kg"]) * p95 * p95 * (1.0 - 1e-9) || em > 0.0);
        }
    }
    // each run's largest speed in its last row is at least its arrival speed
    let csv = b["runs_csv"].as_str().unwrap();
    let arrivals: f64 = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(2).unwrap().parse::<f64>().unwrap())
        .sum();
    let last: f64 = (0..4)
        .filter(|j| m["passages"][7 * 4 + j].as_u64().unwrap() > 0)
        .map(|j| {
            m["passages"][7 * 4 + j].as_u64().unwrap() as f64 * f(&m["speed_mean_m_s"][7 * 4 + j])
        })
        .sum();
    assert!(last >= arrivals * (1.0 - 1e-9), "{last} < {arrivals}");
}

#[tokio::test]
async fn scene_maps_end_at_the_support_each_run_strikes() {
    let app = common::app();
    let body = json!({
        "face": {"length_m": 20},
        "release": {"drop_height_m": 0},
        "supports": [{"along_dip_m": 10}],
        "monte_carlo": {"runs": 20, "seed": 2, "release_across_m": {"min": -1, "max": 1}},
        "migration_output": {"maps": {"cells_along_dip": 20, "cells_across": 4, "across_min_m": -2, "across_max_m": 2}}
    });
    let r = post(&app, "/v1/scene", &body).await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    let m = &b["maps"];
    assert_eq!(m["runs"], 20);
    assert_eq!(
        b["inputs"]["migration_output"]["maps"]["along_dip_max_m"],
        20.0
    );
    let row = |i: usize| -> u64 {
        (0..4)
            .map(|j| m["passages"][i * 4 + j].as_u64().unwrap())
            .sum()
    };
    // a spanning support at 10 m stops every run there: rows 0–9 passed, rows 11–19 never
    for i in 0..10 {
        assert!(row(i) >= 20, "row {i}");
    }
    for i in 11..20 {
        assert_eq!(row(i), 0, "row {i}");
    }
    // the runs are released across [−1, 1]: the outer columns [−2, −1] and [1, 2] stay empty
    for i in 0..20 {
        assert_eq!(m["passages"][i * 4], 0);
        assert_eq!(m["passages"][i * 4 + 3], 0);
    }
}

#[tokio::test]
async fn oversized_or_malformed_grids_are_refused_naming_the_field() {
    let app = common::app();
    let with =
        |maps: Value, runs: u64| json!({"monte_carlo": {"runs": runs}, "output": {"maps": maps}});
    // cells × runs past max_map_cell_runs (5e7): 500 × 400 cells × 1000 runs
    let r = post(
        &app,
        "/v1/migration",
        &with(json!({"cells_along_dip": 500, "cells_across": 400}), 1000),
    )
    .await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/output/maps");
    assert_eq!(p["errors"][0]["value"], 200_000_000u64);
    assert!(
        p["errors"][0]["message"]
            .as_str()
            .unwrap()
            .contains("50000000"),
        "{p}"
    );
    // more cells than max_map_cells (250 000)
    let r = post(
        &app,
        "/v1/migration",
        &with(json!({"cells_along_dip": 2000, "cells_across": 2000}), 1),
    )
    .await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/output/maps");
    assert_eq!(p["errors"][0]["value"], 4_000_000u64);
    for (maps, field) in [
        (
            json!({"cells_along_dip": 0}),
            "/output/maps/cells_along_dip",
        ),
        (json!({"cells_across": 2001}), "/output/maps/cells_across"),
        (
            json!({"across_min_m": 2, "across_max_m": 1}),
            "/output/maps/across_max_m",
        ),
        (
            json!({"along_dip_min_m": 50, "along_dip_max_m": 10}),
            "/output/maps/along_dip_max_m",
        ),
        (json!({"across_min_m": -1e4}), "/output/maps/across_min_m"),
    ] {
        let r = post(&app, "/v1/migration", &with(maps.clone(), 10)).await;
        let p = assert_problem(&r, 422, "invalid_input");
        assert_eq!(p["errors"][0]["field"], field, "{maps}: {p}");
    }
    // maps need an ensemble
    let r = post(&app, "/v1/migration", &json!({"output": {"maps": {}}})).await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/output/maps");
    // a scene names its own output object
    let r = post(
        &app,
        "/v1/scene",
        &json!({"monte_carlo": {"runs": 1000}, "migration_output": {"maps": {"cells_along_dip": 500, "cells_across": 400}}}),
    )
    .await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/migration_output/maps");
}

#[tokio::test]
async fn maps_are_the_same_bytes_whatever_the_thread_count() {
    let app = |threads| {
        gangue::app(gangue::config::Config {
            solver_threads: Some(threads),
            ..Default::default()
        })
    };
    let (one, three) = (app(1), app(3));
    let body = json!({
        "face": {"length_m": 30},
        "monte_carlo": {"runs": 700, "seed": 5, "friction_coefficient": {"distribution": "uniform", "min": 0.1, "max": 0.5}},
        "release": {"across_m": 0.3},
        "output": {"maps": {}}
    });
    let a = post(&one, "/v1/migration", &body).await;
    let b = post(&three, "/v1/migration", &body).await;
    assert_eq!(a.status, 200, "{}", String::from_utf8_lossy(&a.body));
    assert_eq!(a.body, b.body, "same bytes with 1 and 3 threads");
    let m = &a.json()["maps"];
    assert_eq!(m["passages"].as_array().unwrap().len(), 60 * 40);
    let scene = json!({
        "face": {"length_m": 30},
        "supports": [{"along_dip_m": 20, "across_m": 0}],
        "monte_carlo": {"runs": 300, "seed": 5, "release_across_m": {"min": -1, "max": 1}},
        "migration_output": {"maps": {}}
    });
    let a = post(&one, "/v1/scene", &scene).await;
    let b = post(&three, "/v1/scene", &scene).await;
    assert_eq!(a.status, 200, "{}", String::from_utf8_lossy(&a.body));
    assert_eq!(a.body, b.body, "scene: same bytes with 1 and 3 threads");
}

/// The answer with maps, without `maps` and the echoed `maps`, is the answer without them.
fn strip(mut v: Value, output: &str) -> Value {
    v.as_object_mut().unwrap().remove("maps");
    v["inputs"][output].as_object_mut().unwrap().remove("maps");
    // a scene echoes its migration request in the nominal run's migration answer too
    if let Some(m) = v.get_mut("migration") {
        m["inputs"]["output"]
            .as_object_mut()
            .unwrap()
            .remove("maps");
    }
    v
}

#[tokio::test]
async fn omitting_maps_leaves_the_answer_unchanged() {
    let app = common::app();
    for (path, output, body) in [
        (
            "/v1/migration",
            "output",
            json!({"face": {"length_m": 30}, "monte_carlo": {"runs": 50, "seed": 1}, "output": {"runs_csv": true}}),
        ),
        (
            "/v1/migration",
            "output",
            json!({"method": "rigid_block", "face": {"length_m": 4}, "release": {"drop_height_m": 0.2}, "monte_carlo": {"runs": 3, "seed": 1}}),
        ),
        (
            "/v1/scene",
            "migration_output",
            json!({"face": {"length_m": 30}, "supports": [{"along_dip_m": 20}], "monte_carlo": {"runs": 40, "seed": 1}, "migration_output": {"runs_csv": true}}),
        ),
    ] {
        let without = post(&app, path, &body).await;
        assert_eq!(without.status, 200);
        let mut with_maps = body.clone();
        with_maps[output]["maps"] = json!({"cells_along_dip": 30, "cells_across": 10});
        let with = post(&app, path, &with_maps).await;
        assert_eq!(with.status, 200, "{}", String::from_utf8_lossy(&with.body));
        let w = with.json();
        assert!(w["maps"]["passages"].is_array());
        assert!(without.json().get("maps").is_none());
        assert_eq!(strip(w, output), without.json(), "{path}");
    }
}

fn scratch(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("gangue-maps-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[tokio::test]
async fn migration_maps_of_merged_shards_are_the_bytes_of_one_request() {
    let dir = scratch("merge");
    for (name, body) in [
        (
            "lumped",
            json!({"face": {"length_m": 40}, "monte_carlo": {"runs": 23, "seed": 7, "friction_coefficient": {"distribution": "uniform", "min": 0.1, "max": 0.5}},
                   "release": {"across_m": 0.4}, "output": {"runs_csv": true, "maps": {"cells_along_dip": 20, "cells_across": 8}}}),
        ),
        (
            "rigid",
            json!({"method": "rigid_block", "face": {"length_m": 4}, "release": {"drop_height_m": 0.2},
                   "monte_carlo": {"runs": 3, "seed": 1}, "output": {"maps": {"cells_along_dip": 8, "cells_across": 4, "across_min_m": -1, "across_max_m": 1}}}),
        ),
    ] {
        let want = post(&common::app(), "/v1/migration", &body).await;
        assert_eq!(want.status, 200, "{}", String::from_utf8_lossy(&want.body));
        assert!(want.json()["maps"]["passages"].is_array());
        let req = dir.join(format!("{name}.json"));
        std::fs::write(&req, serde_json::to_vec(&body).unwrap()).unwrap();
        for k in [1u64, 3] {
            let mut parts = Vec::new();
            for i in 0..k {
                let out = dir.join(format!("{name}-{k}-{i}"));
                let o = gangue(&[
                    "compute",
                    "--request",
                    req.to_str().unwrap(),
                    "--kind",
                    "migration",
                    "--shard",
                    &format!("{i}/{k}"),
                    "--out",
                    out.to_str().unwrap(),
                ]);
                assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
                parts.push(out.to_str().unwrap().to_string());
            }
            let mut args = vec!["merge"];
            args.extend(parts.iter().map(String::as_str));
            let o = gangue(&args);
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            assert!(
                o.stdout == want.body,
                "{name}, {k} shards: the merged answer differs from the request's"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_sharded_scene_refuses_maps_naming_the_field() {
    let body = json!({"monte_carlo": {"runs": 5}, "migration_output": {"maps": {}}});
    let (ok, text) = common::scene_shard(&body, "maps-shard");
    assert!(!ok, "maps in a scene shard must be refused");
    assert!(text.contains("/migration_output/maps"), "{text}");
    assert!(text.contains("sharded"), "{text}");
}
