//! Keyframe interpolation as the glTF 2.0 spec defines it (section 3.11,
//! appendix C): STEP, LINEAR (spherical for rotations, along the short arc)
//! and CUBICSPLINE (cubic Hermite with the stored tangents scaled by the
//! keyframe interval). Times outside the keyframes clamp to the first or
//! last value: vkpt does not loop animations. Values are computed in f64
//! from the file's f32 keyframes.

use glam::DQuat;

/// How a sampler interpolates between its keyframes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Interpolation {
    Step,
    Linear,
    CubicSpline,
}

impl Interpolation {
    /// How many output elements each keyframe holds (CUBICSPLINE stores an
    /// in-tangent, the value and an out-tangent).
    pub fn elements_per_key(self) -> usize {
        match self {
            Interpolation::CubicSpline => 3,
            _ => 1,
        }
    }
}

/// One sampler's keyframes: strictly increasing `times`, and `values` with
/// `width` numbers per element (3 for translation and scale, 4 for a
/// rotation quaternion x, y, z, w; the morph target count for weights),
/// `elements_per_key` elements per keyframe.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Keyframes {
    pub times: Vec<f64>,
    pub values: Vec<f64>,
    pub width: usize,
    pub interpolation: Interpolation,
}

/// Where `t` falls: the keyframe before it and the fraction of the way to
/// the next, or `None` when `t` is at or beyond an end (then the index of
/// the value to hold).
enum Segment {
    Hold(usize),
    Between { k: usize, u: f64, dt: f64 },
}

impl Keyframes {
    /// The first and last keyframe times.
    pub fn range(&self) -> (f64, f64) {
        (self.times[0], self.times[self.times.len() - 1])
    }

    fn segment(&self, t: f64) -> Segment {
        let n = self.times.len();
        if n == 1 || t <= self.times[0] {
            return Segment::Hold(0);
        }
        if t >= self.times[n - 1] {
            return Segment::Hold(n - 1);
        }
        // The last keyframe at or before t (times are strictly increasing).
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let dt = self.times[k + 1] - self.times[k];
        Segment::Between {
            k,
            u: (t - self.times[k]) / dt,
            dt,
        }
    }

    /// Element `e` (0: in-tangent, 1: value, 2: out-tangent for
    /// CUBICSPLINE; 0 otherwise) of keyframe `k`.
    fn element(&self, k: usize, e: usize) -> &[f64] {
        let at = (k * self.interpolation.elements_per_key() + e) * self.width;
        &self.values[at..at + self.width]
    }

    /// The value of keyframe `k`.
    fn value(&self, k: usize) -> &[f64] {
        let e = usize::from(self.interpolation == Interpolation::CubicSpline);
        self.element(k, e)
    }

    /// The interpolated value at `t`, component by component (translation,
    /// scale, morph weights).
    pub fn sample(&self, t: f64) -> Vec<f64> {
        match self.segment(t) {
            Segment::Hold(k) => self.value(k).to_vec(),
            Segment::Between { k, u, dt } => match self.interpolation {
                Interpolation::Step => self.value(k).to_vec(),
                Interpolation::Linear => {
                    let (a, b) = (self.value(k), self.value(k + 1));
                    a.iter().zip(b).map(|(a, b)| a + (b - a) * u).collect()
                }
                Interpolation::CubicSpline => self.hermite(k, u, dt),
            },
        }
    }

    /// The cubic Hermite spline between keyframes `k` and `k + 1` at
    /// fraction `u`: the out-tangent of `k` and the in-tangent of `k + 1`
    /// are derivatives per second, so they are multiplied by the interval
    /// `dt` to be derivatives per unit of `u`.
    fn hermite(&self, k: usize, u: f64, dt: f64) -> Vec<f64> {
        let (u2, u3) = (u * u, u * u * u);
        let h_v0 = 2.0 * u3 - 3.0 * u2 + 1.0;
        let h_b0 = u3 - 2.0 * u2 + u;
        let h_v1 = -2.0 * u3 + 3.0 * u2;
        let h_a1 = u3 - u2;
        let v0 = self.element(k, 1);
        let b0 = self.element(k, 2);
        let v1 = self.element(k + 1, 1);
        let a1 = self.element(k + 1, 0);
        (0..self.width)
            .map(|i| h_v0 * v0[i] + dt * h_b0 * b0[i] + h_v1 * v1[i] + dt * h_a1 * a1[i])
            .collect()
    }

    /// The rotation at `t`: STEP holds, LINEAR is spherical linear
    /// interpolation along the shorter arc, CUBICSPLINE is the spline of
    /// the components, normalized. The result is a unit quaternion (the
    /// identity if the file's values make a zero one).
    pub fn sample_rotation(&self, t: f64) -> DQuat {
        let q = match (self.segment(t), self.interpolation) {
            (Segment::Between { k, u, .. }, Interpolation::Linear) => {
                slerp_short(quat(self.value(k)), quat(self.value(k + 1)), u)
            }
            _ => quat(&self.sample(t)),
        };
        if q.length_squared() > 0.0 && q.is_finite() {
            q.normalize()
        } else {
            DQuat::IDENTITY
        }
    }
}

fn quat(v: &[f64]) -> DQuat {
    DQuat::from_xyzw(v[0], v[1], v[2], v[3])
}

/// Spherical linear interpolation from `a` to `b` at `u` along the shorter
/// of the two arcs (q and -q are the same rotation: when the quaternions
/// are more than 90° apart, `b` is negated first). Nearly equal
/// quaternions are interpolated linearly, where sin θ would lose precision.
pub(crate) fn slerp_short(a: DQuat, b: DQuat, u: f64) -> DQuat {
    let a = a.normalize();
    let mut b = b.normalize();
    let mut d = a.dot(b);
    if d < 0.0 {
        b = -b;
        d = -d;
    }
    if d > 1.0 - 1e-9 {
        return (a * (1.0 - u) + b * u).normalize();
    }
    let theta = d.min(1.0).acos();
    let s = theta.sin();
    a * (((1.0 - u) * theta).sin() / s) + b * ((u * theta).sin() / s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};

    fn keys(times: &[f64], values: &[f64], width: usize, i: Interpolation) -> Keyframes {
        Keyframes {
            times: times.to_vec(),
            values: values.to_vec(),
            width,
            interpolation: i,
        }
    }

    fn close(a: &[f64], b: &[f64]) {
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() < 1e-12, "{a:?} != {b:?}");
        }
    }

    #[test]
    fn step_holds_the_earlier_keyframe_until_the_next_time() {
        let k = keys(
            &[0.0, 1.0, 2.0],
            &[0., 0., 0., 1., 2., 3., 5., 5., 5.],
            3,
            Interpolation::Step,
        );
        close(&k.sample(0.999), &[0., 0., 0.]);
        close(&k.sample(1.0), &[1., 2., 3.]);
        close(&k.sample(1.5), &[1., 2., 3.]);
        close(&k.sample(2.5), &[5., 5., 5.]);
    }

    #[test]
    fn linear_interpolates_and_clamps_outside_the_keyframes() {
        let k = keys(
            &[1.0, 3.0],
            &[0., 10., 20., 4., 10., 0.],
            3,
            Interpolation::Linear,
        );
        close(&k.sample(2.5), &[3.0, 10.0, 5.0]);
        close(&k.sample(0.0), &[0., 10., 20.]);
        close(&k.sample(-5.0), &[0., 10., 20.]);
        close(&k.sample(7.0), &[4., 10., 0.]);
    }

    #[test]
    fn a_single_keyframe_is_constant() {
        for i in [Interpolation::Step, Interpolation::Linear] {
            let k = keys(&[0.5], &[1., 2., 3.], 3, i);
            close(&k.sample(9.0), &[1., 2., 3.]);
        }
    }

    /// About Y by `angle`: (0, sin(a/2), 0, cos(a/2)).
    fn about_y(angle: f64) -> [f64; 4] {
        [0.0, (angle / 2.0).sin(), 0.0, (angle / 2.0).cos()]
    }

    #[test]
    fn linear_rotation_is_slerp_at_constant_angular_speed() {
        // 0 to 90° about Y: a quarter of the way is 22.5°, not the
        // normalized lerp's angle.
        let v: Vec<f64> = [about_y(0.0), about_y(FRAC_PI_2)].concat();
        let k = keys(&[0.0, 1.0], &v, 4, Interpolation::Linear);
        let q = k.sample_rotation(0.25);
        close(&q.to_array(), &about_y(FRAC_PI_2 / 4.0));
    }

    #[test]
    fn linear_rotation_takes_the_short_arc() {
        // +170° about Y to -170° about Y (stored as q with w > 0 on both
        // sides, so their dot is negative): the short way goes through
        // 180°, 20° in all, not back through 0 (340°). Halfway is 180°.
        let v: Vec<f64> = [about_y(170f64.to_radians()), about_y(-170f64.to_radians())].concat();
        let k = keys(&[0.0, 1.0], &v, 4, Interpolation::Linear);
        let q = k.sample_rotation(0.5);
        // 180° about Y is (0, ±1, 0, 0).
        assert!((q.y.abs() - 1.0).abs() < 1e-12, "{q:?}");
        assert!(q.w.abs() < 1e-12, "{q:?}");
        // A quarter of the way: 175°.
        let q = k.sample_rotation(0.25);
        let angle = 2.0 * q.w.abs().acos();
        assert!((angle - 175f64.to_radians()).abs() < 1e-9, "{angle}");
    }

    #[test]
    fn slerp_of_nearly_equal_quaternions_is_finite_and_unit() {
        let a = DQuat::from_rotation_y(0.3);
        let b = DQuat::from_rotation_y(0.3 + 1e-12);
        let q = slerp_short(a, b, 0.5);
        assert!(q.is_finite() && (q.length() - 1.0).abs() < 1e-12);
        let q = slerp_short(a, -a, 0.5);
        assert!((q.dot(a).abs() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn cubic_spline_scales_tangents_by_the_keyframe_interval() {
        // One component, keyframes at t = 0 and t = 2 (interval 2), values
        // 0 and 1, out-tangent of the first 3 (per second), in-tangent of
        // the second -1. At u = 0.5 (t = 1):
        //   h00 = 0.5, h10 = 0.125, h01 = 0.5, h11 = -0.125
        //   p = 0.5*0 + 2*0.125*3 + 0.5*1 + 2*(-0.125)*(-1) = 1.5
        // (unscaled tangents give 0.5 + 0.375 + 0.125 = 1.0).
        let v = [9.0, 0.0, 3.0, -1.0, 1.0, 9.0];
        let k = keys(&[0.0, 2.0], &v, 1, Interpolation::CubicSpline);
        close(&k.sample(1.0), &[1.5]);
        // At u = 0.25 (t = 0.5): h00 = 0.84375, h10 = 0.140625,
        // h01 = 0.15625, h11 = -0.046875:
        //   0 + 2*0.140625*3 + 0.15625 + 2*(-0.046875)*(-1) = 1.09375
        close(&k.sample(0.5), &[1.09375]);
        // Ends hold the values, not the tangents.
        close(&k.sample(-1.0), &[0.0]);
        close(&k.sample(2.0), &[1.0]);
        close(&k.sample(5.0), &[1.0]);
    }

    #[test]
    fn cubic_spline_rotation_is_normalized() {
        let a = about_y(0.0);
        let b = about_y(FRAC_PI_2);
        let zero = [0.0; 4];
        let v: Vec<f64> = [zero, a, zero, zero, b, zero].concat();
        let k = keys(&[0.0, 1.0], &v, 4, Interpolation::CubicSpline);
        let q = k.sample_rotation(0.5);
        assert!((q.length() - 1.0).abs() < 1e-12);
        // Zero tangents: halfway is the normalized average of a and b,
        // 45° about Y.
        close(&q.to_array(), &about_y(FRAC_PI_4));
    }
}
