//! voxel-art: turns glTF/GLB models into animated voxel art — a Bevy app over the `voxel-core` library.
//!
//! Plugins (one per module, `pub(super) fn plugin`): `library` (the model list), `voxelize` (async
//! voxelization into [`voxelize::VoxelModel`] assets), `instancing` (one entity per voxel, one mesh, one
//! material, colour in `MeshTag`), `transition` (per-voxel tweened morphs), `style` (Lego, bubbles,
//! falling, mouse repel), `input`, and the render-side `stage`, `camera`, `ui`, `preview`,
//! `screenshot`. [`LogicPlugin`] holds everything that runs without a GPU, for tests.

pub mod args;
mod camera;
pub mod headless;
pub mod input;
pub mod instancing;
pub mod library;
mod preview;
pub mod rng;
mod screenshot;
pub mod settings;
mod stage;
pub mod style;
pub mod threads;
pub mod transition;
mod ui;
pub mod voxelize;

use bevy::asset::io::AssetSourceBuilder;
use bevy::prelude::*;
use bevy::window::{PresentMode, WindowResolution};

pub use voxel_core as voxel;

/// The app's system sets, chained once in `Update`: input, then simulation, then animation, then the sync of
/// voxel entities to the render data.
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

/// The asset source that reads any file on disk (models named on the command line or dropped).
pub const FILE_SOURCE: &str = "fs";

/// Everything that runs without a GPU: settings, model library, voxelization, the voxel pool, input.
pub struct LogicPlugin;

impl Plugin for LogicPlugin {
    fn build(&self, app: &mut App) {
        app.configure_sets(
            Update,
            (AppSystems::Input, AppSystems::Simulate, AppSystems::Animate, AppSystems::Sync).chain(),
        );
        app.add_plugins((
            settings::plugin,
            library::plugin,
            voxelize::plugin,
            instancing::plugin,
            transition::plugin,
            style::plugin,
            input::plugin,
        ));
    }

    fn cleanup(&self, app: &mut App) {
        threads::choose_executor(app);
    }
}

/// The whole app on top of `DefaultPlugins`.
pub struct AppPlugin {
    /// Parsed command line.
    pub args: args::AppArgs,
}

impl Plugin for AppPlugin {
    fn build(&self, app: &mut App) {
        app.register_asset_source(FILE_SOURCE, AssetSourceBuilder::platform_default("/", None));
        app.add_plugins(
            DefaultPlugins
                .set(threads::task_pools())
                .set(WindowPlugin {
                    primary_window: Some(Window {
                        title: "voxel-art".into(),
                        resolution: WindowResolution::new(1280, 720),
                        present_mode: PresentMode::AutoVsync,
                        ..default()
                    }),
                    ..default()
                })
                .set(AssetPlugin { file_path: args::asset_root().display().to_string(), ..default() }),
        );
        app.insert_resource(self.args.clone());
        if self.args.screenshot.is_some() {
            // Screenshots step time by exactly 1/60 s a frame, so frame N is the same moment of an animation
            // however slowly a software renderer draws.
            app.insert_resource(bevy::time::TimeUpdateStrategy::ManualDuration(std::time::Duration::from_secs_f64(
                1.0 / 60.0,
            )));
        }
        // Render-side registration first (the voxel material's asset type comes from its MaterialPlugin).
        app.add_plugins((
            instancing::render_plugin,
            stage::plugin,
            camera::plugin,
            ui::plugin,
            preview::plugin,
            screenshot::plugin,
        ));
        app.add_plugins(LogicPlugin);
    }
}

/// Runs the app with command-line `args` (the first is the program name); returns the exit status.
pub fn run(args: Vec<std::ffi::OsString>) -> i32 {
    let args = match args::AppArgs::parse_from(args) {
        Ok(a) => a,
        Err(code) => return code,
    };
    let exit = App::new().add_plugins(AppPlugin { args }).run();
    match exit {
        AppExit::Success => 0,
        AppExit::Error(code) => i32::from(code.get()),
    }
}
