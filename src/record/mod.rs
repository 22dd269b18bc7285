//! Recording the stage as an animated GIF: `--record out.gif --seconds S [--then M] [--record-size WxH]`
//! headless (it exits as `--screenshot` does), Ctrl+R or the panel's button in the window (into the exports
//! folder; Ctrl+R again stops, at the latest after [`MAX_WINDOW_SECONDS`]).
//!
//! What is recorded is the stage alone: a record camera, a child of the main camera (so it follows the orbit)
//! with the same lens, MSAA, tonemapping and shadow filtering, renders render layer 0 — the voxels, floor,
//! backdrop and lights, never the egui panel (its own camera) or the preview tiles (layers 1 and up) — into an
//! image of the record size, and a `Screenshot` of that image is taken whenever the [`FrameClock`] says a frame
//! is due ([`RECORD_FPS`] a second; headless, time steps a fixed 1/60 s a frame, so every other frame is taken
//! whatever the renderer's speed). The screenshots come back asynchronously and go straight to the
//! [`GifWriter`]'s thread, which quantizes and compresses them while the app goes on. The camera exists only
//! while recording, and renders a few frames before the first is taken (its pipelines compile meanwhile).

mod clock;
mod encoder;

use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Duration;

use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::light::ShadowFilteringMethod;
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured};

use crate::camera::MainCamera;
use crate::cue::{Cue, CueParams, CueState};
use crate::export::ExportDir;
use crate::input::ToggleRecord;
use crate::model::ModelLibrary;
use crate::schedule::AppSystems;

pub use clock::FrameClock;
pub use encoder::{FrameSender, GifFrame, GifSummary, GifWriter};

/// Frames a second of a recording (GIF delays of 3, 3 and 4 centiseconds).
pub const RECORD_FPS: u32 = 30;
/// Seconds a headless `--record` lasts when `--seconds` is not given.
pub const DEFAULT_SECONDS: f32 = 4.0;
/// The longest recording the window takes (Ctrl+R again stops it sooner).
pub const MAX_WINDOW_SECONDS: f32 = 20.0;
/// Frames a new record camera renders before its first frame is taken.
const WARM_UP_FRAMES: u32 = 10;

/// The size of recorded GIFs in pixels (`--record-size WxH`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RecordSize {
    /// Width.
    pub width: u16,
    /// Height.
    pub height: u16,
}

impl RecordSize {
    /// The largest edge accepted.
    pub const MAX_EDGE: u16 = 4096;
}

impl Default for RecordSize {
    /// 480×270: a 4 s recording of a morph stays around a few MB.
    fn default() -> Self {
        Self { width: 480, height: 270 }
    }
}

impl FromStr for RecordSize {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let edge = |e: &str| e.trim().parse::<u16>().ok().filter(|v| (2..=Self::MAX_EDGE).contains(v));
        match s.split_once(['x', 'X', '×']).map(|(w, h)| (edge(w), edge(h))) {
            Some((Some(width), Some(height))) => Ok(Self { width, height }),
            _ => Err(format!("expected WIDTHxHEIGHT, each 2 to {} pixels (e.g. 480x270)", Self::MAX_EDGE)),
        }
    }
}

/// The headless `--record`: where, how long, and the model to morph to first.
#[derive(Clone, Debug, PartialEq)]
pub struct HeadlessRecord {
    /// The GIF to write.
    pub path: PathBuf,
    /// Seconds to record.
    pub seconds: f32,
    /// Once the first model has settled, switch to this model and record from the morph's start.
    pub then: Option<usize>,
}

/// Records the stage: Ctrl+R and the panel in the window, [`HeadlessRecord`] headless.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct RecordPlugin {
    /// The size of the GIFs.
    pub size: RecordSize,
    /// The headless recording, if this run is one.
    pub headless: Option<HeadlessRecord>,
}

/// What the recorder does, for the panel.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub enum RecordStatus {
    /// Nothing recorded yet.
    #[default]
    Idle,
    /// Recording into this file; seconds recorded so far.
    Recording(PathBuf, f32),
    /// The last frames are being written.
    Writing(PathBuf),
    /// A GIF was written.
    Saved(GifSummary),
    /// It failed: `<file>: <reason>`.
    Failed(String),
}

impl RecordStatus {
    /// The panel's line.
    pub fn message(&self) -> Option<String> {
        match self {
            RecordStatus::Idle => None,
            RecordStatus::Recording(path, seconds) => Some(format!("recording {} … {seconds:.1} s", path.display())),
            RecordStatus::Writing(path) => Some(format!("writing {} …", path.display())),
            RecordStatus::Saved(summary) => Some(format!("saved {}", summary.describe())),
            RecordStatus::Failed(reason) => Some(format!("recording failed: {reason}")),
        }
    }
}

/// A recording under way.
struct Take {
    /// The record camera.
    camera: Entity,
    /// The image it renders into.
    target: Handle<Image>,
    clock: FrameClock,
    /// Frames the camera has rendered so far.
    rendered: u32,
    /// Whether the recording may begin (headless: the cue came; in the window: at once).
    cued: bool,
    /// The app's elapsed time at the first frame taken.
    began: Option<Duration>,
    /// Frames taken.
    frames: u32,
    path: PathBuf,
    writer: GifWriter,
}

/// The recorder's state.
#[derive(Resource, Default)]
enum Recorder {
    #[default]
    Idle,
    Recording(Box<Take>),
    /// The writer finishes the file.
    Writing(GifWriter),
}

/// Creates the file, its writer thread and the record camera under the main camera.
fn begin(
    commands: &mut Commands,
    images: &mut Assets<Image>,
    main_camera: Entity,
    size: RecordSize,
    path: &Path,
    slots: u32,
    cued: bool,
) -> Result<Take, String> {
    let writer = GifWriter::create(path, size.width, size.height)?;
    let image =
        Image::new_target_texture(u32::from(size.width), u32::from(size.height), TextureFormat::Rgba8UnormSrgb, None);
    let target = images.add(image);
    // The main camera's look (stage.rs and camera.rs give it these): the same pixels, another frame.
    let camera = commands
        .spawn((
            Name::new("record camera"),
            Camera3d::default(),
            Camera { order: -1, ..default() },
            RenderTarget::Image(target.clone().into()),
            Msaa::Sample4,
            Tonemapping::None,
            ShadowFilteringMethod::Gaussian,
            Transform::default(),
            ChildOf(main_camera),
        ))
        .id();
    let clock = FrameClock::new(RECORD_FPS, slots);
    Ok(Take { camera, target, clock, rendered: 0, cued, began: None, frames: 0, path: path.to_owned(), writer })
}

/// Ends a take: the camera goes, the writer is told how many frames to expect.
fn end(commands: &mut Commands, take: Take, status: &mut RecordStatus) -> Recorder {
    commands.entity(take.camera).despawn();
    take.writer.finish(take.frames);
    *status = RecordStatus::Writing(take.path);
    Recorder::Writing(take.writer)
}

/// Where a recording from the window goes: `<exports>/<model>-<n>.gif`, the first n not taken.
fn window_path(dir: &Path, model: &str) -> PathBuf {
    (1..).map(|n| dir.join(format!("{model}-{n}.gif"))).find(|p| !p.exists()).unwrap_or_default()
}

/// Headless: arms the recording at start (the file is created at once, so an unwritable path fails fast).
fn arm_headless(
    mut commands: Commands,
    plugin: Res<RecordPlugin>,
    mut images: ResMut<Assets<Image>>,
    main_camera: Query<Entity, With<MainCamera>>,
    mut recorder: ResMut<Recorder>,
    mut exit: MessageWriter<AppExit>,
) {
    let (Some(headless), Ok(main_camera)) = (&plugin.headless, main_camera.single()) else { return };
    let slots = FrameClock::slots_in(RECORD_FPS, headless.seconds);
    match begin(&mut commands, &mut images, main_camera, plugin.size, &headless.path, slots, false) {
        Ok(take) => *recorder = Recorder::Recording(Box::new(take)),
        Err(reason) => fail_headless(&reason, &mut exit),
    }
}

fn fail_headless(reason: &str, exit: &mut MessageWriter<AppExit>) {
    eprintln!("error: {reason}");
    exit.write(AppExit::error());
}

/// Headless: the recording begins on the cue (the first model settled, or the morph to `--then` begun).
fn cue_headless(
    plugin: Res<RecordPlugin>,
    mut recorder: ResMut<Recorder>,
    mut cue: Local<Cue>,
    mut params: CueParams,
    mut exit: MessageWriter<AppExit>,
) {
    let (Some(headless), Recorder::Recording(take)) = (&plugin.headless, &mut *recorder) else { return };
    if take.cued {
        return;
    }
    match cue.poll(&mut params, headless.then) {
        CueState::Waiting => {}
        CueState::Ready => {
            info!("recording {} for {} s", headless.path.display(), headless.seconds);
            take.cued = true;
        }
        CueState::Failed(reason) => {
            fail_headless(&format!("{}: {reason}", headless.path.display()), &mut exit);
            *recorder = Recorder::Idle;
        }
    }
}

/// In the window: Ctrl+R (or the panel) starts a recording of the stage into the exports folder, or stops the
/// one under way.
fn toggle(
    mut commands: Commands,
    mut toggles: MessageReader<ToggleRecord>,
    plugin: Res<RecordPlugin>,
    mut images: ResMut<Assets<Image>>,
    main_camera: Query<Entity, With<MainCamera>>,
    library: Res<ModelLibrary>,
    dir: Res<ExportDir>,
    mut recorder: ResMut<Recorder>,
    mut status: ResMut<RecordStatus>,
) {
    if toggles.read().count() == 0 || plugin.headless.is_some() {
        return;
    }
    match std::mem::take(&mut *recorder) {
        Recorder::Idle => {
            let Ok(main_camera) = main_camera.single() else { return };
            let model = library.current_entry().map_or("stage", |e| e.name.as_str());
            let path = window_path(&dir.0, model);
            let slots = FrameClock::slots_in(RECORD_FPS, MAX_WINDOW_SECONDS);
            let started = std::fs::create_dir_all(&dir.0)
                .map_err(|e| format!("{}: {e}", dir.0.display()))
                .and_then(|()| begin(&mut commands, &mut images, main_camera, plugin.size, &path, slots, true));
            match started {
                Ok(take) => {
                    *status = RecordStatus::Recording(path, 0.0);
                    *recorder = Recorder::Recording(Box::new(take));
                }
                Err(reason) => {
                    warn!("recording failed: {reason}");
                    *status = RecordStatus::Failed(reason);
                }
            }
        }
        Recorder::Recording(take) => *recorder = end(&mut commands, *take, &mut status),
        // One GIF at a time: a toggle while the last one is written is ignored.
        writing @ Recorder::Writing(_) => *recorder = writing,
    }
}

/// Takes a screenshot of the record camera's image whenever a frame is due; ends the take the frame after its last.
fn capture(mut commands: Commands, time: Res<Time>, mut recorder: ResMut<Recorder>, mut status: ResMut<RecordStatus>) {
    let Recorder::Recording(take) = &mut *recorder else { return };
    if take.clock.done() {
        // The camera lives one frame past the last screenshot: despawned with it, that frame comes back black.
        let Recorder::Recording(take) = std::mem::take(&mut *recorder) else { return };
        *recorder = end(&mut commands, *take, &mut status);
        return;
    }
    take.rendered += 1;
    if !take.cued || take.rendered <= WARM_UP_FRAMES {
        return;
    }
    let began = *take.began.get_or_insert(time.elapsed());
    let elapsed = time.elapsed().saturating_sub(began);
    if let Some(delay_cs) = take.clock.tick(elapsed) {
        let (frames, index) = (take.writer.frames(), take.frames);
        commands.spawn(Screenshot::image(take.target.clone())).observe(move |captured: On<ScreenshotCaptured>| {
            let rgba = captured.image.clone().try_into_dynamic().map(|i| i.into_rgba8().into_raw()).unwrap_or_default();
            frames.send(GifFrame { index, delay_cs, rgba });
        });
        take.frames += 1;
    }
    if let RecordStatus::Recording(_, seconds) = &mut *status {
        *seconds = elapsed.as_secs_f32();
    }
}

/// Reports the written GIF (headless: and exits, 0 when written, 1 with `error: <file>: <reason>` when not).
fn finish(
    plugin: Res<RecordPlugin>,
    mut recorder: ResMut<Recorder>,
    mut status: ResMut<RecordStatus>,
    mut exit: MessageWriter<AppExit>,
) {
    let Recorder::Writing(writer) = &mut *recorder else { return };
    let Some(result) = writer.poll() else { return };
    *recorder = Recorder::Idle;
    match result {
        Ok(summary) => {
            info!("recorded {}", summary.describe());
            *status = RecordStatus::Saved(summary);
            if plugin.headless.is_some() {
                exit.write(AppExit::Success);
            }
        }
        Err(reason) => {
            warn!("recording failed: {reason}");
            if plugin.headless.is_some() {
                fail_headless(&reason, &mut exit);
            }
            *status = RecordStatus::Failed(reason);
        }
    }
}

impl Plugin for RecordPlugin {
    fn build(&self, app: &mut App) {
        if self.headless.is_some() {
            // Time steps exactly one fixed step (1/60 s) a frame, as for --screenshot.
            app.insert_resource(bevy::time::TimeUpdateStrategy::ManualDuration(crate::schedule::FIXED_STEP));
        }
        app.insert_resource(self.clone());
        app.init_resource::<Recorder>();
        app.init_resource::<RecordStatus>();
        app.add_systems(PostStartup, arm_headless);
        app.add_systems(Update, (cue_headless, toggle, capture, finish).chain().in_set(AppSystems::Present));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn record_sizes_parse_and_wrong_ones_say_what_is_expected() {
        assert_eq!("320x180".parse(), Ok(RecordSize { width: 320, height: 180 }));
        assert_eq!("64X48".parse(), Ok(RecordSize { width: 64, height: 48 }));
        for bad in ["320", "0x10", "10x99999", "axb", "5000x10"] {
            let err = bad.parse::<RecordSize>().unwrap_err();
            assert!(err.contains("WIDTHxHEIGHT"), "{bad}: {err}");
        }
    }

    #[test]
    fn window_recordings_take_the_first_free_number() {
        let dir = std::env::temp_dir().join(format!("voxel-art-record-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("apple-1.gif"), b"").unwrap();
        assert_eq!(window_path(&dir, "apple"), dir.join("apple-2.gif"));
        assert_eq!(window_path(&dir, "cherry"), dir.join("cherry-1.gif"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
