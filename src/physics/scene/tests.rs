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
