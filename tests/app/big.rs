//! A big file in the app: its preview tile comes from its voxels (Bevy's glTF loader never reads it), its
//! job reports its stages, a stale job is cancelled, a file dropped while it loads (held there: a pipe) is
//! served at once, a piped file gets its tile from its voxels, and the panel's voxel memory is the model's.

use std::time::Duration;

use bevy::prelude::*;
use voxel_art::config::AppArgs;
use voxel_art::library::LibraryRequest;
use voxel_art::model::{ModelLibrary, ModelStatus};
use voxel_art::settings::VoxelSettings;
use voxel_art::voxelize::TILE_TRIANGLES;
use voxel_core::shapes::uv_sphere;
use voxel_core::{Stage, TriangleSoup};

use crate::harness::{all_settled, held_file, run_until, shipped, temp_file, test_app};

/// A sphere of just over [`TILE_TRIANGLES`] triangles as .glb bytes.
fn big_sphere() -> Vec<u8> {
    let sphere = uv_sphere(1.0, 360);
    assert!(sphere.triangles.len() > TILE_TRIANGLES, "{} triangles", sphere.triangles.len());
    let soup = TriangleSoup::from_mesh(&sphere, [0.9, 0.3, 0.2, 1.0]);
    voxel_core::glb::soup_to_glb(&soup).unwrap()
}

/// The big sphere written as `name` (each test its own file: tests run at once).
fn big_sphere_file(name: &str) -> std::path::PathBuf {
    temp_file(name, &big_sphere())
}

#[test]
fn a_big_file_gets_a_tile_from_its_voxels_and_a_small_one_its_gltf() {
    let big = big_sphere_file("big-sphere-tile.glb");
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
    let big = big_sphere_file("big-sphere-cancel.glb");
    let mut app = test_app(AppArgs { models: vec![big], no_shipped: true, ..default() });
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
    // The big file is a named pipe that the test fills only once the apple is shown: its job is still reading.
    let (path, release) = held_file("big-sphere-held.glb", big_sphere());
    let mut app = test_app(AppArgs { models: vec![path], no_shipped: true, ..default() });
    app.update();
    let big = app.world().resource::<ModelLibrary>().entries[0].progress.clone();
    // The job lanes are the process's, shared with the other tests: the big job may wait for one before reading.
    run_until(&mut app, Duration::from_secs(120), |_| big.stage() == Stage::Reading);
    app.world_mut().write_message(LibraryRequest::Add(shipped("apple.glb")));
    let apple_ready = |app: &mut App| {
        app.world().resource::<ModelLibrary>().entries.get(1).is_some_and(|e| e.status == ModelStatus::Ready)
    };
    run_until(&mut app, Duration::from_secs(120), apple_ready);
    assert_eq!(big.stage(), Stage::Reading, "the big file's job is still reading");
    assert!(!big.is_cancelled(), "the big file's job was given up");
    drop(release);
    run_until(&mut app, Duration::from_secs(120), all_settled);
    let library = app.world().resource::<ModelLibrary>();
    assert_eq!(library.entries[0].status, ModelStatus::Ready);
    assert_eq!(big.stage(), Stage::Done);
}

#[test]
fn a_model_read_from_a_pipe_gets_its_tile_from_its_voxels() {
    let apple = std::fs::read(shipped("apple.glb")).unwrap();
    let (path, release) = held_file("apple-piped.glb", apple);
    drop(release);
    let mut app = test_app(AppArgs { models: vec![path], no_shipped: true, ..default() });
    run_until(&mut app, Duration::from_secs(120), all_settled);
    let entry = &app.world().resource::<ModelLibrary>().entries[0];
    assert_eq!(entry.status, ModelStatus::Ready);
    assert!(entry.tile_mesh.is_some(), "a pipe cannot be read again for Bevy's glTF loader");
    assert_eq!(entry.gltf, Handle::default());
}
