//! The model list: shipped models, command-line paths, dropped files; loading state and the current pick.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use bevy::asset::{AssetPath, LoadState};
use bevy::gltf::Gltf;
use bevy::prelude::*;
use bevy::window::FileDragAndDrop;
use voxel_core::TriangleSoup;

use crate::voxelize::VoxelModel;
use crate::{AppSystems, FILE_SOURCE};

/// Where a model is in its life.
#[derive(Clone, Debug, PartialEq)]
pub enum ModelStatus {
    /// The asset server is reading it.
    Loading,
    /// Loaded; a voxelization task runs.
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
    /// The asset path it loads from.
    pub asset_path: String,
    /// The loaded glTF (also spawned in its preview).
    pub gltf: Handle<Gltf>,
    /// Loading/voxelizing state.
    pub status: ModelStatus,
    /// The triangles, read once from the loaded glTF.
    pub soup: Option<Arc<TriangleSoup>>,
    /// The latest voxelization.
    pub voxels: Option<Handle<VoxelModel>>,
    /// The settings generation `voxels` was made with.
    pub voxels_generation: Option<u64>,
    /// How long the latest voxelization took.
    pub voxelize_ms: f32,
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
    /// The entry shown.
    pub fn current_entry(&self) -> Option<&ModelEntry> {
        self.entries.get(self.current)
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

/// The asset path for a file on disk (through the `fs` source, so any folder works).
pub fn file_asset_path(path: &Path) -> String {
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_owned());
    let text = absolute.to_string_lossy().replace('\\', "/");
    format!("{FILE_SOURCE}://{}", text.trim_start_matches('/'))
}

impl ModelLibrary {
    /// Adds a model by asset path; returns its index.
    pub fn add(&mut self, asset_server: &AssetServer, name: String, asset_path: String) -> usize {
        if let Some(i) = self.entries.iter().position(|e| e.asset_path == asset_path) {
            return i;
        }
        let gltf = asset_server.load(AssetPath::parse(&asset_path).into_owned());
        self.entries.push(ModelEntry {
            name,
            asset_path,
            gltf,
            status: ModelStatus::Loading,
            soup: None,
            voxels: None,
            voxels_generation: None,
            voxelize_ms: 0.0,
        });
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
        self.entries.push(ModelEntry {
            name,
            asset_path,
            gltf: Handle::default(),
            status: ModelStatus::Failed(reason),
            soup: None,
            voxels: None,
            voxels_generation: None,
            voxelize_ms: 0.0,
        });
        self.entries.len() - 1
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

/// Adds the shipped models (`assets/models`) and the command-line ones.
fn populate(
    mut library: ResMut<ModelLibrary>,
    asset_server: Res<AssetServer>,
    args: Option<Res<crate::args::AppArgs>>,
) {
    let shipped = crate::args::asset_root().join("models");
    let skip = args.as_ref().is_some_and(|a| a.no_shipped);
    for file in voxel_core::cli::expand_inputs(&[shipped]).into_iter().filter(|_| !skip) {
        if let Some(name) = file.file_name() {
            let stem = file.file_stem().unwrap_or(name).to_string_lossy().into_owned();
            library.add(&asset_server, stem, format!("models/{}", name.to_string_lossy()));
        }
    }
    if let Some(args) = args {
        for path in &args.models {
            library.add_path(&asset_server, path);
        }
        library.current = args.start.min(library.entries.len().saturating_sub(1));
    }
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
    app.add_message::<LibraryRequest>();
    app.add_message::<FileDragAndDrop>();
    app.add_systems(Startup, populate);
    app.add_systems(
        Update,
        (dropped_files, handle_requests, watch_loading).chain().in_set(AppSystems::Simulate).in_set(LibrarySystems),
    );
}
