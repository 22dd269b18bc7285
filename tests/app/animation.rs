//! Animated models in the app: the Fox (skinned) plays its clips live as voxels, the pose is the core's, cells
//! that stay keep their voxel, one pose job at a time, pause, clip picking; a static model has no animation.

use std::collections::{HashMap, HashSet};
use std::time::Duration;

use bevy::prelude::*;
use voxel_art::animation::{AnimationRequest, CellSlots, PoseJob};
use voxel_art::config::AppArgs;
use voxel_art::instancing::VoxelPool;
use voxel_art::library::LibraryRequest;
use voxel_art::model::{ModelLibrary, Playback, VoxelModelAsset};
use voxel_art::settings::VoxelSettings;
use voxel_art::style::Style;
use voxel_art::style::falling::FallingPile;
use voxel_art::transition::ActiveTransition;

use crate::common::models_dir;
use crate::harness::{all_settled, app_options, flights, looks, run_until, test_app};

const LIMIT: Duration = Duration::from_secs(120);

/// The Fox (and any `more` corpus files), without the shipped models.
fn fox_app(args: AppArgs, more: &[&str]) -> Option<App> {
    let dir = models_dir()?;
    let mut models = vec![dir.join("khronos-fox.glb")];
    models.extend(more.iter().map(|m| dir.join(m)));
    Some(test_app(AppArgs { models, no_shipped: true, ..args }))
}

fn playback(app: &App) -> &Playback {
    app.world().resource::<ModelLibrary>().entries[0].animation.as_ref().expect("the Fox is animated")
}

/// The Fox's pose asset, once it is placed.
fn pose(app: &App) -> Option<VoxelModelAsset> {
    let handle = playback(app).pose.clone()?;
    app.world().resource::<Assets<VoxelModelAsset>>().get(&handle).cloned()
}

/// Whether the Fox's pose is laid out: shown, no morph running, every placed pose applied.
fn following(app: &App) -> bool {
    let slots = app.world().resource::<CellSlots>();
    let shown = app.world().resource::<VoxelPool>().shown;
    slots.model().is_some()
        && slots.model() == shown
        && !slots.is_stale()
        && app.world().resource::<ActiveTransition>().running.is_none()
}

/// The cells shown (centre bits) and the pool slot showing each.
fn shown_cells(app: &App) -> HashMap<[u32; 3], usize> {
    let slots = app.world().resource::<CellSlots>();
    slots.cells().map(|(p, slot)| (p.to_array().map(f32::to_bits), slot as usize)).collect()
}

/// The cells of a model as shown (centre bits).
fn model_cells(model: &VoxelModelAsset, hollow: bool) -> HashSet<[u32; 3]> {
    model.shown(hollow).map(|v| model.center(&v).map(f32::to_bits)).collect()
}

/// Steps until the pose placed last differs from `before` and is laid out.
fn next_pose(app: &mut App, before: &HashMap<[u32; 3], usize>) -> HashMap<[u32; 3], usize> {
    let mut after = HashMap::new();
    run_until(app, LIMIT, |app| {
        if !following(app) {
            return false;
        }
        after = shown_cells(app);
        after.keys().collect::<HashSet<_>>() != before.keys().collect::<HashSet<_>>()
    });
    after
}

#[test]
fn the_fox_loads_as_animated_with_its_clips_and_a_static_model_has_no_animation() {
    let Some(mut app) = fox_app(AppArgs::default(), &["khronos-duck.glb"]) else { return };
    run_until(&mut app, LIMIT, |app| following(app));
    let p = playback(&app);
    let names: Vec<&str> = p.clips.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["Survey", "Walk", "Run"]);
    assert_eq!((p.clip, p.playing, p.speed), (0, true, 1.0));
    assert!(p.clips.iter().all(|c| c.duration > 0.5 && c.channels > 0), "{:?}", p.clips);
    let library = app.world().resource::<ModelLibrary>();
    let duck = &library.entries[1];
    assert!(duck.animation.is_none(), "the Duck has no clips, so no animation state");
    assert_eq!(duck.shown_handle(), duck.voxels.as_ref(), "a static model shows its voxelization");
    // The Fox shows its pose, not the rest voxelization the import made.
    let fox = &library.entries[0];
    assert_eq!(app.world().resource::<VoxelPool>().shown, fox.shown_handle().map(|h| h.id()));
    assert_ne!(fox.shown_handle(), fox.voxels.as_ref());
}

#[test]
fn the_pose_shown_is_the_cores_pose_in_the_clips_grid() {
    let args = AppArgs { clip: Some("Run".into()), anim_time: vec![0.4], ..default() };
    let Some(mut app) = fox_app(args, &[]) else { return };
    run_until(&mut app, LIMIT, |app| following(app));
    let p = playback(&app);
    assert_eq!((p.clip, p.playing), (2, false), "--clip Run --anim-time pauses the Run clip");
    let time = p.time;
    // The pose shown is the frame --anim-time falls in (30 poses a second).
    let frame_time = (time * 30.0).floor() / 30.0;
    let mut core = voxel_core::load_animated_file(&models_dir().unwrap().join("khronos-fox.glb")).unwrap();
    let bounds = core.clip_bounds(2).unwrap();
    let mut soup = voxel_core::TriangleSoup::default();
    core.pose_into(2, frame_time, &mut soup).unwrap();
    let expected = voxel_core::voxelize_within(&soup, &app_options(&app), bounds).unwrap();
    let shown = pose(&app).unwrap();
    assert_eq!(shown.spec, expected.spec);
    assert_eq!(shown.stats, expected.stats);
    assert!(shown.voxels().eq(expected.voxels()), "other cells or colours than the core's pose");
    // The voxels on screen are exactly the pose's cells.
    let hollow = app.world().resource::<VoxelSettings>().hollow;
    let cells = shown_cells(&app);
    assert_eq!(cells.keys().copied().collect::<HashSet<_>>(), model_cells(&shown, hollow));
    let pool = app.world().resource::<VoxelPool>();
    let looks = looks(&app);
    for (key, slot) in cells {
        assert_eq!(pool.slots[slot].home.position, Vec3::from_array(key.map(f32::from_bits)));
        assert!(looks[slot].shows(), "slot {slot} of a cell hidden");
    }
}

#[test]
fn new_poses_change_cells_in_one_grid_and_cells_that_stay_keep_their_voxel() {
    let Some(mut app) = fox_app(AppArgs { clip: Some("Run".into()), ..default() }, &[]) else { return };
    run_until(&mut app, LIMIT, |app| following(app));
    let spec = pose(&app).unwrap().spec;
    let handle = playback(&app).pose.clone().unwrap();
    let first = shown_cells(&app);
    let second = next_pose(&mut app, &first);
    let after = pose(&app).unwrap();
    assert_eq!(after.spec, spec, "the grid stays the clip's");
    assert_eq!(playback(&app).pose.as_ref(), Some(&handle), "the pose is updated in place (no morph)");
    let hollow = app.world().resource::<VoxelSettings>().hollow;
    assert_eq!(second.keys().copied().collect::<HashSet<_>>(), model_cells(&after, hollow));
    let stayed: Vec<_> = first.keys().filter(|k| second.contains_key(*k)).collect();
    let (appeared, emptied) = (
        second.keys().filter(|k| !first.contains_key(*k)).count(),
        first.keys().filter(|k| !second.contains_key(*k)).count(),
    );
    assert!(stayed.len() > first.len() / 2, "{} of {} cells stayed", stayed.len(), first.len());
    assert!(appeared + emptied > 0);
    for k in stayed {
        assert_eq!(first[k], second[k], "a cell filled in both poses changed its voxel");
    }
    // Every cell shown has its own voxel, and a voxel that left its cell is vacant (after its pop-out).
    let used: HashSet<usize> = second.values().copied().collect();
    assert_eq!(used.len(), second.len());
    let pool = app.world().resource::<VoxelPool>();
    let vacant: Vec<usize> = (0..pool.slots.len()).filter(|s| pool.slots[*s].vacant).collect();
    assert!(vacant.iter().all(|s| !used.contains(s)));
    assert!(vacant.len() >= emptied.saturating_sub(appeared), "{} vacant, {emptied} emptied", vacant.len());
}

#[test]
fn at_most_one_pose_job_runs_and_poses_keep_coming_until_paused() {
    let Some(mut app) = fox_app(AppArgs::default(), &[]) else { return };
    run_until(&mut app, LIMIT, |app| following(app));
    let mut most = 0;
    for _ in 0..90 {
        app.update();
        std::thread::sleep(Duration::from_millis(2));
        let mut jobs = app.world_mut().query::<&PoseJob>();
        most = most.max(jobs.iter(app.world()).filter(|j| j.entry == 0).count());
    }
    assert_eq!(most, 1, "one pose job at a time");
    let counts = playback(&app).counts;
    assert!(counts.placed >= 10, "{counts:?}");
    assert!(counts.requested >= counts.placed + counts.dropped, "{counts:?}");
    // Pause: once the last job is in, nothing changes any more.
    app.world_mut().write_message(AnimationRequest::Play(false));
    run_until(&mut app, LIMIT, |app| {
        let mut jobs = app.world_mut().query::<&PoseJob>();
        jobs.iter(app.world()).next().is_none() && following(app)
    });
    let (time, counts, cells) = (playback(&app).time, playback(&app).counts, shown_cells(&app));
    for _ in 0..60 {
        app.update();
    }
    let p = playback(&app);
    assert_eq!((p.time, p.counts), (time, counts), "paused: time and poses stand still");
    assert_eq!(shown_cells(&app), cells);
    app.world_mut().write_message(AnimationRequest::TogglePlay);
    next_pose(&mut app, &cells);
    assert!(playback(&app).playing && playback(&app).time != time);
}

#[test]
fn picking_a_clip_by_index_plays_it_in_its_own_grid() {
    let Some(mut app) = fox_app(AppArgs::default(), &[]) else { return };
    run_until(&mut app, LIMIT, |app| following(app));
    let survey = pose(&app).unwrap().spec;
    app.world_mut().write_message(AnimationRequest::Clip(2));
    app.update();
    assert_eq!((playback(&app).clip, playback(&app).playing), (2, true));
    run_until(&mut app, LIMIT, |app| following(app) && pose(app).is_some_and(|p| p.spec != survey));
    let mut core = voxel_core::load_animated_file(&models_dir().unwrap().join("khronos-fox.glb")).unwrap();
    let bounds = core.clip_bounds(2).unwrap();
    let mut soup = voxel_core::TriangleSoup::default();
    core.pose_into(2, 0.0, &mut soup).unwrap();
    let run = voxel_core::voxelize_within(&soup, &app_options(&app), bounds).unwrap();
    assert_eq!(pose(&app).unwrap().spec, run.spec, "the Run clip's grid");
    // A clip that does not exist changes nothing.
    app.world_mut().write_message(AnimationRequest::Clip(3));
    app.update();
    assert_eq!(playback(&app).clip, 2);
}

#[test]
fn a_morph_to_another_model_starts_from_the_current_pose() {
    let Some(mut app) = fox_app(AppArgs { clip: Some("Run".into()), ..default() }, &["khronos-duck.glb"]) else {
        return;
    };
    run_until(&mut app, LIMIT, |app| following(app) && all_settled(app));
    let cells = shown_cells(&app);
    app.world_mut().write_message(LibraryRequest::Select(1));
    app.update();
    // Every voxel of the pose takes off from its cell (the morph plans from where the voxels are).
    let from: HashMap<usize, Vec3> = flights(&app).into_iter().map(|(s, t)| (s, t.from)).collect();
    assert!(from.len() >= cells.len(), "{} flights for {} cells", from.len(), cells.len());
    for (cell, slot) in &cells {
        let home = Vec3::from_array(cell.map(f32::from_bits));
        assert!(from[slot].distance(home) < 1e-4, "a voxel of the pose started away from its cell");
    }
}

#[test]
fn falling_drops_the_pose_and_reassembles_into_the_playing_model() {
    let Some(mut app) = fox_app(AppArgs::default(), &[]) else { return };
    run_until(&mut app, LIMIT, |app| following(app));
    app.world_mut().resource_mut::<NextState<Style>>().set(Style::Falling);
    run_until(&mut app, LIMIT, |app| app.world().get_resource::<FallingPile>().is_some());
    let placed = playback(&app).counts.placed;
    let cells = shown_cells(&app);
    for _ in 0..60 {
        app.update();
        std::thread::sleep(Duration::from_millis(2));
    }
    assert!(playback(&app).counts.placed > placed, "the animation plays on while the voxels lie in the pile");
    assert_eq!(shown_cells(&app), cells, "no pose is laid out while the pool is held");
    app.world_mut().resource_mut::<NextState<Style>>().set(Style::RoundedBoxes);
    run_until(&mut app, LIMIT, |app| app.world().get_resource::<FallingPile>().is_none() && following(app));
    // Back together in the latest pose (a pose placed during the morph is applied once it lands).
    let latest = pose(&app).unwrap();
    let hollow = app.world().resource::<VoxelSettings>().hollow;
    assert_eq!(shown_cells(&app).keys().copied().collect::<HashSet<_>>(), model_cells(&latest, hollow));
}

#[test]
fn in_lego_and_bubbles_exactly_the_cells_show() {
    let Some(mut app) = fox_app(AppArgs { clip: Some("Run".into()), ..default() }, &[]) else { return };
    run_until(&mut app, LIMIT, |app| following(app));
    for style in [Style::Lego, Style::Bubbles] {
        app.world_mut().resource_mut::<NextState<Style>>().set(style);
        app.world_mut().write_message(AnimationRequest::Play(true));
        let placed = playback(&app).counts.placed;
        // Lego voxelizes with taller cells: a new grid, so a morph, then the poses flow again.
        run_until(&mut app, LIMIT, |app| following(app) && playback(app).counts.placed > placed + 10);
        let cell = pose(&app).unwrap().spec.cell;
        assert_eq!(cell[1] / cell[0] > 1.1, style == Style::Lego, "{style:?}: cell {cell:?}");
        // Pause, let the last pops land, and give the style's placement some frames.
        app.world_mut().write_message(AnimationRequest::Play(false));
        run_until(&mut app, LIMIT, |app| {
            let mut jobs = app.world_mut().query_filtered::<(), With<PoseJob>>();
            jobs.iter(app.world()).next().is_none() && flights(app).is_empty() && following(app)
        });
        for _ in 0..30 {
            app.update();
        }
        let cells = shown_cells(&app);
        let looks = looks(&app);
        for slot in cells.values() {
            assert!(looks[*slot].shows(), "{style:?}: a cell hidden");
        }
        let showing = looks.iter().filter(|v| v.shows()).count();
        assert_eq!(showing, cells.len(), "{style:?}: voxels showing besides the cells (a vacant slot?)");
    }
}

#[test]
fn the_morph_cube_shows_its_weights_pose() {
    let Some(dir) = models_dir() else { return };
    let path = dir.join("khronos-animatedmorphcube/AnimatedMorphCube.gltf");
    let args = AppArgs { models: vec![path.clone()], no_shipped: true, anim_time: vec![1.0], ..default() };
    let mut app = test_app(args);
    run_until(&mut app, LIMIT, |app| following(app));
    let mut core = voxel_core::load_animated_file(&path).unwrap();
    let bounds = core.clip_bounds(0).unwrap();
    let mut soup = voxel_core::TriangleSoup::default();
    core.pose_into(0, 1.0, &mut soup).unwrap();
    let expected = voxel_core::voxelize_within(&soup, &app_options(&app), bounds).unwrap();
    let shown = pose(&app).unwrap();
    assert_eq!((shown.spec, shown.stats), (expected.spec, expected.stats));
    assert!(shown.voxels().eq(expected.voxels()), "other cells or colours than the core's pose");
    let hollow = app.world().resource::<VoxelSettings>().hollow;
    assert_eq!(shown_cells(&app).keys().copied().collect::<HashSet<_>>(), model_cells(&shown, hollow));
}

/// A one-triangle .glb with a clip whose translation sampler has two keyframe times and one value.
fn broken_clip_glb() -> Vec<u8> {
    let bytes = |floats: &[f32]| floats.iter().flat_map(|f| f.to_le_bytes()).collect::<Vec<u8>>();
    let mut builder = voxel_core::glb::GlbBuilder::default();
    let triangle = builder.accessor(
        &bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
        serde_json::json!({"componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}),
    );
    let times = builder.accessor(
        &bytes(&[0.0, 1.0]),
        serde_json::json!({"componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1]}),
    );
    let values = builder
        .accessor(&bytes(&[2.0, 0.0, 0.0]), serde_json::json!({"componentType": 5126, "count": 1, "type": "VEC3"}));
    let primitive = serde_json::json!({"attributes": {"POSITION": triangle}, "material": 0});
    let (mut doc, bin) = builder.one_mesh("animation test", vec![primitive], serde_json::json!([{}]));
    doc["animations"] = serde_json::json!([{
        "name": "slide",
        "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}],
        "samplers": [{"input": times, "output": values}]
    }]);
    voxel_core::glb::pack_document(&doc, &bin).unwrap()
}

#[test]
fn an_animation_the_core_refuses_shows_the_model_still_with_a_warning_naming_why() {
    let file = crate::harness::temp_file("broken-clip.glb", &broken_clip_glb());
    let apple = crate::harness::shipped("apple.glb");
    let mut app = test_app(AppArgs { models: vec![file.clone(), apple], no_shipped: true, ..default() });
    run_until(&mut app, LIMIT, all_settled);
    let library = app.world().resource::<ModelLibrary>();
    let entry = &library.entries[0];
    assert_eq!(entry.status, voxel_art::model::ModelStatus::Ready, "the model still shows");
    assert!(entry.animation.is_none(), "no playback for a refused animation");
    let reason = voxel_core::load_animated_file(&file).unwrap_err().to_string();
    assert!(reason.contains("animation slide"), "{reason}");
    assert_eq!(entry.warning.as_deref(), Some(format!("the animation is ignored: {reason}").as_str()));
    assert_eq!(library.entries[1].warning, None, "a file without clips has nothing to warn about");
}
