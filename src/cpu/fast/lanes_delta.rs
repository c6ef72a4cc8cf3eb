//! Smooth glTF mirrors and glass, and vkpt's own mirrors, in the lanes
//! (`lanes`): `gltf_sample`'s delta branches and the mirror's reflection
//! (`bsdf.rs`) for all the lanes at once, with the same float operations in
//! the same order, so each lane's bounce is the scalar one bit for bit.
//! Only materials whose every lobe is a delta and that have nothing else
//! (no textures, no extension lobes): then the layers, iridescence and the
//! diffuse lobe are identities or absent, and only the Fresnel choice
//! between reflection and refraction is left.

use super::simd::{Bools, Floats, V3, and, not, or, select, select3};
use crate::constants::{MATERIAL_GLTF, MATERIAL_MIRROR};
use crate::cpu::common::bsdf::bsdf_is_delta;
use crate::cpu::common::bsdf::gltf_thin;
use crate::cpu::common::textures::material_has_textures;
use crate::packed::layout::MaterialData;

/// Whether the lanes shade this material with [`DeltaLanes`]: a smooth
/// glTF metal or fully transmissive dielectric without textures or
/// extension lobes (its diffuse lobe then has no weight, so `gltf_sample`
/// never draws it).
pub fn lanes_shade_delta(m: &MaterialData) -> bool {
    let gltf =
        m.kind == MATERIAL_GLTF && bsdf_is_delta(m) && (m.metallic == 1.0 || m.transmission == 1.0);
    (gltf || m.kind == MATERIAL_MIRROR) && !material_has_textures(m) && m.lobes == 0
}

/// The materials of the lanes on such surfaces (other lanes hold zeros).
#[derive(Clone, Copy, Default)]
pub struct DeltaLanes {
    pub base_color: V3,
    pub specular_color: V3,
    pub metallic: Floats,
    pub transmission: Floats,
    pub ior: Floats,
    pub specular_factor: Floats,
    /// `KHR_materials_volume`'s attenuation coefficient.
    pub attenuation: V3,
    /// thickness > 0: a closed volume (`gltf_eta`).
    pub thick: Bools,
    /// A closed volume that absorbs (some attenuation above 0): elsewhere
    /// Beer–Lambert's factor is exp(-0 t) = 1 exactly, and is skipped.
    pub absorbing: Bools,
    /// `gltf_thin`: transmission goes straight through.
    pub thin: Bools,
    /// `MATERIAL_MIRROR`: reflection about the shading normal, tinted by
    /// the base colour.
    pub mirror: Bools,
}

/// A lane's delta sample: the direction, the weight, whether there is one
/// (`gltf_sample` returns none under total internal reflection, or for a
/// direction below the shading frame), and the relative index.
pub struct DeltaSample {
    pub wi: V3,
    pub weight: V3,
    pub sampled: Bools,
    pub eta: Floats,
}

impl DeltaLanes {
    pub fn set_lane(&mut self, l: usize, m: &MaterialData) {
        self.base_color.set_lane(l, m.base_color.into());
        self.specular_color.set_lane(l, m.specular_color.into());
        self.metallic.0[l] = m.metallic;
        self.transmission.0[l] = m.transmission;
        self.ior.0[l] = m.ior;
        self.specular_factor.0[l] = m.specular_factor;
        self.attenuation.set_lane(l, m.attenuation.into());
        self.thick[l] = m.thickness > 0.0;
        self.absorbing[l] =
            m.thickness > 0.0 && glam::Vec3::from(m.attenuation).max_element() > 0.0;
        self.thin[l] = gltf_thin(m);
        self.mirror[l] = m.kind == MATERIAL_MIRROR;
    }

    /// Whether a refraction of the lane scales the path by eta^2 (a glTF
    /// volume's interface; `shade_path`'s eta_scale).
    #[inline(always)]
    pub fn bends(&self) -> Bools {
        and(not(self.thin), not(self.mirror))
    }

    /// `shade_path`'s Beer–Lambert: the lanes in `on` whose ray reached the
    /// back face of a closed volume travelled `t` inside it (the
    /// exponentials lane by lane, as the scalar code takes them; none at
    /// all where no lane absorbs).
    #[inline(always)]
    pub fn absorb(&self, on: &Bools, front: Bools, t: Floats, throughput: &mut V3) {
        let absorbs = and(and(*on, not(front)), self.absorbing);
        if !absorbs.iter().any(|&a| a) {
            return;
        }
        for (l, &absorbs) in absorbs.iter().enumerate() {
            if absorbs {
                let a = self.attenuation.lane(l) * -t.0[l];
                let lost = glam::Vec3::new(a.x.exp(), a.y.exp(), a.z.exp());
                throughput.set_lane(l, throughput.lane(l) * lost);
            }
        }
    }

    /// `gltf_eta`.
    #[inline(always)]
    pub fn eta(&self, front: Bools) -> Floats {
        select(
            and(self.thick, not(front)),
            Floats::splat(1.0) / self.ior,
            self.ior,
        )
    }

    /// `gltf_sample` on the shading frame (t, b, n) for `wo_world`, with
    /// lobe number `u_lobe` (the delta branches draw no direction).
    #[inline(always)]
    pub fn sample(
        &self,
        front: Bools,
        wo_world: V3,
        frame: (V3, V3, V3),
        u_lobe: Floats,
    ) -> DeltaSample {
        let (zero, one) = (Floats::splat(0.0), Floats::splat(1.0));
        let (t, b, n) = frame;
        // to_local
        let wo = V3 {
            x: wo_world.dot(t),
            y: wo_world.dot(b),
            z: wo_world.dot(n),
        };
        let co = wo.z;
        let eta = self.eta(front);
        // gltf_lobe_probs; the diffuse lobe's share is zero for these
        // materials ((1 - metallic) or (1 - transmission) is), so u_lobe <
        // pd never holds and the diffuse_reflected factor (1) is left out.
        let base_weight = self.base_weight(co, eta);
        let base = (one - self.metallic) * base_weight * mean(self.base_color);
        let d = (one - self.transmission) * base;
        let reflection = self.reflection_color(co, eta);
        let r = mean(reflection);
        let tr = self.transmission * base;
        let sum = d + r + tr;
        let some = sum.gt(zero);
        let pd = select(some, d / sum, zero);
        let pr = select(some, r / sum, zero);
        let pt = select(some, tr / sum, zero);
        let reflects = u_lobe.lt(pd + pr);
        // Reflection: mirror_z(-wo), weighted by its colour over pr.
        let reflected = V3 {
            x: -wo.x,
            y: -wo.y,
            z: -(-wo.z),
        };
        let reflected_weight = reflection / pr;
        // Refraction: straight through a thin wall, else refract_about(wo,
        // +z, eta), which fails under total internal reflection.
        let h = V3 {
            x: zero,
            y: zero,
            z: one,
        };
        let c = wo.dot(h);
        let (f, cos_t) = fresnel_dielectric_lanes(c, eta);
        let bent = ((-wo) / eta + h * (c / eta - cos_t)).normalize();
        let refracted = select3(self.thin, -wo, bent);
        let scale = select(self.thin, one, one / (eta * eta));
        let refracted_weight = self.base_color
            * ((one - self.metallic) * self.transmission * base_weight * scale / pt);
        let refracts = and(
            not(reflects),
            and(pt.gt(zero), or(self.thin, not(f.ge(one)))),
        );
        let local = select3(reflects, reflected, refracted);
        // The mirror: reflect_about(wo, n), 2 (n . wo) n - wo, not
        // normalized, always drawn.
        let mirrored = n * (Floats::splat(2.0) * n.dot(wo_world)) - wo_world;
        DeltaSample {
            wi: select3(
                self.mirror,
                mirrored,
                (t * local.x + b * local.y + n * local.z).normalize(),
            ),
            weight: select3(
                self.mirror,
                self.base_color,
                select3(reflects, reflected_weight, refracted_weight),
            ),
            sampled: or(self.mirror, and(not(co.le(zero)), or(reflects, refracts))),
            eta,
        }
    }

    /// `gltf_base_weight` (no iridescence).
    #[inline(always)]
    fn base_weight(&self, c: Floats, eta: Floats) -> Floats {
        Floats::splat(1.0)
            - self.specular_factor
                * specular_fresnel_lanes(self.specular_color, c, eta).max_element()
    }

    /// `gltf_reflection_color` (no iridescence).
    #[inline(always)]
    fn reflection_color(&self, c: Floats, eta: Floats) -> V3 {
        let metal = fresnel_schlick_lanes(self.base_color, c);
        let dielectric = specular_fresnel_lanes(self.specular_color, c, eta) * self.specular_factor;
        metal * self.metallic + dielectric * (Floats::splat(1.0) - self.metallic)
    }
}

/// `bsdf::mean`.
#[inline(always)]
fn mean(c: V3) -> Floats {
    (c.x + c.y + c.z) / Floats::splat(3.0)
}

/// glam's `min`: `a < b ? a : b` per component.
#[inline(always)]
fn min_glam(a: Floats, b: Floats) -> Floats {
    select(a.lt(b), a, b)
}

/// `bsdf::fresnel_dielectric`: (reflectance, cos θt); (1, 0) under total
/// internal reflection.
#[inline(always)]
pub fn fresnel_dielectric_lanes(cos_i: Floats, eta: Floats) -> (Floats, Floats) {
    let (zero, one) = (Floats::splat(0.0), Floats::splat(1.0));
    let sin2_t = (one - cos_i * cos_i) / (eta * eta);
    let total = sin2_t.ge(one);
    let cos_t = (one - sin2_t).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let f = Floats::splat(0.5) * (rs * rs + rp * rp);
    (select(total, one, f), select(total, zero, cos_t))
}

/// `bsdf::specular_fresnel`.
#[inline(always)]
fn specular_fresnel_lanes(specular_color: V3, c: Floats, eta: Floats) -> V3 {
    let one = Floats::splat(1.0);
    let (f, _) = fresnel_dielectric_lanes(c, eta);
    let q = (eta - one) / (eta + one);
    let f0 = q * q;
    let rise = select(
        f0.lt(one),
        ((f - f0) / (one - f0)).max(Floats::splat(0.0)),
        one,
    );
    let channel = |s: Floats| {
        let f0c = min_glam(f0 * s, one);
        f0c + (one - f0c) * rise
    };
    V3 {
        x: channel(specular_color.x),
        y: channel(specular_color.y),
        z: channel(specular_color.z),
    }
}

/// `bsdf::fresnel_schlick`.
#[inline(always)]
fn fresnel_schlick_lanes(f0: V3, c: Floats) -> V3 {
    let (zero, one) = (Floats::splat(0.0), Floats::splat(1.0));
    // f32::clamp(0, 1)
    let x = one - c;
    let x = select(x.lt(zero), zero, x);
    let x = select(x.gt(one), one, x);
    let x2 = x * x;
    let s = x2 * x2 * x;
    let channel = |f: Floats| f + (one - f) * s;
    V3 {
        x: channel(f0.x),
        y: channel(f0.y),
        z: channel(f0.z),
    }
}

#[cfg(test)]
mod tests {
    use super::super::wide::WIDTH;
    use super::*;
    use crate::cpu::common::bsdf::{ShadingFrame, bsdf_sample, fresnel_dielectric};
    use crate::cpu::common::rng::pcg_hash;
    use crate::cpu::common::sampling::build_onb;
    use glam::{Vec2, Vec3};

    /// Random glTF mirrors and glass (thin and closed, indices below and
    /// above 1, coloured specular) and vkpt mirrors, frames and directions
    /// from both sides: each lane's sample is `bsdf_sample`'s bit for bit.
    #[test]
    fn delta_lanes_sample_as_gltf_sample_does() {
        let state = std::cell::Cell::new(11u32);
        let unit = || {
            state.set(pcg_hash(state.get()));
            state.get() as f32 / u32::MAX as f32
        };
        let (mut differing, mut reflected, mut refracted, mut none) = (0, 0, 0, 0);
        for case in 0..4000 {
            let mut mats = Vec::new();
            let mut lanes = DeltaLanes::default();
            let mut front = [false; WIDTH];
            let (mut wo, mut t, mut b, mut n) =
                (V3::default(), V3::default(), V3::default(), V3::default());
            let mut u_lobe = Floats::splat(0.0);
            for l in 0..WIDTH {
                let mut m = MaterialData {
                    kind: MATERIAL_GLTF,
                    base_color: [unit(), unit(), unit()],
                    specular_color: [1.0, unit() * 2.0, 1.0],
                    specular_factor: if l % 2 == 0 { 1.0 } else { unit() },
                    roughness: 0.0,
                    ior: [1.5, 0.67, 1.0 + unit(), 1.00005][(case + l) % 4],
                    thickness: if l % 3 == 0 { 0.0 } else { 1.0 },
                    ..Default::default()
                };
                match (case + l) % 4 {
                    0 => m.metallic = 1.0,
                    1 => m.kind = MATERIAL_MIRROR,
                    _ => m.transmission = 1.0,
                }
                // (Default's texture indices are 0, not NO_TEXTURE, and
                // gltf_sample reads no texture: `bsdf_is_delta` is the test.)
                assert!(
                    bsdf_is_delta(&m),
                    "case {case} lane {l}: not a delta material"
                );
                lanes.set_lane(l, &m);
                let normal = Vec3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5).normalize();
                let (ft, fb) = build_onb(normal);
                let w = Vec3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5).normalize();
                front[l] = unit() < 0.5;
                wo.set_lane(l, w);
                t.set_lane(l, ft);
                b.set_lane(l, fb);
                n.set_lane(l, normal);
                u_lobe.0[l] = unit();
                mats.push(m);
            }
            let s = lanes.sample(front, wo, (t, b, n), u_lobe);
            for (l, m) in mats.iter().enumerate() {
                let frame = ShadingFrame {
                    n: n.lane(l),
                    t: t.lane(l),
                    b: b.lane(l),
                    coat_n: n.lane(l),
                };
                let want = bsdf_sample(m, &frame, front[l], wo.lane(l), u_lobe.0[l], Vec2::ZERO);
                let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                let same = if want.delta {
                    s.sampled[l]
                        && bits(want.wi) == bits(s.wi.lane(l))
                        && bits(want.weight) == bits(s.weight.lane(l))
                } else {
                    !s.sampled[l] && want.pdf == 0.0
                };
                differing += !same as u32;
                if want.delta && want.wi.dot(n.lane(l)) > 0.0 {
                    reflected += 1;
                } else if want.delta {
                    refracted += 1;
                } else {
                    none += 1;
                }
            }
        }
        assert_eq!(differing, 0, "lanes that differ from gltf_sample");
        for (what, count) in [
            ("reflected", reflected),
            ("refracted", refracted),
            ("none", none),
        ] {
            assert!(
                count > 1000,
                "only {count} lanes {what}: the test exercises little"
            );
        }
    }

    /// The lanes' Fresnel equations are the scalar ones, total internal
    /// reflection included.
    #[test]
    fn fresnel_of_the_lanes_equals_the_scalar_one() {
        for k in 0..2000 {
            let c = Floats(std::array::from_fn(|l| {
                ((k * 8 + l) as f32 / 16000.0).max(1e-6)
            }));
            let eta = Floats(std::array::from_fn(|l| [1.5, 0.67, 1.33, 0.9][(k + l) % 4]));
            let (f, cos_t) = fresnel_dielectric_lanes(c, eta);
            for l in 0..WIDTH {
                let (sf, sc) = fresnel_dielectric(c.0[l], eta.0[l]);
                assert_eq!(
                    (f.0[l].to_bits(), cos_t.0[l].to_bits()),
                    (sf.to_bits(), sc.to_bits()),
                    "cos {} eta {}",
                    c.0[l],
                    eta.0[l]
                );
            }
        }
    }
}
