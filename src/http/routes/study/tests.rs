//! Unit tests of the study route.

use super::*;
use crate::calc::study::Parameter;

/// Bases a study may start from: each rule that derives one field from another (the corner
/// radius from L, a sphere's radius from L, the contact radius from D₁), given or derived,
/// on both models.
fn bases() -> Vec<Value> {
    vec![
        json!({}),
        json!({"contact": {"law": "hertz_point"}}),
        json!({"contact": {"law": "hertz_point"}, "rock": {"corner_radius_m": 0.03}}),
        json!({"contact": {"law": "hertz_point"}, "rock": {"shape": "sphere"}}),
        json!({"contact": {"law": "hertz_point"}, "rock": {"shape": "sphere", "radius_m": 0.1}}),
        json!({"contact": {"law": "johnson", "effective_modulus": "two_body"},
               "column": {"contact_radius_m": 0.2}}),
        json!({"column": {"damping_ratio": 0.02}}),
        json!({"model": "coupled", "end_time_s": 0.02}),
        json!({"rock": {"dimensions_m": [0.2, 0.3, 0.4],
                        "random": {"semi_axes_m": [0.1, 0.2, 0.3]},
                        "vertices_m": [[0, 0, 0], [0.3, 0, 0], [0, 0.3, 0], [0, 0, 0.3]]}}),
    ]
}

const NAMES: [&str; 26] = [
    "velocity_m_s",
    "rock.side_length_m",
    "rock.radius_m",
    "rock.dimensions_m.1",
    "rock.vertices_m.2.0",
    "rock.random.semi_axes_m.2",
    "rock.density_kg_m3",
    "rock.elastic_modulus_pa",
    "rock.poisson_ratio",
    "rock.corner_radius_m",
    "column.outer_diameter_m",
    "column.inner_diameter_m",
    "column.length_m",
    "column.elastic_modulus_pa",
    "column.poisson_ratio",
    "column.density_kg_m3",
    "column.yield_stress_pa",
    "column.contact_radius_m",
    "column.damping_coefficient_n_s_m2",
    "column.damping_ratio",
    "initial_midpoint_displacement_m",
    "end_time_s",
    "output.duration_s",
    "velocity_m_s.x",
    "rock.dimensions_m.9",
    "contact.law.x",
];

/// The case of a study point made on the base case equals the case of the base request with
/// the same values set and resolved, for every field a study sweeps, alone and two at a
/// time (the pairs that move a derived field), at values across each field's range.
#[test]
fn a_point_case_is_the_resolved_request_with_its_values() {
    let config = Config::default();
    let mut compared = 0;
    for base in bases() {
        let sent: ColumnRequest = from_value(&base).unwrap();
        let sent_json = serde_json::to_value(&sent).unwrap();
        let mut resolved = sent.clone();
        let case = resolved.resolve(&config).unwrap();
        let study = StudyCase {
            case,
            given: Given {
                corner_radius: sent.rock.corner_radius_m.is_some(),
                radius: sent.rock.radius_m.is_some(),
                contact_radius: sent.column.contact_radius_m.is_some(),
            },
        };
        assert_eq!(study.point(&[]), study.case, "{base}");
        let fields: Vec<(&str, SweptField)> = NAMES
            .iter()
            .filter_map(|n| SweptField::of(n, &sent, &sent_json).map(|f| (*n, f)))
            .collect();
        for &(name, f) in &fields {
            let b = f.get(&resolved).unwrap_or(0.1);
            for x in [
                0.01,
                0.05,
                0.13,
                0.3,
                0.7,
                0.5 * b,
                0.9 * b,
                1.1 * b,
                2.0 * b,
            ] {
                let mut sets = vec![(f, x)];
                let mut cases = vec![sets.clone()];
                for &(_, g) in &fields {
                    if g != f {
                        sets.push((g, 0.9 * g.get(&resolved).unwrap_or(0.1)));
                        cases.push(sets.clone());
                        sets.pop();
                    }
                }
                for sets in cases {
                    let Ok(want) = resolve_point(&config, &sent, &sets) else {
                        continue;
                    };
                    let params: Vec<(Parameter, f64)> =
                        sets.iter().map(|&(g, x)| (g.parameter(), x)).collect();
                    assert_eq!(study.point(&params), want, "{base}: {name} {sets:?}");
                    compared += 1;
                }
            }
        }
    }
    assert!(compared > 2000, "{compared} points compared");
}

/// A path through a number or past an array's end sets nothing; a path the request does not
/// have, or to a field that is not a number, names no field (the request's own refusal).
#[test]
fn swept_names_map_to_the_fields_they_set() {
    let sent: ColumnRequest =
        from_value(&json!({"rock": {"dimensions_m": [0.2, 0.3, 0.4]}})).unwrap();
    let v = serde_json::to_value(&sent).unwrap();
    let of = |n: &str| SweptField::of(n, &sent, &v);
    assert_eq!(of("rock.density_kg_m3"), Some(SweptField::RockDensity));
    assert_eq!(
        of("rock.dimensions_m.2"),
        Some(SweptField::RockDimension(2))
    );
    assert_eq!(
        of("rock.dimensions_m.+1"),
        Some(SweptField::RockDimension(1))
    );
    assert_eq!(of("rock.dimensions_m.3"), None);
    assert_eq!(of("velocity_m_s.x"), None);
    assert_eq!(of("rock.densty_kg_m3"), None);
    assert_eq!(of("galerkin.modes"), None);
    assert_eq!(of("rock.vertices_m.0.0"), None);
    // the base value as a JSON Pointer reads it
    let f = SweptField::RockDimension(1);
    assert_eq!(f.base("rock.dimensions_m.1", &sent), Some(0.3));
    assert_eq!(f.base("rock.dimensions_m.+1", &sent), None);
    assert_eq!(f.base("rock.dimensions_m.01", &sent), None);
}
