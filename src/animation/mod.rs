//! Animated models play live as voxels. The model shown plays a clip in a loop ([`Playback`], in the model
//! data); each new pose frame (30 a second) is posed and voxelized on the `AsyncComputeTaskPool` in the grid
//! fitted to the whole clip, so cells keep their place from pose to pose. A model has at most one pose job at a
//! time (the job borrows its [`Rig`]); a pose that comes due while one runs waits, and a later one replaces it
//! (latest wins). A placed pose replaces the voxels of the model's pose in place when the grid is the same (the
//! `follow` pass then moves only the cells that changed), or becomes a new pose that the transition morphs to
//! (another clip, other settings). The panel and P send [`AnimationRequest`]s.

mod follow;

use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, Task, futures::check_ready};
use voxel_core::palette::ColorStage;
use voxel_core::{VoxelModel, VoxelizeOptions};

use crate::model::playback::{PoseRequest, Rig};
use crate::model::{ModelLibrary, Playback, VoxelModelAsset};
use crate::schedule::AnimationSystems;
use crate::settings::{ColorSettings, VoxelSettings};
use crate::style::Style;
use crate::voxelize::VoxelizeGeneration;

pub use follow::{CellSlots, POP_SECONDS};

/// Changes to the current model's playback (the panel, the P key, tests).
#[derive(Message, Clone, Copy, Debug, PartialEq)]
pub enum AnimationRequest {
    /// Play clip `index` from its start.
    Clip(usize),
    /// Play (`true`) or pause.
    Play(bool),
    /// Play if paused, pause if playing.
    TogglePlay,
    /// Set the playback rate (1: the file's pace).
    Speed(f32),
    /// Jump to this many seconds into the clip.
    Seek(f32),
}

/// How animated models start (the command line's `--clip` and `--anim-time`): applied to each model's playback
/// the first time it is shown.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct AnimationStart {
    /// The clip to play, by name or index (default: the first).
    pub clip: Option<String>,
    /// Start paused at this many seconds into the clip (deterministic frames for screenshots).
    pub time: Option<f32>,
}

/// Sent when a pose replaced the voxels of a model's pose in place (same asset, same grid).
#[derive(Message, Clone, Copy, Debug, PartialEq, Eq)]
pub struct PosePlaced {
    /// The pose asset.
    pub model: AssetId<VoxelModelAsset>,
}

/// A running pose job of library entry `entry`.
#[derive(Component)]
pub struct PoseJob {
    /// Library index.
    pub entry: usize,
    /// The settings generation it voxelizes with.
    pub generation: u64,
    /// The clip and time posed.
    pub request: PoseRequest,
    task: Task<(Box<Rig>, Result<VoxelModel, String>)>,
}

/// Poses `request` into the rig's soup and voxelizes it in the clip's grid (computed once per clip).
fn pose(rig: &mut Rig, request: PoseRequest, options: &VoxelizeOptions) -> voxel_core::Result<VoxelModel> {
    let bounds = match rig.bounds[request.clip] {
        Some(bounds) => bounds,
        None => *rig.bounds[request.clip].insert(rig.model.clip_bounds(request.clip)?),
    };
    rig.model.pose_into(request.clip, request.time, &mut rig.soup)?;
    let model = voxel_core::voxelize_within(&rig.soup, options, bounds)?;
    // The panel shows the pose's colour count: counted here, off the frame.
    model.color_count();
    Ok(model)
}

/// Applies the panel's and keys' requests, and the command line's start to a model shown the first time.
fn apply_requests(
    mut requests: MessageReader<AnimationRequest>,
    start: Res<AnimationStart>,
    mut library: ResMut<ModelLibrary>,
) {
    let current = library.current;
    let Some(playback) = library.entries.get_mut(current).and_then(|e| e.animation.as_mut()) else {
        requests.clear();
        return;
    };
    if playback.due.is_none() {
        if let Some(clip) = start.clip.as_deref().and_then(|name| find_clip(playback, name)) {
            playback.select(clip);
        }
        if let Some(time) = start.time {
            playback.time = time;
            playback.playing = false;
        }
    }
    for request in requests.read() {
        match *request {
            AnimationRequest::Clip(clip) => playback.select(clip),
            AnimationRequest::Play(play) => playback.playing = play,
            AnimationRequest::TogglePlay => playback.playing = !playback.playing,
            AnimationRequest::Speed(speed) => playback.speed = speed.max(0.0),
            AnimationRequest::Seek(time) => playback.time = time.clamp(0.0, playback.clip_info().duration),
        }
    }
}

/// The clip named `name`, else the clip whose index `name` spells.
fn find_clip(playback: &Playback, name: &str) -> Option<usize> {
    let clips = &playback.clips;
    clips.iter().position(|c| c.name == name).or_else(|| name.parse().ok().filter(|&i| i < clips.len()))
}

/// Moves the current model's time on and asks for the pose of each new frame.
fn advance(time: Res<Time>, generation: Res<VoxelizeGeneration>, mut library: ResMut<ModelLibrary>) {
    let current = library.current;
    if let Some(playback) = library.entries.get_mut(current).and_then(|e| e.animation.as_mut()) {
        playback.advance(time.delta_secs());
        playback.request(generation.0);
    }
}

/// Starts the pose waiting for the current model when no job has its rig.
fn start_jobs(
    mut commands: Commands,
    mut library: ResMut<ModelLibrary>,
    settings: Res<VoxelSettings>,
    style: Res<State<Style>>,
    generation: Res<VoxelizeGeneration>,
) {
    let current = library.current;
    let Some(playback) = library.entries.get_mut(current).and_then(|e| e.animation.as_mut()) else { return };
    let (Some(request), Some(_)) = (playback.pending, playback.rig.as_ref()) else { return };
    let Some(mut rig) = playback.rig.take() else { return };
    playback.pending = None;
    let options = settings.voxelize_options(style.get().cell_height_ratio());
    let task = AsyncComputeTaskPool::get().spawn(async move {
        let voxels = pose(&mut rig, request, &options).map_err(|e| e.to_string());
        (rig, voxels)
    });
    commands.spawn(PoseJob { entry: current, generation: generation.0, request, task });
}

/// Collects finished poses: the rig goes home, and a pose of the current clip and settings is placed.
fn finish_jobs(
    mut commands: Commands,
    mut library: ResMut<ModelLibrary>,
    generation: Res<VoxelizeGeneration>,
    colors: Res<ColorSettings>,
    mut models: ResMut<Assets<VoxelModelAsset>>,
    mut jobs: Query<(Entity, &mut PoseJob)>,
    mut placed: MessageWriter<PosePlaced>,
) {
    for (entity, mut job) in &mut jobs {
        let Some((rig, voxels)) = check_ready(&mut job.task) else { continue };
        commands.entity(entity).despawn();
        let Some(entry) = library.entries.get_mut(job.entry) else { continue };
        let Some(playback) = entry.animation.as_mut() else { continue };
        playback.rig = Some(rig);
        if job.generation != generation.0 || job.request.clip != playback.clip {
            playback.counts.dropped += 1;
            continue;
        }
        match voxels {
            Ok(model) => {
                playback.counts.placed += 1;
                if let Some(id) = place(playback, &mut models, model, &colors.0) {
                    placed.write(PosePlaced { model: id });
                }
            }
            Err(reason) => {
                playback.playing = false;
                let message = format!("{}: pose at {:.2} s: {reason}", entry.name, job.request.time);
                warn!("{message}");
                library.last_error = Some(message);
            }
        }
    }
}

/// Puts a pose's voxels (as sampled) in the model, in the colours of `colors`: in place when the grid is the
/// same (returns the asset), else as a new pose (the transition morphs to it).
fn place(
    playback: &mut Playback,
    models: &mut Assets<VoxelModelAsset>,
    model: VoxelModel,
    colors: &ColorStage,
) -> Option<AssetId<VoxelModelAsset>> {
    let colored = VoxelModelAsset::colored(&model, colors);
    playback.sampled = Some(model);
    if let Some(handle) = &playback.pose
        && let Some(mut shown) = models.get_mut(handle)
        && shown.spec == colored.spec
    {
        *shown = colored;
        return Some(handle.id());
    }
    playback.pose = Some(models.add(colored));
    None
}

pub(super) fn plugin(app: &mut App) {
    app.init_resource::<AnimationStart>();
    app.init_resource::<CellSlots>();
    app.add_message::<AnimationRequest>();
    app.add_message::<PosePlaced>();
    app.add_systems(
        Update,
        (
            apply_requests.in_set(AnimationSystems::Request),
            advance.in_set(AnimationSystems::Advance),
            finish_jobs.in_set(AnimationSystems::Finish),
            start_jobs.in_set(AnimationSystems::Start),
            follow::follow.in_set(AnimationSystems::Follow),
        ),
    );
}
