//! glTF animation samplers: keyframe times and values, sampled with STEP, LINEAR (slerp for rotations) or
//! CUBICSPLINE interpolation as the glTF 2.0 specification (§3.11, Appendix C) defines them.

use glam::Quat;

use crate::error::{Result, VoxelError};

/// How values between keyframes are found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// The value of the previous keyframe.
    Step,
    /// Linear between keyframes; spherical linear for rotations.
    Linear,
    /// Cubic Hermite spline; every keyframe stores (in-tangent, value, out-tangent).
    CubicSpline,
}

/// One animation sampler: `times` (ascending) and `width` values per keyframe (three blocks of `width` per
/// keyframe for CUBICSPLINE: in-tangent, value, out-tangent).
#[derive(Clone, Debug, PartialEq)]
pub struct Sampler {
    times: Vec<f32>,
    values: Vec<f32>,
    width: usize,
    interpolation: Interpolation,
    /// Values are unit quaternions (x, y, z, w): LINEAR slerps and every result is normalized.
    rotation: bool,
}

impl Sampler {
    /// Checks and builds a sampler; `what` names it in errors. Times must be finite and non-decreasing,
    /// and there must be exactly one value block (three for CUBICSPLINE) of `width` per time.
    pub fn new(
        times: Vec<f32>,
        values: Vec<f32>,
        width: usize,
        interpolation: Interpolation,
        rotation: bool,
        what: &str,
    ) -> Result<Self> {
        if times.is_empty() {
            return Err(VoxelError::Invalid(format!("{what}: the sampler has no keyframes")));
        }
        if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|w| w[1] < w[0]) {
            return Err(VoxelError::Invalid(format!("{what}: keyframe times must be finite and ascending")));
        }
        let blocks = if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        let expected = times.len() * blocks * width;
        if width == 0 || values.len() != expected {
            return Err(VoxelError::Invalid(format!(
                "{what}: {} keyframes need {expected} output values, found {}",
                times.len(),
                values.len()
            )));
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err(VoxelError::NonFinite(format!("{what} output")));
        }
        Ok(Self { times, values, width, interpolation, rotation })
    }

    /// The keyframe times.
    pub fn times(&self) -> &[f32] {
        &self.times
    }

    /// Values per keyframe (3 for translation and scale, 4 for rotation, the target count for weights).
    pub fn width(&self) -> usize {
        self.width
    }

    /// The value block `block` (0 in-tangent, 1 value, 2 out-tangent for CUBICSPLINE; 0 otherwise) of key `k`.
    fn block(&self, k: usize, block: usize) -> &[f32] {
        let blocks = if self.interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        let start = (k * blocks + block) * self.width;
        &self.values[start..start + self.width]
    }

    /// The keyframe value of key `k`.
    fn value(&self, k: usize) -> &[f32] {
        self.block(k, usize::from(self.interpolation == Interpolation::CubicSpline))
    }

    /// Writes the value at time `t` into `out` (`out.len()` must be [`Sampler::width`]). Before the first
    /// keyframe the first value holds, after the last the last.
    pub fn sample(&self, t: f32, out: &mut [f32]) {
        let next = self.times.partition_point(|&k| k <= t);
        if next == 0 || next == self.times.len() {
            out.copy_from_slice(self.value(if next == 0 { 0 } else { self.times.len() - 1 }));
            return self.normalize(out);
        }
        let k = next - 1;
        let dt = self.times[next] - self.times[k];
        let s = if dt > 0.0 { (t - self.times[k]) / dt } else { 0.0 };
        match self.interpolation {
            Interpolation::Step => out.copy_from_slice(self.value(k)),
            Interpolation::Linear if self.rotation => {
                let q = |v: &[f32]| Quat::from_xyzw(v[0], v[1], v[2], v[3]).normalize();
                out.copy_from_slice(&q(self.value(k)).slerp(q(self.value(next)), s).to_array());
            }
            Interpolation::Linear => {
                for ((o, a), b) in out.iter_mut().zip(self.value(k)).zip(self.value(next)) {
                    *o = a + (b - a) * s;
                }
            }
            Interpolation::CubicSpline => {
                let (s2, s3) = (s * s, s * s * s);
                let (h00, h10, h01, h11) = (2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s, 3.0 * s2 - 2.0 * s3, s3 - s2);
                let (v0, b0, a1, v1) = (self.block(k, 1), self.block(k, 2), self.block(next, 0), self.block(next, 1));
                for i in 0..self.width {
                    out[i] = h00 * v0[i] + h10 * dt * b0[i] + h01 * v1[i] + h11 * dt * a1[i];
                }
            }
        }
        self.normalize(out);
    }

    /// Rotation results are unit quaternions.
    fn normalize(&self, out: &mut [f32]) {
        if self.rotation {
            let q = Quat::from_xyzw(out[0], out[1], out[2], out[3]).normalize();
            if q.is_finite() {
                out.copy_from_slice(&q.to_array());
            } else {
                out.copy_from_slice(&Quat::IDENTITY.to_array());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scalar(times: &[f32], values: &[f32], interpolation: Interpolation) -> Sampler {
        Sampler::new(times.to_vec(), values.to_vec(), 1, interpolation, false, "test").unwrap()
    }

    fn at(sampler: &Sampler, t: f32) -> f32 {
        let mut out = [0.0];
        sampler.sample(t, &mut out);
        out[0]
    }

    #[test]
    fn step_holds_the_previous_keyframe() {
        let s = scalar(&[0.0, 1.0, 2.0], &[10.0, 20.0, 30.0], Interpolation::Step);
        assert_eq!(at(&s, -1.0), 10.0);
        assert_eq!(at(&s, 0.0), 10.0);
        assert_eq!(at(&s, 0.99), 10.0);
        assert_eq!(at(&s, 1.0), 20.0);
        assert_eq!(at(&s, 1.5), 20.0);
        assert_eq!(at(&s, 5.0), 30.0);
    }

    #[test]
    fn linear_interpolates_between_keyframes() {
        let s = scalar(&[0.0, 2.0], &[1.0, 5.0], Interpolation::Linear);
        assert_eq!(at(&s, 0.5), 2.0);
        assert_eq!(at(&s, 1.0), 3.0);
    }

    #[test]
    fn cubic_spline_follows_hermite_with_tangents_scaled_by_the_key_interval() {
        // Keys at t = 1 and 3 (interval 2): values 0 and 1, out-tangent of the first 0.5, in-tangent of the
        // second -1. Layout per key: in-tangent, value, out-tangent.
        let s = scalar(&[1.0, 3.0], &[9.0, 0.0, 0.5, -1.0, 1.0, 9.0], Interpolation::CubicSpline);
        // s = 0.5: h00 = 0.5, h10 = 0.125, h01 = 0.5, h11 = -0.125; p = 0.125·2·0.5 + 0.5·1 + (-0.125)·2·(-1).
        assert!((at(&s, 2.0) - 0.875).abs() < 1e-6, "{}", at(&s, 2.0));
        // s = 0.25: h10 = 0.140625, h01 = 0.15625, h11 = -0.046875.
        let expected = 0.140625 * 2.0 * 0.5 + 0.15625 + 0.046875 * 2.0;
        assert!((at(&s, 1.5) - expected).abs() < 1e-6, "{}", at(&s, 1.5));
        // At and beyond the keys: the values, never the tangents.
        assert_eq!(at(&s, 1.0), 0.0);
        assert_eq!(at(&s, 3.0), 1.0);
        assert_eq!(at(&s, 0.0), 0.0);
    }

    #[test]
    fn linear_rotation_slerps_at_constant_angular_speed() {
        let half = std::f32::consts::FRAC_1_SQRT_2;
        // Identity to 90° about y.
        let values = vec![0.0, 0.0, 0.0, 1.0, 0.0, half, 0.0, half];
        let s = Sampler::new(vec![0.0, 1.0], values, 4, Interpolation::Linear, true, "test").unwrap();
        let mut out = [0.0; 4];
        s.sample(1.0 / 3.0, &mut out);
        let expected = Quat::from_rotation_y(std::f32::consts::FRAC_PI_6);
        assert!(Quat::from_array(out).angle_between(expected) < 1e-5, "{out:?}");
    }

    #[test]
    fn malformed_samplers_are_errors() {
        let err = Sampler::new(vec![0.0, 1.0], vec![1.0], 1, Interpolation::Linear, false, "anim 0").unwrap_err();
        assert!(err.to_string().contains("2 keyframes need 2 output values, found 1"), "{err}");
        let err = Sampler::new(vec![1.0, 0.0], vec![1.0, 2.0], 1, Interpolation::Step, false, "x").unwrap_err();
        assert!(err.to_string().contains("ascending"), "{err}");
        let cubic = Sampler::new(vec![0.0], vec![1.0], 1, Interpolation::CubicSpline, false, "x").unwrap_err();
        assert!(cubic.to_string().contains("need 3 output values"), "{cubic}");
        assert!(Sampler::new(vec![], vec![], 1, Interpolation::Step, false, "x").is_err());
    }
}
