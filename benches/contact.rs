//! Contact solver timings (physics.md §A): the closed forms per law, and the duration
//! quadrature on its own.

#![allow(clippy::field_reassign_with_default)] // cases read as "the default, except …"
#![allow(missing_docs)] // criterion_group! generates an undocumented pub fn

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use gangue::physics::contact::{impact_maxima, line_duration_integral, solve_impact};
use gangue::physics::material::{ContactLaw, ImpactCase, ModulusConvention};
use gangue::physics::numeric::lambert::branch_u;

fn case(law: ContactLaw, modulus: ModulusConvention, exact: bool) -> ImpactCase {
    let mut c = ImpactCase::default();
    c.contact.law = law;
    c.contact.modulus = modulus;
    c.contact.hertz_exact = exact;
    c
}

fn closed_forms(c: &mut Criterion) {
    let mut g = c.benchmark_group("contact/closed_form");
    for (name, case) in [
        (
            "paper",
            case(ContactLaw::Paper, ModulusConvention::Paper, true),
        ),
        (
            "johnson",
            case(ContactLaw::Johnson, ModulusConvention::TwoBody, true),
        ),
        (
            "hertz_exact",
            case(ContactLaw::HertzPoint, ModulusConvention::TwoBody, true),
        ),
        (
            "hertz_equivalent_radius",
            case(ContactLaw::HertzPoint, ModulusConvention::TwoBody, false),
        ),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| impact_maxima(black_box(&case)).unwrap())
        });
    }
    g.bench_function("branch_u", |b| {
        b.iter(|| branch_u(black_box(1.273_239_544_735_162_8e-6)))
    });
    g.finish();
}

fn durations(c: &mut Criterion) {
    let mut g = c.benchmark_group("contact/duration");
    g.bench_function("quadrature_base", |b| {
        b.iter(|| line_duration_integral(black_box(16.432_269_118_399_564)))
    });
    g.bench_function("quadrature_near_capacity", |b| {
        b.iter(|| line_duration_integral(black_box(1e-5)))
    });
    let base = ImpactCase::default();
    g.bench_function("solve_impact_paper", |b| {
        b.iter(|| solve_impact(black_box(&base)).unwrap())
    });
    g.finish();
}

criterion_group!(benches, closed_forms, durations);
criterion_main!(benches);
