//! Voxelization in the app, off the frame: the file → the core's importer (the same reader
//! as the CLI, so the app and the CLI give the same cells and colours) → triangle soup, kept for later
//! settings → the core voxelizer → [`VoxelModelAsset`]s. A file with animation clips keeps its animation from
//! the same read (the `animation` plugin poses it); a static file costs what it did. A settings change
//! re-voxelizes every model, the one on screen first, and while a setting is dragged ([`SettingDrag`]) only that
//! one; a stale job is cancelled (the core stops at its next stage) and its result dropped (latest wins). Jobs
//! run in the lanes of [`spawn_job`], whose low-priority threads leave the frame first, and report their stage to
//! the model's entry. Once the core has read a file, Bevy's glTF loader is asked for it too, for its preview tile
//! only; a file of more than [`TILE_TRIANGLES`] triangles, or one that can be read only once (a pipe), is not
//! read again: its tile shows the surface of its first voxels, meshed on the worker.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use bevy::asset::AssetPath;
use bevy::prelude::*;
use bevy::tasks::{Task, futures::check_ready};
use voxel_core::{AnimatedModel, Progress, Stage, TriangleSoup, VoxelModel};

use crate::model::surface::surface_mesh;
use crate::model::{ModelLibrary, ModelStatus, Playback, VoxelModelAsset};
use crate::schedule::VoxelizeSystems;
use crate::settings::{ColorSettings, SettingDrag, VoxelSettings};
use crate::style::Style;
use crate::threads::spawn_job;

/// Files with more triangles than this get a preview tile from their voxels instead of Bevy's glTF loader:
/// reading such a file again and uploading its mesh would stall frames.
pub const TILE_TRIANGLES: usize = 500_000;

/// Bumped whenever a setting that shapes voxelization changes; models voxelized with an older
/// generation are redone.
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct VoxelizeGeneration(pub u64);

/// A running voxelization of library entry `entry` with the settings of `generation`.
#[derive(Component)]
pub struct VoxelizeJob {
    /// Library index.
    pub entry: usize,
    /// The settings generation it was started with.
    pub generation: u64,
    started: Instant,
    /// Shared with the task: its stage, and the request to stop.
    progress: Progress,
    task: Task<Option<JobResult>>,
}

/// What a job hands back: what it read (or was given) and its voxels, or why the file failed.
type JobResult = Result<(Imported, VoxelModel), String>;

/// A file as the core's importer read it.
struct Imported {
    soup: Arc<TriangleSoup>,
    /// The animation, when the file has clips the core can play.
    animation: Option<AnimatedModel>,
    /// Why the file's animation data was refused (the model then shows still).
    animation_error: Option<String>,
    /// For a file of more than [`TILE_TRIANGLES`] triangles or one read once, read now: its preview tile.
    tile: Option<Mesh>,
}

/// What a job starts from: the soup read before, or the file the core's importer reads first.
enum JobInput {
    Read(Arc<TriangleSoup>),
    File(PathBuf),
}

impl JobInput {
    /// Imports (if needed) and voxelizes (run in a job lane: [`spawn_job`]), reporting to `progress`.
    fn run(self, options: &voxel_core::VoxelizeOptions, progress: &Progress) -> JobResult {
        let (mut imported, tile_from_voxels) = match self {
            JobInput::Read(soup) => (Imported { soup, animation: None, animation_error: None, tile: None }, false),
            JobInput::File(path) => {
                progress.enter(Stage::Reading).map_err(|e| e.to_string())?;
                // Bevy's glTF loader would read the file again: not a big one, nor one that can be read only once.
                let regular = std::fs::metadata(&path).is_ok_and(|m| m.is_file());
                let imported = read(&path)?;
                let big = imported.soup.triangle_count() > TILE_TRIANGLES;
                (imported, big || !regular)
            }
        };
        let model = voxel_core::voxelize_watched(&imported.soup, options, progress).map_err(|e| e.to_string())?;
        // The panel shows the colour count: counted here, off the frame.
        model.color_count();
        if tile_from_voxels {
            imported.tile = Some(surface_mesh(&model));
        }
        Ok((imported, model))
    }
}

/// Reads a file once: its soup, and its animation when it has clips. A file whose animation data the core
/// refuses still shows, still (its bytes imported again without their animations), with the reason kept for the
/// model list.
fn read(path: &std::path::Path) -> Result<Imported, String> {
    let bytes = voxel_core::read_file(path).map_err(|e| e.to_string())?;
    let (soup, animation, animation_error) = match voxel_core::load_animated_slice(&bytes, path.parent()) {
        Ok(model) if model.clips().is_empty() => (model.into_rest_soup(), None, None),
        Ok(model) => (model.rest_soup().clone(), Some(model), None),
        Err(e) => {
            let soup = voxel_core::load_slice(&bytes, path.parent()).map_err(|e| e.to_string())?;
            (soup, None, Some(e.to_string()))
        }
    };
    Ok(Imported { soup: Arc::new(soup), animation, animation_error, tile: None })
}

/// Starts a new generation when voxelization settings change.
fn track_settings(
    settings: Res<VoxelSettings>,
    style: Res<State<Style>>,
    mut generation: ResMut<VoxelizeGeneration>,
    mut last: Local<Option<voxel_core::VoxelizeOptions>>,
) {
    let options = settings.voxelize_options(style.get().cell_height_ratio());
    if last.is_some_and(|l| l != options) {
        generation.0 += 1;
    }
    *last = Some(options);
}

/// Starts a job for every model whose voxels are missing or stale and that has no current job, the model on
/// screen first (jobs take the free lanes in the order they were spawned: [`JOB_LANES`](crate::threads::JOB_LANES)).
/// While a setting is dragged only the model on screen gets a job; the others wait, marked voxelizing, for the drag
/// to end.
fn start_jobs(
    mut commands: Commands,
    mut library: ResMut<ModelLibrary>,
    settings: Res<VoxelSettings>,
    style: Res<State<Style>>,
    drag: Res<SettingDrag>,
    generation: Res<VoxelizeGeneration>,
    jobs: Query<(Entity, &VoxelizeJob)>,
) {
    let options = settings.voxelize_options(style.get().cell_height_ratio());
    let current = library.current;
    let order = std::iter::once(current).chain((0..library.entries.len()).filter(|&i| i != current));
    for i in order {
        let Some(entry) = library.entries.get_mut(i) else { continue };
        if matches!(entry.status, ModelStatus::Failed(_)) || entry.voxels_generation == Some(generation.0) {
            continue;
        }
        let mut running = false;
        for (job_entity, job) in jobs.iter().filter(|(_, j)| j.entry == i) {
            if job.generation == generation.0 {
                running = true;
            } else {
                // Latest settings win: the core stops at its next stage, and the result is dropped unseen.
                job.progress.cancel();
                commands.entity(job_entity).despawn();
            }
        }
        if running {
            continue;
        }
        if entry.soup.is_some() {
            entry.status = ModelStatus::Voxelizing;
        }
        if drag.0 && i != current {
            continue;
        }
        let input = match &entry.soup {
            Some(soup) => JobInput::Read(soup.clone()),
            None => JobInput::File(entry.path.clone()),
        };
        let progress = Progress::new();
        entry.progress = progress.clone();
        let watched = progress.clone();
        let task = spawn_job(move || input.run(&options, &watched));
        commands.spawn(VoxelizeJob { entry: i, generation: generation.0, started: Instant::now(), progress, task });
    }
}

/// Collects finished jobs: keeps the soup read, asks Bevy for the original glTF (for the preview) the first
/// time, and stores the voxels as sampled and in the colour stage's colours; voxels of an older generation are
/// dropped.
fn finish_jobs(
    mut commands: Commands,
    mut library: ResMut<ModelLibrary>,
    generation: Res<VoxelizeGeneration>,
    colors: Res<ColorSettings>,
    asset_server: Res<AssetServer>,
    mut models: ResMut<Assets<VoxelModelAsset>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut jobs: Query<(Entity, &mut VoxelizeJob)>,
) {
    for (entity, mut job) in &mut jobs {
        let Some(done) = check_ready(&mut job.task) else { continue };
        let mut result = done.unwrap_or_else(|| Err("the voxelizer stopped unexpectedly".to_owned()));
        commands.entity(entity).despawn();
        if let (Ok((imported, _)), Some(entry)) = (&mut result, library.entries.get_mut(job.entry))
            && entry.soup.is_none()
        {
            entry.soup = Some(imported.soup.clone());
            entry.animation = imported.animation.take().map(Playback::new);
            if let Some(reason) = imported.animation_error.take() {
                warn!("{}: the animation is ignored: {reason}", entry.name);
                entry.warning = Some(format!("the animation is ignored: {reason}"));
            }
            match imported.tile.take() {
                Some(tile) => entry.tile_mesh = Some(meshes.add(tile)),
                None => entry.gltf = asset_server.load(AssetPath::parse(&entry.asset_path).into_owned()),
            }
        }
        if job.generation != generation.0 {
            continue;
        }
        match result {
            Ok((_, model)) => {
                if let Some(entry) = library.entries.get_mut(job.entry) {
                    entry.voxels = Some(models.add(VoxelModelAsset::colored(&model, &colors.0)));
                    entry.sampled = Some(Arc::new(model));
                    entry.voxels_generation = Some(job.generation);
                    entry.voxelize_ms = job.started.elapsed().as_secs_f32() * 1e3;
                    entry.status = ModelStatus::Ready;
                }
            }
            Err(reason) => library.fail(job.entry, reason),
        }
    }
}

pub(super) fn plugin(app: &mut App) {
    app.init_asset::<VoxelModelAsset>();
    app.init_resource::<VoxelizeGeneration>();
    app.add_systems(
        Update,
        (
            track_settings.in_set(VoxelizeSystems::Track),
            start_jobs.in_set(VoxelizeSystems::Start),
            finish_jobs.in_set(VoxelizeSystems::Finish),
        ),
    );
}
