//! The library plugin: fills the model list (shipped models, command-line paths, dropped files), handles the
//! requests that change the pick, and marks files that fail to load.

use std::path::{Path, PathBuf};

use bevy::asset::{AssetPath, LoadState};
use bevy::prelude::*;
use bevy::window::FileDragAndDrop;

use crate::assets::{asset_root, file_asset_path};
use crate::model::{ModelEntry, ModelLibrary, ModelStatus};
use crate::schedule::AppSystems;

/// The models the list starts with (from the command line).
#[derive(Resource, Clone, Debug)]
pub struct LibrarySetup {
    /// Whether the shipped models (`assets/models`) come first.
    pub shipped: bool,
    /// Extra models or folders of models, after the shipped ones.
    pub extra: Vec<PathBuf>,
    /// The index of the model shown first.
    pub start: usize,
}

impl Default for LibrarySetup {
    fn default() -> Self {
        Self { shipped: true, extra: Vec::new(), start: 0 }
    }
}

/// Requests that change the list or the pick (keys, clicks, the panel, dropped files).
#[derive(Message, Clone, Debug, PartialEq)]
pub enum LibraryRequest {
    /// Show model `index`.
    Select(usize),
    /// Show the next model (wrapping).
    Next,
    /// Show the previous model (wrapping).
    Previous,
    /// Add a file or folder and show (the first of) it.
    Add(PathBuf),
}

/// The library's systems (request handling, load tracking), ahead of voxelization in `AppSystems::Simulate`.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct LibrarySystems;

impl ModelLibrary {
    /// Adds a model by asset path; returns its index.
    pub fn add(&mut self, asset_server: &AssetServer, name: String, asset_path: String) -> usize {
        if let Some(i) = self.entries.iter().position(|e| e.asset_path == asset_path) {
            return i;
        }
        let gltf = asset_server.load(AssetPath::parse(&asset_path).into_owned());
        self.entries.push(ModelEntry::new(name, asset_path, gltf, ModelStatus::Loading));
        self.entries.len() - 1
    }

    /// Adds a file or every model in a folder; returns the index of the first added. A path that is
    /// neither becomes a failed entry, so the panel shows why.
    pub fn add_path(&mut self, asset_server: &AssetServer, path: &Path) -> Option<usize> {
        let files =
            if path.is_dir() { voxel_core::cli::expand_inputs(&[path.to_owned()]) } else { vec![path.to_owned()] };
        let mut first = None;
        for file in files {
            let name =
                file.file_stem().map_or_else(|| file.display().to_string(), |s| s.to_string_lossy().into_owned());
            let index = if !file.is_file() {
                self.fail_entry(name, file_asset_path(&file), format!("cannot read {}: no such file", file.display()))
            } else if !voxel_core::cli::is_model_file(&file) {
                self.fail_entry(name, file_asset_path(&file), format!("{} is not a .glb or .gltf file", file.display()))
            } else {
                self.add(asset_server, name, file_asset_path(&file))
            };
            first.get_or_insert(index);
        }
        if first.is_none() {
            self.last_error = Some(format!("no .glb or .gltf files in {}", path.display()));
            warn!("no .glb or .gltf files in {}", path.display());
        }
        first
    }

    fn fail_entry(&mut self, name: String, asset_path: String, reason: String) -> usize {
        warn!("{name}: {reason}");
        self.last_error = Some(format!("{name}: {reason}"));
        self.entries.push(ModelEntry::new(name, asset_path, Handle::default(), ModelStatus::Failed(reason)));
        self.entries.len() - 1
    }
}

/// Adds the shipped models and the command-line ones.
fn populate(mut library: ResMut<ModelLibrary>, asset_server: Res<AssetServer>, setup: Res<LibrarySetup>) {
    let shipped = if setup.shipped { vec![asset_root().join("models")] } else { Vec::new() };
    for file in voxel_core::cli::expand_inputs(&shipped) {
        if let Some(name) = file.file_name() {
            let stem = file.file_stem().unwrap_or(name).to_string_lossy().into_owned();
            library.add(&asset_server, stem, format!("models/{}", name.to_string_lossy()));
        }
    }
    for path in &setup.extra {
        library.add_path(&asset_server, path);
    }
    library.current = setup.start.min(library.entries.len().saturating_sub(1));
}

fn handle_requests(
    mut requests: MessageReader<LibraryRequest>,
    mut library: ResMut<ModelLibrary>,
    asset_server: Res<AssetServer>,
) {
    for request in requests.read() {
        let n = library.entries.len();
        match request {
            LibraryRequest::Select(i) if *i < n => library.current = *i,
            LibraryRequest::Select(_) => {}
            LibraryRequest::Next if n > 0 => library.current = (library.current + 1) % n,
            LibraryRequest::Previous if n > 0 => library.current = (library.current + n - 1) % n,
            LibraryRequest::Next | LibraryRequest::Previous => {}
            LibraryRequest::Add(path) => {
                if let Some(i) = library.add_path(&asset_server, path) {
                    library.current = i;
                }
            }
        }
    }
}

fn dropped_files(mut drops: MessageReader<FileDragAndDrop>, mut requests: MessageWriter<LibraryRequest>) {
    for drop in drops.read() {
        if let FileDragAndDrop::DroppedFile { path_buf, .. } = drop {
            requests.write(LibraryRequest::Add(path_buf.clone()));
        }
    }
}

/// Marks entries whose file failed to load.
fn watch_loading(mut library: ResMut<ModelLibrary>, asset_server: Res<AssetServer>) {
    let failed: Vec<(usize, String)> = library
        .entries
        .iter()
        .enumerate()
        .filter(|(_, e)| e.status == ModelStatus::Loading)
        .filter_map(|(i, e)| match asset_server.load_state(&e.gltf) {
            LoadState::Failed(err) => Some((i, err.to_string())),
            _ => None,
        })
        .collect();
    for (i, reason) in failed {
        library.fail(i, reason);
    }
}

pub(super) fn plugin(app: &mut App) {
    app.init_resource::<ModelLibrary>();
    app.init_resource::<LibrarySetup>();
    app.add_message::<LibraryRequest>();
    app.add_message::<FileDragAndDrop>();
    app.add_systems(Startup, populate);
    app.add_systems(
        Update,
        (dropped_files, handle_requests, watch_loading).chain().in_set(AppSystems::Simulate).in_set(LibrarySystems),
    );
}
