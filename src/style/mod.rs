//! Styles: rounded boxes, Lego bricks, bubbles and falling voxels (S cycles, the panel picks), and mouse
//! repel in every style. Each style swaps the shared voxel mesh and material (the single batch stays); Lego
//! re-voxelizes with cells 1.2× taller. Settled voxels (not tweening, not falling) are placed (`place`) from
//! their home cell, their bubble wobble and their repel spring.

pub mod bubbles;
pub mod falling;
pub mod meshes;
pub mod pile;
pub mod place;
pub mod repel;

use bevy::prelude::*;

use crate::instancing::{VoxelAssets, VoxelCloud, VoxelMaterial, mesh::rounded_box};
use crate::schedule::AppSystems;
use crate::settings::{Style, VoxelSettings};
use crate::transition::VoxelTween;
use bubbles::BubbleSettings;
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
        (bubbles::enter_and_leave, bubbles::burst)
            .chain()
            .in_set(AppSystems::Animate)
            .after(crate::transition::TransitionSystems),
    );
    app.add_systems(Update, (place::place_settled, falling::sync, apply_look).in_set(AppSystems::Sync));
}
