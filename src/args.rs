//! The app's command line: `voxel-art [MODEL|FOLDER…] [--screenshot out.png --frames N]`.

use std::path::{Path, PathBuf};

use bevy::prelude::Resource;
use clap::Parser;

use crate::settings::Style;
use crate::transition::Assignment;

/// Parsed command line of the app.
#[derive(Parser, Resource, Clone, Debug, Default)]
#[command(
    name = "voxel-art",
    version,
    about = "Turns glTF/GLB models into animated voxel art.\n\nHeadless voxelizer: voxel-art voxelize --help"
)]
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
    /// With --screenshot: once the first model has settled, switch to this model (0-based) and count
    /// --frames from the switch (a frame of the morph).
    #[arg(long)]
    pub then: Option<usize>,
    /// Start in this style (S cycles them).
    #[arg(long, value_enum)]
    pub style: Option<Style>,
    /// How voxels are matched to the next model's cells (also in the panel).
    #[arg(long = "match", value_enum)]
    pub assignment: Option<Assignment>,
}

impl AppArgs {
    /// Parses `args`; on `--help` or a usage error prints it and returns the exit status to use.
    pub fn parse_from(args: Vec<std::ffi::OsString>) -> Result<Self, i32> {
        Self::try_parse_from(args).map_err(|e| {
            let _ = e.print();
            if e.use_stderr() { 2 } else { 0 }
        })
    }
}

/// The folder holding `models/` and `shaders/`: `BEVY_ASSET_ROOT` or `VOXEL_ART_ASSETS` if set, else
/// `assets` next to the executable's crate when run through cargo, else `assets` in the current folder.
pub fn asset_root() -> PathBuf {
    if let Some(dir) = std::env::var_os("VOXEL_ART_ASSETS") {
        return PathBuf::from(dir);
    }
    let candidates = [
        std::env::var_os("BEVY_ASSET_ROOT").map(|d| PathBuf::from(d).join("assets")),
        std::env::var_os("CARGO_MANIFEST_DIR").map(|d| PathBuf::from(d).join("assets")),
        Some(Path::new(env!("CARGO_MANIFEST_DIR")).join("assets")),
        std::env::current_exe().ok().and_then(|e| e.parent().map(|p| p.join("assets"))),
    ];
    candidates.into_iter().flatten().find(|p| p.join("models").is_dir()).unwrap_or_else(|| PathBuf::from("assets"))
}
