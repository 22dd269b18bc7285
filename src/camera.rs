//! The orbit camera (PanOrbitCamera, not while the pointer is over the panel) and the egui overlay camera.

use bevy::camera::CameraOutputMode;
use bevy::camera::visibility::RenderLayers;
use bevy::prelude::*;
use bevy::render::render_resource::BlendState;
use bevy_egui::{EguiGlobalSettings, PrimaryEguiContext};
use bevy_panorbit_camera::{EguiFocusIncludesHover, PanOrbitCamera, PanOrbitCameraPlugin};

/// The main 3D camera.
#[derive(Component, Debug, Default)]
pub struct MainCamera;

/// Where the camera starts: looking slightly down at the model.
pub fn main_camera() -> impl Bundle {
    (
        Name::new("main camera"),
        MainCamera,
        PanOrbitCamera {
            focus: Vec3::new(0.0, -0.6, 0.0),
            radius: Some(17.0),
            yaw: Some(0.55),
            pitch: Some(0.38),
            zoom_lower_limit: 4.0,
            zoom_upper_limit: Some(60.0),
            pitch_lower_limit: Some(-0.2),
            ..default()
        },
        Camera { order: 0, ..default() },
        Msaa::Sample4,
    )
}

fn setup(mut commands: Commands, mut egui_settings: ResMut<EguiGlobalSettings>) {
    commands.spawn(main_camera());
    // egui draws through its own camera on top of the 3D view and the previews.
    egui_settings.auto_create_primary_context = false;
    commands.spawn((
        Name::new("ui camera"),
        PrimaryEguiContext,
        Camera2d,
        RenderLayers::none(),
        Camera {
            order: 100,
            output_mode: CameraOutputMode::Write {
                blend_state: Some(BlendState::ALPHA_BLENDING),
                clear_color: ClearColorConfig::None,
            },
            clear_color: ClearColorConfig::Custom(Color::NONE),
            ..default()
        },
    ));
}

/// The cursor's ray through the main camera, or none over the panel and previews and until the pointer acts on
/// the stage.
fn cursor_ray(
    window: Query<&Window, With<bevy::window::PrimaryWindow>>,
    camera: Query<(&Camera, &GlobalTransform), With<MainCamera>>,
    over: Res<crate::input::PointerOverUi>,
    pointer: Res<crate::input::StagePointer>,
    mut ray: ResMut<crate::style::CursorRay>,
) {
    let found = (|| {
        let cursor = window.single().ok()?.cursor_position()?;
        let (camera, transform) = camera.single().ok()?;
        camera.viewport_to_world(transform, cursor).ok()
    })();
    ray.set_if_neq(crate::style::CursorRay(found.filter(|_| !over.any() && pointer.active)));
}

pub(super) fn plugin(app: &mut App) {
    app.add_systems(Update, cursor_ray.in_set(crate::schedule::InputSystems::Ray));
    app.add_plugins(PanOrbitCameraPlugin);
    // The panel is an egui Panel: hovering it must already stop the camera.
    app.insert_resource(EguiFocusIncludesHover(true));
    app.add_systems(Startup, setup);
}
