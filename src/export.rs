//! Saving the model as it is shown (Ctrl+S or the panel's Export button): the current model's shown voxels
//! (its grid, fill, pastel colours and the Lego style's taller cells are in the voxelization; hollowing is
//! applied here) go to both `.vox` and `.glb` in the exports folder, written on the IO task pool. The panel
//! shows the files written or why it failed.

use std::path::PathBuf;

use bevy::prelude::*;
use bevy::tasks::{IoTaskPool, Task, futures::check_ready};
use voxel_core::export::{ExportOptions, Saved, write_vox_and_glb};

use crate::model::ModelLibrary;
use crate::model::VoxelModelAsset;
use crate::schedule::ExportSystems;
use crate::settings::VoxelSettings;

/// The folder exports go to when `--export-dir` is not given.
pub const DEFAULT_EXPORT_DIR: &str = "voxel-art-exports";

/// Where exports are written (`--export-dir`).
#[derive(Resource, Clone, Debug, PartialEq, Eq)]
pub struct ExportDir(pub PathBuf);

impl Default for ExportDir {
    fn default() -> Self {
        Self(PathBuf::from(DEFAULT_EXPORT_DIR))
    }
}

/// Save the current model as shown (Ctrl+S, the panel's button).
#[derive(Message, Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExportRequest;

/// What the last export did, for the panel.
#[derive(Resource, Clone, Debug, Default, PartialEq, Eq)]
pub enum ExportStatus {
    /// Nothing asked yet.
    #[default]
    Idle,
    /// Files are being written.
    Writing,
    /// Both files were written.
    Saved(Saved),
    /// Nothing to save, or writing failed: the reason.
    Failed(String),
}

impl ExportStatus {
    /// The panel's line: the files written or the error.
    pub fn message(&self) -> Option<String> {
        match self {
            ExportStatus::Idle => None,
            ExportStatus::Writing => Some("exporting…".into()),
            ExportStatus::Saved(saved) => {
                Some(format!("saved {} and {}", saved.vox.0.display(), saved.glb.0.display()))
            }
            ExportStatus::Failed(reason) => Some(format!("export failed: {reason}")),
        }
    }
}

/// The export being written.
#[derive(Resource, Default)]
struct ExportJob(Option<Task<Result<Saved, String>>>);

/// Starts writing the current model when asked (one export at a time: requests during one are dropped).
fn start_export(
    mut requests: MessageReader<ExportRequest>,
    library: Res<ModelLibrary>,
    models: Res<Assets<VoxelModelAsset>>,
    settings: Res<VoxelSettings>,
    dir: Res<ExportDir>,
    mut job: ResMut<ExportJob>,
    mut status: ResMut<ExportStatus>,
) {
    if requests.read().count() == 0 || job.0.is_some() {
        return;
    }
    let (Some(entry), Some((_, model))) = (library.current_entry(), library.current_ready(&models)) else {
        *status = ExportStatus::Failed("no model is ready to export".into());
        return;
    };
    let model = model.shown_model(settings.hollow);
    let options = ExportOptions { name: entry.name.clone() };
    let dir = dir.0.clone();
    *status = ExportStatus::Writing;
    job.0 = Some(
        IoTaskPool::get().spawn(async move { write_vox_and_glb(&model, &dir, &options).map_err(|e| e.to_string()) }),
    );
}

/// Reports a finished export.
fn finish_export(mut job: ResMut<ExportJob>, mut status: ResMut<ExportStatus>) {
    let Some(result) = job.0.as_mut().and_then(check_ready) else { return };
    job.0 = None;
    *status = match result {
        Ok(saved) => {
            info!("exported {} and {}", saved.vox.0.display(), saved.glb.0.display());
            ExportStatus::Saved(saved)
        }
        Err(reason) => {
            warn!("export failed: {reason}");
            ExportStatus::Failed(reason)
        }
    };
}

pub(super) fn plugin(app: &mut App) {
    app.init_resource::<ExportDir>();
    app.init_resource::<ExportStatus>();
    app.init_resource::<ExportJob>();
    app.add_message::<ExportRequest>();
    app.add_systems(Update, (start_export.in_set(ExportSystems::Start), finish_export.in_set(ExportSystems::Finish)));
}
