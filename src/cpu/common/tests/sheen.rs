//! Tests of `sheen.rs`: the albedo table against f64 quadrature of the
//! lobe (written independently here, in f64), and the f32 lobe against the
//! f64 one.
use super::*;

/// The sheen lobe in f64: (D V cos θi) for white sheen, wo and wi in the
/// upper hemisphere.
pub(crate) fn sheen_f64(r: f64, wo: [f64; 3], wi: [f64; 3]) -> f64 {
    let r = r.max(SHEEN_MIN_ROUGHNESS as f64);
    let alpha = r * r;
    let h = [wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]];
    let hz = h[2] / (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
    let inv = 1.0 / alpha;
    let d = (2.0 + inv) * (1.0 - hz * hz).max(0.0).powf(0.5 * inv) / (2.0 * std::f64::consts::PI);
    let w = (1.0 - alpha) * (1.0 - alpha);
    let l = |x: f64| {
        let m = |a: f64, b: f64| a * (1.0 - w) + b * w;
        m(21.5473, 25.3245) / (1.0 + m(3.82987, 3.32435) * x.powf(m(0.19823, 0.16801)))
            + m(-1.97760, -1.27393) * x
            + m(-4.32054, -4.85967)
    };
    let lambda = |c: f64| {
        if c < 0.5 {
            l(c).exp()
        } else {
            (2.0 * l(0.5) - l(1.0 - c)).exp()
        }
    };
    d / (4.0 * wo[2] * (1.0 + lambda(wo[2]) + lambda(wi[2])))
}

/// E(mu, r) = ∫ f_sheen cos θi dωi by the midpoint rule in (cos θi, φi)
/// (φ symmetric: [0, π] doubled); mu below 1e-3 is evaluated at 1e-3.
pub(crate) fn sheen_albedo_f64(mu: f64, r: f64, n: usize) -> f64 {
    let mu = mu.max(1e-3);
    let wo = [(1.0 - mu * mu).sqrt(), 0.0, mu];
    let mut sum = 0.0;
    for i in 0..n {
        let c = (i as f64 + 0.5) / n as f64;
        let s = (1.0 - c * c).sqrt();
        for j in 0..n / 2 {
            let phi = (j as f64 + 0.5) / (n / 2) as f64 * std::f64::consts::PI;
            sum += sheen_f64(r, wo, [s * phi.cos(), s * phi.sin(), c]);
        }
    }
    sum * (1.0 / n as f64) * (2.0 * std::f64::consts::PI / (n / 2) as f64)
}

/// Node values of the table, row j = roughness j / (N - 1), column i =
/// cos θo (i / (N - 1))² (E changes fastest at grazing angles).
fn table_f64(n: usize) -> Vec<f64> {
    let size = SHEEN_TABLE_SIZE as usize;
    let last = (size - 1) as f64;
    (0..size * size)
        .map(|k| {
            sheen_albedo_f64(
                ((k % size) as f64 / last).powi(2),
                (k / size) as f64 / last,
                n,
            )
        })
        .collect()
}

/// The checked-in table is the quadrature (resolution 400), rounded to
/// f32. `VKPT_WRITE_SHEEN_TABLE=1` rewrites `src/packed/sheen_table.rs`.
#[test]
fn sheen_table_is_the_quadrature_of_the_lobe() {
    let table = table_f64(400);
    if std::env::var_os("VKPT_WRITE_SHEEN_TABLE").is_some() {
        let mut s = String::from(
            "//! Directional albedo of the white `KHR_materials_sheen` lobe (`cpu/sheen.rs`):\n\
             //! row j = sheen roughness j / 31, column i = cos θo (i / 31)². Written by\n\
             //! `VKPT_WRITE_SHEEN_TABLE=1 cargo test --release --lib sheen_table`\n\
             //! (f64 quadrature, `cpu/sheen_tests.rs`); the kernels read it as the binding `sheen_albedo_table`.\n\n\
             pub const SHEEN_ALBEDO: [f32; 1024] = [\n",
        );
        for v in &table {
            s.push_str(&format!("    {:?},\n", *v as f32));
        }
        s.push_str("];\n");
        std::fs::write(
            concat!(env!("CARGO_MANIFEST_DIR"), "/src/packed/sheen_table.rs"),
            s,
        )
        .unwrap();
    }
    for (k, (&t, &q)) in SHEEN_ALBEDO.iter().zip(&table).enumerate() {
        assert!((t as f64 - q).abs() < 1e-6, "node {k}: table {t} vs {q}");
    }
}

/// Resolution 400 is converged: doubling it moves no node by more than
/// 2e-4 (the narrowest lobe, roughness 0.07, is the hard case).
#[test]
fn sheen_quadrature_is_converged() {
    let mut worst = 0.0f64;
    for (mu, r) in [(0.05, 0.0), (0.3, 0.0), (1.0, 0.0), (0.5, 0.3), (0.02, 1.0)] {
        let a = sheen_albedo_f64(mu, r, 400);
        let b = sheen_albedo_f64(mu, r, 1600);
        worst = worst.max((a - b).abs());
        println!("E({mu}, {r}) = {a:.6} (400) vs {b:.6} (1600)");
    }
    assert!(worst < 2e-4, "{worst}");
}

/// The bilinear table between its nodes against a fresh quadrature at the
/// cell centres, for the clamped energy min(1, E) that scales the base (the
/// albedo scaling's error; E above 1 only normalises the lobe).
#[test]
fn sheen_table_interpolation_error_is_small() {
    let size = SHEEN_TABLE_SIZE as usize;
    let last = (size - 1) as f64;
    let mut worst = (0.0f64, 0.0, 0.0);
    for j in 0..size - 1 {
        for i in 0..size - 1 {
            let (mu, r) = (((i as f64 + 0.5) / last).powi(2), (j as f64 + 0.5) / last);
            let q = sheen_albedo_f64(mu, r, 200).min(1.0);
            let e = (sheen_energy(mu as f32, r as f32) as f64 - q).abs();
            if e > worst.0 {
                worst = (e, mu, r);
            }
        }
    }
    println!(
        "largest interpolation error of min(1, E): {:.5} at cos θo {:.4}, roughness {:.3}",
        worst.0, worst.1, worst.2
    );
    assert!(worst.0 < 0.015, "{worst:?}");
}

/// The f32 lobe the renderers evaluate is the f64 model.
#[test]
fn sheen_f32_matches_f64() {
    for (r, wo, wi) in [
        (
            0.5f32,
            Vec3::new(0.6, 0.0, 0.8),
            Vec3::new(-0.3, 0.4, 0.866),
        ),
        (0.1, Vec3::new(0.99, 0.0, 0.141), Vec3::new(-0.8, 0.1, 0.59)),
        (1.0, Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.95, 0.312)),
    ] {
        let (wo, wi) = (wo.normalize(), wi.normalize());
        let a = sheen_eval_white(r, wo, wi) as f64;
        let b = sheen_f64(r as f64, wo.as_dvec3().into(), wi.as_dvec3().into());
        assert!((a - b).abs() <= 1e-4 * b.max(1e-3), "{a} vs {b}");
    }
}
