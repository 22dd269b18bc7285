//! Repel springs, drawn by the GPU. A voxel the cursor pushes is drawn off its look by a critically damped
//! spring; once the cursor lets it go, the spring returns home in closed form, `(x₀ + (v₀ + ω x₀) τ) e^(−ω τ)`,
//! so the vertex shaders draw it from one record and the frame's clock (assets/shaders/voxel_spring.wgsl) and
//! the CPU does nothing more for it. Each pool slot has a [`Spring`] (the CPU's state) and its [`GpuSpring`]
//! (16 bytes: offset and velocity as half floats, the clock time they hold at); the styles write records only for
//! the voxels the cursor pushes now. A voxel held at its target by a still cursor has `since` = [`HELD`]: drawn
//! there, unmoving, until the cursor lets it go.

use bevy::prelude::*;
use bevy::render::storage::ShaderBuffer;
use bytemuck::{Pod, Zeroable};
use half::f16;

use super::gpu::{GpuVoxel, Mirror, Mirrored, Record};
use super::{Slot, VoxelMaterial};

/// Spring stiffness (1/s²); the damping is critical.
pub const STIFFNESS: f32 = 140.0;

/// `since` of a spring held where it is (by a still cursor): its clock never runs.
pub const HELD: f32 = f32::MAX;

/// Seconds after which any free spring is home, within a micrometre: its offset was at most 10 and its speed
/// 100 (`(10 + 218 τ) e^(−ω τ)` < 10⁻⁶ at τ = 2).
pub const SETTLED_AFTER: f32 = 2.0;

/// A voxel's repel spring (in the cloud's frame, like its home): its offset and velocity at clock time `since`,
/// free from then on (returning home) unless `since` is [`HELD`]. The default is at rest, home.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Spring {
    /// Displacement at `since`.
    pub offset: Vec3,
    /// Velocity at `since`.
    pub velocity: Vec3,
    /// The flight clock's time the state holds at ([`HELD`]: always).
    pub since: f32,
}

/// The natural frequency ω of the critically damped spring.
fn omega() -> f32 {
    STIFFNESS.sqrt()
}

/// The critically damped spring's state `tau` seconds after (`offset`, `velocity`), pulled to the origin.
fn decayed(offset: Vec3, velocity: Vec3, tau: f32) -> (Vec3, Vec3) {
    faded(offset, velocity, tau, (-omega() * tau).exp())
}

/// [`decayed`] with its fade `e^(−ω tau)` given.
#[inline]
fn faded(offset: Vec3, velocity: Vec3, tau: f32, fade: f32) -> (Vec3, Vec3) {
    let w = omega();
    let b = velocity + offset * w;
    ((offset + b * tau) * fade, (velocity - b * (w * tau)) * fade)
}

/// One frame of pulling: its length and the spring's fade over it, worked out once for every spring.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    /// Seconds.
    pub dt: f32,
    /// `e^(−ω dt)`.
    fade: f32,
}

impl Step {
    /// A frame of `dt` seconds.
    pub fn new(dt: f32) -> Self {
        let dt = dt.max(0.0);
        Self { dt, fade: (-omega() * dt).exp() }
    }
}

impl Spring {
    /// Offset and velocity at clock time `time` (free since `since`, or held).
    #[inline]
    pub fn at(&self, time: f32) -> (Vec3, Vec3) {
        let tau = time - self.since;
        if tau <= 0.0 {
            return (self.offset, self.velocity);
        }
        decayed(self.offset, self.velocity, tau)
    }

    /// Whether it is held where it is.
    pub fn held(&self) -> bool {
        self.since == HELD
    }

    /// Whether it is home and still at clock time `time` (exactly, or within a millimetre and a centimetre per
    /// second).
    pub fn rests(&self, time: f32) -> bool {
        if *self == Spring::default() || time - self.since >= SETTLED_AFTER {
            return true;
        }
        let (offset, velocity) = self.at(time);
        !self.held() && offset.length_squared() < 1e-6 && velocity.length_squared() < 1e-4
    }

    /// The spring at clock time `time`, pulled towards `target` for the last `step` (free before it); held at
    /// the target once within a millimetre and a centimetre per second of it (at rest when the target is home),
    /// so a voxel held by a still cursor, or back home, is not written again.
    #[inline]
    pub fn pulled(&self, target: Vec3, time: f32, step: Step) -> Spring {
        let (offset, velocity) = self.at(time - step.dt);
        let (toward, velocity) = faded(offset - target, velocity, step.dt, step.fade);
        if toward.length_squared() < 1e-6 && velocity.length_squared() < 1e-4 {
            return if target == Vec3::ZERO {
                Spring::default()
            } else {
                Spring { offset: target, velocity: Vec3::ZERO, since: HELD }
            };
        }
        Spring { offset: toward + target, velocity, since: time }
    }

    /// The same spring let go at clock time `time`: free from where it is.
    pub fn released(&self, time: f32) -> Spring {
        let (offset, velocity) = self.at(time);
        Spring { offset, velocity, since: time }
    }
}

/// One slot's spring as the vertex shaders read it (16 bytes): offset and velocity as half floats, and `since`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSpring {
    /// Offset x | y << 16 (half floats).
    offset_xy: u32,
    /// Offset z | velocity x << 16.
    offset_z_velocity_x: u32,
    /// Velocity y | z << 16.
    velocity_yz: u32,
    /// The clock time the state holds at.
    since: f32,
}

/// Two floats as half floats in one word (the first in the low half, as WGSL's `unpack2x16float`).
fn pack(a: f32, b: f32) -> u32 {
    u32::from(f16::from_f32(a).to_bits()) | u32::from(f16::from_f32(b).to_bits()) << 16
}

/// The two half floats of a word.
fn unpack(word: u32) -> (f32, f32) {
    (f16::from_bits(word as u16).to_f32(), f16::from_bits((word >> 16) as u16).to_f32())
}

impl From<Spring> for GpuSpring {
    fn from(s: Spring) -> Self {
        Self {
            offset_xy: pack(s.offset.x, s.offset.y),
            offset_z_velocity_x: pack(s.offset.z, s.velocity.x),
            velocity_yz: pack(s.velocity.y, s.velocity.z),
            since: s.since,
        }
    }
}

impl GpuSpring {
    /// The spring as the GPU reads it (half-float precision).
    pub fn spring(&self) -> Spring {
        let ((ox, oy), (oz, vx), (vy, vz)) =
            (unpack(self.offset_xy), unpack(self.offset_z_velocity_x), unpack(self.velocity_yz));
        Spring { offset: Vec3::new(ox, oy, oz), velocity: Vec3::new(vx, vy, vz), since: self.since }
    }

    /// `look` moved by the spring at clock time `time` (the offset turned with the voxel): the shaders' `sprung`.
    pub fn sprung(&self, look: &GpuVoxel, time: f32) -> GpuVoxel {
        let (offset, _) = self.spring().at(time);
        let width = Vec2::from(look.x_axis).length();
        let (c, s) = if width > 0.0 { (look.x_axis[0] / width, -look.x_axis[1] / width) } else { (1.0, 0.0) };
        let turned = Vec3::new(c * offset.x + s * offset.z, offset.y, c * offset.z - s * offset.x);
        GpuVoxel { translation: (look.position() + turned).into(), ..*look }
    }
}

impl Record for GpuSpring {
    /// Springs do not decide what is drawn.
    fn weight(&self) -> f32 {
        0.0
    }

    fn bind(material: &mut VoxelMaterial, buffer: Handle<ShaderBuffer>) {
        material.extension.springs = buffer;
    }
}

/// The springs by pool slot, the GPU buffer's mirror.
#[derive(Resource, Debug, Default, Deref, DerefMut)]
pub struct GpuSprings(pub Mirror<GpuSpring>);

impl Mirrored for GpuSprings {
    type Item = GpuSpring;
    fn mirror(&self) -> &Mirror<GpuSpring> {
        &self.0
    }
    fn mirror_mut(&mut self) -> &mut Mirror<GpuSpring> {
        &mut self.0
    }
}

impl GpuSprings {
    /// Sends slot `index`'s voxel (`slot`) home at once: a voxel leaving home (to fly, fall or hide) takes its
    /// displacement along, and its spring must not move it later.
    pub fn clear(&mut self, index: usize, slot: &mut Slot) {
        if slot.repel != Spring::default() {
            slot.repel = Spring::default();
            self.set(index, GpuSpring::default());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::instancing::Turn;

    #[test]
    fn a_pulled_spring_reaches_its_target_without_overshoot_is_held_and_returns_home_freely() {
        let target = Vec3::new(0.3, 0.0, -0.4);
        let (mut spring, mut time, dt) = (Spring::default(), 0.0, 1.0 / 60.0);
        let step = Step::new(dt);
        let mut farthest = 0.0f32;
        for _ in 0..60 {
            time += dt;
            spring = spring.pulled(target, time, step);
            farthest = farthest.max(spring.offset.length());
        }
        assert!(spring.offset.distance(target) < 0.01, "after 1 s: {:?}", spring.offset);
        assert!(farthest <= target.length() * 1.001, "overshot to {farthest}");
        // Held: the same pull again leaves it as it is, and time does not move it.
        while !spring.held() {
            time += dt;
            spring = spring.pulled(target, time, step);
        }
        assert_eq!(spring.pulled(target, time + dt, step), spring);
        assert_eq!(spring.at(time + 5.0).0, target);
        assert!(!spring.rests(time + 5.0));
        // Let go: free, it is home within 0.8 s and stays there.
        let free = spring.released(time);
        assert_eq!(free.at(time).0, target);
        let back = free.at(time + 0.8).0;
        assert!(back.length() < 1e-3 && back.length() > 0.0, "{back}");
        assert!(!free.rests(time + 0.5) && free.rests(time + 0.9));
        assert!(free.at(time + SETTLED_AFTER).0.length() < 1e-6);
        assert!(free.at(time + 0.05).0.length() < target.length(), "it returns, no overshoot");
    }

    #[test]
    fn free_decay_solves_the_spring_equation() {
        // x'' = −K x − 2ω x', checked by finite differences along the closed form.
        let spring = Spring { offset: Vec3::new(0.5, -0.2, 0.1), velocity: Vec3::new(-3.0, 1.0, 4.0), since: 1.0 };
        let h = 1e-3;
        for tau in [0.01f32, 0.1, 0.3] {
            let t = 1.0 + tau;
            let (x, v) = spring.at(t);
            let (before, after) = (spring.at(t - h).0, spring.at(t + h).0);
            let speed = (after - before) / (2.0 * h);
            let accel = (after - 2.0 * x + before) / (h * h);
            assert!(speed.distance(v) < 1e-2, "τ {tau}: v {v} for {speed}");
            let expected = -x * STIFFNESS - v * 2.0 * omega();
            assert!(accel.distance(expected) < 0.05 * expected.length().max(1.0), "τ {tau}: a {accel} for {expected}");
        }
        assert_eq!(spring.at(0.5), (spring.offset, spring.velocity), "before `since` it holds");
    }

    #[test]
    fn a_record_keeps_the_spring_in_half_floats_and_moves_the_turned_look() {
        assert_eq!(size_of::<GpuSpring>(), 16);
        let spring = Spring { offset: Vec3::new(0.25, -0.5, 1.0), velocity: Vec3::new(3.0, -2.0, 0.125), since: 7.5 };
        assert_eq!(GpuSpring::from(spring).spring(), spring, "exact in half floats");
        let rough = Spring { offset: Vec3::splat(0.123_456), ..spring };
        assert!(GpuSpring::from(rough).spring().offset.distance(rough.offset) < 1e-4);
        // The offset is in the cloud's frame: the look is turned a quarter about y.
        let turn = Turn::new(Quat::from_rotation_y(std::f32::consts::FRAC_PI_2));
        let look = turn.place(Vec3::new(1.0, 2.0, 3.0), Vec3::splat(0.2), 7);
        let held = GpuSpring::from(Spring { since: HELD, ..spring });
        let moved = held.sprung(&look, 100.0);
        assert!(moved.position().distance(look.position() + turn.rotation * spring.offset) < 1e-5);
        assert_eq!((moved.color, moved.x_axis, moved.scale_y), (look.color, look.x_axis, look.scale_y));
        assert_eq!(GpuSpring::default().sprung(&look, 3.0), look);
    }
}
