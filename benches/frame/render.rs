//! `cargo bench --bench frame -- render [SCENARIO…] [100k|1m] [alone]`: a whole frame's CPU cost with Bevy's
//! renderer; `render load`: the frames while a 100 MB file loads.
//!
//! Each case is the app's own plugins (`DefaultPlugins` without winit and without a window, the voxel material,
//! the `LogicPlugin`) with the renderer on wgpu's no-op backend: GPU commands cost nothing, every CPU cost
//! counts (extraction, batching, uploads, pipelined rendering as the app has it). One `Camera3d` renders into a
//! 1280×720 image beside a shadow-casting `DirectionalLight`. Every case is stepped in turn with an `empty` app
//! (the same plugins, no voxels), frame by frame, so the difference between the two is the voxels' share and
//! not the machine's mood. Lines: `render <scenario> <N> voxels: median <X> ms/frame, p90 <Y> ms/frame, worst
//! <W> ms, <T> triangles/frame` (triangles over the main and the shadow pass, as submitted).

use std::time::Instant;

use bevy::app::PluginsState;
use bevy::camera::RenderTarget;
use bevy::light::CascadeShadowConfigBuilder;
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use bevy::time::TimeUpdateStrategy;
use voxel_art::config::AppArgs;
use voxel_art::instancing::VoxelPool;
use voxel_art::model::{ModelLibrary, VoxelModelAsset};
use voxel_art::style::Style;
use voxel_art::transition::ActiveTransition;
use voxel_core::shapes::uv_sphere;
use voxel_core::{GridSize, TriangleSoup, VoxelizeOptions, voxelize};

#[path = "../../crates/voxel-core/tests/support/scenes.rs"]
mod scenes;

/// Frames measured per case.
const FRAMES: usize = 300;

/// The app's plugins as `args` configure them, with the renderer on the no-op backend, a camera rendering into
/// an image and the key light, after its first frame.
fn bare_app(args: AppArgs) -> App {
    let mut app = App::new();
    let plugins = voxel_art::noop::default_plugins(&mut app);
    app.add_plugins(plugins);
    args.configure(&mut app);
    app.add_plugins(voxel_art::instancing::render_plugin);
    app.add_plugins(voxel_art::LogicPlugin);
    app.insert_resource(TimeUpdateStrategy::ManualDuration(voxel_art::schedule::FIXED_STEP));
    app.add_systems(Startup, stage);
    while app.plugins_state() == PluginsState::Adding {
        bevy::tasks::tick_global_task_pools_on_main_thread();
    }
    app.finish();
    app.cleanup();
    app.update();
    app
}

/// [`bare_app`] with `models` in its library (the first shown, solid), in `style`.
fn render_app(models: Vec<voxel_core::VoxelModel>, style: Style) -> App {
    let mut app = bare_app(AppArgs { no_shipped: true, style: Some(style), ..Default::default() });
    app.world_mut().resource_mut::<voxel_art::settings::VoxelSettings>().hollow = false;
    if !models.is_empty() {
        let handles: Vec<_> = models
            .into_iter()
            .map(|m| app.world_mut().resource_mut::<Assets<VoxelModelAsset>>().add(VoxelModelAsset(m)))
            .collect();
        let mut library = app.world_mut().resource_mut::<ModelLibrary>();
        library.entries =
            handles.into_iter().enumerate().map(|(i, h)| super::entry(&format!("model {i}"), h)).collect();
        library.current = 0;
        for _ in 0..600 {
            app.update();
            if super::settled(&app) {
                break;
            }
        }
        assert!(super::settled(&app), "the model never settled");
    }
    app
}

/// The camera (rendering into an image, as the app's: MSAA 4×) and the shadow-casting key light.
fn stage(mut commands: Commands, mut images: ResMut<Assets<Image>>) {
    let image = images.add(Image::new_target_texture(1280, 720, TextureFormat::Rgba8UnormSrgb, None));
    commands.spawn((
        Camera3d::default(),
        RenderTarget::Image(image.into()),
        Msaa::Sample4,
        Transform::from_xyz(9.0, 6.0, 14.0).looking_at(Vec3::new(0.0, -0.6, 0.0), Vec3::Y),
    ));
    commands.spawn((
        DirectionalLight { illuminance: 7_000.0, shadow_maps_enabled: true, ..default() },
        CascadeShadowConfigBuilder { num_cascades: 1, maximum_distance: 60.0, ..default() }.build(),
        Transform::from_xyz(3.0, 12.0, 6.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
}

/// A solid sphere `resolution` cells across (58: about 100k voxels; 126: about 1M).
fn sphere(resolution: u32) -> voxel_core::VoxelModel {
    let soup = TriangleSoup::from_mesh(&uv_sphere(1.0, 64), [0.9, 0.5, 0.6, 1.0]);
    voxelize(&soup, &VoxelizeOptions { grid: GridSize::Resolution(resolution), hollow: false, ..Default::default() })
        .expect("voxelize")
}

/// A solid cube of about as many voxels as a sphere `resolution` cells across.
fn cube(resolution: u32) -> voxel_core::VoxelModel {
    let soup = TriangleSoup::from_mesh(&voxel_core::shapes::cuboid([0.0; 3], [1.0; 3]), [0.5, 0.6, 0.9, 1.0]);
    let side = (resolution as f32 * (std::f32::consts::PI / 6.0).cbrt()).round() as u32;
    voxelize(&soup, &VoxelizeOptions { grid: GridSize::Resolution(side), hollow: false, ..Default::default() })
        .expect("voxelize")
}

/// Triangles a frame: every voxel that shows, once in the main pass and once in the shadow pass.
fn triangles(app: &mut App) -> u64 {
    voxel_art::instancing::triangles_per_frame(app.world_mut()) * 2
}

/// Milliseconds of `frames` updates of `case` and of `empty` (if any), stepped in turn; `each` runs before every frame
/// of the case (with the frame's number).
fn interleaved(
    case: &mut App,
    mut empty: Option<&mut App>,
    frames: usize,
    mut each: impl FnMut(&mut App, usize),
) -> (Vec<f64>, Vec<f64>, u64) {
    let time = |app: &mut App| {
        let t = Instant::now();
        app.update();
        t.elapsed().as_secs_f64() * 1e3
    };
    let (mut case_ms, mut empty_ms, mut most) = (Vec::new(), Vec::new(), 0);
    for frame in 0..frames {
        if let Some(empty) = empty.as_deref_mut() {
            empty_ms.push(time(empty));
        }
        each(case, frame);
        case_ms.push(time(case));
        most = most.max(triangles(case));
    }
    (case_ms, empty_ms, most)
}

/// Prints a line: median, p90, worst, triangles.
fn report(scenario: &str, voxels: usize, ms: &[f64], triangles: u64) {
    let (median, p90) = super::median_p90(ms);
    let worst = ms.iter().copied().fold(0.0, f64::max);
    println!(
        "render {scenario} {voxels} voxels: median {median:.2} ms/frame, p90 {p90:.2} ms/frame, worst {worst:.1} ms, \
         {triangles} triangles/frame"
    );
}

/// The voxels shown by `app`'s pool.
fn shown(app: &App) -> usize {
    app.world().resource::<VoxelPool>().visible
}

/// Whether the filter arguments after `render` (scenarios and sizes) ask for `word` (all when none is given
/// of its kind).
fn asked(word: &str, kind: &[&str]) -> bool {
    let words: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with('-') && a != "render").collect();
    let of_kind: Vec<&String> = words.iter().filter(|w| kind.contains(&w.as_str())).collect();
    of_kind.is_empty() || of_kind.iter().any(|w| *w == word)
}

const SCENARIOS: [&str; 5] = ["static", "morph", "repel", "bubbles", "falling"];
const SIZES: [&str; 2] = ["100k", "1m"];

/// Runs the render cases asked for.
pub fn run() {
    println!("render: threads {}", bevy::tasks::available_parallelism());
    if std::env::args().any(|a| a == "load") {
        run_load();
        return;
    }
    for (size, resolution) in [("100k", 58), ("1m", 126)] {
        if !asked(size, &SIZES) {
            continue;
        }
        let model = sphere(resolution);
        for scenario in SCENARIOS {
            if !asked(scenario, &SCENARIOS) {
                continue;
            }
            run_case(scenario, &model, resolution);
        }
    }
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    if let Some(peak) = status.lines().find(|l| l.starts_with("VmHWM")) {
        println!("render: peak memory of this process: {}", peak.trim_start_matches("VmHWM:").trim());
    }
}

fn run_case(scenario: &str, model: &voxel_core::VoxelModel, resolution: u32) {
    // `alone`: no empty app beside the case (the process's peak memory is then the case's own).
    let mut empty = (!std::env::args().any(|a| a == "alone")).then(|| render_app(Vec::new(), Style::RoundedBoxes));
    let style = match scenario {
        "bubbles" => Style::Bubbles,
        "falling" => Style::Falling,
        _ => Style::RoundedBoxes,
    };
    let models = if scenario == "morph" { vec![model.clone(), cube(resolution)] } else { vec![model.clone()] };
    let mut case = render_app(models, style);
    let voxels = shown(&case);
    let (ms, empty_ms, tris) = match scenario {
        // A morph every 60 frames (one second): the median is mid-morph, the worst the frame that starts one.
        "morph" => interleaved(&mut case, empty.as_mut(), FRAMES, |app, frame| {
            if frame % 60 == 0 {
                app.world_mut().write_message(voxel_art::library::LibraryRequest::Next);
            }
        }),
        "repel" | "bubbles" => {
            case.add_systems(First, super::circling_cursor);
            interleaved(&mut case, empty.as_mut(), FRAMES, |_, _| {})
        }
        _ => interleaved(&mut case, empty.as_mut(), FRAMES, |_, _| {}),
    };
    if !empty_ms.is_empty() {
        report("empty", 0, &empty_ms, 0);
    }
    report(scenario, voxels, &ms, tris);
    let running = case.world().resource::<ActiveTransition>().running.is_some();
    if scenario == "morph" {
        let worst = |frames: &[f64]| frames.iter().copied().fold(0.0, f64::max);
        println!(
            "  worst frame of the first morph (the cube's layout made in a task): {:.1} ms; of the later ones: {:.1} \
             ms; a transition running at the end: {running}",
            worst(&ms[..60]),
            worst(&ms[60..])
        );
        // A million voxels take off over 17 frames (`CHUNKS_PER_FRAME`): the first 20 of each second.
        let median = |taking_off: bool| {
            let frames = ms.iter().enumerate().filter(|(f, _)| (f % 60 < 20) == taking_off).map(|(_, m)| *m);
            super::median_p90(&frames.collect::<Vec<_>>()).0
        };
        println!("  median of the frames taking off: {:.2} ms; of the rest: {:.2} ms", median(true), median(false));
    }
}

/// `render load`: every frame while the app reads, voxelizes and shows a 100 MB file dropped on it (4M
/// triangles of overlapping vertex-coloured spheres, generated: the `big` bench's spheres-4m), from the drop
/// until its model has settled, stepped in turn with `empty`. The app has run 120 frames first (its pipelines
/// made, the placeholder boxes floating).
fn run_load() {
    let dir = std::env::temp_dir().join("voxel-art-load");
    std::fs::create_dir_all(&dir).expect("a folder for the file");
    let path = dir.join("spheres-4m.glb");
    std::fs::write(&path, scenes::to_glb(&scenes::spheres(4096))).expect("write the file");
    let megabytes = std::fs::metadata(&path).map_or(0, |m| m.len()) as f64 / 1e6;
    let mut empty = render_app(Vec::new(), Style::RoundedBoxes);
    let mut case = bare_app(AppArgs { no_shipped: true, ..Default::default() });
    interleaved(&mut case, Some(&mut empty), 120, |_, _| {});
    case.world_mut().write_message(voxel_art::library::LibraryRequest::Add(path));
    let (started, limit) = (Instant::now(), std::time::Duration::from_secs(600));
    let (mut ms, mut empty_ms) = (Vec::new(), Vec::new());
    while !super::settled(&case) && started.elapsed() < limit {
        let (frame, empty_frame, _) = interleaved(&mut case, Some(&mut empty), 1, |_, _| {});
        ms.extend(frame);
        empty_ms.extend(empty_frame);
    }
    assert!(super::settled(&case), "the file was not shown within {limit:?}");
    report("empty", 0, &empty_ms, 0);
    let triangles = triangles(&mut case);
    report(&format!("load ({megabytes:.0} MB file)"), shown(&case), &ms, triangles);
    let seconds = started.elapsed().as_secs_f64();
    println!("  {} frames in {seconds:.1} s from the drop to the model settled on screen", ms.len());
}
