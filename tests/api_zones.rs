//! `face.zones` (floors of several materials) through the router: equal materials give the
//! one-material answer bit for bit in both methods, single runs and ensembles; a slide that
//! changes μ at a zone boundary against its closed form; restitution per zone; polygons in map
//! coordinates against the same polygons in face coordinates; the code grid; bad zones name
//! their pointer.

mod common;
use common::migrate_ok as ok;

use common::{post, rel};
use gangue::physics::migration::MapFrame;
use serde_json::{Value, json};

/// The answer without `inputs`, `meta` and the events' zone codes: what the physics gave.
fn physics_of(mut b: Value) -> Value {
    let o = b.as_object_mut().unwrap();
    o.remove("inputs");
    o.remove("meta");
    if let Some(ev) = o.get_mut("events").and_then(|e| e.as_array_mut()) {
        for e in ev {
            e.as_object_mut().unwrap().remove("zone");
        }
    }
    b
}

fn with_face(mut body: Value, key: &str, v: Value) -> Value {
    body["face"][key] = v;
    body
}

/// Polygons splitting a face at x = `x` (face coordinates): code 2 down-dip of it, code 1
/// (the outside) above.
fn split_at(x: f64) -> Value {
    json!([{"code": 2, "points_m": [[x, -1000.0], [2000.0, -1000.0], [2000.0, 1000.0], [x, 1000.0]]}])
}

#[tokio::test]
async fn equal_materials_give_the_one_material_answer_bit_for_bit() {
    let app = common::app();
    let lumped_ensemble = json!({"monte_carlo": {"runs": 40, "seed": 7,
        "friction_coefficient": {"distribution": "uniform", "min": 0.15, "max": 0.35}},
        "output": {"runs_csv": true}});
    let rigid = json!({"method": "rigid_block", "face": {"length_m": 12.0},
        "rock": {"shape": "cube", "side_length_m": 0.5}, "end_time_s": 1.5});
    let rigid_ensemble = json!({"method": "rigid_block", "face": {"length_m": 8.0},
        "rock": {"shape": "cube", "side_length_m": 0.5}, "end_time_s": 0.6,
        "monte_carlo": {"runs": 3, "seed": 3,
            "friction_coefficient": {"distribution": "uniform", "min": 0.15, "max": 0.35},
            "critical_damping_ratio": {"distribution": "uniform", "min": 0.2, "max": 0.5}}});
    for base in [
        json!({}),
        json!({"face": {"friction_coefficient": 0.35, "restitution_normal": 0.45}}),
        lumped_ensemble,
        rigid,
        rigid_ensemble,
    ] {
        let plain = ok(&app, &base).await;
        // two materials that name nothing are the face's material; so are two that repeat it
        let face = &base["face"];
        let mu = face["friction_coefficient"].as_f64().unwrap_or(0.2);
        let en = face["restitution_normal"].as_f64().unwrap_or(0.3);
        for materials in [
            json!([{"code": 1, "name": "scree"}, {"code": 2, "name": "meadow"}]),
            json!([{"code": 1}, {"code": 2, "friction_coefficient": mu, "restitution_normal": en,
                    "rigid_block": {"friction_coefficient": mu}}]),
        ] {
            let equal_explicit = materials[1].get("friction_coefficient").is_some();
            if equal_explicit && base.get("monte_carlo").is_some() {
                // a given μ is not drawn: equal only without an ensemble
                continue;
            }
            let mut zoned = base.clone();
            if zoned.get("face").is_none() {
                zoned["face"] = json!({});
            }
            let zoned = with_face(
                zoned,
                "zones",
                json!({"polygons": split_at(3.0), "materials": materials}),
            );
            let b = ok(&app, &zoned).await;
            assert_eq!(
                physics_of(b.clone()),
                physics_of(plain.clone()),
                "{base} with {materials}"
            );
            assert_eq!(b["inputs"]["face"]["zones"]["kind"], "polygons");
            assert_eq!(
                b["inputs"]["face"]["zones"]["sha256"]
                    .as_str()
                    .unwrap()
                    .len(),
                64
            );
            if let Some(ev) = b["events"].as_array() {
                assert!(
                    ev.iter().all(|e| e["zone"] == 1 || e["zone"] == 2),
                    "{ev:?}"
                );
            }
        }
        // without zones the answer has no zone field at all
        assert!(plain["inputs"]["face"].get("zones").is_none());
        if let Some(ev) = plain["events"].as_array() {
            assert!(ev.iter().all(|e| e.get("zone").is_none()));
        }
    }
}

/// A slide from rest on the 45° plane whose μ changes from μ₁ to μ₂ at along-dip s_b: the speed
/// at the lower end L is √(2 a₁ s_b + 2 a₂ (L − s_b)), aᵢ = g (sin θ − μᵢ cos θ).
#[tokio::test]
async fn a_slide_into_a_rougher_zone_reaches_the_closed_form_speed() {
    let app = common::app();
    let (th, g, l, sb) = (45f64.to_radians(), 9.81, 100.0, 40.0);
    for (mu1, mu2) in [(0.2, 0.5), (0.5, 0.2), (0.1, 0.9)] {
        let body = json!({"face": {"length_m": l, "friction_coefficient": mu1,
            "zones": {"polygons": split_at(sb * th.cos()),
                      "materials": [{"code": 1}, {"code": 2, "name": "meadow",
                                     "friction_coefficient": mu2}]}},
            "release": {"drop_height_m": 0.0}});
        let b = ok(&app, &body).await;
        let a = |mu: f64| g * (th.sin() - mu * th.cos());
        let v = (2.0 * a(mu1) * sb + 2.0 * a(mu2) * (l - sb)).sqrt();
        let got = b["arrival"]["speed_m_s"].as_f64().unwrap();
        assert!(rel(got, v) < 1e-9, "μ {mu1} → {mu2}: {got} vs {v}");
        assert_eq!(b["arrival"]["stop_reason"], "lower_end");
        // the friction booked is μ₁ g cos θ s_b + μ₂ g cos θ (L − s_b) per kg
        let m = b["rock"]["mass_kg"]
            .as_f64()
            .or_else(|| b["mass_kg"].as_f64())
            .unwrap();
        let fric = m * g * th.cos() * (mu1 * sb + mu2 * (l - sb));
        let booked = b["energy"]["friction_j"].as_f64().unwrap();
        assert!(rel(booked, fric) < 1e-9, "{booked} vs {fric}");
        assert!(b["energy"]["residual_j"].as_f64().unwrap().abs() < 1e-9 * fric);
        // and without the boundary (μ₁ everywhere) it is faster or slower as μ₂ says
        let one = ok(
            &app,
            &json!({"face": {"length_m": l, "friction_coefficient": mu1},
            "release": {"drop_height_m": 0.0}}),
        )
        .await;
        let v1 = one["arrival"]["speed_m_s"].as_f64().unwrap();
        assert_eq!(got < v1, mu2 > mu1);
    }
}

/// e_n = 0 under the release ends the bouncing at the first impact; e_n = 0.5 there bounces
/// as the face with e_n = 0.5 does, impact for impact, and each impact names zone 2.
#[tokio::test]
async fn restitution_is_the_struck_zone_s() {
    let app = common::app();
    let zone = |en: f64| {
        json!({"face": {"zones": {"polygons": [{"code": 2,
            "points_m": [[-10.0, -10.0], [10.0, -10.0], [10.0, 10.0], [-10.0, 10.0]]}],
            "outside_code": 1,
            "materials": [{"code": 1}, {"code": 2, "restitution_normal": en}]}}})
    };
    let dead = ok(&app, &zone(0.0)).await;
    assert_eq!(dead["impact_count"], 1);
    let live = ok(&app, &zone(0.5)).await;
    let face = ok(&app, &json!({"face": {"restitution_normal": 0.5}})).await;
    let plain = ok(&app, &json!({})).await;
    let n = live["impact_count"].as_u64().unwrap();
    assert!(n > 1 && n > dead["impact_count"].as_u64().unwrap());
    assert_ne!(face["impact_count"], plain["impact_count"]);
    // every impact of the bouncing lies within 10 m of the release: all on zone 2
    let impacts: Vec<&Value> = live["events"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["kind"] == "impact")
        .collect();
    assert_eq!(impacts.len() as u64, n);
    for e in &impacts {
        let x = e["position_m"][0].as_f64().unwrap();
        assert_eq!(e["zone"], if x.abs() < 10.0 { 2 } else { 1 }, "{e}");
    }
    // the bounces are the face's with e_n = 0.5; the slide beyond x = 10 m is cut there, which
    // moves the last bits only
    assert_eq!(live["impact_count"], face["impact_count"]);
    for k in ["speed_m_s", "time_s"] {
        let (u, v) = (
            live["arrival"][k].as_f64().unwrap(),
            face["arrival"][k].as_f64().unwrap(),
        );
        assert!(rel(u, v) < 1e-12, "{k}: {u} vs {v}");
    }
    // in an ensemble, a zone's e_n without a distribution holds at every impact
    let mut ens = zone(0.0);
    ens["monte_carlo"] = json!({"runs": 20});
    let b = ok(&app, &ens).await;
    assert_eq!(
        b["statistics"]["impact_count"]["max"], 1.0,
        "{}",
        b["statistics"]
    );
}

/// Polygons given in map coordinates on a grid floor with `map` (the 40° plane turned to an
/// azimuth, in UTM coordinates) and the same polygons moved into face coordinates by the map
/// frame on the plane: the same answer (the floors agree to 1e-9, the zones exactly).
#[tokio::test]
async fn polygons_in_map_coordinates_match_the_same_polygons_on_the_face() {
    let app = common::app();
    let (o, a) = ([512345.5, 3987654.25], 123.4f64);
    let (s, c) = a.to_radians().sin_cos();
    let t = 40f64.to_radians().tan();
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
    let floor = json!({"kind": "grid", "origin_m": [o[0] - 40.0, o[1] - 40.0], "spacing_m": 1.0,
        "heights_m": heights, "map": {"origin_m": o, "dip_direction_deg": a}});
    let frame = MapFrame {
        origin: o,
        dip_direction_deg: a,
    };
    // a band across the face 8 to 14 m down the dip, in map coordinates
    let band_face = [[8.0, -30.0], [14.0, -30.0], [14.0, 30.0], [8.0, 30.0]];
    let band_map: Vec<[f64; 2]> = band_face
        .iter()
        .map(|&[x, y]| {
            // the inverse of MapFrame::to_face
            [o[0] + x * s - y * c, o[1] + x * c + y * s]
        })
        .collect();
    let back: Vec<[f64; 2]> = band_map.iter().map(|&p| frame.to_face(p)).collect();
    let body = |pts: &Vec<[f64; 2]>| {
        json!({"face": {"length_m": 25, "dip_deg": 40, "floor": floor, "zones": {
            "polygons": [{"code": 2, "points_m": pts}],
            "materials": [{"code": 1}, {"code": 2, "friction_coefficient": 0.6,
                                        "restitution_normal": 0.05}]}}})
    };
    let in_map = ok(&app, &body(&band_map)).await;
    // on the plane (no map), the band in face coordinates gives the same along-dip story
    let on_plane = ok(
        &app,
        &json!({"face": {"length_m": 25, "dip_deg": 40, "zones": {
        "polygons": [{"code": 2, "points_m": back}],
        "materials": [{"code": 1}, {"code": 2, "friction_coefficient": 0.6,
                                    "restitution_normal": 0.05}]}}}),
    )
    .await;
    for k in ["speed_m_s", "time_s"] {
        let (u, v) = (
            in_map["arrival"][k].as_f64().unwrap(),
            on_plane["arrival"][k].as_f64().unwrap(),
        );
        assert!(rel(u, v) < 1e-9, "{k}: {u} vs {v}");
    }
    assert_eq!(in_map["impact_count"], on_plane["impact_count"]);
    // the band slows the rock: without zones it is faster
    let plain = ok(&app, &json!({"face": {"length_m": 25, "dip_deg": 40}})).await;
    assert!(
        plain["arrival"]["speed_m_s"].as_f64().unwrap()
            > in_map["arrival"]["speed_m_s"].as_f64().unwrap()
    );
}

/// An ESRI ASCII code grid splitting the face at x = 40 m gives the polygons' answer (to
/// rounding: the boundary is the same line, given by other end points).
#[tokio::test]
async fn a_code_grid_gives_the_polygons_answer() {
    let app = common::app();
    let (th, g, l) = (45f64.to_radians(), 9.81, 100.0);
    let asc = "ncols 10\nnrows 2\nxllcorner 0\nyllcorner -10\ncellsize 10\nNODATA_value -9999\n\
               1 1 1 1 2 2 2 2 2 2\n-9999 1 1 1 2 2 2 2 2 2\n";
    let mats = json!([{"code": 1}, {"code": 2, "friction_coefficient": 0.6}]);
    let grid = ok(
        &app,
        &json!({"face": {"length_m": l,
        "zones": {"esri_ascii": asc, "materials": mats}},
        "release": {"drop_height_m": 0.0}}),
    )
    .await;
    let poly = ok(&app, &json!({"face": {"length_m": l,
        "zones": {"polygons": [{"code": 2, "points_m": [[40, -10], [100, -10], [100, 10], [40, 10]]}],
                  "materials": mats}},
        "release": {"drop_height_m": 0.0}}))
    .await;
    let (u, v) = (
        grid["arrival"]["speed_m_s"].as_f64().unwrap(),
        poly["arrival"]["speed_m_s"].as_f64().unwrap(),
    );
    assert!(rel(u, v) < 1e-12, "{u} vs {v}");
    let sb = 40.0 / th.cos();
    let a = |mu: f64| g * (th.sin() - mu * th.cos());
    let want = (2.0 * a(0.2) * sb + 2.0 * a(0.6) * (l - sb)).sqrt();
    assert!(rel(u, want) < 1e-9, "{u} vs {want}");
    assert_eq!(grid["inputs"]["face"]["zones"]["kind"], "esri_ascii");
}

/// The rigid block takes each contact's zone: a cube sliding down a 30° plane (μ 0.2) into a
/// zone of μ 0.9 (> tan 30°) stops in it, past the boundary, where the one-material cube slides
/// on to the lower end; a μ given for the block alone does the same.
#[tokio::test]
async fn the_rigid_block_takes_each_contact_s_zone() {
    let app = common::app();
    let th = 30f64.to_radians();
    let sb = 4.0;
    let base = json!({"method": "rigid_block", "rock": {"shape": "cube", "side_length_m": 0.5},
        "face": {"dip_deg": 30, "length_m": 12.0},
        "release": {"drop_height_m": 0.0, "speed_m_s": 2.0}, "end_time_s": 6.0});
    let plain = ok(&app, &base).await;
    assert_eq!(
        plain["arrival"]["stop_reason"], "lower_end",
        "{}",
        plain["arrival"]
    );
    let zoned = with_face(
        base.clone(),
        "zones",
        json!({"polygons": split_at(sb * th.cos()),
               "materials": [{"code": 1}, {"code": 2, "friction_coefficient": 0.9}]}),
    );
    let b = ok(&app, &zoned).await;
    assert_eq!(b["arrival"]["stop_reason"], "at_rest", "{}", b["arrival"]);
    let s = b["arrival"]["along_dip_m"].as_f64().unwrap();
    assert!(s > sb && s < 12.0, "{s}");
    // μ given for the block alone acts the same
    let block_only = with_face(
        base.clone(),
        "zones",
        json!({"polygons": split_at(sb * th.cos()),
               "materials": [{"code": 1},
                             {"code": 2, "rigid_block": {"friction_coefficient": 0.9}}]}),
    );
    let c = ok(&app, &block_only).await;
    assert_eq!(physics_of(c), physics_of(b.clone()));
    let e = &b["energy"];
    let total = e["total_start_j"].as_f64().unwrap();
    assert!(
        e["residual_j"].as_f64().unwrap().abs() < 2e-3 * total,
        "{e}"
    );
}

#[tokio::test]
async fn bad_zones_name_their_pointer() {
    let app = common::app();
    let square = json!([[0, 0], [1, 0], [1, 1], [0, 1]]);
    for (zones, pointer, words) in [
        (
            json!({"polygons": [{"code": 1, "points_m": square}],
                   "materials": [{"code": 1}, {"code": 1}]}),
            "/face/zones/materials/1/code",
            "duplicate",
        ),
        (
            json!({"polygons": [{"code": 1, "points_m": [[0, 0], [1, 0]]}],
                   "materials": [{"code": 1}]}),
            "/face/zones/polygons/0/points_m",
            "at least 3",
        ),
        (
            json!({"polygons": [{"code": 1, "points_m": [[0, 0], [1, 1], [1, 0], [0, 1]]}],
                   "materials": [{"code": 1}]}),
            "/face/zones/polygons/0/points_m",
            "intersects itself",
        ),
        (
            json!({"polygons": [{"code": 3, "points_m": square}], "materials": [{"code": 1}]}),
            "/face/zones/polygons/0/code",
            "no material",
        ),
        (
            json!({"polygons": [{"code": 1, "points_m": square}],
                   "materials": [{"code": 1, "friction_coefficient": 2.5}]}),
            "/face/zones/materials/0/friction_coefficient",
            "[0, 2]",
        ),
        (
            json!({"polygons": [{"code": 1, "points_m": square}],
                   "materials": [{"code": 1, "rigid_block": {"normal_stiffness_n_m": 10.0}}]}),
            "/face/zones/materials/0/rigid_block/normal_stiffness_n_m",
            "must be in [1000, 1e12]",
        ),
        (
            json!({"polygons": [{"code": 1, "points_m": square}],
                   "materials": [{"code": 1, "restitution_normal_distribution":
                                  {"distribution": "uniform", "min": 0.2, "max": 1.4}}]}),
            "/face/zones/materials/0/restitution_normal_distribution/max",
            "[0, 1]",
        ),
        (
            json!({"esri_ascii": "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 1\n1 2.5\n",
                   "materials": [{"code": 1}]}),
            "/face/zones/esri_ascii",
            "line 7: value 2: '2.5' is not an integer code",
        ),
        (
            json!({"esri_ascii": "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 7\n1 1\n",
                   "materials": [{"code": 1}]}),
            "/face/zones/esri_ascii",
            "code 7 on the grid has no material",
        ),
        (
            json!({"polygons": [{"code": 1, "points_m": square}],
                   "outside_code": 9, "materials": [{"code": 1}]}),
            "/face/zones/outside_code",
            "no material",
        ),
        (json!({"materials": [{"code": 1}]}), "/face/zones", "one of"),
        (
            json!({"polygons": [{"code": 1, "points_m": square}], "materials": []}),
            "/face/zones/materials",
            "1 to 64",
        ),
    ] {
        let r = post(&app, "/v1/migration", &json!({"face": {"zones": zones}})).await;
        assert_eq!(
            r.status,
            422,
            "{zones}: {}",
            String::from_utf8_lossy(&r.body)
        );
        let b = r.json();
        let errs = b["errors"].as_array().unwrap();
        assert!(
            errs.iter()
                .any(|e| e["field"] == pointer && e["message"].as_str().unwrap().contains(words)),
            "{zones}: {errs:?}"
        );
    }
    // too many vertices
    let many: Vec<[f64; 2]> = (0..10_001)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 10_001.0;
            [a.cos(), a.sin()]
        })
        .collect();
    let r = post(
        &app,
        "/v1/migration",
        &json!({"face": {"zones": {
        "polygons": [{"code": 1, "points_m": many}], "materials": [{"code": 1}]}}}),
    )
    .await;
    assert_eq!(r.status, 422);
    assert_eq!(r.json()["errors"][0]["field"], "/face/zones/polygons");
}

#[tokio::test]
async fn scenes_take_zones_through_the_face() {
    let app = common::app();
    let zones = json!({"polygons": split_at(30.0),
        "materials": [{"code": 1}, {"code": 2, "friction_coefficient": 0.9}]});
    let plain = post(&app, "/v1/scene", &json!({"monte_carlo": {"runs": 20}})).await;
    assert_eq!(
        plain.status,
        200,
        "{}",
        String::from_utf8_lossy(&plain.body)
    );
    let zoned = post(
        &app,
        "/v1/scene",
        &json!({"monte_carlo": {"runs": 20}, "face": {"zones": zones}}),
    )
    .await;
    assert_eq!(
        zoned.status,
        200,
        "{}",
        String::from_utf8_lossy(&zoned.body)
    );
    let (p, z) = (plain.json(), zoned.json());
    assert_eq!(z["inputs"]["face"]["zones"]["kind"], "polygons");
    assert_ne!(p["statistics"], z["statistics"]);
    assert_ne!(p["migration"], z["migration"]);
}
