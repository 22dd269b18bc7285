//! An animated model's playback, as data: its clips, which one plays, where and how fast, the posable model
//! (away while a pose job has it) and the voxels of its latest pose. The `animation` plugin plays it.

use bevy::prelude::*;
use voxel_core::{AnimatedModel, Bounds, ClipInfo, TriangleSoup, VoxelModel};

use super::VoxelModelAsset;

/// Poses per second an animation is voxelized at: the pose shown at time t is the one at ⌊t · rate⌋ / rate.
pub const POSES_PER_SECOND: f32 = 30.0;

/// What a pose job borrows: the posable model, the soup it poses into (reused from pose to pose) and the grid
/// box of each clip once computed.
#[derive(Debug)]
pub struct Rig {
    /// The file's node tree, skins, morph targets and clips.
    pub model: AnimatedModel,
    /// The last pose's triangles.
    pub soup: TriangleSoup,
    /// Each clip's bounds over all its poses (the fixed grid its poses are voxelized in), when computed.
    pub bounds: Vec<Option<Bounds>>,
}

/// How many poses were asked for, shown and skipped (for the panel and the benchmark).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PoseCounts {
    /// Pose frames that came due while playing (each new ⌊t · rate⌋), and poses asked for by a change of clip,
    /// time or settings.
    pub requested: u64,
    /// Voxelized poses placed in the model.
    pub placed: u64,
    /// Poses superseded by a later one before a job could start them.
    pub dropped: u64,
}

/// A pose the model should show: clip and time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseRequest {
    /// Clip index.
    pub clip: usize,
    /// Seconds into the clip (a multiple of 1 / [`POSES_PER_SECOND`]).
    pub time: f32,
}

/// An animated model's playback. See the module documentation.
#[derive(Debug)]
pub struct Playback {
    /// The clips (name, duration, channels).
    pub clips: Vec<ClipInfo>,
    /// The posable model; `None` while a pose job has it (so at most one job per model runs).
    pub rig: Option<Box<Rig>>,
    /// The clip playing.
    pub clip: usize,
    /// Seconds into the clip.
    pub time: f32,
    /// Whether time runs.
    pub playing: bool,
    /// Playback rate (1: the file's pace).
    pub speed: f32,
    /// The pose frame last asked for: (clip, ⌊time · rate⌋, settings generation).
    pub due: Option<(usize, i64, u64)>,
    /// A pose asked for and not started yet (a job was running).
    pub pending: Option<PoseRequest>,
    /// The voxels of the latest pose placed, in the colour stage's colours: what the model shows.
    pub pose: Option<Handle<VoxelModelAsset>>,
    /// The latest pose placed as sampled (before the colour stage): a new palette recolours `pose` from it.
    pub sampled: Option<VoxelModel>,
    /// Poses asked for, placed and dropped.
    pub counts: PoseCounts,
}

impl Playback {
    /// Playback of `model`'s first clip from its start, playing, at the file's pace.
    pub fn new(model: AnimatedModel) -> Self {
        let clips = model.clips().to_vec();
        let rig = Rig { bounds: vec![None; clips.len()], model, soup: TriangleSoup::default() };
        Self {
            clips,
            rig: Some(Box::new(rig)),
            clip: 0,
            time: 0.0,
            playing: true,
            speed: 1.0,
            due: None,
            pending: None,
            pose: None,
            sampled: None,
            counts: PoseCounts::default(),
        }
    }

    /// The clip playing.
    pub fn clip_info(&self) -> &ClipInfo {
        &self.clips[self.clip]
    }

    /// The pose frame the current time falls in (⌊time · rate⌋).
    pub fn frame(&self) -> i64 {
        (self.time * POSES_PER_SECOND).floor() as i64
    }

    /// Plays clip `clip` from its start (ignored when there is no such clip).
    pub fn select(&mut self, clip: usize) {
        if clip < self.clips.len() && clip != self.clip {
            self.clip = clip;
            self.time = 0.0;
        }
    }

    /// Moves time on by `dt` seconds (scaled by the speed) when playing, wrapping into the clip.
    pub fn advance(&mut self, dt: f32) {
        let duration = self.clip_info().duration;
        if self.playing && duration > 0.0 {
            self.time = (self.time + dt * self.speed).rem_euclid(duration);
        }
    }

    /// Asks for the pose of the current frame when it differs from the last one asked for under settings
    /// `generation` (a pose still waiting for a job is then dropped: the latest wins).
    pub fn request(&mut self, generation: u64) {
        let due = (self.clip, self.frame(), generation);
        if self.due == Some(due) {
            return;
        }
        self.due = Some(due);
        self.counts.requested += 1;
        if self.pending.is_some() {
            self.counts.dropped += 1;
        }
        let time = due.1 as f32 / POSES_PER_SECOND;
        self.pending = Some(PoseRequest { clip: self.clip, time });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn playback(duration: f32) -> Playback {
        let mut p = Playback::new(AnimatedModel::still(TriangleSoup::default()));
        p.clips = vec![
            ClipInfo { name: "a".into(), duration, channels: 1 },
            ClipInfo { name: "b".into(), duration: 2.0, channels: 1 },
        ];
        p
    }

    #[test]
    fn time_wraps_into_the_clip_and_stops_when_paused() {
        let mut p = playback(1.0);
        p.advance(0.75);
        p.advance(0.5);
        assert!((p.time - 0.25).abs() < 1e-6, "{}", p.time);
        p.speed = 2.0;
        p.advance(0.25);
        assert!((p.time - 0.75).abs() < 1e-6);
        p.playing = false;
        p.advance(1.0);
        assert!((p.time - 0.75).abs() < 1e-6);
    }

    #[test]
    fn a_pose_is_asked_for_once_per_frame_and_a_waiting_one_is_dropped() {
        let mut p = playback(1.0);
        p.request(0);
        assert_eq!(p.pending, Some(PoseRequest { clip: 0, time: 0.0 }));
        p.advance(0.01);
        p.request(0);
        assert_eq!(p.counts, PoseCounts { requested: 1, placed: 0, dropped: 0 }, "same frame: no new pose");
        p.advance(0.03);
        p.request(0);
        assert_eq!(p.counts, PoseCounts { requested: 2, placed: 0, dropped: 1 });
        assert_eq!(p.pending, Some(PoseRequest { clip: 0, time: 1.0 / POSES_PER_SECOND }));
        p.pending = None;
        p.request(1);
        assert_eq!(p.counts.requested, 3, "new settings ask for the pose again");
        assert_eq!(p.counts.dropped, 1);
    }

    #[test]
    fn selecting_a_clip_restarts_it_and_a_missing_one_is_ignored() {
        let mut p = playback(1.0);
        p.advance(0.5);
        p.select(1);
        assert_eq!((p.clip, p.time), (1, 0.0));
        p.advance(0.5);
        p.select(7);
        assert_eq!((p.clip, p.time), (1, 0.5));
    }
}
