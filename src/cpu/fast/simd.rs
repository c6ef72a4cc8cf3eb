//! A register of f32 lanes (sixteen with AVX-512, eight with AVX2) and
//! 3-vectors of them, for the lane schedule (`lanes`).
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

pub use super::wide::WIDTH;

/// Floats, one per lane.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Floats(pub [f32; WIDTH]);

/// Conditions, one per lane.
pub type Bools = [bool; WIDTH];

/// A comparison method: one AVX compare where the build targets AVX2 and
/// BMI2, the per-lane loop elsewhere.
macro_rules! comparison {
    ($name:ident, $op:tt, $predicate:ident) => {
        #[inline(always)]
        pub fn $name(self, o: Floats) -> Bools {
            #[cfg(all(
                target_arch = "x86_64",
                target_feature = "avx2",
                target_feature = "bmi2"
            ))]
            {
                use std::arch::x86_64::*;
                avx::bools(avx::cmp::<$predicate>(avx::load(self), avx::load(o)))
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

impl Floats {
    #[inline(always)]
    pub fn splat(x: f32) -> Floats {
        Floats([x; WIDTH])
    }

    // Plain loops, not `array::map` or `from_fn`: those are not always
    // inlined, and then nothing is vectorized.
    #[inline(always)]
    pub fn map(self, f: impl Fn(f32) -> f32) -> Floats {
        let mut r = [0.0; WIDTH];
        for i in 0..WIDTH {
            r[i] = f(self.0[i]);
        }
        Floats(r)
    }

    #[inline(always)]
    pub fn zip(self, o: Floats, f: impl Fn(f32, f32) -> f32) -> Floats {
        let mut r = [0.0; WIDTH];
        for i in 0..WIDTH {
            r[i] = f(self.0[i], o.0[i]);
        }
        Floats(r)
    }

    #[inline(always)]
    pub fn test(self, o: Floats, f: impl Fn(f32, f32) -> bool) -> Bools {
        let mut r = [false; WIDTH];
        for i in 0..WIDTH {
            r[i] = f(self.0[i], o.0[i]);
        }
        r
    }

    #[inline(always)]
    pub fn sqrt(self) -> Floats {
        #[cfg(all(
            target_arch = "x86_64",
            target_feature = "avx2",
            target_feature = "bmi2"
        ))]
        {
            avx::store(avx::sqrt(avx::load(self)))
        }
        #[cfg(not(all(
            target_arch = "x86_64",
            target_feature = "avx2",
            target_feature = "bmi2"
        )))]
        self.map(f32::sqrt)
    }

    #[inline(always)]
    pub fn abs(self) -> Floats {
        self.map(f32::abs)
    }

    /// `f32::max` (IEEE maxNum) per lane.
    #[inline(always)]
    pub fn max(self, o: Floats) -> Floats {
        self.zip(o, f32::max)
    }

    /// `f32::min` per lane.
    #[inline(always)]
    pub fn min(self, o: Floats) -> Floats {
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
pub fn select(m: Bools, a: Floats, b: Floats) -> Floats {
    #[cfg(all(
        target_arch = "x86_64",
        target_feature = "avx2",
        target_feature = "bmi2"
    ))]
    {
        avx::store(avx::blend(avx::mask(m), avx::load(a), avx::load(b)))
    }
    #[cfg(not(all(
        target_arch = "x86_64",
        target_feature = "avx2",
        target_feature = "bmi2"
    )))]
    {
        let mut r = [0.0; WIDTH];
        for i in 0..WIDTH {
            r[i] = if m[i] { a.0[i] } else { b.0[i] };
        }
        Floats(r)
    }
}

/// `if m { a } else { b }` per lane, of masks.
#[inline(always)]
pub fn select_mask(m: Bools, a: Bools, b: Bools) -> Bools {
    let m = word(m);
    mask_of((m & word(a)) | ((m ^ ONES) & word(b)))
}

// Masks as one 64-bit word, a byte (0 or 1) per lane: the logic is one
// integer instruction.

#[cfg(not(all(
    target_arch = "x86_64",
    target_feature = "avx512f",
    target_feature = "avx512bw",
    target_feature = "avx512vl"
)))]
type Word = u64;
#[cfg(all(
    target_arch = "x86_64",
    target_feature = "avx512f",
    target_feature = "avx512bw",
    target_feature = "avx512vl"
))]
type Word = u128;

#[inline(always)]
fn word(m: Bools) -> Word {
    Word::from_ne_bytes(m.map(u8::from))
}

#[inline(always)]
fn mask_of(w: Word) -> Bools {
    // SAFETY: every byte of `w` is 0 or 1, a valid bool: the callers
    // combine such words with and, or, and xor with `ONES`, or deposit
    // bits into `ONES`' positions (`avx::bools`).
    unsafe { std::mem::transmute::<Word, [bool; WIDTH]>(w) }
}

const ONES: Word = Word::from_ne_bytes([1; WIDTH]);

#[inline(always)]
pub fn and(a: Bools, b: Bools) -> Bools {
    mask_of(word(a) & word(b))
}

#[inline(always)]
pub fn or(a: Bools, b: Bools) -> Bools {
    mask_of(word(a) | word(b))
}

#[inline(always)]
pub fn not(a: Bools) -> Bools {
    mask_of(word(a) ^ ONES)
}

/// Where the build targets AVX2 (`target-cpu=native` in
/// `.cargo/config.toml` on these machines), the four operations, the square
/// root, comparisons and selects are one vector instruction each
/// (`wide`'s), written as such: left to the compiler, the lanes' larger
/// functions came out with them partly as scalar instructions (`vmulss`
/// where `vmulps` was meant). IEEE operations give each lane the scalar
/// result either way.
#[cfg(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "bmi2"
))]
#[allow(unused_unsafe)]
mod avx {
    // `wide`'s AVX2 functions enable their feature themselves (calling one
    // takes an `unsafe` block here, where the build targets AVX2 but the
    // function does not say so); its AVX-512 ones are plain functions.
    use super::super::wide::{self, F, Mask};
    use super::{Bools, Floats, WIDTH};

    macro_rules! binary {
        ($($f:ident),*) => {$(
            #[inline(always)]
            pub fn $f(a: F, b: F) -> F {
                // SAFETY: the build targets AVX2 (the module's cfg).
                unsafe { wide::$f(a, b) }
            }
        )*};
    }
    binary!(add, sub, mul, div);

    #[inline(always)]
    pub fn sqrt(a: F) -> F {
        // SAFETY: as above.
        unsafe { wide::sqrt(a) }
    }

    #[inline(always)]
    pub fn cmp<const P: i32>(a: F, b: F) -> Mask {
        // SAFETY: as above.
        unsafe { wide::cmp::<P>(a, b) }
    }

    /// `m ? a : b` per lane.
    #[inline(always)]
    pub fn blend(m: Mask, a: F, b: F) -> F {
        // SAFETY: as above.
        unsafe { wide::blend(m, a, b) }
    }

    #[inline(always)]
    pub fn load(a: Floats) -> F {
        // SAFETY: WIDTH f32 are a register either way.
        unsafe { std::mem::transmute::<[f32; WIDTH], F>(a.0) }
    }

    #[inline(always)]
    pub fn store(v: F) -> Floats {
        // SAFETY: as for `load`.
        Floats(unsafe { std::mem::transmute::<F, [f32; WIDTH]>(v) })
    }

    /// A comparison's lanes as bools.
    #[inline(always)]
    pub fn bools(c: Mask) -> Bools {
        // SAFETY: the build targets AVX2 and BMI2 (the module's cfg).
        unsafe { wide::to_bools(c) }
    }

    /// Bools as a select's mask.
    #[inline(always)]
    pub fn mask(m: Bools) -> Mask {
        // SAFETY: as above.
        unsafe { wide::from_bools(m) }
    }

    /// `table`'s lane `idx[l]` in each lane l.
    #[inline(always)]
    pub fn permute(table: F, idx: &[u32; WIDTH]) -> F {
        // SAFETY: as above.
        unsafe { wide::permute(table, wide::load_i(idx)) }
    }
}

macro_rules! lanewise {
    ($trait:ident, $f:ident, $op:tt) => {
        impl $trait for Floats {
            type Output = Floats;
            #[inline(always)]
            fn $f(self, o: Floats) -> Floats {
                #[cfg(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "bmi2"))]
                {
                    avx::store(avx::$f(avx::load(self), avx::load(o)))
                }
                #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "bmi2")))]
                self.zip(o, |a, b| a $op b)
            }
        }
    };
}
lanewise!(Add, add, +);
lanewise!(Sub, sub, -);
lanewise!(Mul, mul, *);
lanewise!(Div, div, /);

impl Neg for Floats {
    type Output = Floats;
    #[inline(always)]
    fn neg(self) -> Floats {
        self.map(|a| -a)
    }
}

/// 3-vectors, a lane each (glam's `Vec3` per lane).
#[derive(Clone, Copy, Debug, Default)]
pub struct V3 {
    pub x: Floats,
    pub y: Floats,
    pub z: Floats,
}

impl V3 {
    /// `v` in every lane.
    #[inline(always)]
    pub fn splat(v: Vec3) -> V3 {
        V3 {
            x: Floats::splat(v.x),
            y: Floats::splat(v.y),
            z: Floats::splat(v.z),
        }
    }

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
    pub fn dot(self, o: V3) -> Floats {
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
    pub fn length(self) -> Floats {
        self.dot(self).sqrt()
    }

    /// glam's `normalize`: times the reciprocal length.
    #[inline(always)]
    pub fn normalize(self) -> V3 {
        self * (Floats::splat(1.0) / self.length())
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
        let m = |a: Floats, b: Floats| select(a.gt(b), a, b);
        V3 {
            x: m(self.x, o.x),
            y: m(self.y, o.y),
            z: m(self.z, o.z),
        }
    }

    /// glam's `max_element`.
    #[inline(always)]
    pub fn max_element(self) -> Floats {
        let m = |a: Floats, b: Floats| select(a.gt(b), a, b);
        m(self.x, m(self.y, self.z))
    }
}

/// `table`'s value at each lane's index (`table.0[idx[l]]`, every index
/// below `WIDTH`): one permute instruction where the build targets AVX2, for
/// per-material values looked up by the lanes' materials.
#[inline(always)]
pub fn permute(table: Floats, idx: &[u32; WIDTH]) -> Floats {
    #[cfg(all(
        target_arch = "x86_64",
        target_feature = "avx2",
        target_feature = "bmi2"
    ))]
    {
        avx::store(avx::permute(avx::load(table), idx))
    }
    #[cfg(not(all(
        target_arch = "x86_64",
        target_feature = "avx2",
        target_feature = "bmi2"
    )))]
    Floats(std::array::from_fn(|l| table.0[idx[l] as usize % WIDTH]))
}

impl V3 {
    /// `permute` of each axis.
    #[inline(always)]
    pub fn permute(self, idx: &[u32; WIDTH]) -> V3 {
        V3 {
            x: permute(self.x, idx),
            y: permute(self.y, idx),
            z: permute(self.z, idx),
        }
    }
}

/// `if m { a } else { b }` per lane.
#[inline(always)]
pub fn select3(m: Bools, a: V3, b: V3) -> V3 {
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
impl Mul<Floats> for V3 {
    type Output = V3;
    #[inline(always)]
    fn mul(self, s: Floats) -> V3 {
        V3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

impl Div<Floats> for V3 {
    type Output = V3;
    #[inline(always)]
    fn div(self, s: Floats) -> V3 {
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
            let h = crate::cpu::common::rng::pcg_hash(seed.wrapping_mul(31).wrapping_add(i));
            match h % 7 {
                0 => 0.0,
                1 => -0.0,
                2 => 1e-30 * (h as f32),
                3 => -1e30 / (h as f32 + 1.0),
                _ => (h as f32 / u32::MAX as f32) * 4.0 - 2.0,
            }
        };
        let mut v = V3::default();
        for l in 0..WIDTH {
            let i = 3 * l as u32;
            v.set_lane(l, Vec3::new(pick(i), pick(i + 1), pick(i + 2)));
        }
        v
    }

    fn same(a: Vec3, b: Vec3) -> bool {
        a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)
    }

    /// `permute` picks each lane's table entry, at either width.
    #[test]
    fn permute_takes_each_lanes_entry_of_the_table() {
        let table = Floats(std::array::from_fn(|k| k as f32 * 1.5 - 3.0));
        for shift in 0..WIDTH as u32 {
            let idx: [u32; WIDTH] = std::array::from_fn(|l| (l as u32 * 7 + shift) % WIDTH as u32);
            let p = permute(table, &idx);
            for l in 0..WIDTH {
                assert_eq!(p.0[l].to_bits(), table.0[idx[l] as usize].to_bits());
            }
        }
    }

    /// Every operation is glam's per lane, bit for bit (NaNs included).
    #[test]
    fn lanes_compute_glams_bits() {
        for seed in 0..500 {
            let (a, b) = (lanes(seed), lanes(seed + 1000));
            let s = a.x;
            for l in 0..WIDTH {
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
                // `f32::max` and `min` may return either zero when +0 and
                // -0 meet (Rust's documentation): the value, not the bits.
                let same_value = |p: f32, q: f32| p == q || (p.is_nan() && q.is_nan());
                assert!(same_value(s.max(b.y).0[l], k.max(y.y)));
                assert!(same_value(s.min(b.y).0[l], k.min(y.y)));
                assert_eq!(s.sqrt().0[l].to_bits(), k.sqrt().to_bits());
            }
            // Comparisons (NaN compares false), selects and mask logic.
            let (p, q) = (a.x / b.y, b.z);
            let (gt, ge, lt, le) = (p.gt(q), p.ge(q), p.lt(q), p.le(q));
            let r = [gt, ge, lt, le];
            for l in 0..WIDTH {
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
