//! User-tunable parameters (the side panel edits them).

use bevy::prelude::*;
use voxel_core::palette::{ColorStage, Palette};
use voxel_core::{FillMode, GridSize, VoxelizeOptions};

/// Parameters of voxelization and of the voxels' look and pace.
#[derive(Resource, Clone, Debug, PartialEq, Reflect)]
#[reflect(Resource)]
pub struct VoxelSettings {
    /// Cell width in model units (the model's diagonal is 9).
    pub grid_size: f32,
    /// Fill mode: winding (default), parity, flood or surface only.
    #[reflect(ignore)]
    pub fill: FillMode,
    /// Show only the voxels that can be seen (the model keeps its interior: falling drops it too).
    pub hollow: bool,
    /// Box edge as a fraction of the cell.
    pub box_size: f32,
    /// Corner radius as a fraction of the box edge.
    pub roundness: f32,
    /// Animation speed multiplier.
    pub speed: f32,
}

impl Default for VoxelSettings {
    fn default() -> Self {
        Self { grid_size: 0.24, fill: FillMode::Winding, hollow: true, box_size: 1.0, roundness: 0.125, speed: 1.0 }
    }
}

impl VoxelSettings {
    /// The smallest and largest grid sizes the panel offers (0.03: about 256 cells along a model's longest side).
    pub const GRID_RANGE: std::ops::RangeInclusive<f32> = 0.03..=0.6;

    /// The voxelizer options these settings ask for, with cells `cell_height_ratio` times taller than wide (the
    /// style's `Style::cell_height_ratio`: settings know nothing of styles, which read the settings).
    pub fn voxelize_options(&self, cell_height_ratio: f32) -> VoxelizeOptions {
        VoxelizeOptions {
            grid: GridSize::Cell(self.grid_size.clamp(*Self::GRID_RANGE.start(), *Self::GRID_RANGE.end())),
            cell_height_ratio,
            fill: self.fill,
            // Every solid voxel is kept (each marked visible or not): hollowing is a matter of display.
            hollow: false,
            // Colours come out as sampled: the colour stage ([`ColorSettings`]) maps them afterwards.
            // The grid is bounded by the core's memory budget; what the app draws is capped by `MAX_DRAWN`
            // voxels instead.
            ..VoxelizeOptions::default()
        }
    }
}

/// The colour stage applied to every model's sampled colours (the panel's palette, colour limit and dither):
/// changing it recolours the models without voxelizing them again.
#[derive(Resource, Clone, Debug, PartialEq, Eq)]
pub struct ColorSettings(pub ColorStage);

impl Default for ColorSettings {
    /// The article's pastel remap, no limit, no dithering.
    fn default() -> Self {
        Self(ColorStage { palette: Palette::Pastel, max_colors: None, dither: false })
    }
}

/// Mouse repel: voxels near the cursor ray are pushed away.
#[derive(Resource, Clone, Debug, PartialEq, Reflect)]
#[reflect(Resource)]
pub struct RepelSettings {
    /// Whether the cursor repels voxels (R toggles).
    pub enabled: bool,
    /// Radius around the cursor ray, in model units (bubbles burst within 0.6 of it).
    pub radius: f32,
    /// How far a voxel on the ray is pushed, as a fraction of the radius.
    pub strength: f32,
}

impl Default for RepelSettings {
    fn default() -> Self {
        Self { enabled: true, radius: 1.2, strength: 0.8 }
    }
}

/// Whether a voxelization setting is being dragged (the panel's grid slider): UI state the panel sets. While
/// it is, only the model on screen is re-voxelized, on every change, and its voxels are placed on their cells at
/// once (no morph); the other models follow, with the last settings, when the drag ends.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SettingDrag(pub bool);

/// Whether the side panel shows (H toggles): UI state, not a setting of the voxels.
#[derive(Resource, Clone, Copy, Debug, PartialEq, Eq)]
pub struct PanelOpen(pub bool);

impl Default for PanelOpen {
    fn default() -> Self {
        Self(true)
    }
}

pub(super) fn plugin(app: &mut App) {
    app.init_resource::<RepelSettings>();
    app.init_resource::<PanelOpen>();
    app.init_resource::<SettingDrag>();
    app.init_resource::<VoxelSettings>();
    app.init_resource::<ColorSettings>();
}
