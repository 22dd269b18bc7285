//! Voxelization in the app: loaded glTF assets → triangle soup → the core voxelizer on the
//! `AsyncComputeTaskPool` → [`VoxelModelAsset`]s. A settings change re-voxelizes every model; results of
//! stale settings are dropped (latest wins).

pub mod from_gltf;

use std::sync::Arc;
use std::time::Instant;

use bevy::gltf::{Gltf, GltfMaterial, GltfMesh, GltfNode};
use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, Task, futures::check_ready};

use crate::model::{ModelLibrary, ModelStatus, VoxelModelAsset};
use crate::schedule::AppSystems;
use crate::settings::{Style, VoxelSettings};
use from_gltf::{GltfAssets, soup_from_gltf};

/// The voxelization systems (in `AppSystems::Simulate`).
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct VoxelizeSystems;

/// Bumped whenever a setting that shapes voxelization changes; models voxelized with an older
/// generation are redone.
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct VoxelizeGeneration(pub u64);

/// A running voxelization of library entry `entry` with the settings of `generation`.
#[derive(Component)]
pub struct VoxelizeJob {
    /// Library index.
    pub entry: usize,
    /// The settings generation it was started with.
    pub generation: u64,
    started: Instant,
    task: Task<Result<voxel_core::VoxelModel, String>>,
}

/// Starts a new generation when voxelization settings change.
fn track_settings(
    settings: Res<VoxelSettings>,
    style: Res<State<Style>>,
    mut generation: ResMut<VoxelizeGeneration>,
    mut last: Local<Option<voxel_core::VoxelizeOptions>>,
) {
    let options = settings.voxelize_options(*style.get());
    if last.is_some_and(|l| l != options) {
        generation.0 += 1;
    }
    *last = Some(options);
}

/// Reads newly loaded models into triangle soups.
fn read_loaded(
    mut library: ResMut<ModelLibrary>,
    asset_server: Res<AssetServer>,
    gltfs: Res<Assets<Gltf>>,
    nodes: Res<Assets<GltfNode>>,
    meshes: Res<Assets<GltfMesh>>,
    mesh_data: Res<Assets<Mesh>>,
    materials: Res<Assets<GltfMaterial>>,
    images: Res<Assets<Image>>,
) {
    let assets =
        GltfAssets { nodes: &nodes, meshes: &meshes, mesh_data: &mesh_data, materials: &materials, images: &images };
    let mut failures = Vec::new();
    for (i, entry) in library.entries.iter_mut().enumerate() {
        if entry.status != ModelStatus::Loading || !asset_server.is_loaded_with_dependencies(&entry.gltf) {
            continue;
        }
        let Some(gltf) = gltfs.get(&entry.gltf) else { continue };
        match soup_from_gltf(gltf, &assets) {
            Ok(soup) => {
                entry.soup = Some(Arc::new(soup));
                entry.status = ModelStatus::Voxelizing;
            }
            Err(reason) => failures.push((i, reason)),
        }
    }
    for (i, reason) in failures {
        library.fail(i, reason);
    }
}

/// Starts a job for every model whose voxels are missing or stale and that has no current job.
fn start_jobs(
    mut commands: Commands,
    mut library: ResMut<ModelLibrary>,
    settings: Res<VoxelSettings>,
    style: Res<State<Style>>,
    generation: Res<VoxelizeGeneration>,
    jobs: Query<(Entity, &VoxelizeJob)>,
) {
    let options = settings.voxelize_options(*style.get());
    let pool = AsyncComputeTaskPool::get();
    for (i, entry) in library.entries.iter_mut().enumerate() {
        let Some(soup) = entry.soup.clone() else { continue };
        if matches!(entry.status, ModelStatus::Failed(_)) || entry.voxels_generation == Some(generation.0) {
            continue;
        }
        let mut running = false;
        for (job_entity, job) in jobs.iter().filter(|(_, j)| j.entry == i) {
            if job.generation == generation.0 {
                running = true;
            } else {
                // Dropping the task cancels it: latest settings win.
                commands.entity(job_entity).despawn();
            }
        }
        if !running {
            entry.status = ModelStatus::Voxelizing;
            let task = pool.spawn(async move { voxel_core::voxelize(&soup, &options).map_err(|e| e.to_string()) });
            commands.spawn(VoxelizeJob { entry: i, generation: generation.0, started: Instant::now(), task });
        }
    }
}

/// Collects finished jobs; results of an older generation are dropped.
fn finish_jobs(
    mut commands: Commands,
    mut library: ResMut<ModelLibrary>,
    generation: Res<VoxelizeGeneration>,
    mut models: ResMut<Assets<VoxelModelAsset>>,
    mut jobs: Query<(Entity, &mut VoxelizeJob)>,
) {
    for (entity, mut job) in &mut jobs {
        let Some(result) = check_ready(&mut job.task) else { continue };
        commands.entity(entity).despawn();
        if job.generation != generation.0 {
            continue;
        }
        match result {
            Ok(model) => {
                if let Some(entry) = library.entries.get_mut(job.entry) {
                    entry.voxels = Some(models.add(VoxelModelAsset(model)));
                    entry.voxels_generation = Some(job.generation);
                    entry.voxelize_ms = job.started.elapsed().as_secs_f32() * 1e3;
                    entry.status = ModelStatus::Ready;
                }
            }
            Err(reason) => library.fail(job.entry, reason),
        }
    }
}

pub(super) fn plugin(app: &mut App) {
    app.init_asset::<VoxelModelAsset>();
    app.init_resource::<VoxelizeGeneration>();
    app.add_systems(
        Update,
        (track_settings, read_loaded, start_jobs, finish_jobs)
            .chain()
            .in_set(AppSystems::Simulate)
            .in_set(VoxelizeSystems),
    );
}
