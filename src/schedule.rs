//! The app's public system sets and its time step. Every `Update` system of the app is in one of the
//! [`AppSystems`], chained once: where the pointer is, input, the colour stage, simulation, animation, the sync of voxel entities
//! to what the renderer reads, then the stage around them. The falling pile steps in `FixedUpdate` at
//! [`FIXED_STEP`], which is also the frame step of headless runs and screenshots (one frame, one step).

use std::time::Duration;

use bevy::prelude::*;

/// The fixed simulation step (60 per second).
pub const FIXED_STEP: Duration = Duration::from_nanos(1_000_000_000 / 60);

/// The app's system sets, in the order they run in `Update` (`Simulate` also orders `FixedUpdate`).
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

pub(super) fn plugin(app: &mut App) {
    app.configure_sets(
        Update,
        (
            AppSystems::Pointer,
            AppSystems::Input,
            AppSystems::Color,
            AppSystems::Simulate,
            AppSystems::Animate,
            AppSystems::Sync,
            AppSystems::Present,
        )
            .chain(),
    );
    app.insert_resource(Time::<Fixed>::from_duration(FIXED_STEP));
}
