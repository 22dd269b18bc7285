//! Exports from the app: Ctrl+S (or an `ExportRequest`) saves the shown model as .vox and .glb, an unwritable
//! folder is reported and the app goes on, and Bevy's own glTF loader reads an exported Duck.

use std::path::{Path, PathBuf};
use std::time::Duration;

use bevy::asset::LoadState;
use bevy::gltf::{Gltf, GltfMesh};
use bevy::prelude::*;
use voxel_art::config::AppArgs;
use voxel_art::export::{ExportDir, ExportRequest, ExportStatus};
use voxel_art::model::{ModelLibrary, VoxelModelAsset};
use voxel_art::settings::VoxelSettings;
use voxel_art::style::Style;
use voxel_core::export::{ExportOptions, Saved};
use voxel_core::{GridSize, ShellMode, VoxelModel, VoxelizeOptions};

use crate::common::{models_dir, scratch_dir};
use crate::harness::{all_settled, run_until, shipped, tap, test_app};

const LIMIT: Duration = Duration::from_secs(60);

/// The app showing one shipped model, exporting to `dir`.
fn app_exporting_to(dir: &Path, style: Style) -> App {
    let models = vec![shipped("donut.glb")];
    let mut app = test_app(AppArgs {
        no_shipped: true,
        models,
        export_dir: Some(dir.to_owned()),
        style: Some(style),
        ..default()
    });
    run_until(&mut app, LIMIT, all_settled);
    app
}

/// The current model as the app shows it now.
fn shown(app: &App) -> VoxelModel {
    let hollow = app.world().resource::<VoxelSettings>().hollow;
    let library = app.world().resource::<ModelLibrary>();
    let (_, model) = library.current_ready(app.world().resource::<Assets<VoxelModelAsset>>()).expect("a model ready");
    model.shown_model(hollow)
}

/// Steps the app until the export is no longer being written; returns its status.
fn finished_export(app: &mut App) -> ExportStatus {
    run_until(app, LIMIT, |app| {
        !matches!(app.world().resource::<ExportStatus>(), ExportStatus::Idle | ExportStatus::Writing)
    });
    app.world().resource::<ExportStatus>().clone()
}

/// Checks that both files hold `model`: the .vox its voxels, the .glb a surface that voxelizes back to its
/// cells (at the same cell size, with the same hollowing).
fn assert_files_hold(saved: &Saved, model: &VoxelModel, hollow: bool) {
    let vox = dot_vox::load(saved.vox.0.to_str().unwrap()).unwrap();
    assert_eq!(vox.models.iter().map(|m| m.voxels.len()).sum::<usize>(), model.len());
    assert_eq!(saved.vox.1.voxels, model.len());

    let soup = voxel_core::load_file(&saved.glb.0).unwrap();
    assert_eq!(soup.triangle_count(), 2 * saved.glb.1.quads);
    let sides: [u32; 3] = std::array::from_fn(|a| {
        let (lo, hi) = model.voxels().fold((u16::MAX, 0), |(lo, hi), v| (lo.min(v.cell[a]), hi.max(v.cell[a])));
        u32::from(hi - lo) + 1
    });
    let options = VoxelizeOptions {
        grid: GridSize::Resolution(sides.into_iter().max().unwrap()),
        cell_height_ratio: model.spec.cell[1] / model.spec.cell[0],
        shell: ShellMode::None,
        hollow,
        ..default()
    };
    let back = voxel_core::voxelize(&soup, &options).unwrap();
    assert_eq!(back.spec.dims, sides);
    assert_eq!(back.len(), model.len(), "the .glb voxelizes back to the cells shown");
}

#[test]
fn ctrl_s_saves_the_hollow_model_shown_as_vox_and_glb() {
    let dir = scratch_dir("ctrl-s").join("exports");
    let mut app = app_exporting_to(&dir, Style::RoundedBoxes);
    assert!(app.world().resource::<VoxelSettings>().hollow, "hollow is the default");
    app.world_mut().resource_mut::<ButtonInput<KeyCode>>().press(KeyCode::ControlLeft);
    tap(&mut app, KeyCode::KeyS);
    app.world_mut().resource_mut::<ButtonInput<KeyCode>>().release(KeyCode::ControlLeft);
    assert_eq!(*app.world().resource::<State<Style>>().get(), Style::RoundedBoxes, "Ctrl+S is not S");

    let ExportStatus::Saved(saved, None) = finished_export(&mut app) else {
        panic!("{:?}", app.world().resource::<ExportStatus>())
    };
    let model = shown(&app);
    let [nx, ny, nz] = model.spec.dims;
    assert_eq!(saved.vox.0, dir.join(format!("donut-{nx}x{ny}x{nz}.vox")));
    assert_eq!(saved.glb.0, dir.join(format!("donut-{nx}x{ny}x{nz}.glb")));
    assert!(model.len() < model.stats.voxels, "hollow: {} of {} voxels", model.len(), model.stats.voxels);
    assert_eq!(model.len(), model.stats.visible);
    assert_files_hold(&saved, &model, true);
    let message = ExportStatus::Saved(saved.clone(), None).message().unwrap();
    assert!(message.contains(&saved.glb.0.display().to_string()), "{message}");
}

#[test]
fn an_export_request_saves_solid_lego_cells() {
    let dir = scratch_dir("lego").join("exports");
    let mut app = app_exporting_to(&dir, Style::Lego);
    app.world_mut().resource_mut::<VoxelSettings>().hollow = false;
    app.world_mut().write_message(ExportRequest);
    let ExportStatus::Saved(saved, None) = finished_export(&mut app) else {
        panic!("{:?}", app.world().resource::<ExportStatus>())
    };
    let model = shown(&app);
    assert_eq!(model.len(), model.stats.voxels, "solid: every voxel");
    assert!((model.spec.cell[1] / model.spec.cell[0] - 1.2).abs() < 1e-4, "Lego cells: {:?}", model.spec.cell);
    assert_files_hold(&saved, &model, false);
}

#[test]
fn an_unwritable_folder_is_reported_and_the_app_goes_on() {
    let scratch = scratch_dir("unwritable");
    let file = scratch.join("a-file");
    std::fs::write(&file, b"not a folder").unwrap();
    let blocked = file.join("exports");
    let mut app = app_exporting_to(&blocked, Style::RoundedBoxes);
    app.world_mut().write_message(ExportRequest);
    let status = finished_export(&mut app);
    let message = status.message().unwrap();
    assert!(message.starts_with(&format!("export failed: cannot write {}: ", blocked.display())), "{message}");

    // The app goes on: the next export, into a writable folder, is written.
    let good: PathBuf = scratch.join("exports");
    app.world_mut().insert_resource(ExportDir(good.clone()));
    app.world_mut().write_message(ExportRequest);
    let ExportStatus::Saved(saved, None) = finished_export(&mut app) else {
        panic!("{:?}", app.world().resource::<ExportStatus>())
    };
    assert!(saved.glb.0.starts_with(&good) && saved.glb.0.is_file());
}

#[test]
fn bevy_loads_the_exported_duck_with_vertex_colours() {
    let Some(models) = models_dir() else { return };
    let soup = voxel_core::load_file(&models.join("khronos-duck.glb")).unwrap();
    let model = voxel_core::voxelize(&soup, &VoxelizeOptions { grid: GridSize::Resolution(64), ..default() }).unwrap();
    let path = scratch_dir("bevy-duck").join("duck.glb");
    let stats = voxel_core::export::gltf::write_glb(&model, &path, &ExportOptions { name: "duck".into() }).unwrap();

    let mut app = test_app(AppArgs { no_shipped: true, ..default() });
    let handle: Handle<Gltf> = app.world().resource::<AssetServer>().load(voxel_art::assets::file_asset_path(&path));
    run_until(&mut app, LIMIT, |app| match app.world().resource::<AssetServer>().load_state(&handle) {
        LoadState::Failed(e) => panic!("Bevy cannot load the export: {e}"),
        _ => app.world().resource::<AssetServer>().is_loaded_with_dependencies(&handle),
    });
    let world = app.world();
    let gltf = world.resource::<Assets<Gltf>>().get(&handle).unwrap();
    assert_eq!(gltf.meshes.len(), 1);
    assert!(gltf.named_meshes.contains_key("duck"), "{:?}", gltf.named_meshes.keys());
    let gltf_mesh = world.resource::<Assets<GltfMesh>>().get(&gltf.meshes[0]).unwrap();
    assert_eq!(gltf_mesh.primitives.len(), 1);
    let mesh = world.resource::<Assets<Mesh>>().get(&gltf_mesh.primitives[0].mesh).unwrap();
    let colors = mesh.attribute(Mesh::ATTRIBUTE_COLOR).expect("COLOR_0 becomes Mesh::ATTRIBUTE_COLOR");
    assert_eq!(colors.len(), stats.vertices);
    assert_eq!(mesh.count_vertices(), stats.vertices);
    assert!(mesh.attribute(Mesh::ATTRIBUTE_NORMAL).is_some());
    assert_eq!(mesh.indices().map(|i| i.len()), Some(6 * stats.quads));
    assert!(stats.quads < stats.faces, "greedy merging: {} quads of {} faces", stats.quads, stats.faces);
}
