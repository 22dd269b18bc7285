//! The stage: a gradient backdrop behind everything, a floor that catches the voxels' soft shadow, and a light
//! rig that turns with the camera so the model always looks lit (the article's `lightHolder`).

use bevy::asset::RenderAssetUsages;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::light::{CascadeShadowConfigBuilder, NotShadowCaster, NotShadowReceiver, ShadowFilteringMethod};
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::*;

use crate::camera::MainCamera;
use crate::instancing::{VoxelPool, floor_height};
use crate::model::VoxelModelAsset;
use crate::schedule::StageSystems;

/// Top colour of the background gradient (pink to lilac, like the article's demo).
pub const GRADIENT_TOP: Color = Color::srgb(0.99, 0.80, 0.86);
/// Bottom colour of the background gradient.
pub const GRADIENT_BOTTOM: Color = Color::srgb(0.78, 0.76, 0.97);
/// The floor's colour (its edge fades into the background).
pub const FLOOR_COLOR: Color = Color::srgb(0.97, 0.93, 0.98);
/// Radius of the floor disc.
pub const FLOOR_RADIUS: f32 = 10.0;

/// Turns with the camera's yaw; the lights are its children.
#[derive(Component, Debug, Default)]
pub struct LightRig;

/// The light that casts the voxels' shadow.
#[derive(Component, Debug, Default)]
pub struct KeyLight;

/// The floor disc under the model.
#[derive(Component, Debug, Default)]
pub struct Floor;

/// A disc in the xz plane facing up, opaque in the middle and fading to transparent at its rim.
fn fading_disc(radius: f32, segments: u32, rings: u32) -> Mesh {
    let mut positions = vec![[0.0, 0.0, 0.0]];
    let mut colors = vec![[1.0, 1.0, 1.0, 1.0]];
    for r in 1..=rings {
        let t = r as f32 / rings as f32;
        let alpha = (1.0 - ((t - 0.55) / 0.45).clamp(0.0, 1.0)).powi(2);
        for s in 0..segments {
            let a = s as f32 / segments as f32 * std::f32::consts::TAU;
            positions.push([radius * t * a.cos(), 0.0, radius * t * a.sin()]);
            colors.push([1.0, 1.0, 1.0, alpha]);
        }
    }
    let at = |r: u32, s: u32| 1 + (r - 1) * segments + s % segments;
    let mut indices = Vec::new();
    for s in 0..segments {
        indices.extend_from_slice(&[0, at(1, s + 1), at(1, s)]);
    }
    for r in 1..rings {
        for s in 0..segments {
            indices.extend_from_slice(&[
                at(r, s),
                at(r, s + 1),
                at(r + 1, s + 1),
                at(r, s),
                at(r + 1, s + 1),
                at(r + 1, s),
            ]);
        }
    }
    let normals = vec![[0.0, 1.0, 0.0]; positions.len()];
    Mesh::new(PrimitiveTopology::TriangleList, RenderAssetUsages::default())
        .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions)
        .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, normals)
        .with_inserted_attribute(Mesh::ATTRIBUTE_COLOR, colors)
        .with_inserted_indices(Indices::U32(indices))
}

/// A quad with a vertical colour gradient (vertex colours), for the backdrop.
fn gradient_quad(top: Color, bottom: Color) -> Mesh {
    let (t, b) = (top.to_linear().to_f32_array(), bottom.to_linear().to_f32_array());
    Mesh::new(PrimitiveTopology::TriangleList, RenderAssetUsages::default())
        .with_inserted_attribute(
            Mesh::ATTRIBUTE_POSITION,
            vec![[-0.5, -0.5, 0.0], [0.5, -0.5, 0.0], [0.5, 0.5, 0.0], [-0.5, 0.5, 0.0]],
        )
        .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, vec![[0.0, 0.0, 1.0]; 4])
        .with_inserted_attribute(Mesh::ATTRIBUTE_COLOR, vec![b, b, t, t])
        .with_inserted_indices(Indices::U32(vec![0, 1, 2, 0, 2, 3]))
}

fn setup(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    camera: Query<Entity, With<MainCamera>>,
) {
    commands.insert_resource(ClearColor(GRADIENT_BOTTOM));
    commands.insert_resource(GlobalAmbientLight { color: Color::WHITE, brightness: 350.0, ..default() });
    // The backdrop hangs in front of the camera's far end and moves with it: a screen-space gradient.
    if let Ok(camera) = camera.single() {
        // No tonemapping: the pastel colours and the gradient keep their brightness.
        commands.entity(camera).insert((ShadowFilteringMethod::Gaussian, Tonemapping::None));
        commands.spawn((
            Name::new("backdrop"),
            Mesh3d(meshes.add(gradient_quad(GRADIENT_TOP, GRADIENT_BOTTOM))),
            MeshMaterial3d(materials.add(StandardMaterial {
                base_color: Color::WHITE,
                unlit: true,
                fog_enabled: false,
                ..default()
            })),
            Transform::from_xyz(0.0, 0.0, -150.0).with_scale(Vec3::new(520.0, 170.0, 1.0)),
            NotShadowCaster,
            NotShadowReceiver,
            ChildOf(camera),
        ));
    }
    commands.spawn((
        Name::new("floor"),
        Floor,
        Mesh3d(meshes.add(fading_disc(FLOOR_RADIUS, 64, 12))),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: FLOOR_COLOR,
            perceptual_roughness: 1.0,
            reflectance: 0.1,
            alpha_mode: AlphaMode::Blend,
            ..default()
        })),
        Transform::from_xyz(0.0, -4.8, 0.0),
        NotShadowCaster,
    ));
    let shadows = CascadeShadowConfigBuilder { num_cascades: 1, maximum_distance: 60.0, ..default() }.build();
    commands.spawn((Name::new("light rig"), LightRig, Transform::default(), Visibility::default())).with_children(
        |rig| {
            rig.spawn((
                Name::new("key light"),
                KeyLight,
                DirectionalLight {
                    illuminance: 7_000.0,
                    shadow_maps_enabled: true,
                    shadow_depth_bias: 0.06,
                    shadow_normal_bias: 1.2,
                    ..default()
                },
                shadows,
                Transform::from_xyz(3.0, 12.0, 6.0).looking_at(Vec3::ZERO, Vec3::Y),
            ));
            rig.spawn((
                Name::new("fill light"),
                DirectionalLight { illuminance: 2_000.0, shadow_maps_enabled: false, ..default() },
                Transform::from_xyz(-8.0, 3.0, 4.0).looking_at(Vec3::ZERO, Vec3::Y),
            ));
        },
    );
}

/// The light rig copies the camera's yaw.
fn follow_camera(
    camera: Query<&Transform, (With<MainCamera>, Without<LightRig>)>,
    mut rig: Query<&mut Transform, With<LightRig>>,
) {
    let (Ok(camera), Ok(mut rig)) = (camera.single(), rig.single_mut()) else { return };
    let forward = camera.forward();
    let yaw = (-forward.x).atan2(-forward.z);
    rig.rotation = Quat::from_rotation_y(yaw);
}

/// The floor settles just under the model shown.
fn place_floor(
    pool: Res<VoxelPool>,
    models: Res<Assets<VoxelModelAsset>>,
    time: Res<Time>,
    mut floor: Query<&mut Transform, With<Floor>>,
) {
    let Ok(mut floor) = floor.single_mut() else { return };
    let target = pool.shown.and_then(|id| models.get(id)).map_or(-4.5, |m| floor_height(m));
    let k = 1.0 - (-4.0 * time.delta_secs()).exp();
    floor.translation.y += (target - floor.translation.y) * k;
}

pub(super) fn plugin(app: &mut App) {
    // PostStartup: the camera (spawned in Startup) exists, so the backdrop can hang from it.
    app.add_systems(PostStartup, setup);
    app.add_systems(Update, (follow_camera.in_set(StageSystems::Lights), place_floor.in_set(StageSystems::Floor)));
}
