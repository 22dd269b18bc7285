//! Styles: rounded boxes, Lego bricks, bubbles and falling voxels (S cycles, the panel picks), and mouse
//! repel in every style. The style is a Bevy state ([`Style`]): entering one swaps the shared voxel mesh and
//! the material's look (the single batch stays) and sets up what the style needs (bubbles, a falling pile);
//! leaving tears it down. Lego re-voxelizes with cells 1.2× taller (the voxelizer options follow the state).
//! Settled voxels (not tweening, not falling) are placed (`place`) from their home cell, their bubble wobble
//! and their repel spring.

pub mod bubbles;
pub mod falling;
pub mod meshes;
pub mod pile;
pub mod place;
pub mod repel;

use bevy::prelude::*;

use crate::instancing::mesh::{facing_box, rounded_box};
use crate::instancing::{Vacant, VoxelAssets, VoxelCloud, VoxelMaterial};
use crate::schedule::AppSystems;
use crate::settings::{Style, VoxelSettings};
use crate::transition::VoxelTween;
use falling::Falling;
use repel::RepelActive;

/// Voxels that styles may move: not flying in a transition (or popping), not falling, not a vacant slot.
pub type Settled = (Without<VoxelTween>, Without<Falling>, Without<VoxelCloud>, Without<Vacant>);

/// The mesh of a style.
pub fn style_mesh(style: Style, roundness: f32) -> Mesh {
    match style {
        Style::RoundedBoxes | Style::Falling => rounded_box(roundness, 2),
        Style::Lego => meshes::brick(),
        Style::Bubbles => meshes::bubble(),
    }
}

/// The low detail mesh of a style (drawn when voxels cover a few pixels): the three faces of a box that face the
/// viewer, shaded like a sphere for bubbles.
pub fn style_low_mesh(style: Style) -> Mesh {
    facing_box(style == Style::Bubbles)
}

/// The material look of a style: (perceptual roughness, reflectance).
fn style_surface(style: Style) -> (f32, f32) {
    match style {
        Style::Lego => (0.25, 0.6),
        Style::Bubbles => (0.08, 0.8),
        Style::RoundedBoxes | Style::Falling => (0.55, 0.35),
    }
}

/// Dresses the pool in the style's mesh and look (on entering a style, and when the roundness changes).
fn wear_style(
    style: Res<State<Style>>,
    settings: Res<VoxelSettings>,
    assets: Res<VoxelAssets>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<VoxelMaterial>>,
) {
    let style = *style.get();
    let _ = meshes.insert(&assets.mesh, style_mesh(style, settings.roundness));
    let _ = meshes.insert(&assets.low_mesh, style_low_mesh(style));
    if let Some(mut material) = materials.get_mut(&assets.material) {
        (material.base.perceptual_roughness, material.base.reflectance) = style_surface(style);
    }
}

/// Whether the roundness setting changed since the last frame.
fn roundness_changed(settings: Res<VoxelSettings>, mut last: Local<Option<f32>>) -> bool {
    let changed = last.is_some_and(|r| r != settings.roundness);
    *last = Some(settings.roundness);
    changed
}

pub(super) fn plugin(app: &mut App) {
    app.init_resource::<RepelActive>();
    for style in Style::ALL {
        app.add_systems(OnEnter(style), wear_style);
    }
    app.add_systems(Update, wear_style.run_if(roundness_changed).in_set(AppSystems::Sync));
    app.add_systems(Update, place::place_settled.in_set(AppSystems::Sync));
    app.add_plugins((bubbles::plugin, falling::plugin));
}
