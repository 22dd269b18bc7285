//! The library plugin: fills the model list (shipped models, command-line paths, dropped files) and handles the
//! requests that change the pick.

use std::path::PathBuf;

use bevy::prelude::*;
use bevy::window::FileDragAndDrop;

use crate::assets::asset_root;
use crate::model::ModelLibrary;
use crate::palette::is_palette_file;
use crate::schedule::LibrarySystems;

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
        (dropped_files.in_set(LibrarySystems::Drop), handle_requests.in_set(LibrarySystems::Request)),
    );
}
