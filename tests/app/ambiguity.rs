//! The ambiguity check over the whole app: every schedule of the main app and of the render sub-app, built with
//! Bevy's renderer on wgpu's no-op backend, has no pair of our systems (or of ours and Bevy's) that share data
//! and run in an undefined order. Bevy's own pairs are Bevy's business.

use std::collections::HashMap;

use bevy::app::PluginsState;
use bevy::prelude::*;
use bevy::render::pipelined_rendering::PipelinedRenderingPlugin;
use bevy::render::{MainWorld, RenderApp};
use voxel_art::config::AppArgs;

/// The ambiguities in `world`'s schedules where a system is one of `ours` (its path starts with one of them: Bevy's
/// generic systems over our types, such as `Assets<OurAsset>::asset_events`, are Bevy's), one line each:
/// `Schedule: system × system on [what they share]`.
pub fn ambiguities(world: &mut World, ours: &[&str]) -> Vec<String> {
    let labels: Vec<_> = world.resource::<Schedules>().iter().map(|(_, schedule)| schedule.label()).collect();
    let mut found = Vec::new();
    for label in labels {
        world.schedule_scope(label, |world, schedule| {
            schedule.initialize(world).unwrap_or_else(|e| panic!("{label:?} does not build: {e}"));
            // Built, the systems live in the executable schedule (the graph keeps only their keys).
            let names: HashMap<_, _> = schedule.systems().expect("built").map(|(key, s)| (key, s.name())).collect();
            for (a, b, on) in schedule.graph().conflicting_systems().iter() {
                let (a, b) = (names[a].to_string(), names[b].to_string());
                let is_ours =
                    |system: &str| ours.iter().any(|path| system.trim_start_matches("Pipe(").starts_with(path));
                if is_ours(&a) || is_ours(&b) {
                    let on: Vec<_> = on.iter().filter_map(|id| world.components().get_name(*id)).collect();
                    found.push(format!("{label:?}: {a} × {b} on {on:?}"));
                }
            }
        });
    }
    found
}

/// The whole app as the window has it (stage, camera, panel, previews, recording, logic), with the renderer on
/// wgpu's no-op backend, without pipelined rendering so the render sub-app stays in reach (pipelining only
/// moves where it runs, not its schedules).
fn whole_app(args: AppArgs) -> App {
    let mut app = App::new();
    let plugins = voxel_art::noop::default_plugins(&mut app).disable::<PipelinedRenderingPlugin>();
    app.add_plugins(plugins);
    app.add_plugins(voxel_art::ShowPlugin { args });
    while app.plugins_state() == PluginsState::Adding {
        bevy::tasks::tick_global_task_pools_on_main_thread();
    }
    app.finish();
    app.cleanup();
    app
}

#[test]
fn no_two_of_our_systems_share_data_in_an_undefined_order_anywhere_in_the_app() {
    // A screenshot run adds its driver to the systems the window has.
    let args = AppArgs { no_shipped: true, screenshot: Some("unused.png".into()), ..Default::default() };
    let mut app = whole_app(args);
    let main = ambiguities(app.world_mut(), &["voxel_art::"]);
    // Extraction systems reach the main world through `MainWorld`, lent to the render world as Bevy's
    // extraction does.
    let mut lent = MainWorld::default();
    std::mem::swap(&mut *lent, app.world_mut());
    let render_world = app.sub_app_mut(RenderApp).world_mut();
    render_world.insert_resource(lent);
    let render = ambiguities(render_world, &["voxel_art::"]);
    let mut lent = render_world.remove_resource::<MainWorld>().expect("lent above");
    std::mem::swap(&mut *lent, app.world_mut());
    let all: Vec<_> = main.iter().chain(&render).collect();
    assert!(
        all.is_empty(),
        "{} ambiguities:\n{}",
        all.len(),
        all.iter().map(|s| s.as_str()).collect::<Vec<_>>().join("\n")
    );
}

#[derive(Resource, Default)]
struct Shared(u32);

fn raise(mut shared: ResMut<Shared>) {
    shared.0 += 1;
}

fn double(mut shared: ResMut<Shared>) {
    shared.0 *= 2;
}

#[test]
fn the_check_names_two_systems_that_write_the_same_resource_unordered() {
    let mut app = App::new();
    app.init_resource::<Shared>();
    app.add_systems(Update, (raise, double));
    let found = ambiguities(app.world_mut(), &["app::ambiguity::"]);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(found[0].starts_with("Update: "), "{}", found[0]);
    assert!(found[0].contains("app::ambiguity::raise") && found[0].contains("app::ambiguity::double"), "{}", found[0]);
    assert!(found[0].contains("Shared"), "{}", found[0]);
    // Ordered, they are fine; and a pair of someone else's systems is not ours to check.
    let mut ordered = App::new();
    ordered.init_resource::<Shared>();
    ordered.add_systems(Update, (raise, double).chain());
    assert_eq!(ambiguities(ordered.world_mut(), &["app::ambiguity::"]), Vec::<String>::new());
    let mut theirs = App::new();
    theirs.init_resource::<Shared>();
    theirs.add_systems(Update, (raise, double));
    assert_eq!(ambiguities(theirs.world_mut(), &["voxel_art::"]), Vec::<String>::new());
}
