//! Colours in the app: pastel by default (the article's look), a palette, a colour limit or dithering recolour
//! the models from their sampled colours without voxelizing again (same assets, no morph: every voxel stays on
//! its cell and takes its new colour), a dropped palette file becomes the palette and a bad one is an error in
//! the panel's status; the Export of an animated model also writes its clip as one animated .glb.

use std::collections::HashSet;
use std::path::PathBuf;
use std::time::Duration;

use bevy::prelude::*;
use bevy::window::FileDragAndDrop;
use voxel_art::animation::AnimationStart;
use voxel_art::config::AppArgs;
use voxel_art::export::{ExportRequest, ExportStatus};
use voxel_art::model::{ModelLibrary, VoxelModelAsset};
use voxel_art::palette::PaletteFiles;
use voxel_art::settings::ColorSettings;
use voxel_art::transition::{ActiveTransition, TransitionStarted};
use voxel_art::voxelize::{VoxelizeGeneration, VoxelizeJob};
use voxel_core::palette::Palette;

use crate::common::{models_dir, scratch_dir};
use crate::harness::{all_settled, app_options, core_voxelize, run_until, shipped, temp_file, test_app};
use crate::transition::{assert_shows_model, settle};

const LIMIT: Duration = Duration::from_secs(60);

/// The app showing the donut, settled (voxelized, its morph over).
fn donut_app() -> App {
    let mut app = test_app(AppArgs { no_shipped: true, models: vec![shipped("donut.glb")], ..default() });
    run_until(&mut app, LIMIT, all_settled);
    settle(&mut app);
    app
}

/// The distinct RGB colours of the shown model's voxels.
fn shown_colors(app: &App) -> HashSet<[u8; 3]> {
    let library = app.world().resource::<ModelLibrary>();
    let (_, model) = library.current_ready(app.world().resource::<Assets<VoxelModelAsset>>()).expect("ready");
    model.voxels().map(|v| [v.color[0], v.color[1], v.color[2]]).collect()
}

/// What says whether the model was voxelized again: its asset, its settings generation, the generation and
/// the voxelization jobs running.
fn voxelization(app: &mut App) -> (AssetId<VoxelModelAsset>, Option<u64>, u64, usize) {
    let jobs = app.world_mut().query::<&VoxelizeJob>().iter(app.world()).count();
    let library = app.world().resource::<ModelLibrary>();
    let entry = library.current_entry().unwrap();
    let id = entry.voxels.as_ref().unwrap().id();
    (id, entry.voxels_generation, app.world().resource::<VoxelizeGeneration>().0, jobs)
}

fn set_colors(app: &mut App, edit: impl FnOnce(&mut ColorSettings)) {
    edit(&mut app.world_mut().resource_mut::<ColorSettings>());
}

fn colors_of(palette: &Palette) -> HashSet<[u8; 3]> {
    let Palette::Fixed { colors, .. } = palette else { panic!("a fixed palette: {palette:?}") };
    colors.iter().copied().collect()
}

/// Steps a few frames, counting the morphs started.
fn step_counting_morphs(app: &mut App, frames: usize) -> usize {
    let mut morphs = 0;
    for _ in 0..frames {
        app.update();
        morphs += app.world().resource::<Messages<TransitionStarted>>().iter_current_update_messages().count();
    }
    morphs
}

#[test]
fn switching_the_palette_recolours_the_shown_voxels_without_voxelizing_or_morphing() {
    let mut app = donut_app();
    // The default is the article's pastel look: the core's pastel voxelization, colour for colour.
    let pastel = app_options(&app);
    assert!(pastel.pastel);
    let core = core_voxelize(&shipped("donut.glb"), &pastel);
    let core_colors: HashSet<[u8; 3]> = core.voxels().map(|v| [v.color[0], v.color[1], v.color[2]]).collect();
    assert_eq!(shown_colors(&app), core_colors);
    assert_shows_model(&mut app);

    let before = voxelization(&mut app);
    let pico8 = Palette::from_arg("pico8").unwrap();
    set_colors(&mut app, |c| c.0.palette = pico8.clone());
    assert_eq!(step_counting_morphs(&mut app, 5), 0, "a recolour is no morph");
    assert_eq!(voxelization(&mut app), before, "same asset, same generation, no job");
    let shown = shown_colors(&app);
    assert!(shown.is_subset(&colors_of(&pico8)) && shown.len() >= 2, "{shown:?}");
    assert!(app.world().resource::<ActiveTransition>().running.is_none());
    // Every voxel is still on its cell, and shows its new colour.
    assert_shows_model(&mut app);

    // Back to pastel: the colours as they were.
    set_colors(&mut app, |c| c.0.palette = Palette::Pastel);
    step_counting_morphs(&mut app, 2);
    assert_eq!(shown_colors(&app), core_colors);
    assert_shows_model(&mut app);
}

#[test]
fn the_colour_limit_keeps_at_most_n_colours_and_dithering_stays_in_the_palette() {
    let mut app = donut_app();
    let before = voxelization(&mut app);
    assert!(shown_colors(&app).len() > 6, "the donut has many colours: {}", shown_colors(&app).len());
    for n in [1, 3, 6] {
        set_colors(&mut app, |c| c.0.max_colors = Some(n));
        step_counting_morphs(&mut app, 2);
        let shown = shown_colors(&app);
        assert!(!shown.is_empty() && shown.len() <= n, "{n}: {shown:?}");
        let library = app.world().resource::<ModelLibrary>();
        let (_, model) = library.current_ready(app.world().resource::<Assets<VoxelModelAsset>>()).unwrap();
        assert_eq!(model.color_count(), shown.len(), "the panel's count");
    }
    let gameboy = Palette::from_arg("gameboy").unwrap();
    set_colors(&mut app, |c| {
        c.0 = voxel_core::palette::ColorStage { palette: gameboy.clone(), max_colors: None, dither: true }
    });
    step_counting_morphs(&mut app, 2);
    assert!(shown_colors(&app).is_subset(&colors_of(&gameboy)));
    assert_shows_model(&mut app);
    assert_eq!(voxelization(&mut app), before);
}

/// Drops `path` on the window.
fn drop_file(app: &mut App, path: PathBuf) {
    app.world_mut().write_message(FileDragAndDrop::DroppedFile { window: Entity::PLACEHOLDER, path_buf: path });
    step_counting_morphs(app, 3);
}

#[test]
fn a_dropped_hex_file_becomes_the_palette_and_a_bad_one_is_an_error() {
    let mut app = donut_app();
    let models = app.world().resource::<ModelLibrary>().entries.len();
    let hex = temp_file("three.hex", b"; three colours\n202020\nf0e0d0\nc04040\n");
    drop_file(&mut app, hex.clone());
    let palette = app.world().resource::<ColorSettings>().0.palette.clone();
    let three: HashSet<[u8; 3]> = [[0x20, 0x20, 0x20], [0xf0, 0xe0, 0xd0], [0xc0, 0x40, 0x40]].into();
    assert_eq!(
        palette,
        Palette::Fixed {
            name: hex.display().to_string(),
            colors: vec![[0x20; 3], [0xf0, 0xe0, 0xd0], [0xc0, 0x40, 0x40]]
        }
    );
    assert!(shown_colors(&app).is_subset(&three), "{:?}", shown_colors(&app));
    assert_eq!(app.world().resource::<ModelLibrary>().entries.len(), models, "a palette is not a model");
    assert_eq!(app.world().resource::<PaletteFiles>().palettes, vec![palette.clone()], "the picker offers it");
    assert_shows_model(&mut app);

    let bad = temp_file("bad.hex", b"ff0000\nnot a colour\n");
    drop_file(&mut app, bad.clone());
    let error = app.world().resource::<PaletteFiles>().error.clone();
    assert_eq!(
        error.as_deref(),
        Some(
            format!("error: {}: not a usable palette: line 2: \"not a colour\" is not a colour rrggbb", bad.display())
                .as_str()
        )
    );
    assert_eq!(app.world().resource::<ColorSettings>().0.palette, palette, "the palette stays");
    assert_eq!(app.world().resource::<ModelLibrary>().entries.len(), models);
}

#[test]
fn exporting_an_animated_model_also_writes_its_clip_as_one_animated_glb() {
    let Some(dir) = models_dir() else { return };
    let out = scratch_dir("export-clip");
    let mut app = test_app(AppArgs {
        no_shipped: true,
        models: vec![dir.join("khronos-fox.glb")],
        export_dir: Some(out.clone()),
        ..default()
    });
    // The Fox's shortest clip, paused (its pose is the one exported as .vox/.glb).
    let fox = voxel_core::load_animated_file(&dir.join("khronos-fox.glb")).unwrap();
    let (index, clip) = fox.clips().iter().enumerate().min_by(|a, b| a.1.duration.total_cmp(&b.1.duration)).unwrap();
    app.insert_resource(AnimationStart { clip: Some(index.to_string()), time: Some(0.0) });
    run_until(&mut app, Duration::from_secs(120), |app| {
        let library = app.world().resource::<ModelLibrary>();
        library.current_ready(app.world().resource::<Assets<VoxelModelAsset>>()).is_some()
    });
    set_colors(&mut app, |c| c.0.palette = Palette::from_arg("pico8").unwrap());
    app.world_mut().write_message(ExportRequest);
    run_until(&mut app, Duration::from_secs(120), |app| {
        !matches!(app.world().resource::<ExportStatus>(), ExportStatus::Idle | ExportStatus::Writing)
    });
    let status = app.world().resource::<ExportStatus>().clone();
    let ExportStatus::Saved(saved, Some(animated)) = &status else { panic!("{status:?}") };
    assert!(saved.vox.0.exists() && saved.glb.0.exists());
    let name: String = clip.name.chars().map(|c| if c.is_alphanumeric() || c == '_' { c } else { '-' }).collect();
    assert_eq!(*animated, out.join(format!("khronos-fox-{name}.glb")));
    assert!(status.message().unwrap().contains(&animated.display().to_string()));
    // One clip of that name and length, whose frames are the poses at 30 a second, in pico8's colours.
    let mut back = voxel_core::load_animated_file(animated).unwrap();
    assert_eq!(back.clips().len(), 1);
    assert_eq!(back.clips()[0].name, clip.name);
    assert!((back.clips()[0].duration - clip.duration).abs() < 1e-3, "{:?}", back.clips()[0]);
    let frames = (clip.duration * 30.0).ceil() as usize;
    // One node a frame, each with its mesh, and one scale channel a frame that shows it in turn.
    let json = glb_json(animated);
    let framed = json["nodes"].as_array().unwrap().iter().filter(|n| n.get("mesh").is_some()).count();
    assert_eq!(framed, frames, "{} nodes", json["nodes"].as_array().unwrap().len());
    let channels = json["animations"][0]["channels"].as_array().unwrap();
    assert_eq!(channels.len(), frames);
    assert!(channels.iter().all(|c| c["target"]["path"] == "scale"), "{channels:?}");
    let mut soup = voxel_core::TriangleSoup::default();
    let pico8 = colors_of(&Palette::from_arg("pico8").unwrap());
    for k in [0, frames / 2, frames - 1] {
        back.pose_into(0, k as f32 / 30.0 + 1e-3, &mut soup).unwrap();
        let shown: HashSet<[u8; 3]> =
            soup.colors().iter().map(|color| [0, 1, 2].map(|c| voxel_core::srgb::linear_to_srgb(color[c]))).collect();
        assert!(!shown.is_empty() && shown.is_subset(&pico8), "frame {k}: {shown:?}");
    }
    std::fs::remove_dir_all(&out).unwrap();
}

/// The JSON chunk of a .glb file.
fn glb_json(path: &std::path::Path) -> serde_json::Value {
    let bytes = std::fs::read(path).unwrap();
    let length = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&bytes[20..20 + length]).unwrap()
}

#[test]
fn the_command_line_sets_the_starting_colour_stage_and_a_bad_palette_is_an_error() {
    use voxel_art::config::Cli;
    use voxel_core::palette::ColorStage;
    let parse = |args: &[&str]| {
        let Ok(Cli { app, .. }) =
            Cli::parse_args(std::iter::once("voxel-art").chain(args.iter().copied()).map(Into::into).collect())
        else {
            panic!("rejected: {args:?}")
        };
        app
    };
    let app = test_app(AppArgs { no_shipped: true, ..parse(&["--palette", "pico8", "--colors", "4", "--dither"]) });
    let pico8 = Palette::from_arg("pico8").unwrap();
    let expected = ColorStage { palette: pico8, max_colors: Some(4), dither: true };
    assert_eq!(app.world().resource::<ColorSettings>().0, expected);
    let app = test_app(AppArgs { no_shipped: true, ..parse(&[]) });
    assert_eq!(*app.world().resource::<ColorSettings>(), ColorSettings::default(), "pastel unless named");
    assert_eq!(ColorSettings::default().0.palette, Palette::Pastel);

    // A bad palette stops the app before it opens a window: status 1 and the reason.
    let bad = temp_file("cli-bad.hex", b"ff0000\nnot a colour\n");
    let run = |palette: &str| {
        std::process::Command::new(env!("CARGO_BIN_EXE_voxel-art")).args(["--palette", palette]).output().unwrap()
    };
    let out = run(bad.to_str().unwrap());
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8(out.stderr).unwrap();
    let reason = "not a usable palette: line 2: \"not a colour\" is not a colour rrggbb";
    assert_eq!(stderr.trim_end(), format!("error: {}: {reason}", bad.display()));
    let out = run("nes");
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(stderr.starts_with("error: nes: not a usable palette: no palette named \"nes\""), "{stderr}");
}

#[test]
fn export_after_a_palette_writes_only_its_colours() {
    let out = scratch_dir("export-palette");
    let mut app = test_app(AppArgs {
        no_shipped: true,
        models: vec![shipped("donut.glb")],
        export_dir: Some(out.clone()),
        ..default()
    });
    run_until(&mut app, LIMIT, all_settled);
    let pico8 = Palette::from_arg("pico8").unwrap();
    set_colors(&mut app, |c| c.0.palette = pico8.clone());
    app.update();
    app.world_mut().write_message(ExportRequest);
    run_until(&mut app, LIMIT, |app| {
        !matches!(app.world().resource::<ExportStatus>(), ExportStatus::Idle | ExportStatus::Writing)
    });
    let status = app.world().resource::<ExportStatus>().clone();
    let ExportStatus::Saved(saved, None) = &status else { panic!("{status:?}") };
    let data = dot_vox::load(saved.vox.0.to_str().unwrap()).unwrap();
    let used: HashSet<[u8; 3]> =
        data.models[0].voxels.iter().map(|v| data.palette[usize::from(v.i)]).map(|c| [c.r, c.g, c.b]).collect();
    assert!(used.len() >= 2 && used.is_subset(&colors_of(&pico8)), "{used:?}");
    assert_eq!(used, shown_colors(&app), "the .vox holds the colours shown");
    std::fs::remove_dir_all(&out).unwrap();
}
