//! A big file in the app: its preview tile comes from its voxels (Bevy's glTF loader never reads it), its
//! job reports its stages, a stale job is cancelled, a file dropped while it loads is served at once, and the
//! panel's voxel memory is the model's.

use std::time::Duration;

use bevy::prelude::*;
use voxel_art::config::AppArgs;
use voxel_art::library::LibraryRequest;
use voxel_art::model::{ModelLibrary, ModelStatus};
use voxel_art::settings::VoxelSettings;
use voxel_art::voxelize::TILE_TRIANGLES;
use voxel_core::shapes::uv_sphere;
use voxel_core::{Stage, TriangleSoup};

use crate::harness::{all_settled, run_until, shipped, temp_file, test_app};

/// A sphere of just over [`TILE_TRIANGLES`] triangles, written as a .glb.
fn big_sphere_file() -> std::path::PathBuf {
    let sphere = uv_sphere(1.0, 360);
    assert!(sphere.triangles.len() > TILE_TRIANGLES, "{} triangles", sphere.triangles.len());
    let soup = TriangleSoup::from_mesh(&sphere, [0.9, 0.3, 0.2, 1.0]);
    temp_file("big-sphere.glb", &voxel_core::glb::soup_to_glb(&soup).unwrap())
}

#[test]
fn a_big_file_gets_a_tile_from_its_voxels_and_a_small_one_its_gltf() {
    let big = big_sphere_file();
    let args = AppArgs { models: vec![big, shipped("apple.glb")], no_shipped: true, ..default() };
    let mut app = test_app(args);
    run_until(&mut app, Duration::from_secs(120), all_settled);
    let library = app.world().resource::<ModelLibrary>();
    let [sphere, apple] = [0, 1].map(|i| &library.entries[i]);
    assert_eq!((sphere.status.clone(), apple.status.clone()), (ModelStatus::Ready, ModelStatus::Ready));
    assert_eq!([sphere.progress.stage(), apple.progress.stage()], [Stage::Done; 2]);

    let tile = sphere.tile_mesh.as_ref().expect("the big file's tile is its voxel surface");
    assert_eq!(sphere.gltf, Handle::default(), "Bevy's glTF loader never reads the big file");
    let mesh = app.world().resource::<Assets<Mesh>>().get(tile).expect("the tile mesh is an asset");
    assert!(mesh.count_vertices() > 1_000, "{} vertices", mesh.count_vertices());
    assert!(apple.tile_mesh.is_none());
    assert_ne!(apple.gltf, Handle::default(), "a small file's tile is its glTF");

    let models = app.world().resource::<Assets<voxel_art::model::VoxelModelAsset>>();
    let voxels = models.get(sphere.voxels.as_ref().unwrap()).unwrap();
    let bytes = voxels.memory_bytes();
    assert!(bytes >= voxels.stats.visible * 12, "{bytes} bytes for {} visible cells", voxels.stats.visible);
}

#[test]
fn a_setting_change_cancels_the_running_job_and_the_new_one_finishes() {
    let mut app = test_app(AppArgs { models: vec![big_sphere_file()], no_shipped: true, ..default() });
    app.update();
    let first = app.world().resource::<ModelLibrary>().entries[0].progress.clone();
    // The file takes far longer to read and voxelize than two frames: its job is still running.
    app.world_mut().resource_mut::<VoxelSettings>().grid_size = 0.3;
    app.update();
    assert!(first.is_cancelled(), "the stale job was asked to stop (it was at {:?})", first.stage());
    assert!(first.stage() < Stage::Done, "a cancelled job never finishes");
    run_until(&mut app, Duration::from_secs(120), all_settled);
    let entry = &app.world().resource::<ModelLibrary>().entries[0];
    assert_eq!(entry.status, ModelStatus::Ready);
    assert!(!entry.progress.is_cancelled());
    assert_eq!(entry.progress.stage(), Stage::Done);
}

#[test]
fn a_file_dropped_while_a_big_one_loads_is_served_beside_it() {
    let mut app = test_app(AppArgs { models: vec![big_sphere_file()], no_shipped: true, ..default() });
    app.update();
    let big = app.world().resource::<ModelLibrary>().entries[0].progress.clone();
    app.world_mut().write_message(LibraryRequest::Add(shipped("apple.glb")));
    let mut frames = 0;
    let apple_ready = |app: &mut App| {
        frames += 1;
        app.world().resource::<ModelLibrary>().entries.get(1).is_some_and(|e| e.status == ModelStatus::Ready)
    };
    run_until(&mut app, Duration::from_secs(120), apple_ready);
    assert!(big.stage() < Stage::Done, "the apple waited for the big file ({frames} frames)");
    assert!(!big.is_cancelled(), "the big file's job was given up");
    run_until(&mut app, Duration::from_secs(120), all_settled);
    let library = app.world().resource::<ModelLibrary>();
    assert_eq!(library.entries[0].status, ModelStatus::Ready);
    assert_eq!(big.stage(), Stage::Done);
}
