//! Runs every case of `../shared/verification/cases.json` through the router and compares each
//! expected value at its JSON Pointer with the case's tolerance (|got − exp| ≤ abs + rel·|exp|).
//! Cases for endpoints not built yet are listed in `PENDING`, in this one place.

mod common;

use serde_json::Value;

/// Cases whose endpoint or method is not implemented yet, with the reason.
const PENDING: &[(&str, &str)] = &[];

fn cases() -> Vec<Value> {
    let path = common::shared_dir().join("verification/cases.json");
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let doc: Value = serde_json::from_str(&text).expect("cases.json is JSON");
    doc["cases"].as_array().expect("cases array").clone()
}

fn compare(id: &str, body: &Value, case: &Value) -> Vec<String> {
    let mut failures = Vec::new();
    let expected = case["expected"].as_object().expect("expected object");
    for (ptr, exp) in expected {
        let got = body.pointer(ptr);
        let tol = &case["tolerance"][ptr];
        match (got, tol) {
            (None, _) => failures.push(format!("{id} {ptr}: missing (expected {exp})")),
            (Some(g), Value::String(s)) if s == "exact" => {
                if g != exp {
                    failures.push(format!("{id} {ptr}: got {g}, expected exactly {exp}"));
                }
            }
            (Some(g), tol) => {
                let (Some(g), Some(e)) = (g.as_f64(), exp.as_f64()) else {
                    if g != exp {
                        failures.push(format!("{id} {ptr}: got {g}, expected {exp}"));
                    }
                    continue;
                };
                let r = tol["rel"].as_f64().unwrap_or(0.0);
                let a = tol["abs"].as_f64().unwrap_or(0.0);
                let bound = a + r * e.abs();
                let within = (g - e).abs() <= bound;
                if !within {
                    failures.push(format!(
                        "{id} {ptr}: got {g:e}, expected {e:e} (|Δ| = {:e} > {bound:e})",
                        (g - e).abs()
                    ));
                }
            }
        }
    }
    failures
}

#[tokio::test]
async fn verification_cases() {
    let app = common::app();
    let mut failures = Vec::new();
    let mut ran = Vec::new();
    for case in cases() {
        let id = case["id"].as_str().unwrap().to_string();
        let Some(endpoint) = case["endpoint"].as_str() else {
            // `analytic:` cases are reference numbers for the solvers' own tests.
            assert!(
                case["kind"].as_str().unwrap_or("").starts_with("analytic:"),
                "{id}"
            );
            continue;
        };
        if PENDING.iter().any(|(p, _)| *p == id) {
            continue;
        }
        let r = common::post(&app, endpoint, &case["request"]).await;
        if let Some(err) = case.get("expect_error") {
            let status = err["status"].as_u64().unwrap() as u16;
            let suffix = err["type_suffix"].as_str().unwrap();
            let body = r.json();
            if r.status.as_u16() != status || !body["type"].as_str().unwrap_or("").ends_with(suffix)
            {
                failures.push(format!(
                    "{id}: expected {status} …{suffix}, got {} {body}",
                    r.status
                ));
            }
        } else if r.status != 200 {
            failures.push(format!(
                "{id}: status {} {}",
                r.status,
                String::from_utf8_lossy(&r.body)
            ));
        } else {
            failures.extend(compare(&id, &r.json(), &case));
        }
        ran.push(id);
    }
    eprintln!("verification: ran {} cases: {}", ran.len(), ran.join(", "));
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
    // The cases this suite must cover now.
    for id in [
        "P01_contact_paper_base",
        "P02_contact_paper_twobody_lowcorner",
        "P03_contact_johnson_base",
        "P04_contact_hertz_point",
        "P14_capacity_error",
        "P12_table1",
        "P13_sensitivity_paper",
        "P15_dem_cube_slide_1s",
    ] {
        assert!(ran.iter().any(|r| r == id), "{id} did not run");
    }
}

#[test]
fn pending_cases_exist() {
    let ids: Vec<String> = cases()
        .iter()
        .map(|c| c["id"].as_str().unwrap().to_string())
        .collect();
    for (p, _) in PENDING {
        assert!(
            ids.iter().any(|i| i == p),
            "pending case {p} is not in cases.json"
        );
    }
}
