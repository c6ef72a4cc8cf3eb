//! Eight f32 lanes and 3-vectors of them, for the lane schedule (`lanes`).
//! Every operation applies the scalar operation glam or `f32` uses to each
//! lane, in glam's order (`dot` is (x x' + y y') + z z', `max` is glam's
//! `a > b ? a : b`), so a lane computes the scalar twin's bits. Where the
//! build targets AVX2 the arithmetic, comparisons and selects are written
//! as vector instructions (`avx`); elsewhere, and for the rest, plain loops
//! over the lanes are left for the compiler to vectorize.

// Loops over lane indices are the point here: each iteration is one lane,
// written so that the compiler turns the loop into vector instructions.
#![allow(clippy::needless_range_loop)]

use glam::Vec3;
use std::ops::{Add, Div, Mul, Neg, Sub};

pub const N: usize = 8;

/// Eight floats, one per lane.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct F8(pub [f32; N]);

/// Eight conditions, one per lane.
pub type M8 = [bool; N];

/// A comparison method: one AVX compare where the build targets AVX2 and
/// BMI2, the per-lane loop elsewhere.
macro_rules! comparison {
    ($name:ident, $op:tt, $predicate:ident) => {
        #[inline(always)]
        pub fn $name(self, o: F8) -> M8 {
            #[cfg(all(
                target_arch = "x86_64",
                target_feature = "avx2",
                target_feature = "bmi2"
            ))]
            {
                use std::arch::x86_64::*;
                // SAFETY: the build targets AVX2.
                avx::bools(unsafe { _mm256_cmp_ps::<$predicate>(avx::load(self), avx::load(o)) })
            }
            #[cfg(not(all(
                target_arch = "x86_64",
                target_feature = "avx2",
                target_feature = "bmi2"
            )))]
            self.test(o, |a, b| a $op b)
        }
    };
}

impl F8 {
    #[inline(always)]
    pub fn splat(x: f32) -> F8 {
        F8([x; N])
    }

    // Plain loops, not `array::map` or `from_fn`: those are not always
    // inlined, and then nothing is vectorized.
    #[inline(always)]
    pub fn map(self, f: impl Fn(f32) -> f32) -> F8 {
        let mut r = [0.0; N];
        for i in 0..N {
            r[i] = f(self.0[i]);
        }
        F8(r)
    }

    #[inline(always)]
    pub fn zip(self, o: F8, f: impl Fn(f32, f32) -> f32) -> F8 {
        let mut r = [0.0; N];
        for i in 0..N {
            r[i] = f(self.0[i], o.0[i]);
        }
        F8(r)
    }

    #[inline(always)]
    pub fn test(self, o: F8, f: impl Fn(f32, f32) -> bool) -> M8 {
        let mut r = [false; N];
        for i in 0..N {
            r[i] = f(self.0[i], o.0[i]);
        }
        r
    }

    #[inline(always)]
    pub fn sqrt(self) -> F8 {
        #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
        {
            // SAFETY: the build targets AVX.
            avx::store(unsafe { std::arch::x86_64::_mm256_sqrt_ps(avx::load(self)) })
        }
        #[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
        self.map(f32::sqrt)
    }

    #[inline(always)]
    pub fn abs(self) -> F8 {
        self.map(f32::abs)
    }

    /// `f32::max` (IEEE maxNum) per lane.
    #[inline(always)]
    pub fn max(self, o: F8) -> F8 {
        self.zip(o, f32::max)
    }

    /// `f32::min` per lane.
    #[inline(always)]
    pub fn min(self, o: F8) -> F8 {
        self.zip(o, f32::min)
    }

    // Ordered comparisons (false where either lane is NaN), as `f32`'s.
    comparison!(gt, >, _CMP_GT_OQ);
    comparison!(ge, >=, _CMP_GE_OQ);
    comparison!(lt, <, _CMP_LT_OQ);
    comparison!(le, <=, _CMP_LE_OQ);
}

/// `if m { a } else { b }` per lane.
#[inline(always)]
pub fn select(m: M8, a: F8, b: F8) -> F8 {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    {
        use std::arch::x86_64::*;
        // SAFETY: the build targets AVX2.
        avx::store(unsafe { _mm256_blendv_ps(avx::load(b), avx::load(a), avx::mask(m)) })
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
    {
        let mut r = [0.0; N];
        for i in 0..N {
            r[i] = if m[i] { a.0[i] } else { b.0[i] };
        }
        F8(r)
    }
}

/// `if m { a } else { b }` per lane, of masks.
#[inline(always)]
pub fn select_mask(m: M8, a: M8, b: M8) -> M8 {
    let m = word(m);
    mask_of((m & word(a)) | ((m ^ ONES) & word(b)))
}

// Masks as one 64-bit word, a byte (0 or 1) per lane: the logic is one
// integer instruction.

#[inline(always)]
fn word(m: M8) -> u64 {
    u64::from_ne_bytes(m.map(u8::from))
}

#[inline(always)]
fn mask_of(w: u64) -> M8 {
    // SAFETY: every byte of `w` is 0 or 1, a valid bool: the callers
    // combine such words with and, or, and xor with `ONES`, or deposit
    // bits into `ONES`' positions (`avx::bools`).
    unsafe { std::mem::transmute::<u64, [bool; 8]>(w) }
}

const ONES: u64 = 0x0101_0101_0101_0101;

#[inline(always)]
pub fn and(a: M8, b: M8) -> M8 {
    mask_of(word(a) & word(b))
}

#[inline(always)]
pub fn or(a: M8, b: M8) -> M8 {
    mask_of(word(a) | word(b))
}

#[inline(always)]
pub fn not(a: M8) -> M8 {
    mask_of(word(a) ^ ONES)
}

/// Where the build targets AVX (`target-cpu=native` in `.cargo/config.toml`
/// on these machines), the four operations and the square root are one
/// vector instruction each, written as such: left to the compiler, the
/// lanes' larger functions came out with them partly as eight scalar
/// instructions (`vmulss` where `vmulps` was meant). IEEE operations give
/// each lane the scalar result either way.
#[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
mod avx {
    use super::F8;
    use std::arch::x86_64::*;

    #[inline(always)]
    pub fn load(a: F8) -> __m256 {
        // SAFETY: eight f32 are 32 bytes either way.
        unsafe { std::mem::transmute::<[f32; 8], __m256>(a.0) }
    }

    #[inline(always)]
    pub fn store(v: __m256) -> F8 {
        // SAFETY: as for `load`.
        F8(unsafe { std::mem::transmute::<__m256, [f32; 8]>(v) })
    }

    /// A comparison's lanes (all ones or zeros) as bools.
    #[cfg(all(target_feature = "avx2", target_feature = "bmi2"))]
    #[inline(always)]
    pub fn bools(c: __m256) -> super::M8 {
        // SAFETY: the build targets AVX2 and BMI2.
        let bits = unsafe { _mm256_movemask_ps(c) } as u32 as u64;
        // Bit l to the low bit of byte l: a word of 0 and 1 bytes.
        // SAFETY: as above.
        super::mask_of(unsafe { _pdep_u64(bits, super::ONES) })
    }

    /// Bools as a blend mask (the sign bit of each lane).
    #[cfg(target_feature = "avx2")]
    #[inline(always)]
    pub fn mask(m: super::M8) -> __m256 {
        // SAFETY: the build targets AVX2; eight bools are eight bytes.
        unsafe {
            let bytes = std::mem::transmute::<[bool; 8], u64>(m);
            let ones = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(bytes as i64));
            _mm256_castsi256_ps(_mm256_slli_epi32::<31>(ones))
        }
    }
}

macro_rules! lanewise {
    ($trait:ident, $f:ident, $op:tt, $intrinsic:ident) => {
        impl $trait for F8 {
            type Output = F8;
            #[inline(always)]
            fn $f(self, o: F8) -> F8 {
                #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
                {
                    // SAFETY: the build targets AVX.
                    avx::store(unsafe {
                        std::arch::x86_64::$intrinsic(avx::load(self), avx::load(o))
                    })
                }
                #[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
                self.zip(o, |a, b| a $op b)
            }
        }
    };
}
lanewise!(Add, add, +, _mm256_add_ps);
lanewise!(Sub, sub, -, _mm256_sub_ps);
lanewise!(Mul, mul, *, _mm256_mul_ps);
lanewise!(Div, div, /, _mm256_div_ps);

impl Neg for F8 {
    type Output = F8;
    #[inline(always)]
    fn neg(self) -> F8 {
        self.map(|a| -a)
    }
}

/// Eight 3-vectors, a lane each (glam's `Vec3` per lane).
#[derive(Clone, Copy, Debug, Default)]
pub struct V3 {
    pub x: F8,
    pub y: F8,
    pub z: F8,
}

impl V3 {
    /// Lane i's vector.
    #[inline(always)]
    pub fn lane(&self, i: usize) -> Vec3 {
        Vec3::new(self.x.0[i], self.y.0[i], self.z.0[i])
    }

    #[inline(always)]
    pub fn set_lane(&mut self, i: usize, v: Vec3) {
        (self.x.0[i], self.y.0[i], self.z.0[i]) = (v.x, v.y, v.z);
    }

    #[inline(always)]
    pub fn dot(self, o: V3) -> F8 {
        (self.x * o.x) + (self.y * o.y) + (self.z * o.z)
    }

    #[inline(always)]
    pub fn cross(self, o: V3) -> V3 {
        V3 {
            x: self.y * o.z - o.y * self.z,
            y: self.z * o.x - o.z * self.x,
            z: self.x * o.y - o.x * self.y,
        }
    }

    #[inline(always)]
    pub fn length(self) -> F8 {
        self.dot(self).sqrt()
    }

    /// glam's `normalize`: times the reciprocal length.
    #[inline(always)]
    pub fn normalize(self) -> V3 {
        self * (F8::splat(1.0) / self.length())
    }

    #[inline(always)]
    pub fn abs(self) -> V3 {
        V3 {
            x: self.x.abs(),
            y: self.y.abs(),
            z: self.z.abs(),
        }
    }

    /// glam's `max`: `a > b ? a : b` per component.
    #[inline(always)]
    pub fn max_glam(self, o: V3) -> V3 {
        let m = |a: F8, b: F8| select(a.gt(b), a, b);
        V3 {
            x: m(self.x, o.x),
            y: m(self.y, o.y),
            z: m(self.z, o.z),
        }
    }

    /// glam's `max_element`.
    #[inline(always)]
    pub fn max_element(self) -> F8 {
        let m = |a: F8, b: F8| select(a.gt(b), a, b);
        m(self.x, m(self.y, self.z))
    }
}

/// `if m { a } else { b }` per lane.
#[inline(always)]
pub fn select3(m: M8, a: V3, b: V3) -> V3 {
    V3 {
        x: select(m, a.x, b.x),
        y: select(m, a.y, b.y),
        z: select(m, a.z, b.z),
    }
}

impl Add for V3 {
    type Output = V3;
    #[inline(always)]
    fn add(self, o: V3) -> V3 {
        V3 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl Sub for V3 {
    type Output = V3;
    #[inline(always)]
    fn sub(self, o: V3) -> V3 {
        V3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl Mul for V3 {
    type Output = V3;
    #[inline(always)]
    fn mul(self, o: V3) -> V3 {
        V3 {
            x: self.x * o.x,
            y: self.y * o.y,
            z: self.z * o.z,
        }
    }
}

/// Each component times the lane's scalar (glam's `Vec3 * f32` and
/// `f32 * Vec3`: the same products).
impl Mul<F8> for V3 {
    type Output = V3;
    #[inline(always)]
    fn mul(self, s: F8) -> V3 {
        V3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

impl Div<F8> for V3 {
    type Output = V3;
    #[inline(always)]
    fn div(self, s: F8) -> V3 {
        V3 {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }
}

impl Neg for V3 {
    type Output = V3;
    #[inline(always)]
    fn neg(self) -> V3 {
        V3 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lanes of awkward values: zeros of both signs, tiny, huge, negative.
    fn lanes(seed: u32) -> V3 {
        let pick = |i: u32| {
            let h = crate::cpu::rng::pcg_hash(seed.wrapping_mul(31).wrapping_add(i));
            match h % 7 {
                0 => 0.0,
                1 => -0.0,
                2 => 1e-30 * (h as f32),
                3 => -1e30 / (h as f32 + 1.0),
                _ => (h as f32 / u32::MAX as f32) * 4.0 - 2.0,
            }
        };
        let mut v = V3::default();
        for l in 0..N {
            let i = 3 * l as u32;
            v.set_lane(l, Vec3::new(pick(i), pick(i + 1), pick(i + 2)));
        }
        v
    }

    fn same(a: Vec3, b: Vec3) -> bool {
        a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)
    }

    /// Every operation is glam's per lane, bit for bit (NaNs included).
    #[test]
    fn lanes_compute_glams_bits() {
        for seed in 0..500 {
            let (a, b) = (lanes(seed), lanes(seed + 1000));
            let s = a.x;
            for l in 0..N {
                let (x, y, k) = (a.lane(l), b.lane(l), s.0[l]);
                assert!(same((a + b).lane(l), x + y));
                assert!(same((a - b).lane(l), x - y));
                assert!(same((a * b).lane(l), x * y));
                assert!(same((a * s).lane(l), x * k));
                assert!(same((a * s).lane(l), k * x));
                assert!(same((a / s).lane(l), x / k));
                assert!(same((-a).lane(l), -x));
                assert!(same(a.cross(b).lane(l), x.cross(y)));
                assert!(same(a.normalize().lane(l), x.normalize()));
                assert!(same(a.abs().lane(l), x.abs()));
                assert!(same(a.max_glam(b).lane(l), x.max(y)));
                assert_eq!(a.dot(b).0[l].to_bits(), x.dot(y).to_bits());
                assert_eq!(a.length().0[l].to_bits(), x.length().to_bits());
                assert_eq!(a.max_element().0[l].to_bits(), x.max_element().to_bits());
                assert_eq!(s.max(b.y).0[l].to_bits(), k.max(y.y).to_bits());
                assert_eq!(s.min(b.y).0[l].to_bits(), k.min(y.y).to_bits());
                assert_eq!(s.sqrt().0[l].to_bits(), k.sqrt().to_bits());
            }
            // Comparisons (NaN compares false), selects and mask logic.
            let (p, q) = (a.x / b.y, b.z);
            let (gt, ge, lt, le) = (p.gt(q), p.ge(q), p.lt(q), p.le(q));
            let r = [gt, ge, lt, le];
            for l in 0..N {
                let (u, v) = (p.0[l], q.0[l]);
                assert_eq!([gt[l], ge[l], lt[l], le[l]], [u > v, u >= v, u < v, u <= v]);
                let picked = select(gt, p, q).0[l];
                assert_eq!(picked.to_bits(), if u > v { u } else { v }.to_bits());
                for (m, n) in [(r[0], r[2]), (r[1], r[3]), (r[3], r[0])] {
                    assert_eq!(and(m, n)[l], m[l] && n[l]);
                    assert_eq!(or(m, n)[l], m[l] || n[l]);
                    assert_eq!(not(m)[l], !m[l]);
                    let chosen = select_mask(m, n, not(n))[l];
                    assert_eq!(chosen, if m[l] { n[l] } else { !n[l] });
                }
            }
        }
    }
}
