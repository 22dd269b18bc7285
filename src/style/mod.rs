//! Styles: rounded boxes, Lego bricks, bubbles and falling voxels (S cycles, the panel picks), and mouse
//! repel in every style. The style is a Bevy state ([`Style`]): entering one swaps the shared voxel mesh and
//! the material's look (the single batch stays) and sets up what the style needs (bubbles, a falling pile);
//! leaving tears it down. Lego re-voxelizes with cells 1.2× taller (the voxelizer options follow the state).
//! Voxels at home (`Slot::at_home`: not flying, not falling, not vacant) are placed (`place`) from their home
//! cell, their bubble wobble and their repel spring.

pub mod bubbles;
pub mod falling;
pub mod meshes;
pub mod pile;
pub mod place;
pub mod repel;

use bevy::prelude::*;

use crate::instancing::mesh::{facing_box, rounded_box};
use crate::instancing::{VoxelAssets, VoxelMaterial};
use crate::schedule::{AppSystems, StyleSystems};
use crate::settings::VoxelSettings;
use repel::RepelActive;

/// How voxels look and move: a Bevy state. Each style sets itself up on entering it and tears itself down on
/// leaving (see the `style` plugin); S cycles them, the panel picks one, `--style` starts in one.
#[derive(States, Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Reflect, clap::ValueEnum)]
pub enum Style {
    /// Rounded boxes (the article's look).
    #[default]
    #[value(name = "boxes")]
    RoundedBoxes,
    /// Lego bricks: studs on top, cells 1.2× taller than wide, shiny plastic.
    Lego,
    /// Glossy bubbles that wobble and burst near the cursor.
    Bubbles,
    /// Voxels drop, bounce and pile up on the floor; F (or another model) reassembles them.
    Falling,
}

impl Style {
    /// Every style, in the order the panel lists them (and S cycles).
    pub const ALL: [Style; 4] = [Style::RoundedBoxes, Style::Lego, Style::Bubbles, Style::Falling];

    /// The panel's label.
    pub fn label(self) -> &'static str {
        match self {
            Style::RoundedBoxes => "Rounded boxes",
            Style::Lego => "Lego bricks",
            Style::Bubbles => "Bubbles",
            Style::Falling => "Falling",
        }
    }

    /// The next style (S key).
    pub fn next(self) -> Style {
        let i = Style::ALL.iter().position(|s| *s == self).unwrap_or(0);
        Style::ALL[(i + 1) % Style::ALL.len()]
    }

    /// Cell height over cell width for this style.
    pub fn cell_height_ratio(self) -> f32 {
        if self == Style::Lego { 1.2 } else { 1.0 }
    }
}

/// The ray under the mouse cursor in world space, when the cursor is over the stage (set by the camera).
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq)]
pub struct CursorRay(pub Option<Ray3d>);

/// F: drop the voxels or call them back (the falling style acts on it).
#[derive(Message, Debug, Clone, Copy, PartialEq, Eq)]
pub struct ToggleFall;

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
    // The default style; the command line's (`AppArgs::configure`) replaces it whether it comes before or after.
    app.init_state::<Style>();
    app.init_resource::<CursorRay>();
    app.add_message::<ToggleFall>();
    app.init_resource::<RepelActive>();
    for style in Style::ALL {
        app.add_systems(OnEnter(style), wear_style);
    }
    app.add_systems(Update, wear_style.run_if(roundness_changed).in_set(AppSystems::Sync));
    app.add_systems(Update, place::place_at_home.in_set(StyleSystems::Place));
    app.add_plugins((bubbles::plugin, falling::plugin));
}
