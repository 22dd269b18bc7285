//! Styles: rounded boxes, Lego bricks, bubbles and falling voxels (S cycles, the panel picks), and mouse
//! repel in every style. Each style swaps the shared voxel mesh and material (the single batch stays); Lego
//! re-voxelizes with cells 1.2× taller. Settled voxels (not tweening, not falling) are composed from their
//! home cell, their bubble wobble and their repel offset.

pub mod bubbles;
pub mod falling;
pub mod meshes;
pub mod pile;
pub mod repel;

use bevy::math::{Affine3A, Mat3A, Vec3A};
use bevy::prelude::*;

use crate::AppSystems;
use crate::instancing::{RepelOffset, VoxelAssets, VoxelCloud, VoxelHome, VoxelMaterial, VoxelPool, VoxelSlot, mesh::rounded_box};
use crate::settings::{Style, VoxelSettings};
use crate::transition::VoxelTween;
use bubbles::{Bubble, BubbleSettings};
use falling::Falling;
use repel::RepelActive;

/// Voxels that styles may move: not flying in a transition, not falling.
pub type Settled = (Without<VoxelTween>, Without<Falling>, Without<VoxelCloud>);

/// The mesh of a style.
pub fn style_mesh(style: Style, roundness: f32) -> Mesh {
    match style {
        Style::RoundedBoxes | Style::Falling => rounded_box(roundness, 2),
        Style::Lego => meshes::brick(),
        Style::Bubbles => meshes::bubble(),
    }
}

/// The material look of a style: (perceptual roughness, reflectance).
fn style_surface(style: Style) -> (f32, f32) {
    match style {
        Style::Lego => (0.25, 0.6),
        Style::Bubbles => (0.08, 0.8),
        Style::RoundedBoxes | Style::Falling => (0.55, 0.35),
    }
}

/// Swaps the shared mesh and the material's look when the style (or roundness) changes.
fn apply_look(
    settings: Res<VoxelSettings>,
    assets: Option<Res<VoxelAssets>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<VoxelMaterial>>,
    mut last: Local<Option<(Style, f32)>>,
) {
    let Some(assets) = assets else { return };
    let now = (settings.style, settings.roundness);
    if *last == Some(now) {
        return;
    }
    // The pool starts with rounded boxes; any other first style (`--style`) swaps at once.
    if last.is_some() || settings.style != Style::RoundedBoxes {
        let _ = meshes.insert(&assets.mesh, style_mesh(settings.style, settings.roundness));
    }
    if let Some(mut material) = materials.get_mut(&assets.material) {
        let (roughness, reflectance) = style_surface(settings.style);
        material.base.perceptual_roughness = roughness;
        material.base.reflectance = reflectance;
    }
    *last = Some(now);
}

/// Places settled voxels: home cell (turned with the model) + bubble wobble, + repel offset; bubble scale and
/// visibility. Runs only while something moves them (and once after, to put them back); without bubbles it
/// touches only the voxels whose repel offset changed.
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
fn compose(
    time: Res<Time>,
    settings: Res<VoxelSettings>,
    timing: Res<BubbleSettings>,
    repel: Res<RepelActive>,
    cloud: Query<&Transform, (With<VoxelCloud>, Without<VoxelHome>)>,
    pool: Res<VoxelPool>,
    mut voxels: Query<(&VoxelSlot, &VoxelHome, Ref<RepelOffset>, Option<&Bubble>, &mut Transform, &mut GlobalTransform, &mut Visibility), Settled>,
    mut was_active: Local<bool>,
) {
    let bubbles = settings.style == Style::Bubbles;
    let active = bubbles || repel.0;
    if !active && !*was_active {
        return;
    }
    *was_active = active;
    let rotation = cloud.single().map_or(Quat::IDENTITY, |t| t.rotation);
    let turn = Mat3A::from_quat(rotation);
    let t = time.elapsed_secs() * settings.speed;
    let in_model = pool.visible;
    voxels.par_iter_mut().for_each(|(slot, home, repel, bubble, mut transform, mut global, mut visibility)| {
        // Without bubbles only voxels whose repel offset moved need placing.
        if slot.0 as usize >= in_model || (bubble.is_none() && !repel.is_changed()) {
            return;
        }
        let cell = home.scale.max_element();
        let (wobble, grow, shown) = match bubble {
            Some(b) => {
                let (grow, shown) = b.scale(&timing);
                (b.wobble(t, home.part, timing.wobble) * cell, grow, shown)
            }
            None => (Vec3::ZERO, 1.0, true),
        };
        let translation = rotation * (home.position + wobble) + repel.offset;
        let scale = home.scale * grow;
        if transform.translation != translation || transform.scale != scale || transform.rotation != rotation {
            // As in the transition step (written out there too: a shared helper measured 2 ms slower a frame):
            // the global transform is written directly and the Transform write skips change detection.
            *transform.bypass_change_detection() = Transform { translation, rotation, scale };
            *global = GlobalTransform::from(Affine3A {
                matrix3: Mat3A::from_cols(turn.x_axis * scale.x, turn.y_axis * scale.y, turn.z_axis * scale.z),
                translation: Vec3A::from(translation),
            });
        }
        if bubble.is_some() {
            visibility.set_if_neq(if shown { Visibility::Inherited } else { Visibility::Hidden });
        }
    });
}

pub(super) fn plugin(app: &mut App) {
    app.init_resource::<BubbleSettings>();
    app.init_resource::<RepelActive>();
    app.init_resource::<falling::FallRequested>();
    app.init_resource::<falling::PileSeed>();
    app.register_type::<BubbleSettings>();
    app.insert_resource(Time::<Fixed>::from_hz(60.0));
    app.add_systems(Update, falling::control.in_set(AppSystems::Simulate).after(crate::voxelize::VoxelizeSystems));
    app.add_systems(FixedUpdate, falling::step);
    app.add_systems(
        Update,
        (bubbles::enter_and_leave, bubbles::burst, repel::repel).chain().in_set(AppSystems::Animate).after(crate::transition::TransitionSystems),
    );
    app.add_systems(Update, (compose, falling::sync, apply_look).in_set(AppSystems::Sync));
}
