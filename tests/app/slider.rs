//! The live grid slider: while it is dragged only the model on screen is re-voxelized and its voxels land on
//! their cells at once; the other models follow with the last settings when the drag ends; a result of stale
//! settings is never shown.

use std::time::{Duration, Instant};

use bevy::prelude::*;
use voxel_art::config::AppArgs;
use voxel_art::instancing::VoxelPool;
use voxel_art::library::LibraryRequest;
use voxel_art::model::{ModelLibrary, ModelStatus, VoxelModelAsset};
use voxel_art::settings::{SettingDrag, VoxelSettings};
use voxel_art::transition::ActiveTransition;
use voxel_art::voxelize::{VoxelizeGeneration, VoxelizeJob};

use crate::harness::{all_settled, app_options, core_voxelize, run_until, shipped, test_app};
use crate::transition::{assert_shows_model, settle};

const LIMIT: Duration = Duration::from_secs(60);

/// A settled app with every shipped model voxelized, showing the cherry (index 2).
fn cherry_app() -> App {
    let mut app = test_app(AppArgs::default());
    run_until(&mut app, LIMIT, all_settled);
    settle(&mut app);
    app.world_mut().write_message(LibraryRequest::Select(2));
    settle(&mut app);
    app
}

fn generation(app: &App) -> u64 {
    app.world().resource::<VoxelizeGeneration>().0
}

/// The library entries the running voxelization jobs are for.
fn job_entries(app: &mut App) -> Vec<usize> {
    let mut jobs = app.world_mut().query::<&VoxelizeJob>();
    jobs.iter(app.world()).map(|j| j.entry).collect()
}

/// Whether the model on screen is the current entry's voxelization of the latest settings, every voxel on its
/// cell (no tween left, no transition running).
fn current_placed(app: &mut App) -> bool {
    let latest = generation(app);
    let library = app.world().resource::<ModelLibrary>();
    let Some(entry) = library.current_entry() else { return false };
    let shown = app.world().resource::<VoxelPool>().shown;
    let fresh = entry.voxels_generation == Some(latest) && entry.voxels.as_ref().map(|h| h.id()) == shown;
    fresh && crate::harness::flights(app).is_empty() && app.world().resource::<ActiveTransition>().running.is_none()
}

/// The cell width of the model the pool shows.
fn shown_cell(app: &App) -> Option<f32> {
    let id = app.world().resource::<VoxelPool>().shown?;
    Some(app.world().resource::<Assets<VoxelModelAsset>>().get(id)?.spec.cell[0])
}

/// Drags the grid slider to `grid` (the panel holds the drag and writes the value).
fn drag_to(app: &mut App, grid: f32) {
    app.world_mut().resource_mut::<SettingDrag>().0 = true;
    app.world_mut().resource_mut::<VoxelSettings>().grid_size = grid;
}

#[test]
fn while_the_grid_is_dragged_only_the_model_on_screen_is_revoxelized_and_shown_at_once() {
    let mut app = cherry_app();
    let current = app.world().resource::<ModelLibrary>().current;
    let before: Vec<Option<u64>> =
        app.world().resource::<ModelLibrary>().entries.iter().map(|e| e.voxels_generation).collect();
    for grid in [0.3, 0.27, 0.2, 0.16] {
        drag_to(&mut app, grid);
        // The frame that sees the change starts the job; voxels arrive once it is done (a few ms).
        let start = Instant::now();
        let mut frames = 0;
        loop {
            app.update();
            frames += 1;
            let jobs = job_entries(&mut app);
            assert!(jobs.iter().all(|&e| e == current), "jobs during a drag: {jobs:?}, current {current}");
            let latest = generation(&app);
            if app.world().resource::<ModelLibrary>().current_entry().unwrap().voxels_generation == Some(latest) {
                break;
            }
            assert!(start.elapsed() < LIMIT, "no voxels for grid {grid}");
            std::thread::sleep(Duration::from_millis(1));
        }
        // Shown in the frame the voxels arrived, or the next when the pool had to grow: no morph.
        if !current_placed(&mut app) {
            app.update();
        }
        assert!(current_placed(&mut app), "grid {grid}: the new voxels are not on their cells after {frames} frames");
        assert_eq!(shown_cell(&app), Some(grid));
        assert_shows_model(&mut app);
    }
    let latest = generation(&app);
    let library = app.world().resource::<ModelLibrary>();
    for (i, entry) in library.entries.iter().enumerate().filter(|(i, _)| *i != current) {
        assert_eq!(entry.voxels_generation, before[i], "{} was redone during the drag", entry.name);
        assert_ne!(entry.voxels_generation, Some(latest));
        assert_eq!(entry.status, ModelStatus::Voxelizing, "{} waits for the drag to end", entry.name);
    }
}

#[test]
fn when_the_drag_ends_the_other_models_follow_with_the_last_settings() {
    let mut app = cherry_app();
    for grid in [0.4, 0.35, 0.3] {
        drag_to(&mut app, grid);
        for _ in 0..3 {
            app.update();
        }
    }
    run_until(&mut app, LIMIT, current_placed);
    assert_eq!(job_entries(&mut app), Vec::<usize>::new(), "nothing but the model on screen was voxelized");
    app.world_mut().resource_mut::<SettingDrag>().0 = false;
    let latest = generation(&app);
    run_until(&mut app, LIMIT, |app| {
        app.world().resource::<ModelLibrary>().entries.iter().all(|e| e.voxels_generation == Some(latest))
    });
    let options = app_options(&app);
    let library = app.world().resource::<ModelLibrary>();
    let models = app.world().resource::<Assets<VoxelModelAsset>>();
    for entry in &library.entries {
        assert_eq!(entry.status, ModelStatus::Ready, "{}", entry.name);
        let model = entry.latest(models).unwrap();
        assert_eq!(model.spec.cell[0], 0.3, "{}", entry.name);
        assert_eq!(
            model.stats,
            core_voxelize(&shipped(&format!("{}.glb", entry.name)), &options).stats,
            "{}",
            entry.name
        );
    }
}

#[test]
fn a_stale_result_is_never_shown() {
    let mut app = cherry_app();
    // A change every frame, faster than voxelization keeps up with: most jobs are overtaken by the next value.
    let sweep: Vec<f32> = (0..40).map(|k| 0.14 + 0.01 * (k % 20) as f32).collect();
    let mut shown = app.world().resource::<VoxelPool>().shown;
    let mut placements = 0;
    for (k, &grid) in sweep.iter().enumerate() {
        drag_to(&mut app, grid);
        if k == sweep.len() - 1 {
            // The last value comes with the release.
            app.world_mut().resource_mut::<SettingDrag>().0 = false;
        }
        app.update();
        let now = app.world().resource::<VoxelPool>().shown;
        if now != shown {
            placements += 1;
            assert_eq!(shown_cell(&app), Some(grid), "frame {k}: a result for another grid was shown");
            shown = now;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    // Whatever arrives after the drag is for its last value, on screen and in every other model.
    let last = *sweep.last().unwrap();
    run_until(&mut app, LIMIT, |app| {
        let now = app.world().resource::<VoxelPool>().shown;
        if now != shown {
            placements += 1;
            assert_eq!(shown_cell(app), Some(last), "after the drag: a result for another grid was shown");
            shown = now;
        }
        all_settled(app)
    });
    settle(&mut app);
    assert!(placements >= 1, "the model on screen was never redone");
    assert_eq!(shown_cell(&app), Some(last));
    let models = app.world().resource::<Assets<VoxelModelAsset>>();
    for entry in &app.world().resource::<ModelLibrary>().entries {
        assert_eq!(entry.latest(models).unwrap().spec.cell[0], last, "{}", entry.name);
    }
}
