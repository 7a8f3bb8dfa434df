//! `a * x + b` against the fused `x.mul_add(a, b)` on one hot numeric pattern (Horner evaluation
//! of a degree-8 polynomial at 100 000 points), for the `suboptimal_flops` decision in
//! Cargo.toml's lint table. Count instructions, whatever the machine's load:
//! `cargo bench --bench flops --no-run`, then
//! `valgrind --tool=callgrind target/release/deps/flops-* plain` and `... fused`.
//! Both variants print their sum, which must agree to the printed digits.

use std::hint::black_box;

fn horner(c: &[f64; 9], x: f64, fused: bool) -> f64 {
    let mut y = c[0];
    for &k in &c[1..] {
        y = if fused { y.mul_add(x, k) } else { y * x + k };
    }
    y
}

fn main() {
    let fused = std::env::args().any(|a| a == "fused");
    let c = black_box([
        1.0,
        -0.5,
        0.25,
        -0.125,
        0.0625,
        -0.03125,
        0.015625,
        -0.007_812_5,
        0.003_906_25,
    ]);
    let mut s = 0.0;
    for i in 0..100_000 {
        s += horner(&c, black_box(f64::from(i) * 1e-5), fused);
    }
    println!("{} {s:.17e}", if fused { "fused" } else { "plain" });
}
