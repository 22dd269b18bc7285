//! When every system of the app runs: all system sets and all of their order live here; a plugin only puts its
//! systems into its sets. The falling pile steps in `FixedUpdate` at [`FIXED_STEP`], which is also the frame
//! step of headless runs and screenshots (one frame, one step).
//!
//! `Update` runs the [`AppSystems`] in turn, so a frame acts on this frame's input and draws this frame's
//! simulation: where the pointer is, input, the colour stage, simulation, animation, the sync of voxels to what the renderer
//! reads, then the stage around them. Within them:
//! - Input: the pointer is tracked first, since the keys, the clicks and the cursor ray ask whether it acts on
//!   the stage; keys, then clicks, then a click turned into a request for the next model (read this frame).
//! - Color: a dropped palette file is read before the models are recoloured (so this frame shows it).
//! - Simulate: the library reads dropped files and requests, so voxelization starts the model asked for this
//!   frame; voxelization tracks a settings change before it starts jobs (a stale generation is never started)
//!   and starts before it finishes them; animation poses what voxelization read (requests, time, finished
//!   poses, new poses); exports save what both made. The pool grows after voxelization and animation, so a
//!   new model or pose finds its slots; the falling pile follows the transition's messages, then reacts to F
//!   and model changes, once the pool has its slots.
//! - Animate: the placeholder floats, a transition starts, the model-level tweens get their speed and step
//!   (bevy_tweening's set), then the voxels' tweens step with this frame's spin and count, and recoloured
//!   voxels take their colours; bubbles (given, then burst) and animated models' voxels follow once the
//!   transition has moved and coloured the voxels.
//! - Present, in turn (each moves what the next shows): the lights follow the camera before the floor settles
//!   under the model; preview tiles spawn, are laid out and turned, then rigged and played; a recording takes
//!   its cue, toggles, captures a due frame, then reports; last, a screenshot run's driver.
//!
//! `PostUpdate`: after Bevy propagates transforms and updates the cameras (the detail reads their projection)
//! and after the panel's pass, before the asset events (a rebuilt chunk mesh is announced this frame) and
//! before Bevy's visibility and bounds (which read the chunks' `Visibility` and `Mesh3d`), the chunk meshes are rebuilt for a new shape, the changed
//! voxels gathered into the buffer's mirror, the detail chosen for the voxels' width on screen, then the chunk
//! entities fitted to the pool (what the renderer extracts). `Render`: a new buffer's contents are written once
//! Bevy has prepared the buffer (`RenderSystems::PrepareResources`).

use std::time::Duration;

use bevy::app::TerminalCtrlCHandlerPlugin;
use bevy::asset::AssetEventSystems;
use bevy::camera::CameraUpdateSystems;
use bevy::camera::visibility::VisibilitySystems;
use bevy::prelude::*;
use bevy::render::{Render, RenderApp, RenderSystems};
use bevy_egui::EguiPostUpdateSet;
use bevy_tweening::AnimationSystem;

/// The fixed simulation step (60 per second).
pub const FIXED_STEP: Duration = Duration::from_nanos(1_000_000_000 / 60);

/// The app's stages, in the order they run in `Update` (`Simulate` also holds the pile's `FixedUpdate` step).
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AppSystems {
    /// Where the pointer is: over a preview tile, the panel or the stage (`PointerOverUi`).
    Pointer,
    /// Keyboard, mouse clicks, the cursor ray, dropped files: turned into requests and messages.
    Input,
    /// The colour stage: dropped palette files, the models recoloured when it changes (before anything reads
    /// the models' colours this frame).
    Color,
    /// Loading, voxelization, the voxel pool, model switching, the falling pile.
    Simulate,
    /// Per-voxel animation (transitions, styles).
    Animate,
    /// Writing voxel data into the entities the renderer reads.
    Sync,
    /// The stage, previews and captures following what the frame shows.
    Present,
}

/// The colour stage's systems (in `AppSystems::Color`).
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PaletteSystems {
    /// A dropped palette file is read.
    Read,
    /// The models are recoloured when the colour stage changed.
    Recolor,
}

/// The input's systems (in `AppSystems::Input`).
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum InputSystems {
    /// Whether the pointer acts on the stage.
    Track,
    /// The cursor's ray through the camera.
    Ray,
    /// The keys.
    Keys,
    /// Clicks on the stage.
    Clicks,
    /// A click on the stage asks for the next model.
    ClickToNext,
}

/// The model library's systems (in `AppSystems::Simulate`).
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LibrarySystems {
    /// Dropped files become requests.
    Drop,
    /// Requests change the library.
    Request,
}

/// Voxelization's systems (in `AppSystems::Simulate`).
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum VoxelizeSystems {
    /// A settings change starts a new generation.
    Track,
    /// Jobs start.
    Start,
    /// Finished jobs are stored.
    Finish,
}

/// Animated models' systems.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AnimationSystems {
    /// The panel's and keys' requests (in `AppSystems::Simulate`, as the next three).
    Request,
    /// The clock moves on.
    Advance,
    /// Finished poses are placed.
    Finish,
    /// New poses start.
    Start,
    /// The voxels follow the pose (in `AppSystems::Animate`).
    Follow,
}

/// Exports' systems (in `AppSystems::Simulate`).
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ExportSystems {
    /// An export starts.
    Start,
    /// A finished export is reported.
    Finish,
}

/// The voxel pool's and the voxel buffer's systems.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum InstancingSystems {
    /// The pool grows for the model to show (`Update`, in `AppSystems::Simulate`).
    Grow,
    /// The chunk meshes follow the voxel shapes (`PostUpdate`, as the next three).
    Meshes,
    /// The chunks of looks changed this frame become its upload ranges.
    Gather,
    /// The GPU buffer follows the pool's size.
    Buffer,
    /// The detail follows the voxels' width on screen.
    Detail,
    /// The chunk entities follow the pool.
    Chunks,
    /// A new buffer gets its contents (`Render`).
    Upload,
}

/// The per-voxel transition's systems (in `AppSystems::Animate`).
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TransitionSystems {
    /// The placeholder is laid out.
    Placeholder,
    /// The placeholder floats.
    Float,
    /// A transition starts.
    Start,
    /// The next batch of its voxels takes off.
    TakeOff,
    /// The model-level tweens get their speed.
    Pace,
    /// The model-level tweens step (bevy_tweening's set).
    Tween,
    /// The voxels' tweens step.
    Step,
    /// Voxels of a recoloured model take their new colours.
    Recolor,
}

/// The styles' systems.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StyleSystems {
    /// The falling pile follows the transition's messages (`Update`, in `AppSystems::Simulate`).
    Rest,
    /// F and model changes let the pile go or call it back.
    Control,
    /// One step of the pile (`FixedUpdate`, in `AppSystems::Simulate`).
    Fall,
    /// Bubbles are given (in `AppSystems::Animate`).
    Give,
    /// Bubbles burst.
    Burst,
    /// The falling voxels take the pile's places (in `AppSystems::Sync`, as the next).
    Pile,
    /// Voxels at home are placed (repel springs, bubble wobble).
    Place,
}

/// The stage's systems (in `AppSystems::Present`).
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StageSystems {
    /// The lights turn with the camera.
    Lights,
    /// The floor settles under the model.
    Floor,
}

/// The preview tiles' systems (in `AppSystems::Present`, but `Pick`).
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PreviewSystems {
    /// A tile under the pointer (in `AppSystems::Pointer`).
    Pick,
    /// Tiles spawn.
    Spawn,
    /// Tiles are laid out and turned.
    Layout,
    /// Animated tiles are rigged.
    Rig,
    /// Animated tiles play.
    Play,
}

/// The recording's systems (in `AppSystems::Present`).
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RecordSystems {
    /// A headless recording takes its cue.
    Cue,
    /// A recording starts or stops.
    Toggle,
    /// A due frame is captured.
    Capture,
    /// A recording is reported.
    Report,
}

/// The screenshot's driver (in `AppSystems::Present`, last: it saves what the frame's other systems made).
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ScreenshotSystems;

/// Configures every set above.
pub(super) struct SchedulePlugin;

impl Plugin for SchedulePlugin {
    fn build(&self, app: &mut App) {
        use AppSystems as A;
        use InstancingSystems as I;
        // Bevy's Ctrl+C handler writes `AppExit` as our keys and captures do: it goes first.
        app.configure_sets(
            Update,
            (A::Pointer, A::Input, A::Color, A::Simulate, A::Animate, A::Sync, A::Present)
                .chain()
                .after(TerminalCtrlCHandlerPlugin::exit_on_flag),
        );
        app.configure_sets(Update, (PaletteSystems::Read, PaletteSystems::Recolor).chain().in_set(A::Color));
        app.configure_sets(
            Update,
            (
                (InputSystems::Track, InputSystems::Keys, InputSystems::Clicks, InputSystems::ClickToNext).chain(),
                InputSystems::Ray.after(InputSystems::Track),
            )
                .in_set(A::Input),
        );
        app.configure_sets(
            Update,
            (
                (LibrarySystems::Drop, LibrarySystems::Request).chain(),
                (VoxelizeSystems::Track, VoxelizeSystems::Start, VoxelizeSystems::Finish).chain(),
                (
                    AnimationSystems::Request,
                    AnimationSystems::Advance,
                    AnimationSystems::Finish,
                    AnimationSystems::Start,
                )
                    .chain(),
                (ExportSystems::Start, ExportSystems::Finish).chain(),
            )
                .chain()
                .in_set(A::Simulate),
        );
        app.configure_sets(
            Update,
            (
                I::Grow.in_set(A::Simulate).after(VoxelizeSystems::Finish).after(AnimationSystems::Start),
                (StyleSystems::Rest, StyleSystems::Control).chain().in_set(A::Simulate).after(I::Grow),
            ),
        );
        app.configure_sets(
            Update,
            (
                TransitionSystems::Placeholder,
                TransitionSystems::Float,
                TransitionSystems::Start,
                TransitionSystems::TakeOff,
                TransitionSystems::Pace,
                TransitionSystems::Tween,
                TransitionSystems::Step,
                TransitionSystems::Recolor,
            )
                .chain()
                .in_set(A::Animate),
        );
        app.configure_sets(Update, AnimationSystem::AnimationUpdate.in_set(TransitionSystems::Tween));
        app.configure_sets(
            Update,
            (
                (StyleSystems::Give, StyleSystems::Burst).chain().after(TransitionSystems::Recolor),
                // Both write the pool's slots.
                AnimationSystems::Follow.after(StyleSystems::Burst),
            )
                .in_set(A::Animate),
        );
        app.configure_sets(Update, (StyleSystems::Pile, StyleSystems::Place).chain().in_set(A::Sync));
        app.configure_sets(Update, PreviewSystems::Pick.in_set(A::Pointer));
        app.configure_sets(
            Update,
            (
                (StageSystems::Lights, StageSystems::Floor).chain(),
                (PreviewSystems::Spawn, PreviewSystems::Layout, PreviewSystems::Rig, PreviewSystems::Play).chain(),
                (RecordSystems::Cue, RecordSystems::Toggle, RecordSystems::Capture, RecordSystems::Report).chain(),
                ScreenshotSystems,
            )
                .chain()
                .in_set(A::Present),
        );
        app.configure_sets(FixedUpdate, StyleSystems::Fall.in_set(A::Simulate));
        app.configure_sets(
            PostUpdate,
            (I::Meshes, I::Gather, I::Buffer, I::Detail, I::Chunks)
                .chain()
                .after(TransformSystems::Propagate)
                .after(CameraUpdateSystems)
                .after(EguiPostUpdateSet::EndPass)
                .before(AssetEventSystems)
                .before(VisibilitySystems::VisibilityPropagate),
        );
        app.insert_resource(Time::<Fixed>::from_duration(FIXED_STEP));
    }

    fn finish(&self, app: &mut App) {
        // The renderer's sub-app, when the app has one (every plugin is built by now, whatever their order).
        if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
            render_app.configure_sets(Render, InstancingSystems::Upload.in_set(RenderSystems::PrepareResources));
        }
    }
}
