//! Renders a glTF file as it is (a mesh, not voxelized) and saves a screenshot of it:
//! `cargo run --example view_gltf -- MODEL.glb OUT.png`. The camera frames the model's bounds from the front
//! left, so two files that sit in the same place (a model and its voxel export) are seen the same way. Without a
//! display, run it under `../shared/tools/headless.sh`.

use std::path::PathBuf;

use bevy::prelude::*;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured, save_to_disk};
use bevy::window::WindowResolution;

/// Frames rendered after the scene has loaded, before the capture (the first frames compile shaders).
const SETTLE_FRAMES: u32 = 30;

/// What to show and where to save it.
#[derive(Resource)]
struct View {
    /// The screenshot's path.
    out: PathBuf,
    /// The scene being shown.
    scene: Handle<WorldAsset>,
    /// Frames since the scene loaded.
    frames: u32,
}

fn main() -> AppExit {
    let args: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    let [model, out] = args.as_slice() else {
        eprintln!("usage: view_gltf MODEL.glb OUT.png");
        return AppExit::from_code(2);
    };
    let bounds = match voxel_core::load_file(model) {
        Ok(soup) => soup.bounds(),
        Err(e) => {
            eprintln!("error: {}: {e}", model.display());
            return AppExit::from_code(1);
        }
    };
    let Some((min, max)) = bounds else {
        eprintln!("error: {}: no triangles to show", model.display());
        return AppExit::from_code(1);
    };
    let (min, max) = (Vec3::from(min), Vec3::from(max));

    let mut app = App::new();
    let asset_plugin = voxel_art::assets::asset_plugin(&mut app);
    let window = Window { title: "view_gltf".into(), resolution: WindowResolution::new(640, 640), ..default() };
    app.add_plugins(DefaultPlugins.set(asset_plugin).set(WindowPlugin { primary_window: Some(window), ..default() }));
    let scene = app
        .world()
        .resource::<AssetServer>()
        .load(GltfAssetLabel::Scene(0).from_asset(voxel_art::assets::file_asset_path(model)));
    app.insert_resource(View { out: out.clone(), scene: scene.clone(), frames: 0 });
    app.insert_resource(ClearColor(Color::srgb(0.93, 0.93, 0.95)));
    app.insert_resource(GlobalAmbientLight { color: Color::WHITE, brightness: 400.0, ..default() });

    let center = (min + max) / 2.0;
    let eye = center + Vec3::new(0.9, 0.35, 0.8).normalize() * (max - min).length() * 1.1;
    // Drawn after any camera the file brings (the Duck has one), so the window shows this view.
    let camera = Camera { order: 1, ..default() };
    app.world_mut().spawn((Camera3d::default(), camera, Transform::from_translation(eye).looking_at(center, Vec3::Y)));
    app.world_mut().spawn((
        DirectionalLight { illuminance: 6_000.0, ..default() },
        Transform::from_xyz(1.5, 2.0, 1.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    app.world_mut().spawn(WorldAssetRoot(scene));
    app.add_systems(Update, capture_when_loaded);
    app.run()
}

/// Once the scene has loaded and a few frames have drawn, captures the window and exits (with an error when the
/// scene cannot load).
fn capture_when_loaded(
    mut commands: Commands,
    mut view: ResMut<View>,
    assets: Res<AssetServer>,
    mut exit: MessageWriter<AppExit>,
) {
    if let bevy::asset::LoadState::Failed(e) = assets.load_state(&view.scene) {
        error!("cannot load the scene: {e}");
        exit.write(AppExit::error());
    }
    if !assets.is_loaded_with_dependencies(&view.scene) || view.frames > SETTLE_FRAMES {
        return;
    }
    view.frames += 1;
    if view.frames <= SETTLE_FRAMES {
        return;
    }
    commands.spawn(Screenshot::primary_window()).observe(save_to_disk(view.out.clone())).observe(
        |_: On<ScreenshotCaptured>, mut exit: MessageWriter<AppExit>| {
            exit.write(AppExit::Success);
        },
    );
}
