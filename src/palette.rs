//! Colours in the app: every model is voxelized with its sampled colours, which the library keeps, and shown
//! in the colours of the core's colour stage ([`ColorSettings`]: palette, colour limit, dither), derived by
//! [`VoxelModelAsset::colored`]. A change of those recolours each model from its sampled colours in place (the
//! same assets: no voxelization, no morph) and says so ([`Recolored`], or [`PosePlaced`] for an animated
//! model's pose), and the voxels on screen take the new colours (the transition's and the animation's passes).
//! A palette file (.hex, .png, .vox) dropped on the window becomes the palette; a bad one is an error in the
//! panel and changes nothing.

use std::path::Path;

use bevy::prelude::*;
use bevy::window::FileDragAndDrop;
use voxel_core::palette::Palette;

use crate::animation::PosePlaced;
use crate::model::{ModelLibrary, Recolored, VoxelModelAsset};
use crate::schedule::AppSystems;
use crate::settings::ColorSettings;

/// The extensions of palette files (a file dropped with one of them is a palette, not a model).
pub const PALETTE_EXTENSIONS: [&str; 3] = ["hex", "png", "vox"];

/// Whether `path` names a palette file by its extension.
pub fn is_palette_file(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| PALETTE_EXTENSIONS.iter().any(|p| e.eq_ignore_ascii_case(p)))
}

/// The palette files read so far (the picker offers them beside the built-ins) and the last file's error.
#[derive(Resource, Clone, Debug, Default, PartialEq, Eq)]
pub struct PaletteFiles {
    /// The palettes read from files, in the order they came (one per path).
    pub palettes: Vec<Palette>,
    /// `error: <file>: <reason>` for the last file that could not be used.
    pub error: Option<String>,
}

/// Reads palette files dropped on the window: a good one becomes the palette, a bad one the error the panel
/// shows (the palette stays).
fn read_dropped(
    mut drops: MessageReader<FileDragAndDrop>,
    mut colors: ResMut<ColorSettings>,
    mut files: ResMut<PaletteFiles>,
) {
    for drop in drops.read() {
        let FileDragAndDrop::DroppedFile { path_buf: path, .. } = drop else { continue };
        if !is_palette_file(path) {
            continue;
        }
        let name = path.display().to_string();
        match voxel_core::palette::file::read(path) {
            Ok(list) => {
                let palette = Palette::Fixed { name: name.clone(), colors: list };
                files.palettes.retain(|p| !matches!(p, Palette::Fixed { name: n, .. } if *n == name));
                files.palettes.push(palette.clone());
                files.error = None;
                colors.0.palette = palette;
            }
            Err(e) => {
                let message = format!("error: {name}: {e}");
                warn!("{message}");
                files.error = Some(message);
            }
        }
    }
}

/// Recolours every model (and every animated model's pose) from its sampled colours when the colour stage
/// changes, and says which assets changed.
fn recolor(
    colors: Res<ColorSettings>,
    library: Res<ModelLibrary>,
    mut models: ResMut<Assets<VoxelModelAsset>>,
    mut recolored: MessageWriter<Recolored>,
    mut placed: MessageWriter<PosePlaced>,
) {
    if !colors.is_changed() || colors.is_added() {
        return;
    }
    for entry in &library.entries {
        if let (Some(sampled), Some(handle)) = (&entry.sampled, &entry.voxels)
            && let Some(mut model) = models.get_mut(handle)
        {
            *model = VoxelModelAsset::colored(sampled, &colors.0);
            recolored.write(Recolored { model: handle.id() });
        }
        if let Some(playback) = &entry.animation
            && let (Some(sampled), Some(handle)) = (&playback.sampled, &playback.pose)
            && let Some(mut model) = models.get_mut(handle)
        {
            *model = VoxelModelAsset::colored(sampled, &colors.0);
            placed.write(PosePlaced { model: handle.id() });
        }
    }
}

pub(super) fn plugin(app: &mut App) {
    app.init_resource::<PaletteFiles>();
    app.add_message::<FileDragAndDrop>();
    app.add_message::<Recolored>();
    app.add_message::<PosePlaced>();
    app.add_systems(Update, (read_dropped, recolor).chain().in_set(AppSystems::Color));
}
