//! Tests of the clearcoat and anisotropy lobes (`clearcoat.rs`,
//! `anisotropy.rs`) through `bsdf_*`, with `bsdf_tests.rs`'s tools:
//! chi-square of sampled directions against the pdf, weight = f cos / pdf,
//! the albedo against quadrature, and the delta rules.
use super::*;
use crate::constants::{LOBE_ANISOTROPY, LOBE_CLEARCOAT};

fn coat(m: &mut MaterialData, factor: f32, roughness: f32) {
    m.lobes |= LOBE_CLEARCOAT;
    m.clearcoat = factor;
    m.clearcoat_roughness = roughness;
}

fn aniso(m: &mut MaterialData, strength: f32, rotation: f32) {
    m.lobes |= LOBE_ANISOTROPY;
    m.anisotropy_strength = strength;
    m.anisotropy_rotation = rotation;
}

/// The frame about +z with the tangent at angle `phi` and coat normal `coat_n`.
fn frame(phi: f32, coat_n: Vec3) -> ShadingFrame {
    let t = Vec3::new(phi.cos(), phi.sin(), 0.0);
    ShadingFrame {
        n: Vec3::Z,
        t,
        b: Vec3::Z.cross(t),
        coat_n: coat_n.normalize(),
    }
}

/// (name, material, frame about +z, front, wo).
fn cases() -> Vec<(&'static str, MaterialData, ShadingFrame, bool, Vec3)> {
    let wo = Vec3::new(0.5, 0.1, 0.86).normalize();
    let grazing = Vec3::new(0.95, 0.0, 0.31).normalize();
    let z = frame(0.0, Vec3::Z);
    vec![
        (
            "rough coat over white diffuse",
            gltf(|m| {
                m.specular_factor = 0.0;
                coat(m, 1.0, 0.4);
            }),
            z,
            true,
            wo,
        ),
        (
            "rough coat over diffuse, grazing",
            gltf(|m| {
                m.specular_factor = 0.0;
                coat(m, 1.0, 0.3);
            }),
            z,
            true,
            grazing,
        ),
        (
            "smooth coat over rough plastic",
            gltf(|m| {
                m.base_color = [0.6, 0.1, 0.1];
                m.roughness = 0.5;
                coat(m, 0.7, 0.0);
            }),
            z,
            true,
            wo,
        ),
        (
            "rough coat over smooth metal (delta base)",
            gltf(|m| {
                m.metallic = 1.0;
                m.roughness = 0.0;
                coat(m, 1.0, 0.3);
            }),
            z,
            true,
            wo,
        ),
        (
            "rough coat with its own normal over rough plastic",
            gltf(|m| {
                m.base_color = [0.2, 0.5, 0.3];
                m.roughness = 0.6;
                coat(m, 0.9, 0.35);
            }),
            frame(0.0, Vec3::new(0.3, -0.2, 0.93)),
            true,
            wo,
        ),
        (
            "anisotropic rough metal",
            gltf(|m| {
                m.metallic = 1.0;
                m.roughness = 0.4;
                aniso(m, 0.8, 0.0);
            }),
            frame(0.7, Vec3::Z),
            true,
            wo,
        ),
        (
            "anisotropic rough metal, grazing across the grain",
            gltf(|m| {
                m.metallic = 1.0;
                m.roughness = 0.5;
                aniso(m, 0.6, 0.0);
            }),
            frame(1.9, Vec3::Z),
            true,
            grazing,
        ),
        (
            "anisotropic rough glass",
            gltf(|m| {
                m.transmission = 1.0;
                m.roughness = 0.45;
                m.thickness = 1.0;
                aniso(m, 0.7, 0.0);
            }),
            frame(0.3, Vec3::Z),
            false,
            wo,
        ),
        (
            "anisotropic thin-walled transmission",
            gltf(|m| {
                m.transmission = 1.0;
                m.roughness = 0.5;
                m.specular_factor = 0.0;
                aniso(m, 0.5, 0.0);
            }),
            frame(-0.8, Vec3::Z),
            true,
            wo,
        ),
        (
            "rough coat over anisotropic plastic",
            gltf(|m| {
                m.base_color = [0.1, 0.2, 0.6];
                m.roughness = 0.45;
                coat(m, 1.0, 0.25);
                aniso(m, 0.9, 0.0);
            }),
            frame(2.5, Vec3::Z),
            true,
            wo,
        ),
    ]
}

#[test]
fn coat_and_anisotropic_lobes_follow_bsdf_pdf_chi_square() {
    for (name, m, f, front, wo) in cases() {
        println!("{name}:");
        let (p, integral, fraction) = chi_square(&m, &f, front, wo, 400_000);
        assert!(p > 1e-3, "{name}: samples do not follow bsdf_pdf (p = {p})");
        assert!(
            (integral - fraction).abs() < 4e-3,
            "{name}: pdf integrates to {integral}, sampling succeeds {fraction}"
        );
    }
}

/// weight = eval / pdf and pdf = bsdf_pdf for every non-delta sample, in a
/// tilted world frame (the frame rotated as a whole).
#[test]
fn coat_and_anisotropic_eval_pdf_and_sample_agree() {
    let n = Vec3::new(0.3, -0.4, 0.866).normalize();
    let (t, b) = build_onb(n);
    let world = |w: Vec3| (w.x * t + w.y * b + w.z * n).normalize();
    let mut cases = cases();
    cases.push((
        "anisotropic metal, roughness 0 (a line highlight)",
        gltf(|m| {
            m.metallic = 1.0;
            m.roughness = 0.0;
            aniso(m, 0.5, 0.0);
        }),
        frame(0.4, Vec3::Z),
        true,
        Vec3::new(0.5, 0.1, 0.86).normalize(),
    ));
    for (name, m, f, front, wo) in cases {
        let f = ShadingFrame {
            n: world(f.n),
            t: world(f.t),
            b: world(f.b),
            coat_n: world(f.coat_n),
        };
        let wo = world(wo);
        let mut rng = Lcg(7);
        let mut checked = 0;
        for _ in 0..4000 {
            let (ul, u0, u1) = (rng.next(), rng.next(), rng.next());
            let s = bsdf_sample(&m, &f, front, wo, ul, Vec2::new(u0, u1));
            assert!(
                s.weight.is_finite() && s.weight.min_element() >= 0.0,
                "{name}"
            );
            if s.delta || s.pdf <= 0.0 {
                continue;
            }
            let pdf = bsdf_pdf(&m, &f, front, wo, s.wi);
            assert!(
                (s.pdf - pdf).abs() <= 1e-3 * pdf.max(1.0),
                "{name}: pdf {} vs {pdf}",
                s.pdf
            );
            let w = bsdf_eval(&m, &f, front, wo, s.wi) / pdf;
            assert!(
                (w - s.weight).abs().max_element() <= 1e-3 * w.max_element().max(1.0),
                "{name}: weight {} vs eval/pdf {w}",
                s.weight
            );
            checked += 1;
        }
        // (A rough coat over a delta base is drawn ~4% of the time.)
        assert!(checked > 120, "{name}: {checked} non-delta samples");
    }
}

/// The albedo of a white coat over a white Lambertian base, sampled, equals
/// (1 - blend) + blend · E_ggx (E_ggx by quadrature of the bare GGX lobe,
/// written out here), stays below 1, and equals the quadrature of eval.
#[test]
fn white_coat_over_white_diffuse_albedo_matches_quadrature() {
    let alpha = 0.5f64 * 0.5;
    let m = gltf(|m| {
        m.specular_factor = 0.0;
        coat(m, 1.0, 0.5);
    });
    let f = frame_of_normal(Vec3::Z);
    for theta in [0.1f32, 0.8, 1.35] {
        let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
        let mu = wo.z as f64;
        // E_ggx(mu): ∫ D G2 / (4 mu) over the hemisphere, midpoint in (cos, φ).
        let lambda = |c: f64| 0.5 * ((1.0 + alpha * alpha * (1.0 - c * c) / (c * c)).sqrt() - 1.0);
        let (nc, np) = (600, 600);
        let mut e_ggx = 0.0;
        for i in 0..nc {
            let c = (i as f64 + 0.5) / nc as f64;
            let s = (1.0 - c * c).sqrt();
            for j in 0..np {
                let phi = (j as f64 + 0.5) / np as f64 * 2.0 * std::f64::consts::PI;
                let h = [
                    mu.mul_add(0.0, wo.x as f64) + s * phi.cos(),
                    s * phi.sin(),
                    mu + c,
                ];
                let len = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
                let hz = h[2] / len;
                let d = alpha * alpha
                    / (std::f64::consts::PI * (hz * hz * (alpha * alpha - 1.0) + 1.0).powi(2));
                e_ggx += d / (1.0 + lambda(mu) + lambda(c)) / (4.0 * mu);
            }
        }
        e_ggx *= 2.0 * std::f64::consts::PI / (nc * np) as f64;
        let x = 1.0 - mu;
        let blend = 0.04 + 0.96 * x.powi(5);
        let expected = (1.0 - blend) + blend * e_ggx;
        let mut rng = Lcg(5);
        let count = 400_000;
        let mut sum = 0.0f64;
        for _ in 0..count {
            let (ul, u0, u1) = (rng.next(), rng.next(), rng.next());
            sum += bsdf_sample(&m, &f, true, wo, ul, Vec2::new(u0, u1))
                .weight
                .x as f64;
        }
        let sampled = sum / count as f64;
        let integrated: f64 = integrated_pdf(&|w| bsdf_eval(&m, &f, true, wo, w).x as f64)
            .iter()
            .sum();
        println!(
            "θo {theta}: blend {blend:.4}, E_ggx {e_ggx:.4}, expected {expected:.4}, sampled {sampled:.4}, eval quadrature {integrated:.4}"
        );
        assert!(expected <= 1.0);
        assert!((sampled - expected).abs() < 4e-3, "θo {theta}");
        assert!((integrated - expected).abs() < 4e-3, "θo {theta}");
    }
}

/// A smooth coat over a delta-only base is delta-only; a rough coat gives
/// it a density; a smooth coat over a rough base leaves the base to NEE,
/// and its mirror sample has weight 1.
#[test]
fn clearcoat_delta_rules() {
    let smooth_metal = |cr| {
        gltf(|m| {
            m.metallic = 1.0;
            m.roughness = 0.0;
            coat(m, 1.0, cr);
        })
    };
    assert!(bsdf_is_delta(&smooth_metal(0.0)));
    assert!(!bsdf_is_delta(&smooth_metal(0.3)));
    let m = gltf(|m| {
        m.roughness = 0.5;
        coat(m, 1.0, 0.0);
    });
    assert!(!bsdf_is_delta(&m));
    let wo = Vec3::new(0.6, 0.0, 0.8);
    let f = frame_of_normal(Vec3::Z);
    let s = bsdf_sample(&m, &f, true, wo, 0.0, Vec2::new(0.3, 0.3));
    assert!(s.delta && s.pdf == 0.0);
    assert!((s.wi - Vec3::new(-0.6, 0.0, 0.8)).length() < 1e-6);
    assert_eq!(s.weight, Vec3::ONE);
    // The mirror direction carries only the base's density.
    let blend = crate::cpu::common::clearcoat::clearcoat_blend(&m, 0.8);
    let base = gltf(|b| b.roughness = 0.5);
    let expect = (1.0 - blend) * bsdf_pdf(&base, &f, true, wo, s.wi);
    assert!((bsdf_pdf(&m, &f, true, wo, s.wi) - expect).abs() < 1e-5);
}

/// Anisotropy stretches the highlight along the tangent: with the tangent
/// along x, the reflection lobe is wider in x than in y, and turning the
/// frame turns the lobe with it.
#[test]
fn anisotropic_lobe_follows_the_tangent() {
    let m = gltf(|m| {
        m.metallic = 1.0;
        m.roughness = 0.3;
        aniso(m, 0.8, 0.0);
    });
    let wo = Vec3::Z;
    let off = 0.3f32;
    let along_x = Vec3::new(off.sin(), 0.0, off.cos());
    let along_y = Vec3::new(0.0, off.sin(), off.cos());
    let fx = frame(0.0, Vec3::Z);
    let fy = frame(std::f32::consts::FRAC_PI_2, Vec3::Z);
    let e = |f: &ShadingFrame, w| bsdf_eval(&m, f, true, wo, w).x;
    assert!(e(&fx, along_x) > 5.0 * e(&fx, along_y));
    assert!((e(&fx, along_x) - e(&fy, along_y)).abs() < 1e-4 * e(&fx, along_x));
    // Strength 0 is the isotropic lobe exactly.
    let iso = gltf(|m| {
        m.metallic = 1.0;
        m.roughness = 0.3;
    });
    let zero = gltf(|m| {
        m.metallic = 1.0;
        m.roughness = 0.3;
        aniso(m, 0.0, 0.0);
    });
    let f0 = frame_of_normal(Vec3::Z);
    assert_eq!(
        bsdf_eval(&iso, &f0, true, wo, along_x),
        bsdf_eval(&zero, &f0, true, wo, along_x)
    );
}
