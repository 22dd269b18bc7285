//! Keys and clicks: ←/→/Space cycle models, 1–9 pick one, S cycles styles, Ctrl+S exports the shown model, F
//! drops/reassembles (falling style), R toggles mouse repel, Ctrl+R starts/stops recording a GIF, P
//! plays/pauses an animated model, H toggles the panel, Esc quits; a short click on
//! the stage goes to the next model, while press-and-hold (or a drag) orbits.

use bevy::input::mouse::MouseButton;
use bevy::prelude::*;
use bevy::window::PrimaryWindow;

use crate::animation::AnimationRequest;
use crate::export::ExportRequest;
use crate::library::LibraryRequest;
use crate::schedule::InputSystems;
use crate::settings::{PanelOpen, RepelSettings};
use crate::style::{Style, ToggleFall};

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

/// When the pointer acts on the stage (repels voxels, bursts bubbles).
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PointerMode {
    /// Once it has moved over the stage: a pointer that merely sits where it was when the window opened (Xvfb
    /// puts it at the window's centre) does not punch a hole into the model.
    #[default]
    AfterMove,
    /// At once, wherever it is (`--screenshot … --repel`).
    Always,
    /// Never (`--screenshot` without `--repel`).
    Never,
}

/// Whether the pointer acts on the stage now (see [`PointerMode`]).
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq)]
pub struct StagePointer {
    /// Where the pointer was first seen in the window.
    first: Option<Vec2>,
    /// Whether it acts on the stage.
    pub active: bool,
}

impl StagePointer {
    /// Takes this frame's cursor position (window coordinates; `None` outside the window) and whether it is over
    /// the panel or a preview.
    pub fn observe(&mut self, mode: PointerMode, cursor: Option<Vec2>, over_ui: bool) {
        self.active = match mode {
            PointerMode::Always => true,
            PointerMode::Never => false,
            PointerMode::AfterMove => {
                self.active
                    || match (self.first, cursor) {
                        (None, Some(at)) => {
                            self.first = Some(at);
                            false
                        }
                        (Some(first), Some(at)) => at != first && !over_ui,
                        (_, None) => false,
                    }
            }
        };
    }
}

/// Ctrl+R (or the panel's button): start recording the stage as a GIF, or stop (the record plugin acts on it).
#[derive(Message, Debug, Clone, Copy, PartialEq, Eq)]
pub struct ToggleRecord;

/// A click on the stage (a short press and release without dragging), in window coordinates.
#[derive(Message, Debug, Clone, Copy, PartialEq)]
pub struct StageClick(pub Vec2);

/// Every key the app answers to.
fn keys(
    keys: Res<ButtonInput<KeyCode>>,
    mut requests: MessageWriter<LibraryRequest>,
    mut panel: ResMut<PanelOpen>,
    mut repel: ResMut<RepelSettings>,
    style: Res<State<Style>>,
    mut next_style: ResMut<NextState<Style>>,
    mut fall: MessageWriter<ToggleFall>,
    mut export: MessageWriter<ExportRequest>,
    mut record: MessageWriter<ToggleRecord>,
    mut animation: MessageWriter<AnimationRequest>,
    mut exit: MessageWriter<AppExit>,
) {
    let ctrl = keys.any_pressed([KeyCode::ControlLeft, KeyCode::ControlRight]);
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
        panel.0 = !panel.0;
    }
    if keys.just_pressed(KeyCode::KeyS) {
        if ctrl {
            export.write(ExportRequest);
        } else {
            next_style.set(style.get().next());
        }
    }
    if keys.just_pressed(KeyCode::KeyF) {
        fall.write(ToggleFall);
    }
    if keys.just_pressed(KeyCode::KeyP) {
        animation.write(AnimationRequest::TogglePlay);
    }
    if keys.just_pressed(KeyCode::KeyR) {
        if ctrl {
            record.write(ToggleRecord);
        } else {
            repel.enabled = !repel.enabled;
        }
    }
    if keys.just_pressed(KeyCode::Escape) {
        exit.write(AppExit::Success);
    }
}

/// Follows the pointer to tell when it starts acting on the stage.
pub(crate) fn track_pointer(
    window: Query<&Window, With<PrimaryWindow>>,
    over_ui: Res<PointerOverUi>,
    mode: Res<PointerMode>,
    mut pointer: ResMut<StagePointer>,
) {
    let cursor = window.single().ok().and_then(Window::cursor_position);
    let mut next = *pointer;
    next.observe(*mode, cursor, over_ui.any());
    pointer.set_if_neq(next);
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
    app.init_resource::<PointerMode>();
    app.init_resource::<StagePointer>();
    app.add_message::<StageClick>();
    app.add_message::<ToggleRecord>();
    app.add_systems(
        Update,
        (
            track_pointer.in_set(InputSystems::Track),
            keys.in_set(InputSystems::Keys),
            clicks.in_set(InputSystems::Clicks),
            click_to_next.in_set(InputSystems::ClickToNext),
        ),
    );
}
