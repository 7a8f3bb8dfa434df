//! Root finding on a bracket: Brent's method (inverse quadratic interpolation with bisection
//! safeguards; R. P. Brent, *Algorithms for Minimization without Derivatives*, 1973, ch. 4).

/// A root of `f` in the bracketing interval [a, b] with f(a)·f(b) ≤ 0 (`fa`, `fb` given),
/// located to 2ε·max(|x|, 1) (at most 200 evaluations).
pub fn brent<F: FnMut(f64) -> f64>(
    mut f: F,
    mut a: f64,
    mut b: f64,
    mut fa: f64,
    mut fb: f64,
) -> f64 {
    if fa == 0.0 {
        return a;
    }
    if fb == 0.0 {
        return b;
    }
    let mut c = a;
    let mut fc = fa;
    let mut d = b - a;
    let mut e = d;
    for _ in 0..200 {
        if (fb > 0.0) == (fc > 0.0) {
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        let tol = 2.0 * f64::EPSILON * b.abs().max(1.0);
        let xm = 0.5 * (c - b);
        if xm.abs() <= tol || fb == 0.0 {
            return b;
        }
        if e.abs() >= tol && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut p, mut q);
            if a == c {
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else {
                let qq = fa / fc;
                let r = fb / fc;
                p = s * (2.0 * xm * qq * (qq - r) - (b - a) * (r - 1.0));
                q = (qq - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if p > 0.0 {
                q = -q;
            } else {
                p = -p;
            }
            if 2.0 * p < (3.0 * xm * q - (tol * q).abs()).min((e * q).abs()) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        a = b;
        fa = fb;
        b += if d.abs() > tol { d } else { tol.copysign(xm) };
        fb = f(b);
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn brent_finds_the_root_of_a_cubic_to_full_precision() {
        // x³ − 2 on [1, 2]: the cube root of 2.
        let f = |x: f64| x * x * x - 2.0;
        let x = brent(f, 1.0, 2.0, f(1.0), f(2.0));
        assert!((x - 2f64.cbrt()).abs() <= 4.0 * f64::EPSILON, "{x}");
    }

    #[test]
    fn brent_returns_an_end_that_is_a_root() {
        let f = |x: f64| x - 1.0;
        assert_eq!(brent(f, 1.0, 3.0, 0.0, 2.0), 1.0);
        assert_eq!(brent(f, -1.0, 1.0, -2.0, 0.0), 1.0);
    }

    #[test]
    fn brent_handles_a_reversed_bracket() {
        let f = |x: f64| (x - 0.25).tanh();
        let x = brent(f, 1.0, -1.0, f(1.0), f(-1.0));
        assert!((x - 0.25).abs() < 1e-15, "{x}");
    }
}
