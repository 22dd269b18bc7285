//! voxel-art: turns glTF/GLB models into animated voxel art — a Bevy app over the `voxel-core` library.
//!
//! Plugins (one per module, `pub(super) fn plugin`): `library` (fills the [`model::ModelLibrary`]), `voxelize`
//! (async voxelization into [`model::VoxelModelAsset`]s), `instancing` (one entity per voxel, colour in
//! `MeshTag`; the changed ones copied into one GPU buffer drawn by a few chunk entities), `transition`
//! (per-voxel tweened morphs), `animation` (animated models posed and voxelized live, their cells followed by
//! the voxels), `style` (Lego, bubbles, falling, mouse repel), `input`, `export` (saves the shown model as .vox
//! and .glb, an animated model's clip as one animated .glb), `palette` (recolours the models from their sampled
//! colours when the colour stage changes, reads dropped palette files), and the render-side `stage`, `camera`,
//! `ui`, `preview`, `screenshot` and `record` (an animated GIF of the stage; `cue` says when a headless capture
//! begins). [`LogicPlugin`] holds everything that runs without a GPU, for tests.

pub mod animation;
pub mod assets;
mod camera;
pub mod config;
mod cue;
pub mod export;
pub mod headless;
pub mod input;
pub mod instancing;
pub mod library;
pub mod model;
pub mod noop;
pub mod palette;
mod preview;
pub mod record;
pub mod rng;
pub mod schedule;
mod screenshot;
pub mod settings;
mod stage;
pub mod style;
pub mod threads;
pub mod transition;
mod ui;
pub mod voxelize;

use bevy::prelude::*;
use bevy::render::RenderPlugin;
use bevy::window::{PresentMode, WindowResolution};

pub use schedule::AppSystems;

/// Everything that runs without a GPU: settings, model library, voxelization, the voxel pool, input.
pub struct LogicPlugin;

impl Plugin for LogicPlugin {
    fn build(&self, app: &mut App) {
        app.add_plugins((
            schedule::SchedulePlugin,
            settings::plugin,
            library::plugin,
            voxelize::plugin,
            instancing::plugin,
            transition::plugin,
            animation::plugin,
            style::plugin,
            input::plugin,
            export::plugin,
            palette::plugin,
        ));
    }

    fn cleanup(&self, app: &mut App) {
        threads::choose_executor(app);
    }
}

/// The whole app: Bevy's `DefaultPlugins` with the window, then the [`ShowPlugin`].
pub struct AppPlugin {
    /// Parsed command line.
    pub args: config::AppArgs,
}

impl Plugin for AppPlugin {
    fn build(&self, app: &mut App) {
        let asset_plugin = assets::asset_plugin(app);
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
                .set(asset_plugin)
                .set(RenderPlugin {
                    // A headless capture draws everything from the frame it first appears in (a pipeline
                    // still compiling would leave it out), so what it shows does not depend on the CPU's load.
                    synchronous_pipeline_compilation: self.args.headless(),
                    ..default()
                }),
        );
        app.add_plugins(ShowPlugin { args: self.args.clone() });
    }
}

/// The app over Bevy's default plugins, whatever their window and renderer: the command line's starting
/// resources, the render side (voxel material and buffer, stage, camera, panel, previews, screenshot, recording)
/// and the [`LogicPlugin`].
pub struct ShowPlugin {
    /// Parsed command line.
    pub args: config::AppArgs,
}

impl Plugin for ShowPlugin {
    fn build(&self, app: &mut App) {
        self.args.configure(app);
        app.add_plugins((instancing::render_plugin, stage::plugin, camera::plugin, ui::plugin, preview::plugin));
        if let Some(screenshot) = self.args.screenshot_plugin() {
            app.add_plugins(screenshot);
        }
        app.add_plugins(self.args.record_plugin());
        app.add_plugins(LogicPlugin);
    }
}

/// Runs the command line `args` (the first is the program name): the app, or `voxel-art voxelize`; returns
/// the exit status.
pub fn run(args: Vec<std::ffi::OsString>) -> i32 {
    match config::Cli::parse_args(args) {
        Ok(config::Cli { command: Some(config::Command::Voxelize(voxelize)), .. }) => {
            voxel_core::cli::prepare_process();
            voxel_core::cli::execute(&voxelize)
        }
        Ok(config::Cli { command: None, app }) => run_app(app),
        Err(code) => code,
    }
}

/// Runs the app until its window closes; returns the exit status.
fn run_app(args: config::AppArgs) -> i32 {
    if let Err(message) = args.color_settings() {
        eprintln!("{message}");
        return 1;
    }
    let exit = App::new().add_plugins(AppPlugin { args }).run();
    match exit {
        AppExit::Success => 0,
        AppExit::Error(code) => i32::from(code.get()),
    }
}
