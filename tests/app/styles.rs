//! Styles: falling piles, mouse repel, bubbles bursting and re-forming, Lego's taller cells.

use std::time::Duration;

use bevy::prelude::*;
use voxel_art::config::AppArgs;
use voxel_art::instancing::{GpuSprings, GpuVoxels, VoxelPool};
use voxel_art::library::LibraryRequest;
use voxel_art::settings::{RepelSettings, VoxelSettings};
use voxel_art::style::CursorRay;
use voxel_art::style::Style;
use voxel_art::style::bubbles::{BubbleSettings, BubbleState, Bubbles};
use voxel_art::style::falling::FallingPile;

use crate::harness::{all_settled, drawn, looks, run_until, test_app, turn};
use crate::logic::shown_model;
use crate::transition::{assert_shows_model, settle};

/// A settled app showing the cherry (index 2).
fn cherry_app() -> App {
    let mut app = test_app(AppArgs::default());
    run_until(&mut app, Duration::from_secs(60), all_settled);
    // Settle first: a switch mid-spin would make the model's final angle depend on load timing.
    settle(&mut app);
    app.world_mut().write_message(LibraryRequest::Select(2));
    settle(&mut app);
    app
}

/// Asks for `style` (it is entered at the next update's state transition).
fn set_style(app: &mut App, style: Style) {
    app.world_mut().resource_mut::<NextState<Style>>().set(style);
}

/// World position of a slot's home cell.
fn home_world(app: &mut App, slot: usize) -> Vec3 {
    turn(app).rotation * app.world().resource::<VoxelPool>().slots[slot].home.position
}

/// World position of a slot's voxel now.
fn translation(app: &mut App, slot: usize) -> Vec3 {
    app.world().resource::<GpuVoxels>().items[slot].position()
}

fn drop_pile(seed_runs: usize) -> Vec<Vec3> {
    let mut app = cherry_app();
    for _ in 0..seed_runs {
        app.update();
    }
    set_style(&mut app, Style::Falling);
    for _ in 0..3 {
        app.update();
    }
    assert!(app.world().get_resource::<FallingPile>().is_some(), "the voxels let go");
    // Ten simulated seconds: 600 steps of 1/60 s.
    while app.world().resource::<FallingPile>().pile.steps < 600 {
        app.update();
    }
    let pile = app.world().resource::<FallingPile>().pile.clone();
    assert!(pile.max_speed() < 0.05, "still moving at {}", pile.max_speed());
    let floor = pile.params.floor + pile.params.radius;
    assert!(pile.positions.iter().all(|p| p.y >= floor - 1e-4), "a voxel sank below the floor");
    let size = {
        let model = shown_model(&app).unwrap();
        model.spec.cell[0] * app.world().resource::<VoxelSettings>().box_size
    };
    assert!(pile.max_overlap(size) < 0.05, "voxels overlap by {} of a cell", pile.max_overlap(size));
    // Every solid voxel fell, the interior a hollow display hides included: a heap, not a one-voxel splash.
    let stats = shown_model(&app).unwrap().stats;
    assert_eq!(pile.positions.len(), stats.voxels, "the pile has the model's volume");
    assert!(stats.voxels > stats.visible, "the cherry has an interior");
    let top = pile.positions.iter().map(|p| p.y).fold(floor, f32::max) - floor;
    assert!(top > 2.0 * size, "the heap is {top} high, {} cells", top / size);
    // The pile lies under the model.
    let model = shown_model(&app).unwrap();
    let turn = turn(&app).rotation;
    let model_com = model.voxels().map(|v| turn * Vec3::from(model.center(&v))).sum::<Vec3>() / model.len() as f32;
    let pile_com = pile.positions.iter().sum::<Vec3>() / pile.positions.len() as f32;
    let sideways = Vec2::new(pile_com.x - model_com.x, pile_com.z - model_com.z).length();
    assert!(sideways < 1.0, "the pile's centre is {sideways} from under the model's");
    assert!(pile_com.y < model_com.y);
    // Drawn where simulated.
    let falling = app.world().resource::<FallingPile>().voxels.clone();
    assert_eq!(falling.len(), pile.positions.len(), "a body per voxel below the cap");
    for v in falling {
        assert!(translation(&mut app, v.slot as usize).distance(pile.positions[v.body as usize]) < 1e-5);
    }
    // F calls them back to their cells.
    app.world_mut().resource_mut::<ButtonInput<KeyCode>>().press(KeyCode::KeyF);
    app.update();
    app.world_mut().resource_mut::<ButtonInput<KeyCode>>().clear();
    settle(&mut app);
    assert!(app.world().get_resource::<FallingPile>().is_none());
    assert_shows_model(&mut app);
    pile.positions.clone()
}

#[test]
fn falling_voxels_pile_up_at_rest_and_reassemble() {
    let first = drop_pile(0);
    let again = drop_pile(0);
    assert_eq!(first, again, "the same seed gives the same pile");
}

/// Voxels in the chunks uploaded for the last frame: (looks, springs).
fn uploaded(app: &App) -> (usize, usize) {
    let count = |ranges: &[(usize, usize)]| ranges.iter().map(|(start, end)| end - start).sum();
    let world = app.world();
    (count(world.resource::<GpuVoxels>().dirty_ranges()), count(world.resource::<GpuSprings>().dirty_ranges()))
}

/// Where the GPU draws a slot's voxel this frame.
fn drawn_at(app: &App, slot: usize) -> Vec3 {
    drawn(app)[slot].position()
}

#[test]
fn repel_pushes_voxels_off_the_cursor_ray_and_they_spring_back() {
    let mut app = cherry_app();
    let (radius, strength) = {
        let s = app.world().resource::<RepelSettings>();
        (s.radius, s.strength)
    };
    let target = home_world(&mut app, 0);
    let far_slot = (0..app.world().resource::<VoxelPool>().visible)
        .max_by(|a, b| home_world(&mut app, *a).distance(target).total_cmp(&home_world(&mut app, *b).distance(target)))
        .unwrap();
    let far_before = drawn_at(&app, far_slot);
    app.insert_resource(CursorRay(Some(Ray3d::new(target + Vec3::Z * 20.0, Dir3::NEG_Z))));
    app.update();
    assert_eq!(uploaded(&app).0, 0, "repel rewrote looks");
    assert!(uploaded(&app).1 > 0, "pushed voxels' springs were not uploaded");
    for _ in 0..59 {
        app.update();
    }
    assert_eq!(uploaded(&app), (0, 0), "voxels held by a still cursor still rewritten every frame");
    let pushed = drawn_at(&app, 0).distance(target);
    assert!(pushed >= 0.9 * radius * strength, "pushed {pushed}, expected about {}", radius * strength);
    assert_eq!(drawn_at(&app, far_slot), far_before, "a far voxel moved");
    // Let go: the springs are written once, then the GPU brings the voxels home.
    app.insert_resource(CursorRay(None));
    app.update();
    assert!(uploaded(&app).1 > 0, "let-go voxels' springs were not uploaded");
    let on_the_way = drawn_at(&app, 0).distance(target);
    assert!(on_the_way > 0.5 * pushed, "jumped home: {on_the_way} of {pushed}");
    for _ in 0..120 {
        app.update();
        assert_eq!(uploaded(&app), (0, 0), "voxels on their way home rewritten");
    }
    let shown: Vec<(usize, Vec3)> =
        drawn(&app).iter().enumerate().filter(|(_, v)| v.shows()).map(|(s, v)| (s, v.position())).collect();
    for (slot, at) in shown {
        let home = home_world(&mut app, slot);
        assert!(at.distance(home) < 1e-3, "slot {slot} did not spring back ({})", at.distance(home));
    }
}

#[test]
fn a_burst_bubble_vanishes_and_reforms_at_its_cell() {
    let mut app = cherry_app();
    app.world_mut().resource_mut::<RepelSettings>().enabled = false;
    set_style(&mut app, Style::Bubbles);
    for _ in 0..3 {
        app.update();
    }
    let timing = app.world().resource::<BubbleSettings>().clone();
    let state = |app: &mut App| (app.world().resource::<Bubbles>().0[0].state, looks(app)[0].shows());
    assert_eq!(state(&mut app).0, BubbleState::Whole);
    let at = home_world(&mut app, 0);
    app.insert_resource(CursorRay(Some(Ray3d::new(at + Vec3::Z * 20.0, Dir3::NEG_Z))));
    app.update();
    app.insert_resource(CursorRay(None));
    assert!(matches!(state(&mut app).0, BubbleState::Bursting(_)));
    let burst_frames = (timing.burst * 60.0).ceil() as usize + 2;
    for _ in 0..burst_frames {
        app.update();
    }
    let (s, visibility) = state(&mut app);
    assert!(matches!(s, BubbleState::Gone(_)), "{s:?}");
    assert!(!visibility, "a burst bubble shows");
    let back_frames = ((timing.reform_max + timing.form) * 60.0).ceil() as usize + 2;
    for _ in 0..back_frames {
        app.update();
    }
    let (s, visibility) = state(&mut app);
    assert_eq!(s, BubbleState::Whole, "re-formed within the configured delay");
    assert!(visibility, "a re-formed bubble is hidden");
    let cell = app.world().resource::<VoxelSettings>().grid_size;
    let drift = translation(&mut app, 0).distance(home_world(&mut app, 0));
    assert!(drift < cell, "the bubble wobbles around its cell ({drift})");
}

#[test]
fn lego_uses_taller_cells_and_morphs_in_and_out() {
    let mut app = cherry_app();
    set_style(&mut app, Style::Lego);
    run_until(&mut app, Duration::from_secs(60), |app| {
        shown_model(app).is_some_and(|m| (m.spec.cell[1] / m.spec.cell[0] - 1.2).abs() < 1e-5)
    });
    settle(&mut app);
    assert_shows_model(&mut app);
    let model = shown_model(&app).unwrap();
    assert!((model.spec.cell[1] / model.spec.cell[0] - 1.2).abs() < 1e-5);
    set_style(&mut app, Style::RoundedBoxes);
    run_until(&mut app, Duration::from_secs(60), |app| {
        shown_model(app).is_some_and(|m| m.spec.cell[1] == m.spec.cell[0])
    });
    settle(&mut app);
    assert_shows_model(&mut app);
}

/// The vertex count of the mesh every voxel shares.
fn pool_mesh_vertices(app: &App) -> Option<usize> {
    let assets = app.world().get_resource::<voxel_art::instancing::VoxelAssets>()?;
    app.world().resource::<Assets<Mesh>>().get(&assets.mesh).map(Mesh::count_vertices)
}

#[test]
fn the_pool_wears_the_style_mesh_from_the_start_and_after_a_switch() {
    use voxel_art::style::style_mesh;
    let vertices = |style: Style| style_mesh(style, VoxelSettings::default().roundness).count_vertices();
    assert_ne!(vertices(Style::Lego), vertices(Style::RoundedBoxes));
    assert_ne!(vertices(Style::Bubbles), vertices(Style::RoundedBoxes));
    let mut app = test_app(AppArgs { style: Some(Style::Lego), no_shipped: true, ..Default::default() });
    for _ in 0..3 {
        app.update();
    }
    assert_eq!(*app.world().resource::<State<Style>>().get(), Style::Lego);
    assert_eq!(pool_mesh_vertices(&app), Some(vertices(Style::Lego)), "started with --style lego: bricks");
    set_style(&mut app, Style::Bubbles);
    app.update();
    assert_eq!(pool_mesh_vertices(&app), Some(vertices(Style::Bubbles)));
    set_style(&mut app, Style::RoundedBoxes);
    app.update();
    assert_eq!(pool_mesh_vertices(&app), Some(vertices(Style::RoundedBoxes)));
}

/// (slots with a bubble, all slots).
fn bubbles_on_slots(app: &App) -> (usize, usize) {
    let bubbles = app.world().get_resource::<Bubbles>().map_or(0, |b| b.0.len());
    (bubbles, app.world().resource::<VoxelPool>().slots.len())
}

/// Slots in the falling pile.
fn falling(app: &App) -> usize {
    app.world().resource::<VoxelPool>().slots.iter().filter(|s| s.falling).count()
}

#[test]
fn bubbles_come_on_entering_the_style_and_leave_every_voxel_on_its_cell() {
    let mut app = cherry_app();
    app.world_mut().resource_mut::<RepelSettings>().enabled = false;
    set_style(&mut app, Style::Bubbles);
    app.update();
    let (bubbles, voxels) = bubbles_on_slots(&app);
    assert!(voxels > 500 && bubbles == voxels, "{bubbles} bubbles on {voxels} voxels");
    // Burst the bubbles under the cursor and let the rest wobble off their cells.
    let at = home_world(&mut app, 0);
    app.insert_resource(CursorRay(Some(Ray3d::new(at + Vec3::Z * 20.0, Dir3::NEG_Z))));
    for _ in 0..12 {
        app.update();
    }
    app.insert_resource(CursorRay(None));
    let hidden = {
        let pool = app.world().resource::<VoxelPool>().visible;
        looks(&app)[..pool].iter().filter(|v| !v.shows()).count()
    };
    assert!(hidden > 0, "no bubble burst");
    assert!(translation(&mut app, 1).distance(home_world(&mut app, 1)) > 1e-3, "bubbles do not wobble");
    set_style(&mut app, Style::RoundedBoxes);
    app.update();
    assert_eq!(bubbles_on_slots(&app).0, 0, "bubbles left behind");
    // Every voxel is back on its cell, shown, at its size.
    assert_shows_model(&mut app);
}

#[test]
fn falling_lets_go_on_entering_the_style_and_reassembles_on_leaving() {
    let mut app = cherry_app();
    set_style(&mut app, Style::Falling);
    for _ in 0..3 {
        app.update();
    }
    let solid = shown_model(&app).unwrap().stats.voxels;
    assert_eq!(falling(&app), solid, "every solid voxel falls");
    for _ in 0..60 {
        app.update();
    }
    set_style(&mut app, Style::Lego);
    app.update();
    assert!(app.world().get_resource::<FallingPile>().is_none(), "the pile outlived the style");
    assert_eq!(falling(&app), 0);
    run_until(&mut app, Duration::from_secs(60), |app| {
        shown_model(app).is_some_and(|m| (m.spec.cell[1] / m.spec.cell[0] - 1.2).abs() < 1e-5)
    });
    settle(&mut app);
    assert_shows_model(&mut app);
}
