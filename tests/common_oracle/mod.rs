//! Runs the 50-digit reference implementation (`../shared/reference/reference.py`, mpmath) as a
//! test oracle through a small Python driver. Missing python3, mpmath or the reference file is a
//! loud test failure, never a skip.

#![allow(dead_code)]

use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Stdio};

use gangue::physics::material::{ContactLaw, ImpactCase, ModulusConvention, RockShape};
use serde_json::{Value, json};

/// The driver: imports reference.py as a module and answers a JSON request on stdin.
/// `u`: G values (as decimal strings, exact round-trip) → [u, W, e^{−u/2}, e^{−u/2}(2+u)] as
/// strings with 30 digits; `cases`: contact cases → reference outputs (or the error code);
/// `hertz`: [rc, R] pairs → [m_e, K, E, κ/E*] at 60 digits with a log-space root solve.
const DRIVER: &str = r#"
import json, sys
sys.path.insert(0, sys.argv[1])
import mpmath as mp
import reference as ref
req = json.load(sys.stdin)
out = {"u": [], "cases": [], "hertz": []}
for g in req.get("u", []):
    u = ref.u_of_G(mp.mpf(g))
    out["u"].append([mp.nstr(x, 30) for x in (u, -1 - u, mp.exp(-u / 2), mp.exp(-u / 2) * (2 + u))])
for case in req.get("cases", []):
    case = dict(case, kind="contact")
    r = ref.run_case(case)
    if "error" in r:
        out["cases"].append({"error": r["error"]["code"]})
    else:
        out["cases"].append({k: (v if isinstance(v, (str, bool)) or v is None else float(v))
                             for k, v in r["output"].items()})
with mp.workdps(60):
    for rc, R in req.get("hertz", []):
        rho = mp.mpf(rc) / mp.mpf(R)
        def f(lx):
            m = 1 / (1 + mp.exp(-lx))
            K = mp.ellipk(m); E = mp.ellipe(m)
            return mp.log((E / (1 - m) + E - 2 * K) / (K - E)) - mp.log(rho)
        lo, hi = mp.log(rho) - 3, mp.log(rho) + 12
        for _ in range(400):
            mid = (lo + hi) / 2
            if f(mid) > 0: hi = mid
            else: lo = mid
        x = (lo + hi) / 2
        m = 1 / (1 + mp.exp(-x))
        K = mp.ellipk(m); E = mp.ellipe(m)
        A = 1 / (2 * mp.mpf(rc))
        kappa_over_es = (2 * mp.pi / (3 * K)) * mp.sqrt((K - E) / (K * m * A))
        out["hertz"].append([mp.nstr(v, 30) for v in (m, K, E, kappa_over_es)])
json.dump(out, sys.stdout)
"#;

/// Path of reference.py: `GANGUE_REFERENCE_DIR`, else `../shared/reference` or
/// `../../shared/reference` from the crate root, else `/work/shared/reference`.
pub(crate) fn reference_dir() -> PathBuf {
    if let Ok(d) = std::env::var("GANGUE_REFERENCE_DIR") {
        return PathBuf::from(d);
    }
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    for cand in [
        root.join("../shared/reference"),
        root.join("../../shared/reference"),
        PathBuf::from("/work/shared/reference"),
    ] {
        if cand.join("reference.py").is_file() {
            return cand;
        }
    }
    panic!(
        "reference.py not found: set GANGUE_REFERENCE_DIR to the directory holding \
         shared/reference/reference.py (needs python3 with mpmath and scipy)"
    );
}

/// Runs the driver on `request` and returns its JSON answer. Panics loudly on any failure.
pub(crate) fn run(request: &Value) -> Value {
    let dir = reference_dir();
    let mut child = Command::new("python3")
        .arg("-c")
        .arg(DRIVER)
        .arg(&dir)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("python3 is required by this test (with mpmath and scipy): could not start it");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(request.to_string().as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "the reference driver failed (is mpmath installed? `pip install mpmath scipy`):\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("reference driver output is JSON")
}

/// A case in the reference's field names (physics.md §F).
pub(crate) fn to_reference(case: &ImpactCase) -> Value {
    assert!(matches!(case.rock.shape, RockShape::Cube));
    json!({
        "v": case.velocity,
        "L": case.rock.side_length,
        "E_rock": case.rock.elastic_modulus,
        "nu_rock": case.rock.poisson_ratio,
        "rho_rock": case.rock.density,
        "E_col": case.column.elastic_modulus,
        "nu_col": case.column.poisson_ratio,
        "R": case.column.contact_radius,
        "corner_radius": case.rock.corner_radius,
        "law": match case.contact.law {
            ContactLaw::Paper => "paper",
            ContactLaw::Johnson => "johnson",
            ContactLaw::HertzPoint => "hertz_point",
        },
        "estar": match case.contact.modulus {
            ModulusConvention::Paper => "paper",
            ModulusConvention::TwoBody => "two_body",
        },
        "hertz_exact": case.contact.hertz_exact,
    })
}

/// A decimal string from the driver as f64.
pub(crate) fn num(v: &Value) -> f64 {
    match v {
        Value::String(s) => s.parse().unwrap(),
        Value::Number(n) => n.as_f64().unwrap(),
        _ => panic!("not a number: {v}"),
    }
}
