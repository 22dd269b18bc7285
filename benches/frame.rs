//! `cargo bench --bench frame`: CPU time per frame of the app's systems (no GPU) with 100k voxels: static,
//! with every voxel's colour changing every frame, and mid-morph (every voxel tweening). Mean and median.

use std::time::Instant;

use bevy::mesh::MeshTag;
use bevy::prelude::*;
use voxel_art::instancing::{VoxelPool, VoxelSlot};
use voxel_art::library::{ModelEntry, ModelLibrary, ModelStatus};
use voxel_art::transition::ActiveTransition;
use voxel_art::voxel::shapes::uv_sphere;
use voxel_art::voxel::{GridSize, TriangleSoup, VoxelizeOptions, voxelize};
use voxel_art::voxelize::VoxelModel;

/// About 100k voxels: a solid sphere 58 cells across.
fn big_model() -> voxel_art::voxel::VoxelModel {
    let soup = TriangleSoup::from_mesh(&uv_sphere(1.0, 48), [0.9, 0.5, 0.6, 1.0]);
    voxelize(&soup, &VoxelizeOptions { grid: GridSize::Resolution(58), hollow: false, ..Default::default() }).expect("voxelize")
}

/// About 100k voxels of another shape: a solid cube 46 cells wide.
fn cube_model() -> voxel_art::voxel::VoxelModel {
    let soup = TriangleSoup::from_mesh(&voxel_art::voxel::shapes::cuboid([0.0; 3], [1.0; 3]), [0.5, 0.6, 0.9, 1.0]);
    voxelize(&soup, &VoxelizeOptions { grid: GridSize::Resolution(46), hollow: false, ..Default::default() }).expect("voxelize")
}

fn entry(name: &str, handle: Handle<VoxelModel>) -> ModelEntry {
    ModelEntry {
        name: name.into(),
        asset_path: String::new(),
        gltf: Handle::default(),
        status: ModelStatus::Ready,
        soup: None,
        voxels: Some(handle),
        voxels_generation: Some(0),
        voxelize_ms: 0.0,
    }
}

fn settled(app: &App) -> bool {
    app.world().resource::<VoxelPool>().shown.is_some() && app.world().resource::<ActiveTransition>().running.is_none()
}

fn app_with(models: Vec<voxel_art::voxel::VoxelModel>) -> App {
    let mut app = voxel_art::headless::headless_app(voxel_art::args::AppArgs { no_shipped: true, ..Default::default() });
    app.update();
    let handles: Vec<_> = models.into_iter().map(|m| app.world_mut().resource_mut::<Assets<VoxelModel>>().add(VoxelModel(m))).collect();
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
fn recolor_everything(time: Res<Time>, mut voxels: Query<(&VoxelSlot, &mut MeshTag)>) {
    let shift = (time.elapsed_secs() * 60.0) as u32;
    voxels.par_iter_mut().for_each(|(slot, mut tag)| tag.0 = slot.0.wrapping_mul(2_654_435_761).wrapping_add(shift) | 0xff00_0000);
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

fn main() {
    let (sphere, cube) = (big_model(), cube_model());
    println!("voxels: sphere {}, cube {}; threads: {}", sphere.voxels.len(), cube.voxels.len(), bevy::tasks::available_parallelism());
    let mut app = app_with(vec![sphere.clone()]);
    let (mean, median) = measure(&mut app, 30, 300);
    println!("static voxels:        mean {mean:.2} ms/frame, median {median:.2} ms/frame");
    let mut app = app_with(vec![sphere.clone()]);
    app.add_systems(Update, recolor_everything);
    let (mean, median) = measure(&mut app, 30, 300);
    println!("recolour every frame: mean {mean:.2} ms/frame, median {median:.2} ms/frame");
    // Mid-morph: frames 12..60 after a switch, when every voxel's delay (≤ 0.2 s) has passed.
    let mut app = app_with(vec![sphere, cube]);
    app.world_mut().write_message(voxel_art::library::LibraryRequest::Next);
    let tweening = |app: &mut App| app.world_mut().query::<&voxel_art::transition::VoxelTween>().iter(app.world()).count();
    let (mean, median) = measure(&mut app, 12, 48);
    println!("mid-morph ({} tweening at the end): mean {mean:.2} ms/frame, median {median:.2} ms/frame", tweening(&mut app));
    // Mouse repel: the cursor ray through the middle of a settled 100k-voxel model.
    let mut app = app_with(vec![big_model()]);
    app.insert_resource(voxel_art::input::CursorRay(Some(Ray3d::new(Vec3::new(0.3, 0.2, 30.0), Dir3::NEG_Z))));
    let (mean, median) = measure(&mut app, 10, 300);
    println!("repel, cursor over 100k voxels: mean {mean:.2} ms/frame, median {median:.2} ms/frame");
    pile_step();
}

/// One physics step of 20k falling voxels (a 28 × 26 × 28 block dropped on the floor), averaged over the
/// first 300 steps (everything in motion) and the next 300 (piling up and falling asleep).
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
    for phase in ["falling", "settling"] {
        let t = Instant::now();
        for _ in 0..300 {
            pile.step();
        }
        println!("pile step, {n} voxels {phase}: mean {:.2} ms/step", t.elapsed().as_secs_f64() * 1e3 / 300.0);
    }
}
