//! Mouse repel: voxels near the cursor ray are pushed away from it and spring back (critically damped) when
//! the cursor leaves. Works in every style; not while the pointer is over the panel (no cursor ray then).
//! The math lives here; `place` steps the spring of every voxel at home in the same pass that places it.

use bevy::prelude::*;

use crate::instancing::RepelOffset;

/// Spring stiffness (1/s²); the damping is critical.
const STIFFNESS: f32 = 140.0;

/// The vector from the closest point of the half-line `ray` to `p` (its length is `p`'s distance to the ray).
pub fn away_from_ray(p: Vec3, ray: Ray3d) -> Vec3 {
    let along = (p - ray.origin).dot(*ray.direction).max(0.0);
    p - (ray.origin + *ray.direction * along)
}

/// The displacement a voxel at `p` should have for a cursor `ray`: away from the ray, falling off linearly
/// to nothing at `radius`; a voxel on the ray is pushed `radius × strength`.
pub fn repel_target(p: Vec3, ray: Option<Ray3d>, radius: f32, strength: f32) -> Vec3 {
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

impl RepelOffset {
    /// Whether the voxel sits at its cell, still.
    pub fn is_rest(&self) -> bool {
        self.offset == Vec3::ZERO && self.velocity == Vec3::ZERO
    }

    /// One step of `dt` seconds of the critically damped spring towards `target`; snaps onto the target (at
    /// rest, with no target) once within a millimetre and a centimetre per second, so voxels held off by a
    /// still cursor, or back home, cost nothing more.
    pub fn stepped(&self, target: Vec3, dt: f32) -> RepelOffset {
        let damping = 2.0 * STIFFNESS.sqrt();
        let accel = (target - self.offset) * STIFFNESS - self.velocity * damping;
        let velocity = self.velocity + accel * dt;
        let offset = self.offset + velocity * dt;
        if offset.distance_squared(target) < 1e-6 && velocity.length_squared() < 1e-4 {
            RepelOffset { offset: target, velocity: Vec3::ZERO }
        } else {
            RepelOffset { offset, velocity }
        }
    }
}

/// Whether any voxel was off its cell last frame (so placing must go on without a cursor, to bring it home).
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct RepelActive(pub bool);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn targets_push_away_from_the_ray_and_vanish_outside_the_radius() {
        let ray = Some(Ray3d::new(Vec3::new(0.0, 0.0, 10.0), Dir3::NEG_Z));
        let on = repel_target(Vec3::ZERO, ray, 1.0, 0.8);
        assert!((on.length() - 0.8).abs() < 1e-5);
        let near = repel_target(Vec3::new(0.5, 0.0, 0.0), ray, 1.0, 0.8);
        assert!((near - Vec3::new(0.4, 0.0, 0.0)).length() < 1e-5);
        assert_eq!(repel_target(Vec3::new(2.0, 0.0, 0.0), ray, 1.0, 0.8), Vec3::ZERO);
        assert_eq!(repel_target(Vec3::ZERO, None, 1.0, 0.8), Vec3::ZERO);
    }

    #[test]
    fn the_spring_reaches_its_target_without_overshoot_and_rests_exactly_at_home() {
        let target = Vec3::new(0.3, 0.0, -0.4);
        let mut spring = RepelOffset::default();
        let mut farthest = 0.0f32;
        for _ in 0..60 {
            spring = spring.stepped(target, 1.0 / 60.0);
            farthest = farthest.max(spring.offset.length());
        }
        assert!(spring.offset.distance(target) < 0.01, "after 1 s: {:?}", spring.offset);
        assert!(farthest <= target.length() * 1.01, "overshot to {farthest}");
        let mut steps = 0;
        while !spring.is_rest() && steps < 600 {
            spring = spring.stepped(Vec3::ZERO, 1.0 / 60.0);
            steps += 1;
        }
        assert!(spring.is_rest() && steps < 60, "still moving after {steps} steps");
    }
}
