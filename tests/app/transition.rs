//! Morphs: arrival, re-triggering mid-flight, rapid switching.

use std::collections::HashMap;
use std::time::Duration;

use bevy::prelude::*;
use voxel_art::config::AppArgs;
use voxel_art::instancing::VoxelTween;
use voxel_art::instancing::{VoxelCloud, VoxelPool, unpack_color};
use voxel_art::library::LibraryRequest;
use voxel_art::settings::VoxelSettings;
use voxel_art::transition::{ActiveTransition, TransitionFinished, TransitionSettings, layout};

use crate::harness::{all_settled, drawn, flights, looks, run_until, test_app, turn};
use crate::logic::shown_model;

/// Steps until no voxel carries a tween (at most 10 s of app time).
pub fn settle(app: &mut App) {
    for _ in 0..600 {
        app.update();
        let shown = app.world().resource::<VoxelPool>().shown;
        let wanted = shown_model(app).is_some() && shown.is_some();
        if wanted && flights(app).is_empty() && app.world().resource::<ActiveTransition>().running.is_none() {
            return;
        }
    }
    panic!("the transition never settled");
}

/// Checks every slot sits exactly on its cell of the shown model with its colour, spares hidden; returns the
/// number of hidden slots.
pub fn assert_shows_model(app: &mut App) -> usize {
    let model = shown_model(app).unwrap();
    let settings = app.world().resource::<VoxelSettings>().clone();
    let transition = app.world().resource::<TransitionSettings>().clone();
    let targets = layout(&model, &settings, &transition);
    let cloud = app.world_mut().query_filtered::<&Transform, With<VoxelCloud>>().single(app.world()).unwrap().rotation;
    let turn = turn(app);
    assert_eq!(cloud, turn.rotation, "the cloud turns with the voxels");
    let mut hidden = 0;
    for (slot, look) in looks(app).iter().enumerate() {
        match targets.get(slot) {
            Some(t) => {
                assert!(look.shows(), "slot {slot} hidden");
                let expected = turn.place(t.position, t.scale, 0);
                assert!(look.position().distance(expected.position()) < 1e-4, "slot {slot} not on its cell");
                assert!(look.scale().distance(t.scale) < 1e-5, "slot {slot} box {} for {}", look.scale(), t.scale);
                assert_eq!(look.x_axis, expected.x_axis, "slot {slot} turned");
                assert_eq!(unpack_color(look.color), t.color, "slot {slot} colour");
            }
            None => {
                assert!(!look.shows(), "spare slot {slot} shows");
                hidden += 1;
            }
        }
    }
    assert_eq!(app.world().resource::<VoxelPool>().visible, targets.len());
    hidden
}

fn ready_app() -> App {
    let mut app = test_app(AppArgs::default());
    run_until(&mut app, Duration::from_secs(60), all_settled);
    settle(&mut app);
    app
}

/// Positions of the visible voxels in the cloud's (model) frame, as drawn.
fn positions(app: &mut App) -> HashMap<usize, Vec3> {
    let turn = turn(app);
    drawn(app).iter().enumerate().filter(|(_, v)| v.shows()).map(|(s, v)| (s, turn.unturn(v.position()))).collect()
}

#[test]
fn after_the_longest_delay_and_duration_every_voxel_is_home() {
    let mut app = ready_app();
    app.init_resource::<Finished>();
    app.add_systems(Update, count_finished);
    // Drain the message of the start-up morph.
    app.update();
    app.update();
    app.world_mut().resource_mut::<Finished>().0 = 0;
    app.world_mut().write_message(LibraryRequest::Next);
    // Longest delay + duration + count: 0.2 + 1.2 + margin, at 60 frames a second.
    let t = app.world().resource::<TransitionSettings>().clone();
    let frames = ((t.max_delay + t.base_duration + t.extra_duration).max(t.count_duration) * 60.0).ceil() as usize + 3;
    let mut moving = 0;
    for k in 0..frames {
        app.update();
        if k == 20 {
            moving = flights(&app).len();
        }
    }
    assert!(moving > 100, "voxels were tweening mid-way ({moving})");
    assert_eq!(flights(&app).len(), 0, "finished tweens land");
    assert_shows_model(&mut app);
    assert_eq!(app.world().resource::<Finished>().0, 1, "TransitionFinished was sent once");
}

#[derive(Resource, Default)]
struct Finished(usize);

fn count_finished(mut messages: MessageReader<TransitionFinished>, mut finished: ResMut<Finished>) {
    finished.0 += messages.read().count();
}

#[test]
fn a_second_switch_half_way_starts_from_where_voxels_are() {
    let mut app = ready_app();
    app.world_mut().write_message(LibraryRequest::Next);
    for _ in 0..25 {
        app.update();
    }
    let before = positions(&mut app);
    let old_bounds: HashMap<usize, f32> = flights(&app).iter().map(|(s, t)| (*s, bound(t))).collect();
    app.world_mut().write_message(LibraryRequest::Next);
    app.update();
    let after = positions(&mut app);
    let new_bounds: HashMap<usize, f32> = flights(&app).iter().map(|(s, t)| (*s, bound(t))).collect();
    let dt = 1.0 / 60.0;
    assert!(after.len() > 500);
    for (slot, p) in after.iter().filter(|(slot, _)| before.contains_key(*slot)) {
        let jump = p.distance(before[slot]);
        let limit =
            old_bounds.get(slot).copied().unwrap_or(0.0).max(new_bounds.get(slot).copied().unwrap_or(0.0)) * dt + 1e-4;
        assert!(jump <= limit, "slot {slot} jumped {jump} (bound {limit})");
    }
    settle(&mut app);
    assert_eq!(app.world().resource::<voxel_art::model::ModelLibrary>().current, 2);
    assert_shows_model(&mut app);
}

/// The fastest a tween can move (units per second): back-out(s) starts at speed (s + 3) × distance / duration.
fn bound(t: &VoxelTween) -> f32 {
    (t.overshoot + 3.0) * t.from.distance(t.to) / t.duration
}

#[test]
fn rapid_switching_keeps_entities_and_tweens_bounded() {
    let mut app = ready_app();
    let entities_before = app.world().entities().count_spawned();
    for _ in 0..20 {
        app.world_mut().write_message(LibraryRequest::Next);
        app.update();
        app.update();
        let pool = app.world().resource::<VoxelPool>().slots.len();
        assert!(flights(&app).len() <= pool);
    }
    // Voxels are slots, not entities: switching spawns none (the two model-level tweens are replaced).
    assert_eq!(app.world().entities().count_spawned(), entities_before);
    settle(&mut app);
    assert_shows_model(&mut app);
}

#[test]
fn the_spin_and_the_visible_count_follow_their_model_level_tweens() {
    use voxel_art::transition::ModelTween;
    let mut app = ready_app();
    let t = app.world().resource::<TransitionSettings>().clone();
    let start_angle = app.world().resource::<ActiveTransition>().angle;
    let old = app.world().resource::<VoxelPool>().visible as f32;
    app.world_mut().write_message(LibraryRequest::Next);
    let frames = (t.spin_duration * 60.0).ceil() as usize + 2;
    for k in 1..=frames {
        // The transition starts in the first frame and every frame steps 1/60 s (speed 1).
        app.update();
        let s = k as f32 / 60.0;
        let active = app.world().resource::<ActiveTransition>();
        let u = (s / t.spin_duration).min(1.0);
        let angle = start_angle + t.spin_angle * u * (2.0 - u);
        assert!((active.angle - angle).abs() < 1e-4, "frame {k}: angle {} instead of {angle}", active.angle);
        let new = app.world().resource::<VoxelPool>().visible as f32;
        let count = old + (new - old) * (s / t.count_duration).min(1.0);
        assert!((active.shown - count).abs() < 0.01 * (new - old).abs() + 1.0, "frame {k}: count {}", active.shown);
        let shown = active.shown;
        let visible = drawn(&app).iter().filter(|v| v.shows()).count() as f32;
        assert!((visible - shown).abs() <= 1.0, "frame {k}: {visible} voxels show for a count of {shown}");
        let mut tweens = app.world_mut().query::<&ModelTween>();
        assert!(tweens.iter(app.world()).count() <= 2, "model-level tweens are replaced, never stacked");
    }
    assert_eq!(app.world().resource::<ActiveTransition>().angle, start_angle + t.spin_angle);
    settle(&mut app);
    assert_shows_model(&mut app);
}
