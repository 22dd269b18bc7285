//! The library plugin: fills the model list (shipped models, command-line paths, dropped files) and handles the
//! requests that change the pick.

use std::path::{Path, PathBuf};

use bevy::prelude::*;
use bevy::window::FileDragAndDrop;

use crate::assets::{asset_root, file_asset_path};
use crate::model::{ModelEntry, ModelLibrary, ModelStatus};
use crate::palette::is_palette_file;
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
    /// Adds the model file `path` (shown through `asset_path` in its preview); returns its index.
    pub fn add(&mut self, name: String, path: PathBuf, asset_path: String) -> usize {
        if let Some(i) = self.entries.iter().position(|e| e.asset_path == asset_path) {
            return i;
        }
        self.entries.push(ModelEntry::new(name, path, asset_path, ModelStatus::Loading));
        self.entries.len() - 1
    }

    /// Adds a file or every model in a folder; returns the index of the first added. A path that is
    /// neither becomes a failed entry, so the panel shows why.
    pub fn add_path(&mut self, path: &Path) -> Option<usize> {
        let files =
            if path.is_dir() { voxel_core::files::expand_inputs(&[path.to_owned()]) } else { vec![path.to_owned()] };
        let mut first = None;
        for file in files {
            let name =
                file.file_stem().map_or_else(|| file.display().to_string(), |s| s.to_string_lossy().into_owned());
            let index = if !file.is_file() {
                self.fail_entry(name, &file, format!("cannot read {}: no such file", file.display()))
            } else if !voxel_core::files::is_model_file(&file) {
                self.fail_entry(name, &file, format!("{} is not a .glb or .gltf file", file.display()))
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

    fn fail_entry(&mut self, name: String, file: &Path, reason: String) -> usize {
        warn!("{name}: {reason}");
        self.last_error = Some(format!("{name}: {reason}"));
        let asset_path = file_asset_path(file);
        self.entries.push(ModelEntry::new(name, file.to_owned(), asset_path, ModelStatus::Failed(reason)));
        self.entries.len() - 1
    }
}

/// Adds the shipped models and the command-line ones; a start index past the list is an error that ends the
/// app (not a silent clamp).
fn populate(mut library: ResMut<ModelLibrary>, setup: Res<LibrarySetup>, mut exit: MessageWriter<AppExit>) {
    let shipped = if setup.shipped { vec![asset_root().join("models")] } else { Vec::new() };
    for file in voxel_core::files::expand_inputs(&shipped) {
        if let Some(name) = file.file_name() {
            let stem = file.file_stem().unwrap_or(name).to_string_lossy().into_owned();
            let asset_path = format!("models/{}", name.to_string_lossy());
            library.add(stem, file, asset_path);
        }
    }
    for path in &setup.extra {
        library.add_path(path);
    }
    let n = library.entries.len();
    if setup.start >= n.max(1) {
        error!("--start {}: the list has {n} models (0 to {})", setup.start, n.saturating_sub(1));
        exit.write(AppExit::error());
    }
    library.current = setup.start.min(n.saturating_sub(1));
}

fn handle_requests(mut requests: MessageReader<LibraryRequest>, mut library: ResMut<ModelLibrary>) {
    for request in requests.read() {
        let n = library.entries.len();
        match request {
            LibraryRequest::Select(i) if *i < n => library.current = *i,
            LibraryRequest::Select(_) => {}
            LibraryRequest::Next if n > 0 => library.current = (library.current + 1) % n,
            LibraryRequest::Previous if n > 0 => library.current = (library.current + n - 1) % n,
            LibraryRequest::Next | LibraryRequest::Previous => {}
            LibraryRequest::Add(path) => {
                if let Some(i) = library.add_path(path) {
                    library.current = i;
                }
            }
        }
    }
}

/// A dropped model file or folder joins the list (a palette file is the `palette` plugin's).
fn dropped_files(mut drops: MessageReader<FileDragAndDrop>, mut requests: MessageWriter<LibraryRequest>) {
    for drop in drops.read() {
        if let FileDragAndDrop::DroppedFile { path_buf, .. } = drop
            && !is_palette_file(path_buf)
        {
            requests.write(LibraryRequest::Add(path_buf.clone()));
        }
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
        (dropped_files, handle_requests).chain().in_set(AppSystems::Simulate).in_set(LibrarySystems),
    );
}
