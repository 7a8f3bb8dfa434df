//! Floors in the formats engineers have (api.md `POST /v1/migration`, Floors), through the
//! router: an ESRI ASCII grid is the same floor as the `heights_m` grid it encodes (bit for bit);
//! NODATA nodes are holes a sliding or landing rock leaves the floor through while a flight over
//! them goes on; GeoJSON contours are the same floor as the `contours` form (bit for bit); map
//! coordinates are a rigid transform, so a floor given in UTM-sized map coordinates and turned to
//! any dip direction answers as the same floor given in face coordinates, to the rounding of the
//! rotation (stated per test); malformed files are refused naming the line or the feature.

mod common;
use common::migrate_ok as ok;

use common::{assert_problem, post, rel};
use serde_json::{Value, json};
use sha2::{Digest, Sha256};

fn data(name: &str) -> String {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/floors")
        .join(name);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The response without its `inputs` echo (which names the floor's form).
fn results(mut v: Value) -> Value {
    v.as_object_mut().unwrap().remove("inputs");
    v
}

fn hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// A case on the sample floors (dip 30°, 18 m) with a trajectory, so that every output is compared.
#[allow(clippy::needless_pass_by_value, reason = "called with json! literals")]
fn case(floor: Value) -> Value {
    json!({
        "face": {"dip_deg": 30, "length_m": 18, "floor": floor},
        "release": {"along_dip_m": 1.0, "drop_height_m": 1.5, "across_m": 0.5},
        "output": {"trajectory": true, "sample_interval_s": 0.05}
    })
}

/// The heights of the sample .asc read independently: rows as written (north first).
fn sample_rows() -> Vec<Vec<f64>> {
    data("face_grid.asc")
        .lines()
        .skip(6)
        .map(|l| l.split_whitespace().map(|t| t.parse().unwrap()).collect())
        .collect()
}

#[tokio::test]
async fn esri_ascii_grid_gives_the_same_bits_as_the_heights_m_grid_it_encodes() {
    let app = common::app();
    let asc = data("face_grid.asc");
    // cell centres: x = xllcorner + (j + ½)·2 = 1 + 2j, y = −8 + 1 + 2i; first data row north
    let mut heights = sample_rows();
    heights.reverse();
    let grid = ok(
        &app,
        &case(json!({"kind": "grid", "origin_m": [1.0, -7.0], "spacing_m": 2.0, "heights_m": heights})),
    )
    .await;
    let esri = ok(&app, &case(json!({"kind": "grid", "esri_ascii": asc}))).await;
    assert!(grid["impact_count"].as_u64().unwrap() >= 1, "{grid}");
    assert_eq!(results(grid.clone()), results(esri.clone()));
    // echo: kind and the hash of the text as sent
    let echo = &esri["inputs"]["face"]["floor"];
    assert_eq!(
        *echo,
        json!({"kind": "grid", "sha256": hex(asc.as_bytes())})
    );
    // xllcenter / yllcenter, header keywords in another order and case, CRLF line ends
    let centred = asc
        .replace("xllcorner    0.0", "XLLCENTER 1.0")
        .replace("yllcorner    -8.0", "yllcenter -7")
        .replacen(
            "ncols        12\nnrows        8\n",
            "nrows 8\nncols 12\n",
            1,
        )
        .replace('\n', "\r\n");
    let b = ok(&app, &case(json!({"kind": "grid", "esri_ascii": centred}))).await;
    assert_eq!(results(b), results(grid));
}

/// A plane grid z = −x tan 30° (0.5 m cells, x ∈ [0, 20], y ∈ [−2, 2]) with one NODATA node at
/// (6, 0): the triangles touching it are removed. At y = 0.1 the hole spans x ∈ (5.6, 6.5).
fn holed_plane() -> String {
    let t = 30f64.to_radians().tan();
    let mut s = String::from(
        "ncols 41\nnrows 9\nxllcenter 0\nyllcenter -2\ncellsize 0.5\nNODATA_value -9999\n",
    );
    for r in 0..9 {
        let y = 2.0 - 0.5 * r as f64;
        let row: Vec<String> = (0..41)
            .map(|j| {
                let x = 0.5 * j as f64;
                if j == 12 && y == 0.0 {
                    "-9999".to_string()
                } else {
                    format!("{:.12}", -x * t)
                }
            })
            .collect();
        s.push_str(&row.join(" "));
        s.push('\n');
    }
    s
}

fn hole_case(x: f64, drop: f64, speed: f64) -> Value {
    let along = x / 30f64.to_radians().cos();
    json!({
        "face": {"dip_deg": 30, "length_m": 20, "floor": {"kind": "grid", "esri_ascii": holed_plane()}},
        "release": {"along_dip_m": along, "drop_height_m": drop, "across_m": 0.1, "speed_m_s": speed}
    })
}

#[tokio::test]
async fn a_rock_sliding_or_landing_into_a_nodata_hole_leaves_the_floor_and_one_flying_over_it_goes_on()
 {
    let app = common::app();
    // sliding from x = 4.5: leaves the floor at the hole's edge x = 5.6 (y = 0.1)
    let b = ok(&app, &hole_case(4.5, 0.0, 0.0)).await;
    let a = &b["arrival"];
    assert_eq!(a["stop_reason"], "left_floor", "{a}");
    assert_eq!(a["phase"], "slide", "{a}");
    let x = a["position_m"][0].as_f64().unwrap();
    assert!((x - 5.6).abs() < 1e-9, "left at x = {x}");
    // dropped 2 m from x = 5 with 1.5 m/s down the dip: the height above the floor is
    // 2 − g t²/2 (the velocity is parallel to the floor), so it comes down after 0.639 s at
    // x = 5 + 1.5 cos 30°·0.639 = 5.83, inside the hole
    let b = ok(&app, &hole_case(5.0, 2.0, 1.5)).await;
    let a = &b["arrival"];
    assert_eq!(a["stop_reason"], "left_floor", "{a}");
    assert_eq!(a["phase"], "flight", "{a}");
    let t_land = (2.0 * 2.0 / 9.81f64).sqrt();
    let x_land = 5.0 + 1.5 * 30f64.to_radians().cos() * t_land;
    let x = a["position_m"][0].as_f64().unwrap();
    assert!(
        (x - x_land).abs() < 1e-9,
        "left at x = {x}, expected {x_land}"
    );
    assert_eq!(b["impact_count"], 0);
    // with 3 m/s it comes down at x = 6.66, past the hole, and slides to the lower end
    let b = ok(&app, &hole_case(5.0, 2.0, 3.0)).await;
    assert_eq!(b["arrival"]["stop_reason"], "lower_end", "{}", b["arrival"]);
    let first = b["events"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["kind"] == "impact")
        .unwrap();
    let x = first["position_m"][0].as_f64().unwrap();
    let x_land = 5.0 + 3.0 * 30f64.to_radians().cos() * t_land;
    assert!((x - x_land).abs() < 1e-9, "first impact at x = {x}");
    // released over the hole: refused
    let r = post(&app, "/v1/migration", &hole_case(6.2, 1.0, 0.0)).await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/release/along_dip_m", "{p}");
    assert!(
        p["errors"][0]["message"].as_str().unwrap().contains("hole"),
        "{p}"
    );
}

/// The sample GeoJSON as the `contours` form.
fn sample_contours(g: &Value) -> Vec<Value> {
    g["features"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            json!({"elevation_m": f["properties"]["elevation"], "points_m": f["geometry"]["coordinates"]})
        })
        .collect()
}

#[tokio::test]
async fn geojson_contours_give_the_same_bits_as_the_contours_form() {
    let app = common::app();
    let g: Value = serde_json::from_str(&data("face_contours.geojson")).unwrap();
    let plain = ok(
        &app,
        &case(json!({"kind": "contours", "contours": sample_contours(&g)})),
    )
    .await;
    let geo = ok(
        &app,
        &case(json!({"kind": "contours", "geojson": g.clone()})),
    )
    .await;
    assert!(plain["impact_count"].as_u64().unwrap() >= 1, "{plain}");
    // the sample is in metres near the origin (within ±180 × ±90, but as wide as it is high):
    // not taken for longitude/latitude, so the answers are the same, warnings included
    let geo_results = results(geo.clone());
    assert!(
        geo_results["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .all(|w| w["code"] != "geographic_coordinates"),
        "{}",
        geo_results["warnings"]
    );
    assert_eq!(geo_results, results(plain.clone()));
    // echo: the hash of the floor object with sorted keys and defaults filled in
    let canonical = json!({"elevation_property": "elevation", "geojson": g,
                           "kind": "contours", "resolution_m": 1.0});
    assert_eq!(
        geo["inputs"]["face"]["floor"],
        json!({"kind": "contours", "sha256": hex(&serde_json::to_vec(&canonical).unwrap())})
    );
    // elevations as third coordinates, two lines in one MultiLineString, another property name
    let feats = g["features"].as_array().unwrap();
    let mut alt = Vec::new();
    let mut k = 0;
    while k < feats.len() {
        let with_z = |f: &Value| -> Value {
            let z = f["properties"]["elevation"].clone();
            f["geometry"]["coordinates"]
                .as_array()
                .unwrap()
                .iter()
                .map(|c| json!([c[0], c[1], z]))
                .collect()
        };
        if k + 1 < feats.len() && k % 3 == 0 {
            alt.push(json!({"type": "Feature", "properties": {"level": null},
                "geometry": {"type": "MultiLineString",
                             "coordinates": [with_z(&feats[k]), with_z(&feats[k + 1])]}}));
            k += 2;
        } else {
            alt.push(json!({"type": "Feature", "properties": {"level": feats[k]["properties"]["elevation"]},
                "geometry": feats[k]["geometry"]}));
            k += 1;
        }
    }
    let alt = json!({"type": "FeatureCollection", "features": alt});
    let b = ok(
        &app,
        &case(json!({"kind": "contours", "geojson": alt, "elevation_property": "level"})),
    )
    .await;
    assert_eq!(results(b)["arrival"], plain["arrival"]);
}

/// Face-frame contours of a curved 30° face whose smallest-x point is the origin (0, 0) at
/// elevation 0, so that `along_dip_m` starts there with and without map coordinates.
fn face_contours() -> Vec<(f64, Vec<[f64; 2]>)> {
    let t = 30f64.to_radians().tan();
    (0..=12)
        .map(|k| {
            let z = -2.0 * k as f64;
            let pts = (-8..=8)
                .map(|yi| {
                    let y = yi as f64;
                    let wiggle = if k == 0 {
                        0.0
                    } else {
                        0.2 * (0.5 * y + k as f64).sin()
                    };
                    [-z / t + 0.3 * (y / 8.0).powi(2) + wiggle, y]
                })
                .collect();
            (z, pts)
        })
        .collect()
}

/// Map coordinates [E, N] of the face point (x, y) for a face at `origin` with dip direction a.
fn to_map(origin: [f64; 2], a_deg: f64, p: [f64; 2]) -> [f64; 2] {
    let (s, c) = a_deg.to_radians().sin_cos();
    [
        origin[0] + s * p[0] - c * p[1],
        origin[1] + c * p[0] + s * p[1],
    ]
}

/// The same run compared to the rounding a rotation of UTM-sized coordinates leaves (about
/// 1e-9 m on 4e6 m): same impacts and stop, speeds and times within 1e-8 relative, positions
/// within 1e-7 m.
fn assert_same_run(a: &Value, b: &Value) {
    assert_eq!(a["impact_count"], b["impact_count"], "{a}\n{b}");
    let (x, y) = (&a["arrival"], &b["arrival"]);
    assert_eq!(x["stop_reason"], y["stop_reason"]);
    assert_eq!(x["phase"], y["phase"]);
    for k in ["speed_m_s", "time_s", "kinetic_energy_j"] {
        let (u, v) = (x[k].as_f64().unwrap(), y[k].as_f64().unwrap());
        assert!(rel(u, v) < 1e-8, "{k}: {u} vs {v}");
    }
    assert!((x["along_dip_m"].as_f64().unwrap() - y["along_dip_m"].as_f64().unwrap()).abs() < 1e-7);
    for i in 0..3 {
        let (u, v) = (
            x["position_m"][i].as_f64().unwrap(),
            y["position_m"][i].as_f64().unwrap(),
        );
        assert!((u - v).abs() < 1e-7, "position {i}: {u} vs {v}");
    }
}

#[tokio::test]
async fn contours_in_rotated_utm_map_coordinates_equal_the_face_frame_contours() {
    let app = common::app();
    let lines = face_contours();
    let plain: Vec<Value> = lines
        .iter()
        .map(|(z, p)| json!({"elevation_m": z, "points_m": p}))
        .collect();
    let body = |floor: Value| {
        json!({"face": {"dip_deg": 30, "length_m": 20, "floor": floor},
               "release": {"along_dip_m": 0.5, "drop_height_m": 1.0, "across_m": 0.3}})
    };
    let reference = ok(
        &app,
        &body(json!({"kind": "contours", "contours": plain, "resolution_m": 100})),
    )
    .await;
    assert!(reference["impact_count"].as_u64().unwrap() >= 1);
    for (origin, a) in [
        ([500123.25, 4200456.5], 37.0),
        ([387654.5, 6543210.75], 211.5),
        ([0.0, 0.0], 90.0),
    ] {
        let features: Vec<Value> = lines
            .iter()
            .map(|(z, p)| {
                let c: Vec<[f64; 2]> = p.iter().map(|q| to_map(origin, a, *q)).collect();
                json!({"type": "Feature", "properties": {"elevation": z},
                       "geometry": {"type": "LineString", "coordinates": c}})
            })
            .collect();
        let map = json!({"origin_m": origin, "dip_direction_deg": a});
        let b = ok(
            &app,
            &body(json!({"kind": "contours", "resolution_m": 100, "map": map,
                "geojson": {"type": "FeatureCollection", "features": features}})),
        )
        .await;
        assert_same_run(&b, &reference);
        assert_eq!(b["inputs"]["face"]["floor"]["map"], map);
        assert!(
            b["warnings"]
                .as_array()
                .unwrap()
                .iter()
                .all(|w| w["code"] != "geographic_coordinates"),
            "{}",
            b["warnings"]
        );
    }
}

/// A rough face-frame grid with column 0 at height 0 (so that the mean plane's reference height
/// is 0 however it is taken): 0.5 m spacing, 41 × 13 nodes from (0, 0).
fn rough_face_grid() -> Vec<Vec<f64>> {
    let t = 35f64.to_radians().tan();
    (0..13)
        .map(|i| {
            let y = 0.5 * i as f64;
            (0..41)
                .map(|j| {
                    let x = 0.5 * j as f64;
                    -x * t
                        + 0.08 * (1.7 * x).sin() * (1.1 * y).cos()
                        + 0.03 * (2.9 * x).sin() * (0.7 * y + 1.0).sin()
                })
                .collect()
        })
        .collect()
}

#[tokio::test]
async fn a_grid_in_map_coordinates_equals_the_face_frame_grid_shifted_or_turned_round() {
    let app = common::app();
    let g = rough_face_grid();
    let body = |floor: Value| {
        json!({"face": {"dip_deg": 35, "length_m": 15, "floor": floor},
               "release": {"along_dip_m": 0.7, "drop_height_m": 1.2, "across_m": 3.1}})
    };
    let reference = ok(
        &app,
        &body(json!({"kind": "grid", "origin_m": [0.0, 0.0], "spacing_m": 0.5, "heights_m": g})),
    )
    .await;
    assert!(reference["impact_count"].as_u64().unwrap() >= 1);
    // dip direction 90° (east): a translation of UTM-sized coordinates, exact: the same bits
    let e0 = [512345.5, 4234567.0];
    let b = ok(
        &app,
        &body(
            json!({"kind": "grid", "origin_m": e0, "spacing_m": 0.5, "heights_m": g,
                     "map": {"origin_m": e0, "dip_direction_deg": 90.0}}),
        ),
    )
    .await;
    assert_eq!(results(b), results(reference.clone()));
    // dip direction 270° (west): the face frame is the map turned by 180°, so the map grid is
    // the face grid reversed in both directions, its face origin at the map grid's north-east
    // corner; the grid becomes a mesh with the same triangles (the rotation rounds to 1e-16)
    let turned: Vec<Vec<f64>> = g
        .iter()
        .rev()
        .map(|r| r.iter().rev().copied().collect())
        .collect();
    let ne = [e0[0] + 20.0, e0[1] + 6.0];
    let b = ok(
        &app,
        &body(
            json!({"kind": "grid", "origin_m": e0, "spacing_m": 0.5, "heights_m": turned,
                     "map": {"origin_m": ne, "dip_direction_deg": 270.0}}),
        ),
    )
    .await;
    assert_same_run(&b, &reference);
}

#[tokio::test]
async fn a_plane_grid_turned_to_any_dip_direction_in_utm_coordinates_is_the_plane() {
    let app = common::app();
    let plane = ok(&app, &json!({"face": {"length_m": 30}})).await;
    let t = 45f64.to_radians().tan();
    for a in [0.0, 123.4, 301.7] {
        let o = [512345.5, 3987654.25];
        let (s, c) = f64::to_radians(a).sin_cos();
        // an 81 × 81 map grid at 1 m around the origin, falling at 45° towards azimuth a
        let heights: Vec<Vec<f64>> = (0..81)
            .map(|i| {
                (0..81)
                    .map(|j| {
                        let (de, dn) = (j as f64 - 40.0, i as f64 - 40.0);
                        -(de * s + dn * c) * t
                    })
                    .collect()
            })
            .collect();
        let b = ok(
            &app,
            &json!({"face": {"length_m": 30, "floor": {"kind": "grid",
                "origin_m": [o[0] - 40.0, o[1] - 40.0], "spacing_m": 1.0, "heights_m": heights,
                "map": {"origin_m": o, "dip_direction_deg": a}}}}),
        )
        .await;
        assert_eq!(b["impact_count"], plane["impact_count"], "{a}°");
        for k in ["speed_m_s", "time_s", "along_dip_m"] {
            let (u, v) = (
                b["arrival"][k].as_f64().unwrap(),
                plane["arrival"][k].as_f64().unwrap(),
            );
            assert!(rel(u, v) < 1e-9, "{a}°, {k}: {u} vs {v}");
        }
    }
}

#[tokio::test]
async fn utm_coordinates_without_map_are_refused_and_the_map_origin_must_be_on_the_floor() {
    let app = common::app();
    let g = rough_face_grid();
    let r = post(
        &app,
        "/v1/migration",
        &json!({"face": {"floor": {"kind": "grid", "origin_m": [512345.5, 4234567.0],
                                   "spacing_m": 0.5, "heights_m": g}}}),
    )
    .await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/face/floor/origin_m/1", "{p}");
    assert!(
        p["errors"][0]["message"]
            .as_str()
            .unwrap()
            .contains("map.origin_m")
    );
    // UTM: the grid's cell centres at E = 500001 … 500023, N = 4199993 … 4200007
    let asc = data("face_grid.asc")
        .replace("xllcorner    0.0", "xllcorner    500000.0")
        .replace("yllcorner    -8.0", "yllcorner    4199992.0");
    let r = post(
        &app,
        "/v1/migration",
        &case(json!({"kind": "grid", "esri_ascii": asc})),
    )
    .await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/face/floor/esri_ascii", "{p}");
    assert!(
        p["errors"][0]["message"]
            .as_str()
            .unwrap()
            .contains("map.origin_m")
    );
    // with map coordinates it runs: the sample grid, its along_dip_m measured from the map
    // origin (on its first column of centres) instead of the mean of that column, so the
    // release moves by millimetres and only the course of the run is compared
    let sample = ok(
        &app,
        &case(json!({"kind": "grid", "esri_ascii": data("face_grid.asc")})),
    )
    .await;
    let b = ok(
        &app,
        &case(json!({"kind": "grid", "esri_ascii": asc,
            "map": {"origin_m": [500001.0, 4200000.0], "dip_direction_deg": 90.0}})),
    )
    .await;
    assert_eq!(b["impact_count"], sample["impact_count"]);
    assert_eq!(
        b["arrival"]["stop_reason"],
        sample["arrival"]["stop_reason"]
    );
    // an origin off the floor is refused
    let r = post(
        &app,
        "/v1/migration",
        &case(json!({"kind": "grid", "esri_ascii": asc,
            "map": {"origin_m": [499990.0, 4200000.0], "dip_direction_deg": 90.0}})),
    )
    .await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/face/floor/map/origin_m", "{p}");
}

#[tokio::test]
async fn malformed_files_are_refused_naming_the_line_or_the_feature() {
    let app = common::app();
    let asc = data("face_grid.asc");
    let mut lines: Vec<String> = asc.lines().map(String::from).collect();
    let short = {
        let mut l = lines.clone();
        let row: Vec<&str> = l[8].split_whitespace().collect();
        l[8] = row[..11].join(" ");
        l.join("\n")
    };
    let bad_value = {
        let mut l = lines.clone();
        l[7] = l[7].replacen("-2.314", "-2.3.14", 1);
        l.join("\n")
    };
    lines.remove(1);
    let no_nrows = lines.join("\n");
    let g: Value = serde_json::from_str(&data("face_contours.geojson")).unwrap();
    let mut no_elevation = g.clone();
    no_elevation["features"][3]["properties"] = json!({"name": "unlabelled"});
    let mut polygon = g.clone();
    polygon["features"][0]["geometry"] = json!({"type": "Polygon", "coordinates": [[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 0.0]]]});
    let mut text_elevation = g.clone();
    text_elevation["features"][1]["properties"]["elevation"] = json!("-2 m");
    let cases: Vec<(Value, &str, &str)> = vec![
        (
            json!({"kind": "grid", "esri_ascii": short}),
            "/face/floor/esri_ascii",
            "line 9: expected 12 values, got 11",
        ),
        (
            json!({"kind": "grid", "esri_ascii": bad_value}),
            "/face/floor/esri_ascii",
            "line 8: value 3: '-2.3.14' is not a number",
        ),
        (
            json!({"kind": "grid", "esri_ascii": no_nrows}),
            "/face/floor/esri_ascii",
            "lacks nrows",
        ),
        (
            json!({"kind": "grid", "esri_ascii": asc, "spacing_m": 1.0}),
            "/face/floor/spacing_m",
            "ESRI ASCII",
        ),
        (
            json!({"kind": "contours", "geojson": no_elevation}),
            "/face/floor/geojson/features/3",
            "no elevation",
        ),
        (
            json!({"kind": "contours", "geojson": polygon}),
            "/face/floor/geojson/features/0/geometry/type",
            "LineString",
        ),
        (
            json!({"kind": "contours", "geojson": text_elevation}),
            "/face/floor/geojson/features/1/properties/elevation",
            "number",
        ),
        (
            json!({"kind": "contours", "geojson": {"type": "Feature"}}),
            "/face/floor/geojson",
            "FeatureCollection",
        ),
        (
            json!({"kind": "contours", "geojson": g, "map": {"origin_m": [0, 0], "dip_direction_deg": 360}}),
            "/face/floor/map/dip_direction_deg",
            "360",
        ),
    ];
    for (floor, field, message) in cases {
        let r = post(&app, "/v1/migration", &case(floor.clone())).await;
        let p = assert_problem(&r, 422, "invalid_input");
        let e = p["errors"]
            .as_array()
            .unwrap()
            .iter()
            .find(|e| e["field"] == field)
            .unwrap_or_else(|| panic!("{field} not named in {p}"));
        assert!(
            e["message"].as_str().unwrap().contains(message),
            "{field}: {} lacks {message:?}",
            e["message"]
        );
    }
}

#[tokio::test]
async fn an_esri_grid_is_measured_from_its_header_before_its_data_are_read() {
    // 1000 × 1000 cells need about 32 MB: over a 20 MB limit, refused from the header alone
    // (the text has a single data row, which would otherwise be a parse error)
    let app = gangue::app(gangue::config::Config {
        max_floor_bytes: 20_000_000,
        ..Default::default()
    });
    let text = format!(
        "ncols 1000\nnrows 1000\nxllcorner 0\nyllcorner 0\ncellsize 1\n{}\n",
        vec!["0"; 1000].join(" ")
    );
    let r = post(
        &app,
        "/v1/migration",
        &case(json!({"kind": "grid", "esri_ascii": text})),
    )
    .await;
    let p = assert_problem(&r, 422, "invalid_input");
    assert_eq!(p["errors"][0]["field"], "/face/floor/esri_ascii", "{p}");
    assert!(
        p["errors"][0]["message"].as_str().unwrap().contains("MB"),
        "{p}"
    );
}

/// The same contours in degrees (about 9e-6 ° per metre, near 8.7° E 46.6° N) are 100 times
/// steeper than any face in metres: they are taken for longitude/latitude and warned about.
#[tokio::test]
async fn contours_in_degrees_are_warned_about_as_geographic() {
    let app = common::app();
    let mut g: Value = serde_json::from_str(&data("face_contours.geojson")).unwrap();
    for f in g["features"].as_array_mut().unwrap() {
        for q in f["geometry"]["coordinates"].as_array_mut().unwrap() {
            let (x, y) = (q[0].as_f64().unwrap(), q[1].as_f64().unwrap());
            *q = json!([8.7 + 9e-6 * x, 46.6 + 9e-6 * y]);
        }
    }
    let r = post(
        &app,
        "/v1/migration",
        &json!({
            "face": {"dip_deg": 30, "length_m": 18, "floor": {"kind": "contours", "geojson": g}},
            "release": {"along_dip_m": 1.0, "drop_height_m": 1.5, "across_m": 46.6}
        }),
    )
    .await;
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let b = r.json();
    let w = b["warnings"].as_array().unwrap();
    assert!(
        w.iter().any(|w| w["code"] == "geographic_coordinates"),
        "{w:?}"
    );
}
