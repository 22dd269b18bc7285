//! The models as data: the list the app cycles through ([`ModelLibrary`], all of its methods: adding files,
//! failing entries, the one lookup of "the current model, if it is ready"), each model's status and its
//! voxelization (the [`VoxelModelAsset`]). No systems live here: the `library` plugin fills the list,
//! `voxelize` turns its entries into voxels, `animation` poses animated ones, the rest read it.

pub mod playback;
pub mod surface;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use bevy::gltf::Gltf;
use bevy::prelude::*;
use voxel_core::palette::ColorStage;
use voxel_core::{Progress, TriangleSoup, Voxel, VoxelModel};

use crate::assets::file_asset_path;

pub use playback::Playback;

/// A voxelized model as a Bevy asset, with every solid voxel (interior ones included); it dereferences to the
/// core's [`VoxelModel`].
#[derive(Asset, TypePath, Debug, Clone, Deref)]
pub struct VoxelModelAsset(pub VoxelModel);

impl VoxelModelAsset {
    /// `sampled` (a voxelization's colours as sampled) in the colours of the colour `stage`: the one place the
    /// app derives the colours it shows. A stage the core refuses (the panel's bounds rule that out) leaves the
    /// sampled colours, with a warning.
    pub fn colored(sampled: &VoxelModel, stage: &ColorStage) -> Self {
        let mut model = sampled.clone();
        if let Err(e) = stage.apply(&mut model) {
            warn!("colour stage: {e}");
            model = sampled.clone();
        }
        Self(model)
    }

    /// The voxels shown: only those that can be seen when `hollow`, else all.
    pub fn shown(&self, hollow: bool) -> Box<dyn Iterator<Item = Voxel> + Send + '_> {
        if hollow { Box::new(self.visible_voxels()) } else { self.voxels() }
    }

    /// The model as shown: only its visible voxels when `hollow`, else all of them (what an export saves).
    pub fn shown_model(&self, hollow: bool) -> VoxelModel {
        if hollow { self.hollowed() } else { self.0.clone() }
    }

    /// How many voxels are shown.
    pub fn shown_count(&self, hollow: bool) -> usize {
        if hollow { self.stats.visible } else { self.len() }
    }
}

/// A model's colours were derived again from its sampled colours (a new colour stage): same asset, same cells.
#[derive(Message, Clone, Copy, Debug, PartialEq, Eq)]
pub struct Recolored {
    /// The recoloured asset.
    pub model: AssetId<VoxelModelAsset>,
}

/// Where a model is in its life.
#[derive(Clone, Debug, PartialEq)]
pub enum ModelStatus {
    /// The core's importer is reading the file.
    Loading,
    /// Loaded; a voxelization task runs (or, for a model not on screen, waits for a slider drag to end).
    Voxelizing,
    /// Voxels are available.
    Ready,
    /// Loading or voxelizing failed; the reason, for the panel and the log.
    Failed(String),
}

/// One model of the list.
#[derive(Debug)]
pub struct ModelEntry {
    /// Display name (file stem).
    pub name: String,
    /// The file on disk, which the core's importer reads (the one glTF reader of the app and the CLI).
    pub path: PathBuf,
    /// The same file as an asset path, for Bevy's glTF loader.
    pub asset_path: String,
    /// The original glTF as Bevy loads it, only to show it in its preview tile. Requested once the core has
    /// read the file, so a file the core refuses never reaches Bevy's loader, and one Bevy cannot show still
    /// voxelizes.
    pub gltf: Handle<Gltf>,
    /// Loading/voxelizing state.
    pub status: ModelStatus,
    /// The triangles, read once by the core's importer.
    pub soup: Option<Arc<TriangleSoup>>,
    /// The latest voxelization, in the colours of the colour stage ([`crate::settings::ColorSettings`]).
    pub voxels: Option<Handle<VoxelModelAsset>>,
    /// The latest voxelization as sampled (before the colour stage): a new palette recolours `voxels` from it.
    pub sampled: Option<Arc<VoxelModel>>,
    /// The settings generation `voxels` was made with.
    pub voxels_generation: Option<u64>,
    /// How long the latest voxelization took.
    pub voxelize_ms: f32,
    /// The animation, when the file has clips (read by the same import as `soup`); `None` for a static model.
    pub animation: Option<Playback>,
    /// How far the latest voxelization job got (shared with the job; cancelling it stops the job).
    pub progress: Progress,
    /// The preview tile's mesh for a file too big to show through Bevy's glTF loader without a stall (the
    /// surface of its first voxels, built off the main thread); `None`: the tile shows `gltf`.
    pub tile_mesh: Option<Handle<Mesh>>,
    /// Something of the file that is not shown, and why (an animation the core refuses: the model shows still).
    pub warning: Option<String>,
}

impl ModelEntry {
    /// An entry with nothing read or voxelized yet.
    pub fn new(name: String, path: PathBuf, asset_path: String, status: ModelStatus) -> Self {
        Self {
            name,
            path,
            asset_path,
            gltf: Handle::default(),
            status,
            soup: None,
            voxels: None,
            sampled: None,
            voxels_generation: None,
            voxelize_ms: 0.0,
            progress: Progress::default(),
            tile_mesh: None,
            animation: None,
            warning: None,
        }
    }

    /// Its latest voxelization, if any (it may be of older settings while a new one runs).
    pub fn latest<'a>(&self, models: &'a Assets<VoxelModelAsset>) -> Option<&'a VoxelModelAsset> {
        self.voxels.as_ref().and_then(|h| models.get(h))
    }

    /// The voxels it is shown with: an animated model's latest pose (none until the first is placed), else its
    /// latest voxelization.
    pub fn shown_handle(&self) -> Option<&Handle<VoxelModelAsset>> {
        match &self.animation {
            Some(animation) => animation.pose.as_ref(),
            None => self.voxels.as_ref(),
        }
    }
}

/// The models the app cycles through and which one is shown.
#[derive(Resource, Debug, Default)]
pub struct ModelLibrary {
    /// All models, in list order.
    pub entries: Vec<ModelEntry>,
    /// Index of the model shown (or wanted: it may still be voxelizing).
    pub current: usize,
    /// The most recent error, for the panel.
    pub last_error: Option<String>,
}

impl ModelLibrary {
    /// The entry picked.
    pub fn current_entry(&self) -> Option<&ModelEntry> {
        self.entries.get(self.current)
    }

    /// The picked model's voxels when they are ready for the current settings.
    pub fn current_ready<'a>(
        &self,
        models: &'a Assets<VoxelModelAsset>,
    ) -> Option<(AssetId<VoxelModelAsset>, &'a VoxelModelAsset)> {
        let entry = self.current_entry().filter(|e| e.status == ModelStatus::Ready)?;
        let handle = entry.shown_handle()?;
        models.get(handle).map(|m| (handle.id(), m))
    }

    /// Adds the model file `path` (shown through `asset_path` in its preview); returns its index.
    pub fn add(&mut self, name: String, path: PathBuf, asset_path: String) -> usize {
        if let Some(i) = self.entries.iter().position(|e| e.asset_path == asset_path) {
            return i;
        }
        self.entries.push(ModelEntry::new(name, path, asset_path, ModelStatus::Loading));
        self.entries.len() - 1
    }

    /// Adds a file (a named pipe too) or every model in a folder; returns the index of the first added. A path
    /// that is neither becomes a failed entry, so the panel shows why.
    pub fn add_path(&mut self, path: &Path) -> Option<usize> {
        let files =
            if path.is_dir() { voxel_core::files::expand_inputs(&[path.to_owned()]) } else { vec![path.to_owned()] };
        let mut first = None;
        for file in files {
            let name =
                file.file_stem().map_or_else(|| file.display().to_string(), |s| s.to_string_lossy().into_owned());
            let index = if !file.exists() {
                self.add_failed(name, &file, format!("cannot read {}: no such file", file.display()))
            } else if !voxel_core::files::is_model_file(&file) {
                self.add_failed(name, &file, format!("{} is not a .glb or .gltf file", file.display()))
            } else {
                let asset_path = file_asset_path(&file);
                self.add(name, file, asset_path)
            };
            first.get_or_insert(index);
        }
        if first.is_none() {
            self.last_error = Some(format!("no .glb or .gltf files in {}", path.display()));
            warn!("no .glb or .gltf files in {}", path.display());
        }
        first
    }

    /// Adds an entry for a file that cannot be a model, failed with `reason`; returns its index.
    fn add_failed(&mut self, name: String, file: &Path, reason: String) -> usize {
        self.entries.push(ModelEntry::new(name, file.to_owned(), file_asset_path(file), ModelStatus::Loading));
        let index = self.entries.len() - 1;
        self.fail(index, reason);
        index
    }

    /// Records that entry `index` failed.
    pub fn fail(&mut self, index: usize, reason: String) {
        if let Some(e) = self.entries.get_mut(index) {
            warn!("{}: {reason}", e.name);
            self.last_error = Some(format!("{}: {reason}", e.name));
            e.status = ModelStatus::Failed(reason);
        }
    }
}
