//! The command line: `voxel-art [MODEL|FOLDER…] [--style S] [--palette P] [--export-dir DIR] [--screenshot out.png --frames
//! N | --record out.gif --seconds S]` opens the app, `voxel-art voxelize FILE…` runs the core's headless voxelizer ([`Cli`]). The app's
//! arguments become its starting configuration in [`AppArgs::configure`], the one place that reads them: it
//! inserts the starting resources the plugins read (no system sees the raw command line).

use std::path::PathBuf;

use bevy::prelude::*;
use clap::{Parser, Subcommand};
use voxel_core::cli::palette::PaletteArgs;
use voxel_core::palette::Palette;

use crate::animation::AnimationStart;
use crate::export::ExportDir;
use crate::input::PointerMode;
use crate::library::LibrarySetup;
use crate::record::{DEFAULT_SECONDS, HeadlessRecord, RecordPlugin, RecordSize};
use crate::screenshot::ScreenshotPlugin;
use crate::settings::{ColorSettings, VoxelSettings};
use crate::style::Style;
use crate::transition::{Assignment, TransitionSettings};

/// The whole command line: the app's arguments, or a subcommand.
#[derive(Parser, Debug)]
#[command(
    name = "voxel-art",
    version,
    propagate_version = true,
    args_conflicts_with_subcommands = true,
    about = "Turns glTF/GLB models into animated voxel art."
)]
pub struct Cli {
    /// A headless command instead of the app.
    #[command(subcommand)]
    pub command: Option<Command>,
    /// The app's arguments (without a subcommand).
    #[command(flatten)]
    pub app: AppArgs,
}

/// The subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    // `voxel-art voxelize …`, the core's headless voxelizer (a plain comment: a doc comment here would
    // replace the help text the core gives it).
    Voxelize(voxel_core::cli::VoxelizeArgs),
}

impl Cli {
    /// Parses `args` (the first is the program name); on `--help`, `--version` or a usage error prints it and
    /// returns the exit status to use (0, or 2 for an error).
    pub fn parse_args(args: Vec<std::ffi::OsString>) -> Result<Self, i32> {
        Self::try_parse_from(args).map_err(|e| voxel_core::cli::report_parse_error(&e))
    }
}

/// Parsed command line of the app.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct AppArgs {
    /// Extra models (.glb/.gltf) or folders of models to add to the shipped ones.
    pub models: Vec<PathBuf>,
    /// Render for --frames frames, save a screenshot of the window to this PNG and exit.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Frames to run before the screenshot.
    #[arg(long, default_value_t = 120)]
    pub frames: u32,
    /// Leave out the shipped models (show only the ones given).
    #[arg(long)]
    pub no_shipped: bool,
    /// Start with the model at this index of the list (0-based).
    #[arg(long, default_value_t = 0)]
    pub start: usize,
    /// With --screenshot or --record: once the first model has settled, switch to this model (0-based) and
    /// count --frames (or record) from the switch: the morph.
    #[arg(long)]
    pub then: Option<usize>,
    /// Record the stage (not the panel or tiles) as an animated GIF once the first model has settled (30
    /// frames a second, time stepping 1/60 s a frame), write it here and exit. In the window, Ctrl+R records.
    #[arg(long, value_name = "OUT.gif", conflicts_with = "screenshot")]
    pub record: Option<PathBuf>,
    /// With --record: seconds to record [default: 4].
    #[arg(long, value_name = "S", requires = "record", value_parser = seconds)]
    pub seconds: Option<f32>,
    /// The size of recorded GIFs (--record and Ctrl+R) [default: 480x270].
    #[arg(long, value_name = "WxH")]
    pub record_size: Option<RecordSize>,
    /// With --screenshot or --record: let the pointer (where the window opened: the centre under Xvfb) repel voxels and
    /// burst bubbles; without it a screenshot ignores the pointer.
    #[arg(long)]
    pub repel: bool,
    /// Cell width in model units (the model's diagonal is 9; the panel's grid size, 0.03 to 0.6).
    #[arg(long, value_name = "CELL", value_parser = grid_cell)]
    pub grid_size: Option<f32>,
    /// Show every voxel, the interior too (hollow off).
    #[arg(long)]
    pub solid: bool,
    /// Start in this style (S cycles them).
    #[arg(long, value_enum)]
    pub style: Option<Style>,
    /// How voxels are matched to the next model's cells (also in the panel).
    #[arg(long = "match", value_enum)]
    pub assignment: Option<Assignment>,
    /// Where Ctrl+S (and the panel's Export button) saves the shown model as .vox and .glb [default:
    /// ./voxel-art-exports].
    #[arg(long, value_name = "DIR")]
    pub export_dir: Option<PathBuf>,
    /// An animated model plays this clip (name or index) [default: its first].
    #[arg(long, value_name = "NAME|INDEX")]
    pub clip: Option<String>,
    /// An animated model starts paused this many seconds into its clip (P plays). With --screenshot, several
    /// times (`0,0.3,0.6`) save one PNG each (`out-0.png`, `out-1.png`, …), --frames after each.
    #[arg(long, value_name = "SECONDS", value_delimiter = ',')]
    pub anim_time: Vec<f32>,
    /// The starting colour stage (the panel's Colours section), as `voxel-art voxelize` takes it; the app's
    /// palette is pastel unless one is named.
    #[command(flatten)]
    pub colors: PaletteArgs,
}

/// Parses a `--grid-size` within the panel's range.
fn grid_cell(text: &str) -> Result<f32, String> {
    let cell: f32 = text.parse().map_err(|e| format!("{e}"))?;
    let range = VoxelSettings::GRID_RANGE;
    if range.contains(&cell) { Ok(cell) } else { Err(format!("{cell} is outside {}..={}", range.start(), range.end())) }
}

impl AppArgs {
    /// The starting colour stage (`--palette`, pastel when none is named, `--colors`, `--dither`), or
    /// `error: <argument>: <reason>`.
    pub fn color_settings(&self) -> Result<ColorSettings, String> {
        self.colors.stage_or(Palette::Pastel).map(ColorSettings).map_err(|(what, e)| format!("error: {what}: {e}"))
    }

    /// Inserts the starting configuration these arguments ask for: the model list, the style (a state: call
    /// after `StatesPlugin`), when the pointer counts, the voxel-to-cell matching and the exports folder (call
    /// before the plugins that read them are added).
    pub fn configure(&self, app: &mut App) {
        let defaults = VoxelSettings::default();
        app.insert_resource(VoxelSettings {
            grid_size: self.grid_size.unwrap_or(defaults.grid_size),
            hollow: defaults.hollow && !self.solid,
            ..defaults
        });
        app.insert_resource(LibrarySetup { shipped: !self.no_shipped, extra: self.models.clone(), start: self.start });
        app.insert_state(self.style.unwrap_or_default());
        app.insert_resource(match (self.headless(), self.repel) {
            (true, true) => PointerMode::Always,
            (true, false) => PointerMode::Never,
            (false, _) => PointerMode::AfterMove,
        });
        let transition = TransitionSettings::default();
        app.insert_resource(TransitionSettings {
            assignment: self.assignment.unwrap_or(transition.assignment),
            ..transition
        });
        app.insert_resource(self.export_dir.clone().map_or_else(ExportDir::default, ExportDir));
        // `run_app` refuses a bad colour stage before the app is built; here it can only be the default.
        app.insert_resource(self.color_settings().unwrap_or_default());
        app.insert_resource(AnimationStart { clip: self.clip.clone(), time: self.anim_time.first().copied() });
    }

    /// The `--screenshot` capture, when asked for.
    pub(crate) fn screenshot_plugin(&self) -> Option<ScreenshotPlugin> {
        let path = self.screenshot.clone()?;
        let seeks = self.anim_time.iter().skip(1).copied().collect();
        Some(ScreenshotPlugin { path, frames: self.frames, then: self.then, seeks })
    }

    /// Whether this run captures headless (`--screenshot` or `--record`) and exits.
    pub(crate) fn headless(&self) -> bool {
        self.screenshot.is_some() || self.record.is_some()
    }

    /// The recorder: Ctrl+R in the window, or the `--record` run.
    pub(crate) fn record_plugin(&self) -> RecordPlugin {
        let headless = self.record.clone().map(|path| HeadlessRecord {
            path,
            seconds: self.seconds.unwrap_or(DEFAULT_SECONDS),
            then: self.then,
        });
        RecordPlugin { size: self.record_size.unwrap_or_default(), headless }
    }
}

/// `--seconds`: a positive number of seconds, at most ten minutes.
fn seconds(s: &str) -> Result<f32, String> {
    s.parse::<f32>()
        .ok()
        .filter(|v| *v > 0.0 && *v <= 600.0)
        .ok_or_else(|| format!("expected seconds between 0 and 600, got {s}"))
}
