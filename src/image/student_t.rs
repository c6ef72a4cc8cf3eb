//! Student's t distribution, for z-scores whose variance was estimated from
//! few values (`estimated_noise.rs`): with an estimated variance the tails
//! are heavier than the normal's, and at the tiny per-test thresholds of a
//! Šidák correction the difference is large (p = 1e-6 is |t| 4.9 for the
//! normal, 7.3 for 15 degrees of freedom).

use super::compare::normal_two_sided_p;

/// Above this many degrees of freedom the normal is used (the difference
/// in p is below 1e-4 relative at |t| = 6).
const NORMAL_DOF: f64 = 1e7;

/// Two-sided p-value of `t` under Student's t with `dof` > 0 degrees of
/// freedom (not necessarily an integer, as Satterthwaite's are):
/// I_x(dof/2, 1/2) with x = dof / (dof + t²), the regularized incomplete
/// beta function, so tail p-values keep their relative accuracy.
pub fn student_t_two_sided_p(t: f64, dof: f64) -> f64 {
    if dof >= NORMAL_DOF {
        return normal_two_sided_p(t);
    }
    let x = dof / (dof + t * t);
    incomplete_beta(0.5 * dof, 0.5, x)
}

/// ln Γ(x) for x > 0 (Lanczos, g = 7, 9 terms: relative error about 1e-15).
fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Γ(x) Γ(1 - x) = π / sin(πx).
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// The regularized incomplete beta function I_x(a, b) (Numerical Recipes'
/// `betai`: the continued fraction on the side where it converges fast).
fn incomplete_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let front =
        (ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln()).exp();
    if x < (a + 1.0) / (a + b + 2.0) {
        front * beta_continued_fraction(a, b, x) / a
    } else {
        1.0 - front * beta_continued_fraction(b, a, 1.0 - x) / b
    }
}

/// Lentz's evaluation of the continued fraction of I_x(a, b).
fn beta_continued_fraction(a: f64, b: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    const EPS: f64 = 1e-15;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < TINY {
        d = TINY;
    }
    d = 1.0 / d;
    let mut h = d;
    for m in 1..=300 {
        let m = m as f64;
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        d = if d.abs() < TINY { TINY } else { d };
        c = 1.0 + aa / c;
        c = if c.abs() < TINY { TINY } else { c };
        d = 1.0 / d;
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        d = if d.abs() < TINY { TINY } else { d };
        c = 1.0 + aa / c;
        c = if c.abs() < TINY { TINY } else { c };
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < EPS {
            break;
        }
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs()
    }

    #[test]
    fn t_with_one_and_two_degrees_of_freedom_matches_the_closed_forms() {
        for t in [0.0f64, 0.3, 1.0, 2.5, 10.0, 1e3, 1e6] {
            // Cauchy: p = 1 - (2/π) atan|t| = (2/π) atan(1/|t|).
            let one = if t == 0.0 {
                1.0
            } else {
                2.0 / std::f64::consts::PI * (1.0 / t).atan()
            };
            let p1 = student_t_two_sided_p(t, 1.0);
            assert!(close(p1, one, 1e-10), "dof 1, t {t}: {p1} vs {one}");
            // dof 2: p = 1 - |t| / sqrt(2 + t²), written without cancellation.
            let two = 2.0 / ((2.0 + t * t).sqrt() * ((2.0 + t * t).sqrt() + t));
            let p2 = student_t_two_sided_p(-t, 2.0);
            assert!(close(p2, two, 1e-10), "dof 2, t {t}: {p2} vs {two}");
        }
    }

    #[test]
    fn t_quantiles_from_the_tables() {
        // Two-sided 5 % and 0.1 % points (any statistics table).
        for (t, dof, p) in [
            (2.228_138_85, 10.0, 0.05),
            (4.586_893_86, 10.0, 0.001),
            (2.131_449_55, 15.0, 0.05),
            (1.983_971_52, 100.0, 0.05),
        ] {
            let got = student_t_two_sided_p(t, dof);
            assert!(close(got, p, 1e-6), "t {t} dof {dof}: {got} vs {p}");
        }
        // Many degrees of freedom: the normal.
        let z = 4.0;
        assert!(close(
            student_t_two_sided_p(z, 1e6),
            normal_two_sided_p(z),
            1e-4
        ));
    }
}
