//! A headless app with the logic plugins (no window, no GPU) and a manual time step.

use std::path::Path;
use std::time::{Duration, Instant};

use bevy::prelude::*;
use voxel_art::config::AppArgs;
use voxel_art::model::{ModelLibrary, ModelStatus};

/// The app under test: the headless app (logic plugins, glTF loading, manual time step).
pub fn test_app(args: AppArgs) -> App {
    voxel_art::headless::headless_app(&args)
}

/// Steps the app until `done` holds (panics after `limit` of wall time, printing the library).
pub fn run_until(app: &mut App, limit: Duration, mut done: impl FnMut(&mut App) -> bool) {
    let start = Instant::now();
    loop {
        app.update();
        if done(app) {
            return;
        }
        if start.elapsed() > limit {
            let library = app.world().resource::<ModelLibrary>();
            let states: Vec<_> = library.entries.iter().map(|e| (&e.name, &e.status)).collect();
            panic!("condition not met within {limit:?}; library: {states:?}");
        }
        std::thread::sleep(Duration::from_millis(2));
    }
}

/// Whether every entry has finished loading and voxelizing (or failed).
pub fn all_settled(app: &mut App) -> bool {
    app.world()
        .resource::<ModelLibrary>()
        .entries
        .iter()
        .all(|e| matches!(e.status, ModelStatus::Ready | ModelStatus::Failed(_)))
}

/// Presses `key` for one frame.
pub fn tap(app: &mut App, key: KeyCode) {
    app.world_mut().resource_mut::<ButtonInput<KeyCode>>().press(key);
    app.update();
    let mut keys = app.world_mut().resource_mut::<ButtonInput<KeyCode>>();
    keys.release(key);
    keys.clear();
    app.update();
}

/// The shipped models folder.
pub fn shipped(name: &str) -> std::path::PathBuf {
    voxel_art::assets::asset_root().join("models").join(name)
}

/// This test process's temp folder.
fn temp_dir() -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("voxel-art-app-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes bytes to a fresh temp file and returns its path.
pub fn temp_file(name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let path = temp_dir().join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// A named pipe (a fresh temp path) that gives `bytes` to its reader only once the returned sender is dropped:
/// until then a job reading it is still reading, however fast the machine.
pub fn held_file(name: &str, bytes: Vec<u8>) -> (std::path::PathBuf, std::sync::mpsc::Sender<()>) {
    let path = temp_dir().join(name);
    let _ = std::fs::remove_file(&path);
    let made = std::process::Command::new("mkfifo").arg(&path).status().expect("mkfifo runs");
    assert!(made.success(), "mkfifo {}", path.display());
    let (release, released) = std::sync::mpsc::channel::<()>();
    let pipe = path.clone();
    std::thread::spawn(move || {
        // Returns once the sender is gone (dropped, or the test panicked); opening the pipe then waits for its
        // reader.
        let _ = released.recv();
        let _ = std::fs::write(pipe, bytes);
    });
    (path, release)
}

/// The voxelizer options whose output the app shows now: its settings in its current style, and its colour
/// stage as the core's pastel remap (the app's default) or no remap (the app samples colours and applies the
/// stage afterwards, which for these two gives the same colours).
pub fn app_options(app: &App) -> voxel_core::VoxelizeOptions {
    use voxel_core::palette::Palette;
    let style = *app.world().resource::<State<voxel_art::style::Style>>().get();
    let options =
        app.world().resource::<voxel_art::settings::VoxelSettings>().voxelize_options(style.cell_height_ratio());
    let stage = &app.world().resource::<voxel_art::settings::ColorSettings>().0;
    assert!(stage.max_colors.is_none() && !stage.dither, "no voxelizer option gives {stage:?}");
    let pastel = match stage.palette {
        Palette::Pastel => true,
        Palette::Original => false,
        Palette::Fixed { .. } => panic!("no voxelizer option gives {stage:?}"),
    };
    voxel_core::VoxelizeOptions { pastel, ..options }
}

/// Voxelizes a file with the core directly (the CLI's front door) for comparison.
pub fn core_voxelize(path: &Path, options: &voxel_core::VoxelizeOptions) -> voxel_core::VoxelModel {
    let soup = voxel_core::load_file(path).unwrap();
    voxel_core::voxelize(&soup, options).unwrap()
}

/// Every pool slot's look (its place, box, colour; zero-sized when hidden), by slot.
pub fn looks(app: &App) -> Vec<voxel_art::instancing::GpuVoxel> {
    let slots = app.world().resource::<voxel_art::instancing::VoxelPool>().slots.len();
    app.world().resource::<voxel_art::instancing::GpuVoxels>().items[..slots].to_vec()
}

/// The flights now: (slot, tween).
pub fn flights(app: &App) -> Vec<(usize, voxel_art::instancing::VoxelTween)> {
    let pool = app.world().resource::<voxel_art::instancing::VoxelPool>();
    let tweens = app.world().resource::<voxel_art::instancing::VoxelTweens>();
    tweens.flying(pool).map(|(slot, t)| (slot, *t)).collect()
}

/// Every pool slot as the GPU draws it this frame (its flight at the frame's clock, else its look moved by its
/// repel spring).
pub fn drawn(app: &App) -> Vec<voxel_art::instancing::GpuVoxel> {
    let world = app.world();
    let tweens = world.resource::<voxel_art::instancing::VoxelTweens>();
    let clock = world.resource::<voxel_art::instancing::GpuClock>();
    let springs = &world.resource::<voxel_art::instancing::GpuSprings>().items;
    tweens.drawn(world.resource::<voxel_art::instancing::VoxelPool>(), &looks(app), springs, clock)
}

/// The model's turn now (the cloud's rotation).
pub fn turn(app: &App) -> voxel_art::instancing::Turn {
    voxel_art::instancing::Turn::new(app.world().resource::<voxel_art::transition::ActiveTransition>().turn())
}
