//! Repel springs, drawn by the GPU. A voxel the cursor reaches is pushed away from the cursor ray by a critically
//! damped spring, and springs back home when the cursor lets it go. Each pool slot has a [`Spring`] (the CPU's
//! state) and its [`GpuSpring`] (16 bytes: offset and velocity as half floats, the clock time they hold at, and
//! whether the cursor pulls it). The vertex shaders draw it in closed form from the record and the frame's clock,
//! which carries the cursor ray (assets/shaders/voxel_flight.wgsl): with `y` the offset from the target `T` (the
//! push at the voxel now, or home once let go), `y(τ) = (y₀ + (v₀ + ω y₀) τ) e^(−ω τ)`. So the CPU writes a
//! record only when the cursor catches a voxel or lets it go: a cursor moving through a million voxels costs the
//! records of the voxels at the edge of its reach, a still cursor nothing.

use bevy::prelude::*;
use bevy::render::storage::ShaderBuffer;
use bytemuck::{Pod, Zeroable};
use half::f16;

use super::flight::GpuClock;
use super::gpu::{GpuVoxel, Mirror, Mirrored, Record};
use super::{Slot, VoxelMaterial};

/// Spring stiffness (1/s²); the damping is critical.
pub const STIFFNESS: f32 = 140.0;

/// Seconds after which any free spring is home, within a micrometre: its offset was at most 10 and its speed
/// 100 (`(10 + 218 τ) e^(−ω τ)` < 10⁻⁶ at τ = 2).
pub const SETTLED_AFTER: f32 = 2.0;

/// The vector from the closest point of the half-line `ray` to `p` (its length is `p`'s distance to the ray).
pub fn away_from_ray(p: Vec3, ray: Ray3d) -> Vec3 {
    let along = (p - ray.origin).dot(*ray.direction).max(0.0);
    p - (ray.origin + *ray.direction * along)
}

/// The displacement the cursor `ray` gives a voxel at `p`: away from the ray, falling off linearly to nothing at
/// `radius`; a voxel on the ray is pushed `radius × strength` sideways.
pub fn push(p: Vec3, ray: Option<Ray3d>, radius: f32, strength: f32) -> Vec3 {
    let Some(ray) = ray else { return Vec3::ZERO };
    let away = away_from_ray(p, ray);
    let d2 = away.length_squared();
    if d2 >= radius * radius {
        return Vec3::ZERO;
    }
    let d = d2.sqrt();
    // On the ray itself, push sideways (perpendicular to the ray, in a fixed direction).
    let n = if d > 1e-5 { away / d } else { ray.direction.any_orthonormal_vector() };
    n * (radius - d) * strength
}

/// A voxel's repel spring (in the cloud's frame, like its home): its offset and velocity at clock time `since`,
/// pulled from then on towards the push of the cursor at the voxel (`pulled`), or home. The default is at rest,
/// home.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Spring {
    /// Displacement at `since`.
    pub offset: Vec3,
    /// Velocity at `since`.
    pub velocity: Vec3,
    /// The flight clock's time the state holds at.
    pub since: f32,
    /// The cursor pulls it (towards its push); else it returns home.
    pub pulled: bool,
}

/// The natural frequency ω of the critically damped spring.
fn omega() -> f32 {
    STIFFNESS.sqrt()
}

/// The critically damped spring's state `tau` seconds after (`offset`, `velocity`), pulled to the origin.
fn decayed(offset: Vec3, velocity: Vec3, tau: f32) -> (Vec3, Vec3) {
    let w = omega();
    let b = velocity + offset * w;
    let fade = (-w * tau).exp();
    ((offset + b * tau) * fade, (velocity - b * (w * tau)) * fade)
}

impl Spring {
    /// Offset and velocity at clock time `time`, `target` being the cursor's push at the voxel now (used only
    /// while it is pulled).
    pub fn at(&self, time: f32, target: Vec3) -> (Vec3, Vec3) {
        let target = if self.pulled { target } else { Vec3::ZERO };
        let (offset, velocity) = decayed(self.offset - target, self.velocity, (time - self.since).max(0.0));
        (offset + target, velocity)
    }

    /// Whether it is home and still at clock time `time` (exactly, or within a millimetre and a centimetre per
    /// second).
    pub fn rests(&self, time: f32) -> bool {
        if self.pulled {
            return false;
        }
        if *self == Spring::default() || time - self.since >= SETTLED_AFTER {
            return true;
        }
        let (offset, velocity) = self.at(time, Vec3::ZERO);
        offset.length_squared() < 1e-6 && velocity.length_squared() < 1e-4
    }

    /// The spring the cursor catches at clock time `time`: from where it is, pulled from now on.
    pub fn caught(&self, time: f32) -> Spring {
        let (offset, velocity) = self.at(time, Vec3::ZERO);
        Spring { offset, velocity, since: time, pulled: true }
    }

    /// The spring the cursor lets go at clock time `time`, `target` being the push it was drawn with last: from
    /// where it is, home.
    pub fn let_go(&self, time: f32, target: Vec3) -> Spring {
        let (offset, velocity) = self.at(time, target);
        Spring { offset, velocity, since: time, pulled: false }
    }
}

/// One slot's spring as the vertex shaders read it (16 bytes): offset and velocity as half floats, and `since`
/// with its sign bit set while the cursor pulls it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSpring {
    /// Offset x | y << 16 (half floats).
    offset_xy: u32,
    /// Offset z | velocity x << 16.
    offset_z_velocity_x: u32,
    /// Velocity y | z << 16.
    velocity_yz: u32,
    /// The clock time the state holds at; its sign bit: pulled.
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

/// The sign bit of a float.
const SIGN: u32 = 1 << 31;

impl From<Spring> for GpuSpring {
    fn from(s: Spring) -> Self {
        let since = s.since.abs().to_bits() | if s.pulled { SIGN } else { 0 };
        Self {
            offset_xy: pack(s.offset.x, s.offset.y),
            offset_z_velocity_x: pack(s.offset.z, s.velocity.x),
            velocity_yz: pack(s.velocity.y, s.velocity.z),
            since: f32::from_bits(since),
        }
    }
}

impl GpuSpring {
    /// The spring as the GPU reads it (half-float precision).
    pub fn spring(&self) -> Spring {
        let ((ox, oy), (oz, vx), (vy, vz)) =
            (unpack(self.offset_xy), unpack(self.offset_z_velocity_x), unpack(self.velocity_yz));
        Spring {
            offset: Vec3::new(ox, oy, oz),
            velocity: Vec3::new(vx, vy, vz),
            since: self.since.abs(),
            pulled: self.since.to_bits() & SIGN != 0,
        }
    }

    /// `look` moved by the spring at `clock` (pushed by the clock's cursor at the look's place, the offset turned
    /// with the voxel): the shaders' `sprung`.
    pub fn sprung(&self, look: &GpuVoxel, clock: &GpuClock) -> GpuVoxel {
        let width = Vec2::from(look.x_axis).length();
        let (c, s) = if width > 0.0 { (look.x_axis[0] / width, -look.x_axis[1] / width) } else { (1.0, 0.0) };
        let turn = |v: Vec3, s: f32| Vec3::new(c * v.x + s * v.z, v.y, c * v.z - s * v.x);
        let home = turn(look.position(), -s);
        let (offset, _) = self.spring().at(clock.time, clock.push(home));
        GpuVoxel { translation: (look.position() + turn(offset, s)).into(), ..*look }
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

    /// Slot `slot`'s look `look` as the GPU draws it at `clock` (moved by its spring).
    pub fn drawn(&self, slot: usize, look: &GpuVoxel, clock: &GpuClock) -> GpuVoxel {
        self.items.get(slot).map_or(*look, |s| s.sprung(look, clock))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::instancing::Turn;

    #[test]
    fn the_push_is_away_from_the_ray_and_vanishes_outside_the_radius() {
        let ray = Some(Ray3d::new(Vec3::new(0.0, 0.0, 10.0), Dir3::NEG_Z));
        let on = push(Vec3::ZERO, ray, 1.0, 0.8);
        assert!((on.length() - 0.8).abs() < 1e-5);
        let near = push(Vec3::new(0.5, 0.0, 0.0), ray, 1.0, 0.8);
        assert!((near - Vec3::new(0.4, 0.0, 0.0)).length() < 1e-5);
        assert_eq!(push(Vec3::new(2.0, 0.0, 0.0), ray, 1.0, 0.8), Vec3::ZERO);
        assert_eq!(push(Vec3::ZERO, None, 1.0, 0.8), Vec3::ZERO);
    }

    #[test]
    fn a_caught_spring_eases_onto_the_push_without_overshoot_and_a_let_go_one_returns_home() {
        let target = Vec3::new(0.3, 0.0, -0.4);
        let spring = Spring::default().caught(1.0);
        assert_eq!(spring.at(1.0, target).0, Vec3::ZERO, "it starts where it was");
        let farthest = (1..=60).map(|f| spring.at(1.0 + f as f32 / 60.0, target).0.length()).fold(0.0, f32::max);
        assert!(spring.at(2.0, target).0.distance(target) < 0.01, "after 1 s: {:?}", spring.at(2.0, target));
        assert!(farthest <= target.length() * 1.001, "overshot to {farthest}");
        assert!(!spring.rests(10.0));
        // Let go where it is drawn: it starts there and is home within 0.8 s.
        let free = spring.let_go(2.0, target);
        assert!(!free.pulled && free.at(2.0, target).0.distance(spring.at(2.0, target).0) < 1e-6);
        let back = free.at(2.8, target).0;
        assert!(back.length() < 1e-3 && back.length() > 0.0, "{back}");
        assert!(!free.rests(2.5) && free.rests(2.9));
        assert!(free.at(2.0 + SETTLED_AFTER, target).0.length() < 1e-6);
        assert!(free.at(2.05, target).0.length() < target.length(), "it returns, no overshoot");
        // Caught again on its way: it goes on from where it is.
        let again = free.caught(2.1);
        assert_eq!(again.at(2.1, target), free.at(2.1, target));
    }

    #[test]
    fn free_decay_solves_the_spring_equation() {
        // x'' = −K x − 2ω x', checked by finite differences along the closed form.
        let spring = Spring {
            offset: Vec3::new(0.5, -0.2, 0.1),
            velocity: Vec3::new(-3.0, 1.0, 4.0),
            since: 1.0,
            pulled: false,
        };
        let h = 1e-3;
        for tau in [0.01f32, 0.1, 0.3] {
            let t = 1.0 + tau;
            let (x, v) = spring.at(t, Vec3::ZERO);
            let (before, after) = (spring.at(t - h, Vec3::ZERO).0, spring.at(t + h, Vec3::ZERO).0);
            let speed = (after - before) / (2.0 * h);
            let accel = (after - 2.0 * x + before) / (h * h);
            assert!(speed.distance(v) < 1e-2, "τ {tau}: v {v} for {speed}");
            let expected = -x * STIFFNESS - v * 2.0 * omega();
            assert!(accel.distance(expected) < 0.05 * expected.length().max(1.0), "τ {tau}: a {accel} for {expected}");
        }
        assert_eq!(spring.at(0.5, Vec3::ZERO), (spring.offset, spring.velocity), "before `since` it holds");
    }

    #[test]
    fn a_record_keeps_the_spring_in_half_floats_and_moves_the_turned_look() {
        assert_eq!(size_of::<GpuSpring>(), 16);
        let spring = Spring {
            offset: Vec3::new(0.25, -0.5, 1.0),
            velocity: Vec3::new(3.0, -2.0, 0.125),
            since: 7.5,
            pulled: true,
        };
        assert_eq!(GpuSpring::from(spring).spring(), spring, "exact in half floats");
        let free = Spring { pulled: false, since: 0.0, ..spring };
        assert_eq!(GpuSpring::from(free).spring(), free);
        let rough = Spring { offset: Vec3::splat(0.123_456), ..spring };
        assert!(GpuSpring::from(rough).spring().offset.distance(rough.offset) < 1e-4);
        // The look is turned a quarter about y; the offset and the cursor are in the cloud's frame.
        let turn = Turn::new(Quat::from_rotation_y(std::f32::consts::FRAC_PI_2));
        let home = Vec3::new(1.0, 2.0, 3.0);
        let look = turn.place(home, Vec3::splat(0.2), 7);
        let ray = Ray3d::new(home + Vec3::new(0.5, 0.0, 10.0), Dir3::NEG_Z);
        let clock = GpuClock::new(100.0, 0.0, 0.0).reaching(Some(ray), 1.0, 0.8);
        let expected = push(home, Some(ray), 1.0, 0.8);
        assert!((expected - Vec3::new(-0.4, 0.0, 0.0)).length() < 1e-5);
        // Pulled long enough: at the push; let go long enough: home.
        let moved = GpuSpring::from(spring).sprung(&look, &clock);
        assert!(moved.position().distance(look.position() + turn.rotation * expected) < 1e-4, "{moved:?}");
        assert_eq!((moved.color, moved.x_axis, moved.scale_y), (look.color, look.x_axis, look.scale_y));
        assert!(GpuSpring::from(free).sprung(&look, &clock).position().distance(look.position()) < 1e-5);
        assert_eq!(GpuSpring::default().sprung(&look, &clock), look);
    }
}
