//! The app's public system sets, chained once in `Update`: input, then simulation, then animation, then the
//! sync of voxel entities to the render data.

use bevy::prelude::*;

/// The app's system sets, in the order they run in `Update`.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AppSystems {
    /// Keyboard, mouse, dropped files, UI requests.
    Input,
    /// Loading, voxelization, model switching.
    Simulate,
    /// Per-voxel animation (transitions, styles).
    Animate,
    /// Writing voxel data into the entities the renderer reads.
    Sync,
}

pub(super) fn plugin(app: &mut App) {
    app.configure_sets(
        Update,
        (AppSystems::Input, AppSystems::Simulate, AppSystems::Animate, AppSystems::Sync).chain(),
    );
}
