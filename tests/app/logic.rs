//! App logic without a GPU: loading, voxelizing, picking models, the voxel pool, settings changes.

use std::time::Duration;

use bevy::prelude::*;
use voxel_art::config::AppArgs;
use voxel_art::instancing::VoxelPool;
use voxel_art::library::LibraryRequest;
use voxel_art::model::{ModelLibrary, ModelStatus, VoxelModelAsset};
use voxel_art::settings::VoxelSettings;
use voxel_art::voxelize::{VoxelizeGeneration, VoxelizeJob};

use crate::harness::{all_settled, app_options, core_voxelize, run_until, shipped, tap, temp_file, test_app};

const LIMIT: Duration = Duration::from_secs(60);

/// The current model's latest voxelization.
pub fn shown_model(app: &App) -> Option<VoxelModelAsset> {
    let library = app.world().resource::<ModelLibrary>();
    let handle = library.current_entry()?.voxels.clone()?;
    app.world().resource::<Assets<VoxelModelAsset>>().get(&handle).cloned()
}

#[test]
fn a_shipped_model_voxelizes_like_the_core_does() {
    let mut app = test_app(AppArgs::default());
    run_until(&mut app, LIMIT, all_settled);
    let library = app.world().resource::<ModelLibrary>();
    assert!(library.entries.len() >= 6, "{} shipped models", library.entries.len());
    assert!(library.entries.iter().all(|e| e.status == ModelStatus::Ready), "{:?}", library.entries);
    let options = app_options(&app);
    for i in 0..library.entries.len() {
        let library = app.world().resource::<ModelLibrary>();
        let entry = &library.entries[i];
        let app_model = app.world().resource::<Assets<VoxelModelAsset>>().get(entry.voxels.as_ref().unwrap()).unwrap();
        let core_model = core_voxelize(&shipped(&format!("{}.glb", entry.name)), &options);
        // One reader: the app gives the cells and colours the core (and so the CLI) gives.
        assert_eq!(app_model.stats, core_model.stats, "{}", entry.name);
        assert!(app_model.voxels().eq(core_model.voxels()), "{}: other cells or colours", entry.name);
    }
}

#[test]
fn the_pool_shows_the_current_model_and_hides_spares() {
    let mut app = test_app(AppArgs::default());
    run_until(&mut app, LIMIT, all_settled);
    // Find the largest and the smallest model.
    let counts: Vec<usize> = {
        let library = app.world().resource::<ModelLibrary>();
        let models = app.world().resource::<Assets<VoxelModelAsset>>();
        let hollow = app.world().resource::<VoxelSettings>().hollow;
        library.entries.iter().map(|e| models.get(e.voxels.as_ref().unwrap()).unwrap().shown_count(hollow)).collect()
    };
    let largest = (0..counts.len()).max_by_key(|&i| counts[i]).unwrap();
    let smallest = (0..counts.len()).min_by_key(|&i| counts[i]).unwrap();
    for pick in [largest, smallest] {
        app.world_mut().write_message(LibraryRequest::Select(pick));
        crate::transition::settle(&mut app);
    }
    let pool = app.world().resource::<VoxelPool>();
    assert_eq!(pool.slots.len(), counts[largest], "the pool grew to the largest model");
    assert_eq!(pool.visible, counts[smallest]);
    let hidden = crate::transition::assert_shows_model(&mut app);
    assert_eq!(hidden, counts[largest] - counts[smallest]);
}

#[test]
fn keys_move_the_current_model() {
    let mut app = test_app(AppArgs::default());
    app.update();
    let n = app.world().resource::<ModelLibrary>().entries.len();
    let current = |app: &App| app.world().resource::<ModelLibrary>().current;
    assert_eq!(current(&app), 0);
    tap(&mut app, KeyCode::ArrowRight);
    assert_eq!(current(&app), 1);
    tap(&mut app, KeyCode::Space);
    assert_eq!(current(&app), 2);
    tap(&mut app, KeyCode::ArrowLeft);
    tap(&mut app, KeyCode::ArrowLeft);
    tap(&mut app, KeyCode::ArrowLeft);
    assert_eq!(current(&app), n - 1, "left wraps around");
    tap(&mut app, KeyCode::Digit4);
    assert_eq!(current(&app), 3);
    tap(&mut app, KeyCode::Digit9);
    assert_eq!(current(&app), 3, "no ninth model: the pick stays");
    let open = app.world().resource::<voxel_art::settings::PanelOpen>().0;
    tap(&mut app, KeyCode::KeyH);
    assert_eq!(app.world().resource::<voxel_art::settings::PanelOpen>().0, !open);
}

#[test]
fn a_bad_file_becomes_an_error_entry_and_the_app_goes_on() {
    let junk = temp_file("junk.glb", b"this is not a glTF file");
    let missing = std::env::temp_dir().join("voxel-art-no-such-model.glb");
    let args = AppArgs { models: vec![junk.clone(), missing], ..default() };
    let mut app = test_app(args);
    run_until(&mut app, LIMIT, all_settled);
    let library = app.world().resource::<ModelLibrary>();
    let junk_entry = library.entries.iter().find(|e| e.name == "junk").unwrap();
    let ModelStatus::Failed(reason) = &junk_entry.status else { panic!("junk loaded: {:?}", junk_entry.status) };
    assert!(!reason.is_empty());
    let missing_entry = library.entries.iter().find(|e| e.name == "voxel-art-no-such-model").unwrap();
    assert!(
        matches!(&missing_entry.status, ModelStatus::Failed(r) if r.contains("no such file")),
        "{:?}",
        missing_entry.status
    );
    assert!(library.last_error.is_some());
    let ready = library.entries.iter().filter(|e| e.status == ModelStatus::Ready).count();
    assert!(ready >= 6, "the good models still voxelize");
    // Picking the failed model keeps the app running and the previous voxels on screen.
    let bad = library.entries.iter().position(|e| e.name == "junk").unwrap();
    app.world_mut().write_message(LibraryRequest::Select(bad));
    for _ in 0..5 {
        app.update();
    }
    assert_eq!(app.world().resource::<ModelLibrary>().current, bad);
    assert!(app.world().resource::<VoxelPool>().shown.is_some());
}

/// Every model file of the corpus: the top folder's and its subfolders'.
fn corpus_files(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut folders = vec![dir.to_owned()];
    folders.extend(std::fs::read_dir(dir).unwrap().flatten().map(|e| e.path()).filter(|p| p.is_dir()));
    let mut files = voxel_core::files::expand_inputs(&folders);
    files.sort();
    files
}

#[test]
fn the_app_voxelizes_every_corpus_model_as_the_cli_does() {
    let Some(dir) = crate::common::models_dir() else { return };
    let files = corpus_files(&dir);
    assert!(files.len() >= 15, "{} corpus files", files.len());
    let mut app = test_app(AppArgs { models: files.clone(), no_shipped: true, ..default() });
    run_until(&mut app, Duration::from_secs(600), all_settled);
    // As the CLI does: voxelized with the colours as sampled, then the colour stage (`voxelize --palette
    // pastel`; its colour count is of RGB colours, where the voxelizer's own remap counts RGBA ones).
    let options = voxel_core::VoxelizeOptions { pastel: false, ..app_options(&app) };
    let stage = app.world().resource::<voxel_art::settings::ColorSettings>().0.clone();
    let library = app.world().resource::<ModelLibrary>();
    assert_eq!(library.entries.len(), files.len());
    let mut ready = 0;
    for entry in &library.entries {
        let core = voxel_core::load_file(&entry.path).and_then(|soup| {
            let mut model = voxel_core::voxelize(&soup, &options)?;
            stage.apply(&mut model)?;
            Ok(model)
        });
        match (&entry.status, core) {
            (ModelStatus::Ready, Ok(core_model)) => {
                let app_model = entry.latest(app.world().resource::<Assets<VoxelModelAsset>>()).unwrap();
                assert_eq!(app_model.stats, core_model.stats, "{}", entry.path.display());
                assert!(app_model.voxels().eq(core_model.voxels()), "{}: other cells or colours", entry.path.display());
                ready += 1;
            }
            (ModelStatus::Failed(reason), Err(e)) => assert_eq!(reason, &e.to_string(), "{}", entry.path.display()),
            (status, core) => panic!("{}: app {status:?}, core {:?}", entry.path.display(), core.map(|m| m.stats)),
        }
    }
    assert!(ready >= 15, "only {ready} corpus models voxelized");
}

/// A one-triangle .glb whose COLOR_0 accessor has two elements for three positions (Bevy's glTF loader panics
/// on it in `Mesh::duplicate_vertices`).
fn short_color_glb() -> Vec<u8> {
    let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let colors: [f32; 8] = [1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0];
    let bin: Vec<u8> = positions.iter().chain(&colors).flat_map(|f| f.to_le_bytes()).collect();
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "COLOR_0": 1}}]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 32}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 2, "type": "VEC4"}
        ]
    });
    voxel_core::glb::pack(&serde_json::to_vec(&json).unwrap(), &bin).unwrap()
}

#[test]
fn a_file_bevy_cannot_load_is_marked_with_the_cores_reason_and_the_app_goes_on() {
    let bad = temp_file("short-colours.glb", &short_color_glb());
    let mut app = test_app(AppArgs { models: vec![bad.clone()], ..default() });
    run_until(&mut app, LIMIT, all_settled);
    let library = app.world().resource::<ModelLibrary>();
    let entry = library.entries.iter().find(|e| e.name == "short-colours").unwrap();
    let ModelStatus::Failed(reason) = &entry.status else { panic!("loaded: {:?}", entry.status) };
    assert!(reason.contains("COLOR_0 has 2 elements but POSITION has 3"), "{reason}");
    let expected = voxel_core::load_file(&bad).unwrap_err().to_string();
    assert_eq!(reason, &expected, "the app names what the CLI names");
    assert!(entry.gltf == Handle::default(), "a file the core refuses is never handed to Bevy's loader");
    assert!(library.entries.iter().filter(|e| e.status == ModelStatus::Ready).count() >= 6);
    assert!(app.should_exit().is_none(), "the app goes on");
}

#[test]
fn a_start_index_past_the_list_is_an_error() {
    let mut app = test_app(AppArgs { start: 40, ..default() });
    app.update();
    assert_eq!(app.should_exit(), Some(AppExit::error()));
    let mut app = test_app(AppArgs { start: 2, ..default() });
    app.update();
    assert_eq!(app.should_exit(), None);
    assert_eq!(app.world().resource::<ModelLibrary>().current, 2);
}

#[test]
fn dropped_files_join_the_list_and_are_picked() {
    let mut app = test_app(AppArgs::default());
    app.update();
    let before = app.world().resource::<ModelLibrary>().entries.len();
    let copy = temp_file("dropped-egg.glb", &std::fs::read(shipped("fried-egg.glb")).unwrap());
    app.world_mut()
        .write_message(bevy::window::FileDragAndDrop::DroppedFile { window: Entity::PLACEHOLDER, path_buf: copy });
    run_until(&mut app, LIMIT, all_settled);
    let library = app.world().resource::<ModelLibrary>();
    assert_eq!(library.entries.len(), before + 1);
    assert_eq!(library.current, before);
    assert_eq!(library.entries[before].name, "dropped-egg");
    assert_eq!(library.entries[before].status, ModelStatus::Ready);
}

#[test]
fn a_parameter_change_revoxelizes_and_stale_results_are_dropped() {
    let mut app = test_app(AppArgs::default());
    run_until(&mut app, LIMIT, all_settled);
    let generation = |app: &App| app.world().resource::<VoxelizeGeneration>().0;
    let g0 = generation(&app);
    // Two changes in a row: the jobs of the first are stale before they finish.
    app.world_mut().resource_mut::<VoxelSettings>().grid_size = 0.3;
    app.update();
    app.world_mut().resource_mut::<VoxelSettings>().grid_size = 0.2;
    app.update();
    assert_eq!(generation(&app), g0 + 2);
    let latest = generation(&app);
    run_until(&mut app, LIMIT, |app| {
        app.world().resource::<ModelLibrary>().entries.iter().all(|e| e.voxels_generation == Some(latest))
    });
    // No job of an older generation survives.
    let mut jobs = app.world_mut().query::<&VoxelizeJob>();
    assert!(jobs.iter(app.world()).all(|j| j.generation == latest));
    let options = app_options(&app);
    let current = shown_model(&app).unwrap();
    let name = app.world().resource::<ModelLibrary>().current_entry().unwrap().name.clone();
    assert_eq!(current.stats, core_voxelize(&shipped(&format!("{name}.glb")), &options).stats);
    assert!((current.spec.cell[0] - 0.2).abs() < 1e-6);
    // The pool morphs to the new voxelization.
    crate::transition::settle(&mut app);
    let hollow = app.world().resource::<VoxelSettings>().hollow;
    assert_eq!(app.world().resource::<VoxelPool>().visible, current.shown_count(hollow));
    crate::transition::assert_shows_model(&mut app);
}

/// Presses the left button, waits `hold` frames (1/60 s each), releases.
fn click(app: &mut App, hold: usize, drag: f32) {
    let window =
        app.world_mut().query_filtered::<Entity, With<bevy::window::PrimaryWindow>>().single(app.world()).unwrap();
    let set_cursor = |app: &mut App, x: f32| {
        app.world_mut().get_mut::<Window>(window).unwrap().set_cursor_position(Some(Vec2::new(x, 300.0)));
    };
    set_cursor(app, 640.0);
    app.world_mut().resource_mut::<ButtonInput<MouseButton>>().press(MouseButton::Left);
    app.update();
    app.world_mut().resource_mut::<ButtonInput<MouseButton>>().clear();
    for _ in 0..hold {
        set_cursor(app, 640.0 + drag);
        app.update();
    }
    app.world_mut().resource_mut::<ButtonInput<MouseButton>>().release(MouseButton::Left);
    app.update();
    app.world_mut().resource_mut::<ButtonInput<MouseButton>>().clear();
    app.update();
}

#[test]
fn a_short_click_on_the_stage_shows_the_next_model_but_a_hold_or_drag_does_not() {
    let mut app = test_app(AppArgs::default());
    app.world_mut().spawn((Window::default(), bevy::window::PrimaryWindow));
    app.update();
    let current = |app: &App| app.world().resource::<ModelLibrary>().current;
    click(&mut app, 3, 0.0);
    assert_eq!(current(&app), 1, "a short click goes to the next model");
    click(&mut app, 40, 0.0);
    assert_eq!(current(&app), 1, "a long press orbits instead");
    click(&mut app, 3, 40.0);
    assert_eq!(current(&app), 1, "a drag orbits instead");
    app.world_mut().resource_mut::<voxel_art::input::PointerOverUi>().panel = true;
    click(&mut app, 3, 0.0);
    assert_eq!(current(&app), 1, "clicks on the panel do not reach the stage");
}

#[test]
fn per_voxel_systems_get_every_core_and_small_machines_run_schedules_on_one_thread() {
    let _app = test_app(AppArgs { no_shipped: true, ..Default::default() });
    let cores = bevy::tasks::available_parallelism();
    // With one compute thread Bevy's `par_iter` runs sequentially; the app's pool has one per core.
    assert!(
        bevy::tasks::ComputeTaskPool::get().thread_num() >= cores,
        "{} compute threads on {cores} cores",
        bevy::tasks::ComputeTaskPool::get().thread_num()
    );
    let mut fresh = App::new();
    fresh.add_plugins(MinimalPlugins.set(voxel_art::threads::task_pools()));
    let switched = voxel_art::threads::choose_executor(&mut fresh);
    if voxel_art::threads::single_threaded(cores) {
        assert!(switched >= 5, "only {switched} schedules switched to the single-threaded executor");
    } else {
        assert_eq!(switched, 0);
    }
}

#[test]
fn no_two_systems_that_share_data_run_in_an_undefined_order() {
    use bevy::ecs::schedule::{LogLevel, ScheduleBuildSettings, Schedules};
    use voxel_art::style::Style;
    let mut app = test_app(AppArgs { no_shipped: true, ..Default::default() });
    let strict = ScheduleBuildSettings { ambiguity_detection: LogLevel::Error, ..Default::default() };
    // The app's schedules (Bevy's own, such as StateTransition, order their systems by other means).
    let mut checked = Vec::new();
    for (label, schedule) in app.world_mut().resource_mut::<Schedules>().iter_mut() {
        let name = format!("{label:?}");
        if ["Update", "FixedUpdate", "Startup"].contains(&name.as_str()) || name.starts_with("On") {
            schedule.set_build_settings(strict.clone());
            checked.push(name);
        }
    }
    assert!(checked.len() >= 3 + 2 * 2, "schedules checked: {checked:?}");
    // Running builds each schedule (an ambiguity panics with the systems and what they share); every style is
    // entered and left once, so their OnEnter/OnExit schedules run too.
    for style in Style::ALL.into_iter().chain([Style::RoundedBoxes]) {
        app.world_mut().resource_mut::<NextState<Style>>().set(style);
        app.update();
        app.update();
    }
}

#[test]
fn the_pointer_acts_on_the_stage_only_once_it_has_moved_there() {
    use voxel_art::input::{PointerMode, StagePointer};
    let (centre, beside) = (Some(Vec2::new(640.0, 360.0)), Some(Vec2::new(700.0, 360.0)));
    let mut pointer = StagePointer::default();
    for _ in 0..30 {
        pointer.observe(PointerMode::AfterMove, centre, false);
        assert!(!pointer.active, "a pointer sitting where the window opened acts");
    }
    pointer.observe(PointerMode::AfterMove, beside, true);
    assert!(!pointer.active, "a move over the panel does not count");
    pointer.observe(PointerMode::AfterMove, None, false);
    assert!(!pointer.active);
    pointer.observe(PointerMode::AfterMove, beside, false);
    assert!(pointer.active, "a move over the stage counts");
    pointer.observe(PointerMode::AfterMove, centre, false);
    assert!(pointer.active, "and keeps counting");
    let mut never = StagePointer::default();
    let mut always = StagePointer::default();
    for cursor in [centre, beside, centre] {
        never.observe(PointerMode::Never, cursor, false);
        always.observe(PointerMode::Always, cursor, false);
        assert!(!never.active && always.active);
    }

    // In the app: the window's pointer starts at its centre and only counts once moved.
    let mut app = test_app(AppArgs { no_shipped: true, ..Default::default() });
    let mut window = Window::default();
    window.set_cursor_position(centre);
    let window = app.world_mut().spawn((window, bevy::window::PrimaryWindow)).id();
    for _ in 0..10 {
        app.update();
    }
    assert!(!app.world().resource::<StagePointer>().active);
    app.world_mut().get_mut::<Window>(window).unwrap().set_cursor_position(beside);
    app.update();
    assert!(app.world().resource::<StagePointer>().active);

    // Screenshots ignore the pointer unless asked for it.
    let shot = |repel| {
        let app = test_app(AppArgs { no_shipped: true, screenshot: Some("x.png".into()), repel, ..Default::default() });
        *app.world().resource::<PointerMode>()
    };
    assert_eq!(shot(false), PointerMode::Never);
    assert_eq!(shot(true), PointerMode::Always);
    assert_eq!(*app.world().resource::<PointerMode>(), PointerMode::AfterMove);
}
