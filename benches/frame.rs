//! `cargo bench --bench frame`: CPU time per frame of the app's systems (no GPU) with 100k voxels: static,
//! with every voxel's colour changing every frame, mid-morph (every voxel tweening) and with the cursor over
//! the model (repel); one falling-pile physics step of 20k voxels; the live grid slider: the latency from a grid
//! change to the model on screen's new voxels on their cells; and the Fox (`../shared/models`) running its Run
//! clip for ten seconds of real time paced at 60 frames a second: the main thread's work per frame and the
//! poses asked for, placed and dropped. Mean and median. `cargo bench --bench frame -- pile` runs only the
//! pile (likewise static, recolour, morph, repel, slider, fox). `cargo bench --bench frame -- render` measures
//! whole frames with Bevy's renderer instead (see `frame/render.rs`).

use std::time::Instant;

use bevy::prelude::*;
use rayon::prelude::*;
use voxel_art::instancing::{GpuVoxels, VoxelPool};
use voxel_art::model::{ModelEntry, ModelLibrary, ModelStatus, VoxelModelAsset};
use voxel_art::transition::ActiveTransition;
use voxel_core::shapes::uv_sphere;
use voxel_core::{GridSize, TriangleSoup, VoxelizeOptions, voxelize};

#[path = "frame/render.rs"]
mod render;

/// About 100k voxels: a solid sphere 58 cells across.
fn big_model() -> voxel_core::VoxelModel {
    let soup = TriangleSoup::from_mesh(&uv_sphere(1.0, 48), [0.9, 0.5, 0.6, 1.0]);
    voxelize(&soup, &VoxelizeOptions { grid: GridSize::Resolution(58), hollow: false, ..Default::default() })
        .expect("voxelize")
}

/// About 100k voxels of another shape: a solid cube 46 cells wide.
fn cube_model() -> voxel_core::VoxelModel {
    let soup = TriangleSoup::from_mesh(&voxel_core::shapes::cuboid([0.0; 3], [1.0; 3]), [0.5, 0.6, 0.9, 1.0]);
    voxelize(&soup, &VoxelizeOptions { grid: GridSize::Resolution(46), hollow: false, ..Default::default() })
        .expect("voxelize")
}

fn entry(name: &str, handle: Handle<VoxelModelAsset>) -> ModelEntry {
    let entry = ModelEntry::new(name.into(), std::path::PathBuf::new(), String::new(), ModelStatus::Ready);
    ModelEntry { voxels: Some(handle), voxels_generation: Some(0), ..entry }
}

fn settled(app: &App) -> bool {
    app.world().resource::<VoxelPool>().shown.is_some() && app.world().resource::<ActiveTransition>().running.is_none()
}

fn app_with(models: Vec<voxel_core::VoxelModel>) -> App {
    let mut app =
        voxel_art::headless::headless_app(&voxel_art::config::AppArgs { no_shipped: true, ..Default::default() });
    // Show every voxel of the solid models, not only the visible ones.
    app.world_mut().resource_mut::<voxel_art::settings::VoxelSettings>().hollow = false;
    app.update();
    let handles: Vec<_> = models
        .into_iter()
        .map(|m| app.world_mut().resource_mut::<Assets<VoxelModelAsset>>().add(VoxelModelAsset(m)))
        .collect();
    let mut library = app.world_mut().resource_mut::<ModelLibrary>();
    library.entries = handles.into_iter().enumerate().map(|(i, h)| entry(&format!("model {i}"), h)).collect();
    library.current = 0;
    for _ in 0..2_000 {
        app.update();
        if settled(&app) {
            break;
        }
    }
    assert!(settled(&app), "the model never settled");
    app
}

/// Changes every voxel's colour (as a colour animation would).
fn recolor_everything(time: Res<Time>, pool: Res<VoxelPool>, mut looks: ResMut<GpuVoxels>) {
    let shift = (time.elapsed_secs() * 60.0) as u32;
    let visible = pool.visible;
    looks.pieces().for_each(|mut piece| {
        for i in 0..piece.items.len().min(visible.saturating_sub(piece.start)) {
            let color = ((piece.start + i) as u32).wrapping_mul(2_654_435_761).wrapping_add(shift) | 0xff00_0000;
            piece.set(i, voxel_art::instancing::GpuVoxel { color, ..piece.items[i] });
        }
    });
}

/// Voxels in flight (or popping).
fn flying(app: &App) -> usize {
    app.world().resource::<VoxelPool>().slots.iter().filter(|s| s.flying).count()
}

fn measure(app: &mut App, warmup: usize, frames: usize) -> (f64, f64) {
    for _ in 0..warmup {
        app.update();
    }
    let mut times: Vec<f64> = (0..frames)
        .map(|_| {
            let t = Instant::now();
            app.update();
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    let mean = times.iter().sum::<f64>() / times.len() as f64;
    times.sort_by(f64::total_cmp);
    (mean, times[times.len() / 2])
}

/// Whether the scenario named `name` (static, recolour, morph, repel, pile, slider) runs: all of them, or the one the
/// first non-flag argument names (`cargo bench --bench frame -- pile`).
fn wanted(name: &str) -> bool {
    std::env::args().skip(1).find(|a| !a.starts_with('-')).is_none_or(|filter| name.contains(&filter))
}

fn main() {
    // The renderer's cases are long (two apps with Bevy's renderer each): only when asked for.
    if std::env::args().skip(1).any(|a| a == "render") {
        render::run();
        return;
    }
    if wanted("pile") {
        pile_step();
    }
    if wanted("slider") {
        slider_sweeps();
    }
    if wanted("fox") {
        fox_running();
    }
    if !["static", "recolour", "morph", "repel"].into_iter().any(wanted) {
        return;
    }
    let sphere = big_model();
    println!("voxels: sphere {}; threads: {}", sphere.len(), bevy::tasks::available_parallelism());
    if wanted("static") {
        let mut app = app_with(vec![sphere.clone()]);
        let (mean, median) = measure(&mut app, 30, 300);
        println!("static voxels:        mean {mean:.2} ms/frame, median {median:.2} ms/frame");
    }
    if wanted("recolour") {
        let mut app = app_with(vec![sphere.clone()]);
        app.add_systems(Update, recolor_everything);
        let (mean, median) = measure(&mut app, 30, 300);
        println!("recolour every frame: mean {mean:.2} ms/frame, median {median:.2} ms/frame");
    }
    if wanted("morph") {
        // Mid-morph: frames 12..60 after a switch, when every voxel's delay (≤ 0.2 s) has passed.
        let cube = cube_model();
        println!("voxels: cube {}", cube.len());
        let mut app = app_with(vec![sphere.clone(), cube]);
        app.world_mut().write_message(voxel_art::library::LibraryRequest::Next);
        let (mean, median) = measure(&mut app, 12, 48);
        println!(
            "mid-morph ({} tweening at the end): mean {mean:.2} ms/frame, median {median:.2} ms/frame",
            flying(&app)
        );
    }
    if wanted("repel") {
        // Mouse repel: the cursor ray circling through a settled 100k-voxel model (one turn in 2 s).
        let mut app = app_with(vec![sphere]);
        app.add_systems(First, circling_cursor);
        let (mean, median) = measure(&mut app, 10, 300);
        let now = app.world().resource::<voxel_art::instancing::GpuClock>().time;
        let displaced = app.world().resource::<VoxelPool>().slots.iter().filter(|s| !s.repel.rests(now)).count();
        println!(
            "repel, cursor moving over 100k voxels ({displaced} displaced at the end): mean {mean:.2} ms/frame, median {median:.2} ms/frame"
        );
    }
}

/// The Fox playing its Run clip (30 poses a second, each posed and voxelized on the async pool) for ten seconds
/// of real time paced at 60 frames a second (a fixed step run flat out would outpace the pose jobs): the main
/// thread's work per frame, and the poses asked for, placed and dropped.
fn fox_running() {
    use std::time::Duration;
    use voxel_art::animation::CellSlots;
    let models = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/models");
    let dir = std::env::var_os("VOXEL_ART_MODELS").map_or(models, std::path::PathBuf::from);
    let fox = dir.join("khronos-fox.glb");
    if !fox.is_file() {
        println!("fox: skipped, {} not found (set VOXEL_ART_MODELS)", fox.display());
        return;
    }
    let args = voxel_art::config::AppArgs {
        models: vec![fox],
        no_shipped: true,
        clip: Some("Run".into()),
        ..Default::default()
    };
    let mut app = voxel_art::headless::headless_app(&args);
    let following = |app: &App| {
        let slots = app.world().resource::<CellSlots>();
        slots.model().is_some()
            && slots.model() == app.world().resource::<VoxelPool>().shown
            && app.world().resource::<ActiveTransition>().running.is_none()
    };
    let start = Instant::now();
    while !following(&app) {
        assert!(start.elapsed() < Duration::from_secs(120), "the Fox never showed");
        app.update();
        std::thread::sleep(Duration::from_millis(2));
    }
    let counts = |app: &App| {
        let library = app.world().resource::<ModelLibrary>();
        library.entries[0].animation.as_ref().expect("the Fox is animated").counts
    };
    app.insert_resource(bevy::time::TimeUpdateStrategy::Automatic);
    let frame = Duration::from_secs_f64(1.0 / 60.0);
    let before = counts(&app);
    let start = Instant::now();
    let mut frames = 0;
    let mut frame_ms = Vec::new();
    while start.elapsed() < Duration::from_secs(10) {
        let t = Instant::now();
        app.update();
        frame_ms.push(t.elapsed().as_secs_f64() * 1e3);
        frames += 1;
        if let Some(rest) = frame.checked_sub(t.elapsed()) {
            std::thread::sleep(rest);
        }
    }
    let after = counts(&app);
    let mean = frame_ms.iter().sum::<f64>() / frame_ms.len() as f64;
    frame_ms.sort_by(f64::total_cmp);
    println!(
        "fox running, 10 s of real time: {frames} frames, mean {mean:.2} ms/frame, median {:.2} ms/frame; \
         poses asked {}, placed {}, dropped {} ({} slots at the end)",
        frame_ms[frame_ms.len() / 2],
        after.requested - before.requested,
        after.placed - before.placed,
        after.dropped - before.dropped,
        app.world().resource::<VoxelPool>().visible
    );
}

/// Moves the cursor ray on a circle of radius 1.5 across the model's front, one turn in 2 s.
fn circling_cursor(time: Res<Time>, mut ray: ResMut<voxel_art::style::CursorRay>) {
    let angle = time.elapsed_secs() * std::f32::consts::PI;
    ray.0 = Some(Ray3d::new(Vec3::new(angle.cos() * 1.5, angle.sin() * 1.5, 30.0), Dir3::NEG_Z));
}

/// One physics step of 20k falling voxels (a 28 × 26 × 28 block dropped on the floor) over the first ten
/// simulated seconds (600 steps: falling, impact, piling up, falling asleep): the mean, and the worst mean of
/// 50 consecutive steps.
fn pile_step() {
    use voxel_art::style::pile::{Pile, PileParams};
    let cell = 0.24;
    let mut positions = Vec::new();
    for x in 0..28 {
        for y in 0..26 {
            for z in 0..28 {
                positions.push(Vec3::new(x as f32, y as f32 + 8.0, z as f32) * cell);
            }
        }
    }
    let n = positions.len();
    let mut pile = Pile::new(positions, PileParams::for_cell(cell, 0.0), 1);
    let windows: Vec<f64> = (0..12)
        .map(|_| {
            let t = Instant::now();
            for _ in 0..50 {
                pile.step();
            }
            t.elapsed().as_secs_f64() * 1e3 / 50.0
        })
        .collect();
    let mean = windows.iter().sum::<f64>() / windows.len() as f64;
    let worst = windows.iter().copied().fold(0.0, f64::max);
    let asleep = pile.calm.iter().filter(|c| **c >= pile.params.sleep_steps).count();
    println!(
        "pile step, {n} voxels, 10 s from the drop: mean {mean:.2} ms/step, worst 50 steps {worst:.2} ms/step \
         (then {asleep} asleep, top speed {:.3}, deepest overlap {:.3} of a cell)",
        pile.max_speed(),
        pile.max_overlap(cell)
    );
}

/// Whether the model on screen is the current entry's voxelization of the latest settings with every voxel on
/// its cell (no tween left, no transition running).
fn current_placed(app: &mut App) -> bool {
    let latest = app.world().resource::<voxel_art::voxelize::VoxelizeGeneration>().0;
    let library = app.world().resource::<ModelLibrary>();
    let Some(entry) = library.current_entry() else { return false };
    let fresh = entry.voxels_generation == Some(latest)
        && entry.voxels.as_ref().map(|h| h.id()) == app.world().resource::<VoxelPool>().shown;
    fresh && flying(app) == 0 && app.world().resource::<ActiveTransition>().running.is_none()
}

/// Steps the app (a quarter of a millisecond apart, as frames waiting on the GPU would leave the cores to the
/// voxelizer) until `done`; panics after a minute.
fn update_until(app: &mut App, mut done: impl FnMut(&mut App) -> bool) {
    let start = Instant::now();
    while !done(app) {
        assert!(start.elapsed().as_secs() < 60, "the app never got there");
        app.update();
        std::thread::sleep(std::time::Duration::from_micros(250));
    }
}

/// Drags the grid slider through `grids`, one value a frame: for each, the milliseconds from the change to the
/// model on screen's new voxels on their cells; then releases it and waits until every model is redone.
fn drag_through(app: &mut App, grids: &[f32]) -> Vec<f64> {
    let latencies = grids
        .iter()
        .map(|&grid| {
            app.world_mut().resource_mut::<voxel_art::settings::SettingDrag>().0 = true;
            app.world_mut().resource_mut::<voxel_art::settings::VoxelSettings>().grid_size = grid;
            let t = Instant::now();
            app.update();
            update_until(app, current_placed);
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    app.world_mut().resource_mut::<voxel_art::settings::SettingDrag>().0 = false;
    let latest = app.world().resource::<voxel_art::voxelize::VoxelizeGeneration>().0;
    update_until(app, |app| {
        app.world().resource::<ModelLibrary>().entries.iter().all(|e| e.voxels_generation == Some(latest))
    });
    latencies
}

/// The median and the 90th percentile.
fn median_p90(values: &[f64]) -> (f64, f64) {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    (sorted[sorted.len() / 2], sorted[(sorted.len() * 9).div_ceil(10) - 1])
}

/// The live grid slider with the six shipped models loaded, each in turn on screen: the slider dragged from 0.12
/// to 0.5 over 60 frames, then 60 frames back and forth around the article's default grid (0.24 ± 0.02).
fn slider_sweeps() {
    let mut app = voxel_art::headless::headless_app(&voxel_art::config::AppArgs::default());
    update_until(&mut app, |app| {
        let library = app.world().resource::<ModelLibrary>();
        !library.entries.is_empty() && library.entries.iter().all(|e| e.status == ModelStatus::Ready)
    });
    let sweep: Vec<f32> = (0..60).map(|k| 0.12 + 0.38 * k as f32 / 59.0).collect();
    let around_default: Vec<f32> = (0..60).map(|k| 0.22 + 0.04 * (k % 5) as f32 / 4.0).collect();
    let names: Vec<String> = app.world().resource::<ModelLibrary>().entries.iter().map(|e| e.name.clone()).collect();
    let (mut all_sweep, mut all_default) = (Vec::new(), Vec::new());
    for (i, name) in names.iter().enumerate() {
        app.world_mut().write_message(voxel_art::library::LibraryRequest::Select(i));
        update_until(&mut app, |app| current_placed(app) && settled(app));
        let swept = drag_through(&mut app, &sweep);
        let near = drag_through(&mut app, &around_default);
        let ((sm, s90), (dm, d90)) = (median_p90(&swept), median_p90(&near));
        println!(
            "slider, {name} on screen: 0.12 → 0.5 median {sm:.2} ms, p90 {s90:.2} ms; around 0.24 median {dm:.2} ms, \
             p90 {d90:.2} ms"
        );
        let frames: Vec<String> = swept.iter().map(|t| format!("{t:.1}")).collect();
        println!("  per frame (ms): {}", frames.join(" "));
        all_sweep.extend(swept);
        all_default.extend(near);
    }
    let ((sm, s90), (dm, d90)) = (median_p90(&all_sweep), median_p90(&all_default));
    println!(
        "slider, all six: 0.12 → 0.5 median {sm:.2} ms, p90 {s90:.2} ms; around 0.24 median {dm:.2} ms, p90 {d90:.2} ms"
    );
}
