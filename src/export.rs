//! Saving the model as it is shown (Ctrl+S or the panel's Export button): the current model's shown voxels
//! (its grid, fill, colours and the Lego style's taller cells are in the voxelization; hollowing is applied
//! here) go to both `.vox` and `.glb` in the exports folder, written on the IO task pool. For an animated
//! model, the clip playing also goes to one animated `<model>-<clip>.glb` (the core's animated export: its
//! poses at the app's rate, in the clip's grid and the colours shown). The panel shows the files written or
//! why it failed.

use std::path::{Path, PathBuf};

use bevy::prelude::*;
use bevy::tasks::{IoTaskPool, Task, futures::check_ready};
use voxel_core::export::animated::AnimatedGltf;
use voxel_core::export::{ExportOptions, Format, Saved, write_vox_and_glb};
use voxel_core::palette::ColorStage;
use voxel_core::{TriangleSoup, VoxelError, VoxelizeOptions, voxelize_within};

use crate::model::playback::POSES_PER_SECOND;
use crate::model::{ModelLibrary, VoxelModelAsset};
use crate::schedule::ExportSystems;
use crate::settings::{ColorSettings, VoxelSettings};
use crate::style::Style;

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
    /// Both files were written, and for an animated model its clip's animated .glb.
    Saved(Saved, Option<PathBuf>),
    /// Nothing to save, or writing failed: the reason.
    Failed(String),
}

impl ExportStatus {
    /// The panel's line: the files written or the error.
    pub fn message(&self) -> Option<String> {
        match self {
            ExportStatus::Idle => None,
            ExportStatus::Writing => Some("exporting…".into()),
            ExportStatus::Saved(saved, animated) => {
                let clip = animated.as_ref().map_or_else(String::new, |p| format!(" and {}", p.display()));
                Some(format!("saved {}, {}{clip}", saved.vox.0.display(), saved.glb.0.display()))
            }
            ExportStatus::Failed(reason) => Some(format!("export failed: {reason}")),
        }
    }
}

/// The export being written.
#[derive(Resource, Default)]
struct ExportJob(Option<Task<Result<(Saved, Option<PathBuf>), String>>>);

/// The clip of an animated model to export: the file, the clip, and the options and colours its poses are
/// shown with.
struct ClipExport {
    file: PathBuf,
    clip: usize,
    options: VoxelizeOptions,
    colors: ColorStage,
}

impl ClipExport {
    /// Poses the clip at the app's rate ([`POSES_PER_SECOND`]), voxelizes each pose in the clip's grid, and
    /// writes the frames as one animated `<dir>/<name>-<clip>.glb` (a clip's frames share the first frame's
    /// colours); returns its path.
    fn write(&self, dir: &Path, name: &str) -> voxel_core::Result<PathBuf> {
        let mut model = voxel_core::load_animated_file(&self.file)?;
        let info = model
            .clips()
            .get(self.clip)
            .cloned()
            .ok_or_else(|| VoxelError::Parameter(format!("the model has no clip {} any more", self.clip)))?;
        let bounds = model.clip_bounds(self.clip)?;
        let frames = ((info.duration * POSES_PER_SECOND).ceil() as usize).max(1);
        let mut animated = AnimatedGltf::new(&ExportOptions { name: name.into() });
        let mut soup = TriangleSoup::default();
        let mut colors = self.colors.for_frames();
        for frame in 0..frames {
            let time = frame as f32 / POSES_PER_SECOND;
            model.pose_into(self.clip, time, &mut soup)?;
            let mut voxels = voxelize_within(&soup, &self.options, bounds)?;
            colors.apply(&mut voxels)?;
            animated.push_frame(&voxels, time)?;
        }
        let clip: String = info.name.chars().map(|c| if c.is_alphanumeric() || c == '_' { c } else { '-' }).collect();
        let path = dir.join(format!("{name}-{clip}.glb"));
        animated.write(&path, Format::Glb, &info.name, info.duration)?;
        Ok(path)
    }
}

/// Starts writing the current model when asked (one export at a time: requests during one are dropped).
fn start_export(
    mut requests: MessageReader<ExportRequest>,
    library: Res<ModelLibrary>,
    models: Res<Assets<VoxelModelAsset>>,
    settings: Res<VoxelSettings>,
    (style, colors): (Res<State<Style>>, Res<ColorSettings>),
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
    let clip = entry.animation.as_ref().map(|playback| ClipExport {
        file: entry.path.clone(),
        clip: playback.clip,
        options: settings.voxelize_options(style.get().cell_height_ratio()),
        colors: colors.0.clone(),
    });
    let dir = dir.0.clone();
    *status = ExportStatus::Writing;
    job.0 = Some(IoTaskPool::get().spawn(async move {
        let saved = write_vox_and_glb(&model, &dir, &options).map_err(|e| e.to_string())?;
        let animated = clip.map(|clip| clip.write(&dir, &options.name)).transpose().map_err(|e| e.to_string())?;
        Ok((saved, animated))
    }));
}

/// Reports a finished export.
fn finish_export(mut job: ResMut<ExportJob>, mut status: ResMut<ExportStatus>) {
    let Some(result) = job.0.as_mut().and_then(check_ready) else { return };
    job.0 = None;
    *status = match result {
        Ok((saved, animated)) => {
            let status = ExportStatus::Saved(saved, animated);
            info!("export: {}", status.message().unwrap_or_default());
            status
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
