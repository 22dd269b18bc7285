//! The side panel (egui): models, style, parameters, stats, progress and the last error.

use bevy::ecs::system::SystemParam;
use bevy::prelude::*;
use bevy_egui::{EguiContexts, EguiPlugin, EguiPrimaryContextPass, egui};
use voxel_core::FillMode;
use voxel_core::palette::{ColorStage, FIXED_NAMES, Palette};

use crate::animation::AnimationRequest;
use crate::export::{ExportRequest, ExportStatus};
use crate::input::{PointerOverUi, ToggleRecord};
use crate::instancing::{MAX_DRAWN, VoxelPool};
use crate::library::LibraryRequest;
use crate::model::{ModelEntry, ModelLibrary, ModelStatus, Playback, VoxelModelAsset};
use crate::palette::PaletteFiles;
use crate::record::RecordStatus;
use crate::settings::{ColorSettings, PanelOpen, RepelSettings, SettingDrag, VoxelSettings};
use crate::style::Style;
use crate::transition::{Assignment, TransitionSettings};

/// The colour limit slider's top (the .vox export holds 255 colours).
const MAX_COLORS_SLIDER: usize = 255;

fn status_mark(entry: &ModelEntry) -> String {
    match entry.status {
        ModelStatus::Loading | ModelStatus::Voxelizing => format!("  ({})", job_stage(entry)),
        ModelStatus::Ready => String::new(),
        ModelStatus::Failed(_) => "  ⚠ failed".into(),
    }
}

/// What a loading or voxelizing model's job is doing, e.g. "filling, 60 %".
fn job_stage(entry: &ModelEntry) -> String {
    let stage = entry.progress.stage();
    match stage {
        voxel_core::Stage::Waiting if entry.status == ModelStatus::Loading => "loading…".into(),
        voxel_core::Stage::Waiting => "voxelizing…".into(),
        _ => format!("{}, {:.0} %", stage.label(), stage.fraction() * 100.0),
    }
}

/// The colour of a failure.
const RED: egui::Color32 = egui::Color32::from_rgb(200, 60, 60);
/// The colour of a warning.
const AMBER: egui::Color32 = egui::Color32::from_rgb(190, 120, 0);

/// A model's line in the list: its name and state; red when it failed, amber with a ⚠ when part of the file is
/// not shown; and the hover text saying why.
fn entry_label(entry: &ModelEntry) -> (String, Option<egui::Color32>, Option<&str>) {
    let label = format!("{}{}", entry.name, status_mark(entry));
    match (&entry.status, &entry.warning) {
        (ModelStatus::Failed(reason), _) => (label, Some(RED), Some(reason)),
        (_, Some(warning)) => (format!("{label}  ⚠"), Some(AMBER), Some(warning)),
        (_, None) => (label, None, None),
    }
}

fn model_list(ui: &mut egui::Ui, library: &ModelLibrary, requests: &mut MessageWriter<LibraryRequest>) {
    ui.heading("Models");
    for (i, entry) in library.entries.iter().enumerate() {
        let key = if i < 9 { format!("{} ", i + 1) } else { "   ".into() };
        let (label, colour, hover) = entry_label(entry);
        let text = egui::RichText::new(format!("{key}{label}"));
        let text = match colour {
            Some(c) => text.color(c),
            None => text,
        };
        let response = ui.selectable_label(i == library.current, text);
        let response = match hover {
            Some(reason) => response.on_hover_text(reason),
            None => response,
        };
        if response.clicked() {
            requests.write(LibraryRequest::Select(i));
        }
    }
    ui.label(egui::RichText::new("Drop .glb/.gltf files on the window to add them.").small());
}

/// The voxels' parameters; returns whether the grid slider is being dragged.
fn parameters(ui: &mut egui::Ui, settings: &mut VoxelSettings, style: &mut Style, repel: &mut RepelSettings) -> bool {
    ui.heading("Voxels");
    egui::ComboBox::from_label("style").selected_text(style.label()).show_ui(ui, |ui| {
        for choice in Style::ALL {
            ui.selectable_value(style, choice, choice.label());
        }
    });
    let grid = ui
        .add(egui::Slider::new(&mut settings.grid_size, VoxelSettings::GRID_RANGE).text("grid size").logarithmic(true));
    ui.add(egui::Slider::new(&mut settings.box_size, 0.4..=1.0).text("box size"));
    ui.add(egui::Slider::new(&mut settings.roundness, 0.0..=0.5).text("roundness"));
    ui.add(egui::Slider::new(&mut settings.speed, 0.2..=3.0).text("speed"));
    ui.horizontal(|ui| {
        ui.label("fill");
        ui.selectable_value(&mut settings.fill, FillMode::Winding, "winding");
        ui.selectable_value(&mut settings.fill, FillMode::Parity, "parity");
        ui.selectable_value(&mut settings.fill, FillMode::Flood, "flood");
        ui.selectable_value(&mut settings.fill, FillMode::None, "surface");
    });
    ui.checkbox(&mut settings.hollow, "hollow (only visible voxels)");
    ui.checkbox(&mut repel.enabled, "mouse repel (R)");
    ui.add_enabled(repel.enabled, egui::Slider::new(&mut repel.radius, 0.2..=4.0).text("repel radius"));
    ui.add_enabled(repel.enabled, egui::Slider::new(&mut repel.strength, 0.0..=2.0).text("repel strength"));
    if *style == Style::Falling {
        ui.label("F: drop / reassemble");
    }
    grid.dragged()
}

/// The panel's name of a palette: a built-in's name, a file's name without its folder.
fn palette_label(palette: &Palette) -> String {
    match palette {
        Palette::Original => "original".into(),
        Palette::Pastel => "pastel".into(),
        Palette::Fixed { name, .. } => {
            std::path::Path::new(name).file_name().map_or_else(|| name.clone(), |f| f.to_string_lossy().into_owned())
        }
    }
}

/// The colour stage: the palette (built-ins and files read), the colour limit (0: off) and dithering, and
/// the last palette file's error.
fn colors(ui: &mut egui::Ui, stage: &mut ColorStage, files: &PaletteFiles) {
    ui.heading("Colours");
    let builtins = [Palette::Original, Palette::Pastel]
        .into_iter()
        .chain(FIXED_NAMES.iter().filter_map(|name| Palette::from_arg(name).ok()));
    egui::ComboBox::from_label("palette").selected_text(palette_label(&stage.palette)).show_ui(ui, |ui| {
        for choice in builtins.chain(files.palettes.iter().cloned()) {
            let label = palette_label(&choice);
            ui.selectable_value(&mut stage.palette, choice, label);
        }
    });
    let mut limit = stage.max_colors.unwrap_or(0);
    let slider = egui::Slider::new(&mut limit, 0..=MAX_COLORS_SLIDER)
        .text("colors")
        .logarithmic(true)
        .custom_formatter(|n, _| if n < 1.0 { "off".into() } else { format!("{n:.0}") });
    ui.add(slider);
    stage.max_colors = (limit > 0).then_some(limit);
    ui.add_enabled(
        matches!(stage.palette, Palette::Fixed { .. }),
        egui::Checkbox::new(&mut stage.dither, "dither (fixed palettes)"),
    );
    ui.label(egui::RichText::new("Drop a .hex, .png or .vox palette on the window to use it.").small());
    if let Some(error) = &files.error {
        ui.colored_label(egui::Color32::from_rgb(200, 60, 60), error);
    }
}

/// The current model's clips (pick one), play / pause, speed and where the clip is; absent for a static model.
fn animation(ui: &mut egui::Ui, playback: &Playback, requests: &mut MessageWriter<AnimationRequest>) {
    ui.heading("Animation");
    for (i, clip) in playback.clips.iter().enumerate() {
        let label = format!("{}  ({:.2} s)", clip.name, clip.duration);
        if ui.selectable_label(i == playback.clip, label).clicked() {
            requests.write(AnimationRequest::Clip(i));
        }
    }
    ui.horizontal(|ui| {
        if ui.button(if playback.playing { "⏸ pause (P)" } else { "▶ play (P)" }).clicked() {
            requests.write(AnimationRequest::Play(!playback.playing));
        }
        ui.label(format!("{:.2} / {:.2} s", playback.time, playback.clip_info().duration));
    });
    let mut speed = playback.speed;
    if ui.add(egui::Slider::new(&mut speed, 0.0..=2.0).text("playback speed")).changed() {
        requests.write(AnimationRequest::Speed(speed));
    }
    let c = playback.counts;
    ui.label(
        egui::RichText::new(format!("poses: {} asked, {} shown, {} skipped", c.requested, c.placed, c.dropped)).small(),
    );
}

fn transition_settings(ui: &mut egui::Ui, t: &mut TransitionSettings) {
    egui::CollapsingHeader::new("Transition").show(ui, |ui| {
        ui.add(egui::Slider::new(&mut t.max_delay, 0.0..=1.0).text("max delay s"));
        ui.add(egui::Slider::new(&mut t.base_duration, 0.1..=2.0).text("duration s"));
        ui.add(egui::Slider::new(&mut t.extra_duration, 0.0..=2.0).text("+ random s"));
        ui.add(egui::Slider::new(&mut t.overshoot, 0.0..=6.0).text("overshoot"));
        ui.add(egui::Slider::new(&mut t.color_delay_factor, 0.0..=1.0).text("colour delay"));
        ui.add(egui::Slider::new(&mut t.spin_angle, 0.0..=4.0 * std::f32::consts::PI).text("spin rad"));
        ui.add(egui::Slider::new(&mut t.spin_duration, 0.1..=3.0).text("spin s"));
        ui.add(egui::Slider::new(&mut t.count_duration, 0.0..=2.0).text("count s"));
        ui.horizontal(|ui| {
            ui.label("match");
            ui.selectable_value(&mut t.assignment, Assignment::Height, "height");
            ui.selectable_value(&mut t.assignment, Assignment::Morton, "Morton");
            ui.selectable_value(&mut t.assignment, Assignment::Grid, "grid");
        });
        if ui.button("reset timings").clicked() {
            *t = TransitionSettings::default();
        }
    });
}

fn stats(ui: &mut egui::Ui, library: &ModelLibrary, models: &Assets<VoxelModelAsset>, pool: &VoxelPool, hollow: bool) {
    ui.heading("Current");
    let Some(entry) = library.current_entry() else {
        ui.label("no models");
        return;
    };
    ui.label(&entry.name);
    match &entry.status {
        ModelStatus::Loading | ModelStatus::Voxelizing => {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label(job_stage(entry));
            });
        }
        ModelStatus::Failed(reason) => {
            ui.colored_label(RED, reason);
        }
        ModelStatus::Ready => {}
    }
    if let Some(warning) = &entry.warning {
        ui.colored_label(AMBER, egui::RichText::new(format!("⚠ {warning}")).small());
    }
    if let Some(model) = entry.shown_handle().and_then(|h| models.get(h)) {
        let s = model.stats;
        let shown = model.shown_count(hollow);
        ui.label(format!("{shown} voxels shown ({} filled, {} visible)", s.voxels, s.visible));
        if shown > MAX_DRAWN {
            ui.colored_label(egui::Color32::from_rgb(200, 60, 60), format!("drawing the first {MAX_DRAWN} (the cap)"));
        }
        ui.label(format!(
            "grid {}×{}×{}, {} triangles, {} colours",
            s.grid[0],
            s.grid[1],
            s.grid[2],
            s.triangles,
            model.color_count()
        ));
        ui.label(format!("voxelized in {:.1} ms, {}", entry.voxelize_ms, megabytes(model.memory_bytes())));
    }
    ui.label(format!("voxel pool: {} slots", pool.slots.len()));
}

/// A byte count for the panel, e.g. "1.4 MB of voxel data".
fn megabytes(bytes: usize) -> String {
    format!("{:.1} MB of voxel data", bytes as f64 / 1e6)
}

/// What the panel's Export and Record buttons read and send.
#[derive(SystemParam)]
struct Outputs<'w> {
    export_status: Res<'w, ExportStatus>,
    export: MessageWriter<'w, ExportRequest>,
    record_status: Res<'w, RecordStatus>,
    record: MessageWriter<'w, ToggleRecord>,
}

/// A small status line under a button, red when `failed`.
fn status_line(ui: &mut egui::Ui, message: Option<String>, failed: bool) {
    if let Some(message) = message {
        let text = egui::RichText::new(message).small();
        if failed {
            ui.colored_label(RED, text);
        } else {
            ui.label(text);
        }
    }
}

/// The Export button (Ctrl+S), the Record button (Ctrl+R) and what the last export and recording did.
fn output_buttons(ui: &mut egui::Ui, outputs: &mut Outputs) {
    let exporting = *outputs.export_status == ExportStatus::Writing;
    if ui.add_enabled(!exporting, egui::Button::new("Export (Ctrl+S)")).clicked() {
        outputs.export.write(ExportRequest);
    }
    let status = &*outputs.export_status;
    status_line(ui, status.message(), matches!(status, ExportStatus::Failed(_)));
    let record = &*outputs.record_status;
    let (label, enabled) = match record {
        RecordStatus::Recording(..) => ("■ Stop recording (Ctrl+R)", true),
        RecordStatus::Writing(_) => ("● Record GIF (Ctrl+R)", false),
        _ => ("● Record GIF (Ctrl+R)", true),
    };
    if ui.add_enabled(enabled, egui::Button::new(label)).clicked() {
        outputs.record.write(ToggleRecord);
    }
    status_line(ui, record.message(), matches!(record, RecordStatus::Failed(_)));
}

fn panel(
    mut contexts: EguiContexts,
    mut settings: ResMut<VoxelSettings>,
    mut drag: ResMut<SettingDrag>,
    mut repel: ResMut<RepelSettings>,
    panel_open: Res<PanelOpen>,
    style: Res<State<Style>>,
    mut next_style: ResMut<NextState<Style>>,
    library: Res<ModelLibrary>,
    models: Res<Assets<VoxelModelAsset>>,
    pool: Res<VoxelPool>,
    mut requests: MessageWriter<LibraryRequest>,
    mut over: ResMut<PointerOverUi>,
    mut transition: ResMut<TransitionSettings>,
    mut outputs: Outputs,
    (mut animation_requests, mut color_settings, palette_files): (
        MessageWriter<AnimationRequest>,
        ResMut<ColorSettings>,
        Res<PaletteFiles>,
    ),
) -> Result {
    let ctx = contexts.ctx_mut()?;
    ctx.set_visuals(egui::Visuals::light());
    over.panel = ctx.is_pointer_over_egui() || ctx.egui_wants_pointer_input();
    if !panel_open.0 {
        drag.set_if_neq(SettingDrag(false));
        return Ok(());
    }
    let mut root = egui::Ui::new(
        ctx.clone(),
        "root".into(),
        egui::UiBuilder::new().layer_id(egui::LayerId::background()).max_rect(ctx.viewport_rect()),
    );
    let mut edited = settings.clone();
    let mut chosen = *style.get();
    let mut edited_repel = repel.clone();
    let mut edited_colors = color_settings.0.clone();
    let mut dragging = false;
    egui::Panel::left("voxel-art panel").resizable(false).exact_size(270.0).show_inside(&mut root, |ui| {
        egui::ScrollArea::vertical().show(ui, |ui| {
            ui.heading("voxel-art");
            model_list(ui, &library, &mut requests);
            ui.separator();
            if let Some(playback) = library.current_entry().and_then(|e| e.animation.as_ref()) {
                animation(ui, playback, &mut animation_requests);
                ui.separator();
            }
            dragging = parameters(ui, &mut edited, &mut chosen, &mut edited_repel);
            ui.separator();
            colors(ui, &mut edited_colors, &palette_files);
            ui.separator();
            let mut edited_transition = transition.clone();
            transition_settings(ui, &mut edited_transition);
            if edited_transition != *transition {
                *transition = edited_transition;
            }
            ui.separator();
            stats(ui, &library, &models, &pool, settings.hollow);
            output_buttons(ui, &mut outputs);
            if let Some(error) = &library.last_error {
                ui.separator();
                ui.colored_label(RED, format!("last error: {error}"));
            }
            ui.separator();
            ui.label(egui::RichText::new("Left/Right/Space: cycle · 1-9: pick · click: next · S: style · Ctrl+S: export · Ctrl+R: record GIF · F: drop · R: repel · P: play/pause · H: panel · Esc: quit").small());
        });
    });
    // Only touch the resource when something changed, so change detection means "edited".
    if edited != *settings {
        *settings = edited;
    }
    drag.set_if_neq(SettingDrag(dragging));
    if edited_repel != *repel {
        *repel = edited_repel;
    }
    if edited_colors != color_settings.0 {
        color_settings.0 = edited_colors;
    }
    if chosen != *style.get() {
        next_style.set(chosen);
    }
    Ok(())
}

pub(super) fn plugin(app: &mut App) {
    app.add_plugins(EguiPlugin::default());
    app.add_systems(EguiPrimaryContextPass, panel);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_model_whose_animation_is_ignored_says_so_in_the_list() {
        let mut entry = ModelEntry::new("fox".into(), "fox.glb".into(), "fox.glb".into(), ModelStatus::Ready);
        assert_eq!(entry_label(&entry), ("fox".to_owned(), None, None));
        entry.warning = Some("the animation is ignored: bad joint".into());
        assert_eq!(
            entry_label(&entry),
            ("fox  ⚠".to_owned(), Some(AMBER), Some("the animation is ignored: bad joint"))
        );
        entry.status = ModelStatus::Failed("unreadable".into());
        assert_eq!(entry_label(&entry), ("fox  ⚠ failed".to_owned(), Some(RED), Some("unreadable")));
    }
}
