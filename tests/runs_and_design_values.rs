//! Each run as it happened (the per-run CSV's release point, drawn rock, stop position and
//! energies) and the design values at each support (data collectors), through the router.
//!
//! Expectations: release points lie in their zones and across ranges, drawn sizes and
//! densities within their distributions' bounds; the stop position agrees with the runout
//! (lumped mass: stop − release = runout, bit for bit on the plane; rigid block: the runout is
//! measured from the centre at release, drop·sin θ up the dip) and with the stop reason (at a
//! column: at the distance reach = column radius + the rock's bounding radius from its axis; at
//! the lower end: at the face's length). Each support's design values are recomputed from the
//! CSV by sorting (type-7 percentiles) and their 95 % intervals from binomial terms summed here;
//! a sliding lumped mass on the plane passes at height 0 with no rotational energy and the
//! translational energy m g s (sin θ − μ cos θ); a rolling one carries ½ (2/5 m r²) ω² = m v²/5.

mod common;
use common::ok;

use common::{post, rel};
use serde_json::{Value, json};

/// The CSV as its header and rows of cells.
struct Csv {
    head: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Csv {
    fn parse(text: &str) -> Self {
        let mut lines = text.lines();
        let head = lines.next().unwrap().split(',').map(String::from).collect();
        let rows = lines
            .map(|l| l.split(',').map(String::from).collect())
            .collect();
        Self { head, rows }
    }

    fn col(&self, name: &str) -> usize {
        self.head
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", self.head))
    }

    fn num(&self, row: &[String], name: &str) -> f64 {
        let c = &row[self.col(name)];
        c.parse()
            .unwrap_or_else(|_| panic!("{name}: {c:?} is not a number"))
    }

    fn text<'a>(&self, row: &'a [String], name: &str) -> &'a str {
        &row[self.col(name)]
    }
}

/// The columns every runs CSV appends after its documented ones, in order.
const RUN_COLUMNS: [&str; 8] = [
    "release_along_dip_m",
    "release_across_m",
    "side_length_m",
    "density_kg_m3",
    "stop_along_dip_m",
    "stop_across_m",
    "translational_energy_j",
    "rotational_energy_j",
];

#[tokio::test]
async fn a_migration_runs_csv_says_where_each_run_started_and_stopped() {
    let app = common::app();
    let req = json!({
        "release": {"along_dip_m": 10.0, "across_m": 0.4},
        "monte_carlo": {"runs": 300, "seed": 5,
            "friction_coefficient": {"distribution": "uniform", "min": 0.2, "max": 1.2}},
        "output": {"runs_csv": true},
    });
    let b = ok(&post(&app, "/v1/migration", &req).await);
    let csv = Csv::parse(b["runs_csv"].as_str().unwrap());
    // api.md's nine columns first and unmoved, then the run columns
    assert_eq!(
        csv.head[..9].join(","),
        "run,time_s,speed_m_s,kinetic_energy_j,impact_count,runout_m,max_bounce_height_m,stop_reason,along_dip_velocity_m_s"
    );
    assert_eq!(csv.head[9..], RUN_COLUMNS);
    assert_eq!(csv.rows.len(), 300);
    let mut reasons = std::collections::BTreeSet::new();
    for r in &csv.rows {
        // nothing drawn: the request's release and rock in every run
        assert_eq!(csv.num(r, "release_along_dip_m"), 10.0);
        assert_eq!(csv.num(r, "release_across_m"), 0.4);
        assert_eq!(csv.num(r, "side_length_m"), 0.3);
        assert_eq!(csv.num(r, "density_kg_m3"), 2500.0);
        let stop = csv.num(r, "stop_along_dip_m");
        // the runout is the stop minus the release, bit for bit (plane floor, lumped mass)
        assert_eq!(stop - 10.0, csv.num(r, "runout_m"), "{r:?}");
        // on the plane nothing pushes the rock across
        assert!((csv.num(r, "stop_across_m") - 0.4).abs() <= 1e-12, "{r:?}");
        let reason = csv.text(r, "stop_reason");
        reasons.insert(reason.to_string());
        match reason {
            "lower_end" => assert!((stop - 120.0).abs() <= 1e-9 * 120.0, "{r:?}"),
            "at_rest" => assert!(stop > 10.0 && stop < 120.0, "{r:?}"),
            other => panic!("unexpected stop reason {other}"),
        }
        // sliding: no rotation; the kinetic energy is the translational one
        assert_eq!(csv.num(r, "rotational_energy_j"), 0.0);
        let (ke, kt) = (
            csv.num(r, "kinetic_energy_j"),
            csv.num(r, "translational_energy_j"),
        );
        assert!(rel(kt, ke) <= 1e-12, "{kt} against {ke}");
        let v = csv.num(r, "speed_m_s");
        assert!(rel(kt, 0.5 * 2500.0 * 0.027 * v * v) <= 1e-12);
    }
    assert_eq!(
        reasons.len(),
        2,
        "both lower-end and at-rest runs: {reasons:?}"
    );
}

/// The scene of the checks below: two rows of three columns 10 m apart, two release zones
/// upstream, the release across, the side length and the density drawn.
fn zoned_scene(runs: u64, percentile: f64) -> Value {
    json!({
        "face": {"length_m": 60},
        "support_rows": {"lowest_along_dip_m": 50, "spacing_m": 10, "count": 2,
                         "across_m": [-1.5, 0, 1.5]},
        "release_zones": [{"from_along_dip_m": 5, "to_along_dip_m": 15, "weight": 1},
                          {"from_along_dip_m": 25, "to_along_dip_m": 30, "weight": 2}],
        "monte_carlo": {"runs": runs, "seed": 3,
            "release_across_m": {"distribution": "uniform", "min": -2.25, "max": 2.25},
            "side_length_m": {"distribution": "uniform", "min": 0.2, "max": 0.3},
            "density_kg_m3": {"distribution": "uniform", "min": 2000, "max": 3000}},
        "contact": {"law": "hertz_point"},
        "design_percentile": percentile,
        "migration_output": {"runs_csv": true},
    })
}

#[tokio::test]
async fn scene_runs_start_in_their_zones_and_stop_where_their_stop_reason_says() {
    let app = common::app();
    let b = ok(&post(&app, "/v1/scene", &zoned_scene(400, 0.95)).await);
    let csv = Csv::parse(b["migration"]["runs_csv"].as_str().unwrap());
    // api.md's columns, the scene's, then the run columns and the passing height
    assert_eq!(
        csv.head[9..16].join(","),
        "support,column_index,impact_velocity_m_s,max_force_n,absorbed_energy_j,stress_utilisation,capacity_exceeded"
    );
    assert_eq!(csv.head[16..24], RUN_COLUMNS);
    assert_eq!(csv.head[24..], ["passing_height_m"]);
    let (mut at_column, mut at_end) = (0, 0);
    let (mut zone1, mut sides, mut dens) = (0, Vec::new(), Vec::new());
    for r in &csv.rows {
        let s0 = csv.num(r, "release_along_dip_m");
        assert!(
            (5.0..=15.0).contains(&s0) || (25.0..=30.0).contains(&s0),
            "release {s0}"
        );
        zone1 += usize::from(s0 <= 15.0);
        let y0 = csv.num(r, "release_across_m");
        assert!((-2.25..=2.25).contains(&y0), "across {y0}");
        let l = csv.num(r, "side_length_m");
        assert!((0.2..=0.3).contains(&l), "side {l}");
        let rho = csv.num(r, "density_kg_m3");
        assert!((2000.0..=3000.0).contains(&rho), "density {rho}");
        sides.push(l);
        dens.push(rho);
        let stop = csv.num(r, "stop_along_dip_m");
        assert_eq!(stop - s0, csv.num(r, "runout_m"), "{r:?}");
        let kt = csv.num(r, "translational_energy_j");
        let v = csv.num(r, "speed_m_s");
        assert!(
            rel(kt, 0.5 * rho * l * l * l * v * v) <= 1e-12,
            "the drawn mass"
        );
        match csv.text(r, "stop_reason") {
            "support" => {
                at_column += 1;
                let k = csv.num(r, "support");
                let j = csv.num(r, "column_index") as usize;
                let (a, y) = (50.0 - (k - 1.0) * 10.0, [-1.5, 0.0, 1.5][j]);
                // reached at the column's radius plus the cube's bounding radius √3·L/2
                let reach = 0.125 + 3f64.sqrt() * l / 2.0;
                let d = (stop - a).hypot(csv.num(r, "stop_across_m") - y);
                assert!(
                    (d - reach).abs() <= 1e-6 * reach,
                    "{d} against {reach}: {r:?}"
                );
                let h = csv.num(r, "passing_height_m");
                assert!(h >= 0.0 && h.is_finite(), "{h}");
            }
            "lower_end" => {
                at_end += 1;
                assert!((stop - 60.0).abs() <= 1e-9 * 60.0, "{r:?}");
                assert_eq!(csv.text(r, "passing_height_m"), "");
            }
            other => assert_eq!(csv.text(r, "passing_height_m"), "", "{other}"),
        }
    }
    assert!(
        at_column > 40 && at_end > 40,
        "{at_column} at columns, {at_end} at the end"
    );
    // the zones' weights 1 : 2 (400 runs: 133 expected in the first, ±5σ)
    assert!((zone1 as f64 - 400.0 / 3.0).abs() < 5.0 * (400.0f64 * 2.0 / 9.0).sqrt());
    // the draws spread over their ranges
    let spread = |v: &[f64]| {
        v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - v.iter().copied().fold(f64::INFINITY, f64::min)
    };
    assert!(spread(&sides) > 0.09 && spread(&dens) > 900.0);
}

/// P(B ≤ k) for B ~ Binomial(n, p), by summing the terms.
fn binomial_cdf(n: u64, p: f64, k: u64) -> f64 {
    let ln_choose = |j: u64| -> f64 {
        (1..=j)
            .map(|i| ((n - j + i) as f64).ln() - (i as f64).ln())
            .sum()
    };
    (0..=k)
        .map(|j| (ln_choose(j) + j as f64 * p.ln() + (n - j) as f64 * (1.0 - p).ln()).exp())
        .sum()
}

#[tokio::test]
async fn design_values_are_what_the_runs_csv_gives() {
    let app = common::app();
    let p = 0.9;
    let b = ok(&post(&app, "/v1/scene", &zoned_scene(400, p)).await);
    let csv = Csv::parse(b["migration"]["runs_csv"].as_str().unwrap());
    let runs = b["statistics"]["runs"].as_f64().unwrap();
    let mut checked = 0;
    let mut with_upper = 0;
    for s in b["statistics"]["supports"].as_array().unwrap() {
        let (k, j) = (s["support"].to_string(), s["column_index"].to_string());
        let rows: Vec<&Vec<String>> = csv
            .rows
            .iter()
            .filter(|r| csv.text(r, "support") == k && csv.text(r, "column_index") == j)
            .collect();
        let dv = &s["design_values"];
        if rows.is_empty() {
            assert!(dv.is_null(), "{s}");
            continue;
        }
        checked += 1;
        assert_eq!(dv["design_percentile"], p);
        let n = rows.len() as u64;
        assert_eq!(
            s["reached_fraction"].as_f64().unwrap(),
            n as f64 / runs,
            "every run that reached it counts"
        );
        for (field, column) in [
            ("impact_speed_m_s", "impact_velocity_m_s"),
            ("kinetic_energy_j", "kinetic_energy_j"),
            ("translational_energy_j", "translational_energy_j"),
            ("rotational_energy_j", "rotational_energy_j"),
            ("passing_height_m", "passing_height_m"),
        ] {
            let d = &dv[field];
            let values: Vec<f64> = rows.iter().map(|r| csv.num(r, column)).collect();
            let mut sorted = values.clone();
            sorted.sort_by(f64::total_cmp);
            assert_eq!(d["count"], n, "{field}");
            let mean = values.iter().sum::<f64>() / n as f64;
            let sm = &d["summary"];
            assert!(
                (sm["mean"].as_f64().unwrap() - mean).abs() <= 1e-12 * mean.abs().max(1e-300),
                "{field} mean"
            );
            for (key, q) in [("p50", 0.5), ("p95", 0.95), ("p99", 0.99)] {
                assert_eq!(
                    sm[key].as_f64().unwrap(),
                    common::type7(&sorted, q),
                    "{field} {key}"
                );
            }
            assert_eq!(sm["max"].as_f64().unwrap(), sorted[sorted.len() - 1]);
            assert_eq!(
                d["design_value"].as_f64().unwrap(),
                common::type7(&sorted, p),
                "{field}"
            );
            // the interval: l the largest rank with P(B ≤ l − 1) ≤ 2.5 %, u the smallest with
            // P(B ≤ u − 1) ≥ 97.5 %, B ~ Binomial(n, p); null where no rank qualifies
            let l = (1..=n).rev().find(|&l| binomial_cdf(n, p, l - 1) <= 0.025);
            let u = (1..=n).find(|&u| binomial_cdf(n, p, u - 1) >= 0.975);
            let at = |r: Option<u64>| r.map_or(Value::Null, |r| json!(sorted[r as usize - 1]));
            assert_eq!(d["design_ci95"][0], at(l), "{field} lower, n {n}");
            assert_eq!(d["design_ci95"][1], at(u), "{field} upper, n {n}");
            with_upper += usize::from(u.is_some());
            if field == "passing_height_m" {
                assert!(sorted[0] >= 0.0);
            }
        }
    }
    assert!(checked >= 3, "{checked} supports reached");
    assert!(
        with_upper > 0,
        "some support reached often enough for an upper bound"
    );
}

/// One spanning support at 20 m of a 30 m face at 40°, μ = 0.3, the rock released on the floor
/// (no flight, no impact): every run is the same slide or roll.
fn slide_scene(motion: &str) -> Value {
    json!({
        "face": {"dip_deg": 40, "length_m": 30, "friction_coefficient": 0.3},
        "release": {"drop_height_m": 0},
        "lumped_mass": {"motion": motion},
        "supports": [{"along_dip_m": 20}],
        "monte_carlo": {"runs": 5, "seed": 1},
        "contact": {"law": "hertz_point"},
    })
}

#[tokio::test]
async fn a_sliding_lumped_mass_passes_at_height_zero_with_the_closed_form_energy() {
    let app = common::app();
    let b = ok(&post(&app, "/v1/scene", &slide_scene("slide")).await);
    let s = &b["statistics"]["supports"][0];
    assert_eq!(s["reached_fraction"], 1.0);
    let dv = &s["design_values"];
    let (g, th, mu, dist) = (9.81, 40f64.to_radians(), 0.3, 20.0);
    let m = 2500.0 * 0.3f64.powi(3);
    // ½ m v² = m g s (sin θ − μ cos θ) on the plane
    let et = m * g * dist * (th.sin() - mu * th.cos());
    let q = "design_value";
    assert!(rel(dv["translational_energy_j"][q].as_f64().unwrap(), et) <= 1e-9);
    assert!(rel(dv["kinetic_energy_j"][q].as_f64().unwrap(), et) <= 1e-9);
    let v = (2.0 * et / m).sqrt();
    assert!(rel(dv["impact_speed_m_s"][q].as_f64().unwrap(), v) <= 1e-9);
    assert_eq!(dv["rotational_energy_j"][q], 0.0);
    assert_eq!(dv["passing_height_m"][q], 0.0);
    assert_eq!(dv["passing_height_m"]["summary"]["max"], 0.0);
    assert_eq!(dv["rotational_energy_j"]["summary"]["max"], 0.0);
    // five runs bound the 95th percentile from below (P(B ≤ 3) = 0.0226 ≤ 2.5 %: X₍₄₎) but not
    // from above (P(B ≤ 4) = 1 − 0.95⁵ < 97.5 %)
    assert_eq!(dv["passing_height_m"]["design_ci95"], json!([0.0, null]));
}

#[tokio::test]
async fn a_rolling_lumped_mass_carries_the_rolling_spheres_rotational_energy() {
    let app = common::app();
    let b = ok(&post(&app, "/v1/scene", &slide_scene("roll")).await);
    let dv = &b["statistics"]["supports"][0]["design_values"];
    let (g, th, dist) = (9.81, 40f64.to_radians(), 20.0);
    let m = 2500.0 * 0.3f64.powi(3);
    // rolling without slip loses nothing: m g s sin θ, of which 2/7 is rotation
    let total = m * g * dist * th.sin();
    let v = dv["impact_speed_m_s"]["design_value"].as_f64().unwrap();
    let (et, er) = (
        dv["translational_energy_j"]["design_value"]
            .as_f64()
            .unwrap(),
        dv["rotational_energy_j"]["design_value"].as_f64().unwrap(),
    );
    assert!(rel(et, 5.0 / 7.0 * total) <= 1e-9, "{et}");
    assert!(rel(er, 2.0 / 7.0 * total) <= 1e-9, "{er}");
    // ½ I ω² of a sphere of any radius r rolling at v: I = 2/5 m r², ω = v/r
    let r = 0.15;
    let sphere = 0.5 * (0.4 * m * r * r) * (v / r).powi(2);
    assert!(rel(er, sphere) <= 1e-12, "{er} against {sphere}");
    assert!(
        rel(
            dv["kinetic_energy_j"]["design_value"].as_f64().unwrap(),
            total
        ) <= 1e-9
    );
    assert_eq!(dv["passing_height_m"]["design_value"], 0.0);
}

#[tokio::test]
async fn a_rigid_block_measures_its_runout_from_its_centre_and_passes_above_the_floor() {
    let app = common::app();
    let drop = 0.5;
    let th = 35f64.to_radians();
    let b = ok(&post(
        &app,
        "/v1/scene",
        &json!({
            "method": "rigid_block",
            "face": {"dip_deg": 35, "length_m": 8, "friction_coefficient": 0.4},
            "release": {"drop_height_m": drop, "along_dip_m": 1.0},
            "supports": [{"along_dip_m": 6}],
            "monte_carlo": {"runs": 4, "seed": 2},
            "contact": {"law": "hertz_point"},
            "migration_output": {"runs_csv": true},
        }),
    )
    .await);
    let csv = Csv::parse(b["migration"]["runs_csv"].as_str().unwrap());
    for r in &csv.rows {
        assert_eq!(csv.text(r, "stop_reason"), "support");
        let (s0, stop) = (
            csv.num(r, "release_along_dip_m"),
            csv.num(r, "stop_along_dip_m"),
        );
        assert_eq!(s0, 1.0);
        // the centre at release is drop·sin θ up the dip of the floor point
        let runout = csv.num(r, "runout_m");
        assert!(
            (stop - s0 - (runout - drop * th.sin())).abs() <= 1e-9,
            "{r:?}"
        );
        // a spanning support is reached where the centre passes its line
        assert!((stop - 6.0).abs() <= 1e-9 * 6.0 + 1e-3, "{stop}");
        let h = csv.num(r, "passing_height_m");
        assert!((0.0..0.5).contains(&h), "{h}");
        let (ke, kt, kr) = (
            csv.num(r, "kinetic_energy_j"),
            csv.num(r, "translational_energy_j"),
            csv.num(r, "rotational_energy_j"),
        );
        assert!(kr >= 0.0 && rel(kt + kr, ke) <= 1e-12);
    }
    let dv = &b["statistics"]["supports"][0]["design_values"];
    assert_eq!(dv["passing_height_m"]["count"], 4);
}

#[tokio::test]
async fn a_design_percentile_outside_its_range_is_refused_naming_it() {
    let app = common::app();
    for bad in [0.4, 1.0, 0.9991] {
        let r = post(&app, "/v1/scene", &json!({"design_percentile": bad})).await;
        let p = common::assert_problem(&r, 422, "invalid_input");
        let e = &p["errors"][0];
        assert_eq!(e["field"], "/design_percentile", "{p}");
        assert_eq!(e["value"], bad);
        assert!(
            e["message"].as_str().unwrap().contains("[0.5, 0.999]"),
            "{p}"
        );
    }
    common::assert_rejections(
        &app,
        "/v1/scene",
        vec![(
            json!({"design_percentile": null}),
            "/design_percentile",
            "invalid_type",
        )],
    )
    .await;
    // the bounds themselves are accepted, and echoed
    for good in [0.5, 0.999] {
        let r = post(&app, "/v1/scene", &json!({"design_percentile": good})).await;
        assert_eq!(ok(&r)["inputs"]["design_percentile"], good);
    }
}
