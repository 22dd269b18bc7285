//! Mouse repel: voxels near the cursor ray are pushed away from it and spring back (critically damped) when
//! the cursor leaves. Works in every style; not while the pointer is over the panel (no cursor ray then).

use bevy::prelude::*;

use crate::input::CursorRay;
use crate::instancing::{RepelOffset, VoxelCloud, VoxelHome};
use crate::settings::VoxelSettings;

use super::Settled;

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
    let d = away.length();
    if d >= radius {
        return Vec3::ZERO;
    }
    // On the ray itself, push sideways (perpendicular to the ray, in a fixed direction).
    let n = if d > 1e-5 { away / d } else { ray.direction.any_orthonormal_vector() };
    n * (radius - d) * strength
}

/// Whether any voxel is displaced or moving (so the composer must run).
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct RepelActive(pub bool);

/// Springs every settled voxel's offset towards its repel target.
pub(super) fn repel(
    time: Res<Time>,
    settings: Res<VoxelSettings>,
    ray: Res<CursorRay>,
    cloud: Query<&Transform, (With<VoxelCloud>, Without<VoxelHome>)>,
    mut voxels: Query<(&VoxelHome, &mut RepelOffset, &Visibility), Settled>,
    mut active: ResMut<RepelActive>,
) {
    let ray = if settings.repel { ray.0 } else { None };
    if ray.is_none() && !active.0 {
        return;
    }
    let dt = time.delta_secs().min(1.0 / 20.0);
    let turn = cloud.single().map_or(Quat::IDENTITY, |t| t.rotation);
    let damping = 2.0 * STIFFNESS.sqrt();
    let moving = std::sync::atomic::AtomicBool::new(false);
    voxels.par_iter_mut().for_each(|(home, mut repel, visibility)| {
        if *visibility == Visibility::Hidden {
            return;
        }
        let target = repel_target(turn * home.position, ray, settings.repel_radius, settings.repel_strength);
        if target == Vec3::ZERO && repel.offset == Vec3::ZERO && repel.velocity == Vec3::ZERO {
            return;
        }
        let accel = (target - repel.offset) * STIFFNESS - repel.velocity * damping;
        let velocity = repel.velocity + accel * dt;
        let offset = repel.offset + velocity * dt;
        // Settle exactly when close enough, so idle voxels cost nothing.
        let done = target == Vec3::ZERO && offset.length() < 1e-3 && velocity.length() < 1e-2;
        *repel = if done { RepelOffset::default() } else { RepelOffset { offset, velocity } };
        moving.store(true, std::sync::atomic::Ordering::Relaxed);
    });
    active.0 = moving.into_inner();
}

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
