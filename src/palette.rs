//! Colours in the app: every model is voxelized with its sampled colours, which the library keeps, and shown
//! in the colours of the core's colour stage ([`ColorSettings`]: palette, colour limit, dither). A change of
//! those recolours each model from its sampled colours in place (the same assets: no voxelization, no
//! morph), and the voxels on screen take the new colours. A palette file (.hex, .png, .vox) dropped on the
//! window becomes the palette; a bad one is an error in the panel.

use std::path::{Path, PathBuf};

use bevy::mesh::MeshTag;
use bevy::prelude::*;
use voxel_core::VoxelModel;
use voxel_core::palette::{ColorStage, Palette};

use crate::animation::{AnimationSystems, PosePlaced};
use crate::instancing::{VoxelPool, pack_color};
use crate::model::{ModelLibrary, VoxelModelAsset};
use crate::schedule::AppSystems;
use crate::settings::{ColorSettings, VoxelSettings};
use crate::transition::{ActiveTransition, TransitionSettings, TransitionSystems, layout};

/// The extensions of palette files (a file dropped with one of them is a palette, not a model).
pub const PALETTE_EXTENSIONS: [&str; 3] = ["hex", "png", "vox"];

/// Whether `path` names a palette file by its extension.
pub fn is_palette_file(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| PALETTE_EXTENSIONS.iter().any(|p| e.eq_ignore_ascii_case(p)))
}

/// Use the palette file at this path (a dropped file).
#[derive(Message, Clone, Debug, PartialEq, Eq)]
pub struct PaletteFile(pub PathBuf);

/// The palette files read so far (the picker offers them beside the built-ins) and the last file's error.
#[derive(Resource, Clone, Debug, Default, PartialEq, Eq)]
pub struct PaletteFiles {
    /// The palettes read from files, in the order they came (one per path).
    pub palettes: Vec<Palette>,
    /// `error: <file>: <reason>` for the last file that could not be used.
    pub error: Option<String>,
}

/// `sampled` in the colours of `stage` (its sampled colours when the stage fails, which the panel's bounds
/// rule out).
pub fn recolored(sampled: &VoxelModel, stage: &ColorStage) -> VoxelModel {
    let mut model = sampled.clone();
    match stage.apply(&mut model) {
        Ok(()) => model,
        Err(e) => {
            warn!("colour stage: {e}");
            sampled.clone()
        }
    }
}

/// Reads dropped palette files: a good one becomes the palette, a bad one the error the panel shows.
fn read_files(
    mut files: MessageReader<PaletteFile>,
    mut colors: ResMut<ColorSettings>,
    mut read: ResMut<PaletteFiles>,
) {
    for PaletteFile(path) in files.read() {
        match voxel_core::palette::file::read(path) {
            Ok(list) => {
                let palette = Palette::Fixed { name: path.display().to_string(), colors: list };
                read.palettes
                    .retain(|p| !matches!(p, Palette::Fixed { name, .. } if *name == path.display().to_string()));
                read.palettes.push(palette.clone());
                read.error = None;
                colors.0.palette = palette;
            }
            Err(e) => {
                let message = format!("error: {}: {e}", path.display());
                warn!("{message}");
                read.error = Some(message);
            }
        }
    }
}

/// Whether a recolour waits to reach the voxels of the static model on screen.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
struct RecolorPending(bool);

/// Recolours every model (and every animated model's pose) from its sampled colours when the colour stage
/// changes; a pose's voxels follow it as for a new pose.
fn recolor(
    colors: Res<ColorSettings>,
    library: Res<ModelLibrary>,
    mut models: ResMut<Assets<VoxelModelAsset>>,
    mut placed: MessageWriter<PosePlaced>,
    mut pending: ResMut<RecolorPending>,
) {
    if !colors.is_changed() || colors.is_added() {
        return;
    }
    for entry in &library.entries {
        if let (Some(sampled), Some(handle)) = (&entry.sampled, &entry.voxels)
            && let Some(mut model) = models.get_mut(handle)
        {
            *model = VoxelModelAsset(recolored(sampled, &colors.0));
        }
        if let Some(playback) = &entry.animation
            && let (Some(sampled), Some(handle)) = (&playback.sampled, &playback.pose)
            && let Some(mut model) = models.get_mut(handle)
        {
            *model = VoxelModelAsset(recolored(sampled, &colors.0));
            placed.write(PosePlaced { model: handle.id() });
        }
    }
    pending.0 = true;
}

/// Gives the voxels of the static model on screen their model's colours after a recolour, once no morph
/// moves them (a morph to another model takes its colours from the model itself; a pose's voxels are
/// recoloured by the animation's follow pass).
fn show_colors(
    mut pending: ResMut<RecolorPending>,
    library: Res<ModelLibrary>,
    models: Res<Assets<VoxelModelAsset>>,
    settings: Res<VoxelSettings>,
    transition: Res<TransitionSettings>,
    active: Res<ActiveTransition>,
    pool: Res<VoxelPool>,
    mut tags: Query<&mut MeshTag>,
) {
    if !pending.0 || active.running.is_some() {
        return;
    }
    pending.0 = false;
    if library.current_entry().is_none_or(|e| e.animation.is_some()) {
        return;
    }
    let Some((_, model)) = library.current_ready(&models).filter(|(id, _)| pool.shown == Some(*id)) else {
        return;
    };
    for (target, &entity) in layout(model, &settings, &transition).iter().zip(&pool.slots) {
        if let Ok(mut tag) = tags.get_mut(entity) {
            let color = pack_color(target.color);
            if tag.0 != color {
                tag.0 = color;
            }
        }
    }
}

pub(super) fn plugin(app: &mut App) {
    app.init_resource::<PaletteFiles>();
    app.init_resource::<RecolorPending>();
    app.add_message::<PaletteFile>();
    app.add_systems(Update, (read_files, recolor).chain().in_set(AppSystems::Simulate).after(AnimationSystems));
    app.add_systems(Update, show_colors.in_set(AppSystems::Animate).after(TransitionSystems));
}
