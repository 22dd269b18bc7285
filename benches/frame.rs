//! `cargo bench --bench frame`: CPU time per frame of the app's systems (no GPU) with 100k voxels, static
//! and with every voxel's colour changing every frame. Mean and median of 300 frames after warm-up.

use std::time::{Duration, Instant};

use bevy::mesh::MeshTag;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use voxel_art::instancing::{VoxelPool, VoxelSlot};
use voxel_art::library::{ModelEntry, ModelLibrary, ModelStatus};
use voxel_art::voxel::shapes::uv_sphere;
use voxel_art::voxel::{GridSize, TriangleSoup, VoxelizeOptions, voxelize};
use voxel_art::voxelize::VoxelModel;

/// About 100k voxels: a solid sphere 58 cells across.
fn big_model() -> voxel_art::voxel::VoxelModel {
    let soup = TriangleSoup::from_mesh(&uv_sphere(1.0, 48), [0.9, 0.5, 0.6, 1.0]);
    voxelize(&soup, &VoxelizeOptions { grid: GridSize::Resolution(58), hollow: false, ..Default::default() }).expect("voxelize")
}

fn app_with(model: voxel_art::voxel::VoxelModel) -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, TransformPlugin, AssetPlugin::default(), bevy::mesh::MeshPlugin));
    app.init_resource::<ButtonInput<KeyCode>>();
    app.init_resource::<ButtonInput<MouseButton>>();
    app.insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f32(1.0 / 60.0)));
    app.add_plugins(voxel_art::LogicPlugin);
    app.finish();
    app.cleanup();
    app.update();
    let handle = app.world_mut().resource_mut::<Assets<VoxelModel>>().add(VoxelModel(model));
    let mut library = app.world_mut().resource_mut::<ModelLibrary>();
    library.entries.clear();
    library.entries.push(ModelEntry {
        name: "sphere".into(),
        asset_path: String::new(),
        gltf: Handle::default(),
        status: ModelStatus::Ready,
        soup: None,
        voxels: Some(handle),
        voxels_generation: Some(0),
        voxelize_ms: 0.0,
    });
    library.current = 0;
    for _ in 0..600 {
        app.update();
        if app.world().resource::<VoxelPool>().shown.is_some() {
            break;
        }
    }
    assert!(app.world().resource::<VoxelPool>().shown.is_some(), "the model never showed");
    app
}

/// Changes every voxel's colour (as a colour animation would).
fn recolor_everything(time: Res<Time>, mut voxels: Query<(&VoxelSlot, &mut MeshTag)>) {
    let shift = (time.elapsed_secs() * 60.0) as u32;
    voxels.par_iter_mut().for_each(|(slot, mut tag)| tag.0 = slot.0.wrapping_mul(2_654_435_761).wrapping_add(shift) | 0xff00_0000);
}

fn measure(app: &mut App, frames: usize) -> (f64, f64) {
    for _ in 0..30 {
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
    let model = big_model();
    let n = model.voxels.len();
    println!("voxels: {n}, threads: {}", bevy::tasks::available_parallelism());
    let mut app = app_with(model.clone());
    let (mean, median) = measure(&mut app, 300);
    println!("static voxels:        mean {mean:.2} ms/frame, median {median:.2} ms/frame");
    let mut app = app_with(model);
    app.add_systems(Update, recolor_everything);
    let (mean, median) = measure(&mut app, 300);
    println!("recolour every frame: mean {mean:.2} ms/frame, median {median:.2} ms/frame");
}
