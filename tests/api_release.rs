//! Where a rock is released on a floor and what a run that leaves it says (api.md `POST
//! /v1/migration`, Release), through the router. Physical expectations: a block is placed
//! face-down with every corner over the floor, so a release at a grid's edge is moved onto it
//! by the overhang (half its side for a cube on its edge) and then slides as on the plane,
//! v² = 2 g (sin θ − μ cos θ) (S − s); a release whose block fits nowhere near is 422 naming the
//! field and where it fits; the default request runs on every floor kind with both methods; a
//! contour floor has no level apron beyond its highest contour; a run that leaves the floor says
//! where and past which boundary.

mod common;
use common::migrate_ok as ok;

use common::{assert_problem, post, rel};
use serde_json::{Value, json};

fn data(name: &str) -> String {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/floors")
        .join(name);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn warning<'a>(b: &'a Value, code: &str) -> Option<&'a str> {
    b["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .find(|w| w["code"] == code)
        .map(|w| w["message"].as_str().unwrap())
}

/// A planar 45° grid: `rows` rows `spacing` apart from y₀, `cols` columns from x = 0, z = −x.
fn planar_grid(y0: f64, spacing: f64, rows: usize, cols: usize) -> Value {
    let row: Vec<f64> = (0..cols).map(|j| -(j as f64) * spacing).collect();
    json!({"kind": "grid", "origin_m": [0.0, y0], "spacing_m": spacing,
           "heights_m": vec![row; rows]})
}

/// The first number after `key` in `text`.
fn number_after(text: &str, key: &str) -> f64 {
    let i = text
        .find(key)
        .unwrap_or_else(|| panic!("{key} not in {text}"))
        + key.len();
    let t: String = text[i..]
        .trim_start()
        .chars()
        .take_while(|c| c.is_ascii_digit() || *c == '.' || *c == '-')
        .collect();
    t.parse()
        .unwrap_or_else(|_| panic!("no number after {key} in {text}"))
}

#[tokio::test]
async fn a_block_released_at_the_grid_edge_starts_on_the_floor() {
    let app = common::app();
    let repro: Value = serde_json::from_str(
        &std::fs::read_to_string(
            common::shared_dir().join("repro/rigid_block_release_at_grid_edge.json"),
        )
        .unwrap(),
    )
    .unwrap();
    let req = &repro["request"];
    let b = ok(&app, req).await;
    let a = &b["arrival"];
    assert_eq!(a["stop_reason"], "lower_end", "{b}");
    // the 0.3 m cube resting on the grid's upper edge overhangs it by half its side: moved
    // down the dip by that (and the 1e-3 r_max kept inside the edge)
    let moved = warning(&b, "release_moved").expect("release_moved");
    let ds = number_after(moved, "floor,");
    let r_max = 3f64.sqrt() * 0.3 / 2.0;
    assert!((0.15..=0.15 + 2e-3 * r_max).contains(&ds), "{moved}");
    assert_eq!(number_after(moved, "dip and"), 0.0, "{moved}");
    // from rest at s = ds the block slides as on the plane to S = 20 m: v² = 2 g (sin θ − μ cos θ)
    // (S − s); the spring–dashpot contact and the step leave 1e-3 (the plane's own answer,
    // 14.899 m/s from s = 0, is within 1e-4 of its closed form)
    let th = 45f64.to_radians();
    let v = (2.0 * 9.81 * (th.sin() - 0.2 * th.cos()) * (20.0 - ds)).sqrt();
    let got = a["speed_m_s"].as_f64().unwrap();
    assert!(rel(got, v) < 1e-3, "{got} vs {v}");
    // with the default drop it lands on the grid and runs on (it used to leave the floor on
    // landing, half its face over the edge)
    let mut dropped = req.clone();
    dropped["release"] = json!({});
    let b = ok(&app, &dropped).await;
    assert_eq!(b["arrival"]["stop_reason"], "lower_end", "{b}");
    assert!(warning(&b, "release_moved").is_some());
    // the point mass needs only its point on the floor: not moved
    dropped["method"] = json!("lumped_mass");
    let b = ok(&app, &dropped).await;
    assert_eq!(b["arrival"]["stop_reason"], "lower_end");
    assert!(warning(&b, "release_moved").is_none(), "{}", b["warnings"]);
}

/// Every floor kind with the default release (along_dip_m 0, across_m 0), both methods: never
/// refused, never off the floor at the start. On the grid from y₀ = 0 the default point is its
/// corner: the block is moved down the dip and across onto it.
#[tokio::test]
async fn default_releases_run_on_every_floor_kind_with_both_methods() {
    let app = common::app();
    let straight: Vec<Value> = (0..=30)
        .map(|k| json!({"elevation_m": -(k as f64), "points_m": [[k as f64, -6.0], [k as f64, 6.0]]}))
        .collect();
    let geojson: Value = serde_json::from_str(&data("face_contours.geojson")).unwrap();
    let floors = [
        ("plane", 45.0, json!({"kind": "plane"})),
        ("grid from y = 0", 45.0, planar_grid(0.0, 1.0, 7, 31)),
        (
            "ESRI ASCII grid",
            33.0,
            json!({"kind": "grid", "esri_ascii": data("face_grid.asc")}),
        ),
        (
            "contours",
            45.0,
            json!({"kind": "contours", "contours": straight}),
        ),
        (
            "GeoJSON contours",
            45.0,
            json!({"kind": "contours", "geojson": geojson}),
        ),
    ];
    for (name, dip, floor) in floors {
        for method in ["lumped_mass", "rigid_block"] {
            let body = json!({"method": method,
                              "face": {"dip_deg": dip, "length_m": 18, "floor": floor}});
            let b = ok(&app, &body).await;
            let a = &b["arrival"];
            let what = format!("{name}, {method}: {a} {}", b["warnings"]);
            assert!(a["time_s"].as_f64().unwrap() > 0.5, "{what}");
            assert_eq!(a["stop_reason"], "lower_end", "{what}");
        }
    }
    // the grid from y₀ = 0: the default point is its corner, and the block is moved down the
    // dip and across by half its side each, to within the search grid's step 2 r_max/32
    let body = json!({"method": "rigid_block",
                      "face": {"length_m": 18, "floor": planar_grid(0.0, 1.0, 7, 31)}});
    let b = ok(&app, &body).await;
    let moved = warning(&b, "release_moved").expect("release_moved");
    let step = 2.0 * 3f64.sqrt() * 0.3 / 2.0 / 32.0;
    for key in ["floor,", "dip and"] {
        let d = number_after(moved, key);
        assert!((0.15..=0.15 + step).contains(&d), "{key}: {moved}");
    }
}

/// A contour floor is the triangulation of its contours' points, which fills their convex hull:
/// beyond the highest contour it joined points of that one contour into level triangles, and a
/// rock released on the top contour of a 45° face landed there and stayed (at rest at 0.16 m).
#[tokio::test]
async fn a_rock_released_on_the_top_contour_does_not_stop_on_a_level_apron() {
    let app = common::app();
    let geojson: Value = serde_json::from_str(&data("face_contours.geojson")).unwrap();
    let floor = json!({"kind": "contours", "geojson": geojson});
    let b = ok(
        &app,
        &json!({"face": {"dip_deg": 45, "length_m": 18, "floor": floor}}),
    )
    .await;
    assert_eq!(b["arrival"]["stop_reason"], "lower_end", "{b}");
    // the first impact is on the floor under the release point, below the top contour's level
    // only down the dip of it: never on a level facet at its elevation up the dip of it
    let first = &b["events"][0];
    assert_eq!(first["kind"], "impact");
    assert!(first["position_m"][0].as_f64().unwrap() >= -1e-9, "{first}");
}

#[tokio::test]
async fn a_release_the_floor_cannot_hold_is_422_with_where_it_fits() {
    let app = common::app();
    // past the grid's lower edge (x = 17 m, 24.04 m along a 45° dip)
    let body = json!({"face": {"length_m": 30, "floor": planar_grid(-3.0, 1.0, 7, 18)},
                      "release": {"along_dip_m": 25}});
    let r = post(&app, "/v1/migration", &body).await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/release/along_dip_m", "{p}");
    let m = p["errors"][0]["message"].as_str().unwrap();
    assert!(
        rel(number_after(m, "at most"), 17.0 * 2f64.sqrt()) < 1e-9,
        "{m}"
    );
    // over a hole (a NODATA node at x = 6 m, y = 0 of a 30° plane grid, x in [0, 20] m): the
    // message gives the floor's along-dip span at that across position, [0, 20/cos 30°]
    let mut asc = String::from(
        "ncols 41\nnrows 9\nxllcenter 0\nyllcenter -2\ncellsize 0.5\nNODATA_value -9999\n",
    );
    for i in (0..9).rev() {
        let row: Vec<String> = (0..41)
            .map(|j| {
                if i == 4 && j == 12 {
                    "-9999".to_string()
                } else {
                    format!("{}", -(f64::from(j) * 0.5) * 30f64.to_radians().tan())
                }
            })
            .collect();
        asc.push_str(&row.join(" "));
        asc.push('\n');
    }
    let th = 30f64.to_radians();
    let body = json!({"face": {"dip_deg": 30, "length_m": 20,
                               "floor": {"kind": "grid", "esri_ascii": asc}},
                      "release": {"along_dip_m": 6.0 / th.cos()}});
    let r = post(&app, "/v1/migration", &body).await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/release/along_dip_m", "{p}");
    let m = p["errors"][0]["message"].as_str().unwrap();
    assert!(number_after(m, "in [").abs() < 1e-4, "{m}");
    assert!(
        (number_after(m, ", ") - 20.0 / th.cos()).abs() < 1e-4,
        "{m}"
    );
    // a strip 0.2 m wide holds no 0.3 m cube anywhere
    let body = json!({"method": "rigid_block",
                      "face": {"length_m": 10, "floor": planar_grid(0.0, 0.1, 3, 120)}});
    let r = post(&app, "/v1/migration", &body).await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/release/along_dip_m", "{p}");
    assert!(
        p["errors"][0]["message"]
            .as_str()
            .unwrap()
            .contains("fits nowhere"),
        "{p}"
    );
    // ... but the point mass runs there
    let mut lm = body.clone();
    lm["method"] = json!("lumped_mass");
    ok(&app, &lm).await;
}

#[tokio::test]
async fn a_run_that_leaves_the_floor_says_where_and_why() {
    let app = common::app();
    // the grid ends at x = 17 m (24.04 m along the dip), the face at 30 m
    let body = json!({"face": {"length_m": 30, "floor": planar_grid(-3.0, 1.0, 7, 18)},
                      "release": {"drop_height_m": 0}});
    let b = ok(&app, &body).await;
    let a = &b["arrival"];
    assert_eq!(a["stop_reason"], "left_floor", "{b}");
    let w = warning(&b, "left_floor").expect("left_floor warning");
    assert!(w.contains("lower edge"), "{w}");
    let s = number_after(w, "floor at");
    assert!((s - a["along_dip_m"].as_f64().unwrap()).abs() < 1e-4, "{w}");
    // the point mass leaves at the edge x = 17 m (the message gives 4 decimals)
    assert!((s - 17.0 * 2f64.sqrt()).abs() < 1e-4, "{w}");
}
