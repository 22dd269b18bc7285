//! Mouse repel: voxels near the cursor ray are pushed away from it and spring back (critically damped) when
//! the cursor leaves. Works in every style; not while the pointer is over the panel (no cursor ray then).
//! Where the cursor pushes lives here; the spring is `instancing::spring`'s; `place` pulls the springs of the
//! voxels the cursor reaches in the pass that places them, and the GPU brings the others home.

use bevy::prelude::*;

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

/// Whether the cursor held a voxel off its cell last frame (so placing must go on without a cursor, to let it
/// go). A voxel let go returns home on the GPU, with nothing more to do here.
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
}
