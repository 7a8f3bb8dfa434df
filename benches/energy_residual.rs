//! The rigid block's energy-account residual against the time step (the time step safety factor
//! 0.4 … 0.025) on the default 45°, 120 m plane: a drop and a slide, linear and Hertz contact, one
//! window ending mid-impact. Prints the order at which the residual converges; a measurement, not
//! a check: `cargo bench --bench energy_residual`.

use gangue::physics::Control;
use gangue::physics::migration::{ContactModel, Method, MigrationCase, run};

const G: f64 = 9.81;

/// The rigid block on the default plane, released at rest on the floor.
fn block() -> MigrationCase {
    let mut c = MigrationCase {
        method: Method::RigidBlock,
        ..MigrationCase::default()
    };
    c.release.drop_height = 0.0;
    c.output.events = true;
    c
}

fn main() {
    for (name, hertz, drop, end) in [
        ("linear drop 0.5 m, end 0.6 s", false, 0.5, 0.6),
        (
            "linear drop 0.5 m, end 0.3213 s (mid-impact)",
            false,
            0.5,
            0.3213,
        ),
        ("hertz drop 0.5 m, end 0.6 s", true, 0.5, 0.6),
        ("linear slide from rest 0.3 s", false, 0.0, 0.3),
    ] {
        println!("{name}");
        for safety in [0.4, 0.2, 0.1, 0.05, 0.025] {
            let mut c = block();
            c.release.drop_height = drop;
            c.end_time = Some(end);
            c.output.events = false;
            c.rigid_block.time_step_safety = safety;
            if hertz {
                c.rigid_block.contact_model = ContactModel::Hertz;
            }
            let r = match run(&c, &Control::unlimited()) {
                Ok(r) => r,
                Err(e) => {
                    println!("  safety {safety}: {e}");
                    continue;
                }
            };
            let e = r.energy;
            let scale = r.mass * G * (r.arrival.along_dip + drop);
            println!(
                "  safety {safety}: dt {:.3e} residual {:+.3e} J ({:+.3e} of {scale:.3e} J) stored {:.3e} damping {:.3e} friction {:.3e}",
                r.rigid_block.map_or(f64::NAN, |b| b.time_step),
                e.residual,
                e.residual / scale,
                e.stored,
                e.damping,
                e.friction
            );
        }
    }
}
