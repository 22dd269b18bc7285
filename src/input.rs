//! Keys and clicks: ←/→/Space cycle models, 1–9 pick one, S cycles styles, F drops/reassembles (falling
//! style), R toggles mouse repel, H toggles the panel, Esc quits; a short click on the stage goes to the next
//! model, while press-and-hold (or a drag) orbits.

use bevy::input::mouse::MouseButton;
use bevy::prelude::*;
use bevy::window::PrimaryWindow;

use crate::library::LibraryRequest;
use crate::schedule::AppSystems;
use crate::settings::VoxelSettings;

/// A press shorter than this (and without dragging) is a click, not an orbit.
pub const CLICK_MAX_SECONDS: f32 = 0.25;
/// A press that moves the cursor more than this many logical pixels is a drag.
pub const CLICK_MAX_TRAVEL: f32 = 6.0;

/// Whether the pointer is over something that is not the stage.
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct PointerOverUi {
    /// Over the egui panel (or egui is using the pointer).
    pub panel: bool,
    /// Over a preview viewport.
    pub preview: bool,
}

impl PointerOverUi {
    /// Over anything but the stage.
    pub fn any(self) -> bool {
        self.panel || self.preview
    }
}

/// The ray under the mouse cursor in world space, when the cursor is over the stage (set by the camera).
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq)]
pub struct CursorRay(pub Option<Ray3d>);

/// A click on the stage (a short press and release without dragging), in window coordinates.
#[derive(Message, Debug, Clone, Copy, PartialEq)]
pub struct StageClick(pub Vec2);

fn keys(
    keys: Res<ButtonInput<KeyCode>>,
    mut requests: MessageWriter<LibraryRequest>,
    mut settings: ResMut<VoxelSettings>,
    mut exit: MessageWriter<AppExit>,
) {
    if keys.just_pressed(KeyCode::ArrowRight) || keys.just_pressed(KeyCode::Space) {
        requests.write(LibraryRequest::Next);
    }
    if keys.just_pressed(KeyCode::ArrowLeft) {
        requests.write(LibraryRequest::Previous);
    }
    let digits = [
        KeyCode::Digit1,
        KeyCode::Digit2,
        KeyCode::Digit3,
        KeyCode::Digit4,
        KeyCode::Digit5,
        KeyCode::Digit6,
        KeyCode::Digit7,
        KeyCode::Digit8,
        KeyCode::Digit9,
    ];
    for (i, key) in digits.iter().enumerate() {
        if keys.just_pressed(*key) {
            requests.write(LibraryRequest::Select(i));
        }
    }
    if keys.just_pressed(KeyCode::KeyH) {
        settings.panel_open = !settings.panel_open;
    }
    if keys.just_pressed(KeyCode::KeyS) {
        settings.style = settings.style.next();
    }
    if keys.just_pressed(KeyCode::KeyR) {
        settings.repel = !settings.repel;
    }
    if keys.just_pressed(KeyCode::Escape) {
        exit.write(AppExit::Success);
    }
}

/// The press being tracked: when and where it started.
#[derive(Default)]
struct Press {
    start: Option<(f32, Vec2)>,
    travelled: f32,
}

/// Turns short, still presses of the left button on the stage into [`StageClick`]s.
fn clicks(
    buttons: Res<ButtonInput<MouseButton>>,
    time: Res<Time>,
    window: Query<&Window, With<PrimaryWindow>>,
    over_ui: Res<PointerOverUi>,
    mut press: Local<Press>,
    mut clicks: MessageWriter<StageClick>,
) {
    let cursor = window.single().ok().and_then(Window::cursor_position);
    let now = time.elapsed_secs();
    if buttons.just_pressed(MouseButton::Left) {
        *press = Press { start: (!over_ui.any()).then_some(()).and(cursor.map(|c| (now, c))), travelled: 0.0 };
    }
    if let (Some((_, origin)), Some(c)) = (press.start, cursor) {
        press.travelled = press.travelled.max(c.distance(origin));
    }
    if buttons.just_released(MouseButton::Left)
        && let Some((t0, origin)) = press.start.take()
        && now - t0 <= CLICK_MAX_SECONDS
        && press.travelled <= CLICK_MAX_TRAVEL
        && !over_ui.any()
    {
        clicks.write(StageClick(cursor.unwrap_or(origin)));
    }
}

/// A click on the stage shows the next model.
fn click_to_next(mut clicks: MessageReader<StageClick>, mut requests: MessageWriter<LibraryRequest>) {
    for _ in clicks.read() {
        requests.write(LibraryRequest::Next);
    }
}

pub(super) fn plugin(app: &mut App) {
    app.init_resource::<PointerOverUi>();
    app.init_resource::<CursorRay>();
    app.add_message::<StageClick>();
    app.add_systems(Update, (keys, clicks, click_to_next).chain().in_set(AppSystems::Input));
}
