//! Tests of the scene: probabilities, checks, strikes, draws and ensembles.

use super::*;

#[test]
fn wilson_interval_of_zero_has_an_upper_bound() {
    let p = probability(0, 200);
    assert_eq!(p.probability, 0.0);
    assert_eq!(p.ci95[0], 0.0);
    assert!(p.ci95[1] > 0.0 && p.ci95[1] < 0.02);
}

#[test]
fn equivalent_cube_keeps_mass_and_density() {
    let rock = Rock {
        shape: RockShape::Sphere { radius: 0.2 },
        ..Rock::default()
    };
    let (_, m) = rock_extent(&rock).unwrap();
    let c = impact_rock(&rock, m);
    assert!((c.mass() - rock.mass()).abs() <= 1e-12 * rock.mass());
    assert_eq!(c.density, rock.density);
}

mod guard_properties {
    use super::*;
    use proptest::prelude::*;

    fn guarded(rating: Option<f64>) -> SceneCase {
        SceneCase {
            guards: vec![rating],
            ..SceneCase::new(
                MigrationCase::default(),
                vec![SupportEntry {
                    support: 1,
                    column_index: 0,
                    along_dip: 30.0,
                    across: None,
                    column: Column::default(),
                }],
                ColumnCase::default(),
            )
        }
    }

    proptest! {
        /// Over the documented domain (rating in [0, 1e12] J, speeds up to 1000 m/s, masses of
        /// rocks from 1 mm to 5 m): the guard never adds energy — the column's energy and the
        /// guard's share sum to the rock's (to rounding), the guard takes at most its rating,
        /// and the speed behind it never exceeds the speed in front; no guard changes nothing.
        #[test]
        fn a_guard_only_takes_energy_and_at_most_its_rating(
            rating in prop_oneof![Just(0.0), Just(1e12), 0.0..1e12_f64, 0.0..100.0_f64],
            v in prop_oneof![Just(0.0), Just(1000.0), 0.0..1000.0_f64, 0.0..1e-3_f64],
            mass in prop_oneof![Just(1e-6), Just(3.4e5), 1e-6..3.4e5_f64],
        ) {
            let (none, speed) = behind_guard(&guarded(None), 0, mass, v);
            prop_assert_eq!((none, speed), (Guard::None, v));
            let (g, left) = behind_guard(&guarded(Some(rating)), 0, mass, v);
            prop_assert!(left.is_finite() && left >= 0.0 && left <= v, "{g:?} {left} > {v}");
            let (e, e_left) = (0.5 * mass * v * v, 0.5 * mass * left * left);
            let taken = e - e_left;
            prop_assert!(taken <= rating * (1.0 + 1e-12) + 1e-9 * e, "took {taken} > {rating}");
            match g {
                Guard::Held => prop_assert!(e <= rating * (1.0 + 1e-12) && left == 0.0),
                Guard::BrokenThrough => {
                    prop_assert!(e > rating * (1.0 - 1e-12));
                    prop_assert!((taken - rating).abs() <= 1e-9 * e.max(rating), "{taken} vs {rating}");
                }
                Guard::None => prop_assert!(false, "a guard reported none"),
            }
        }
    }
}
