//! Where assets come from: the asset folder (shipped models, shaders) and the `fs` source that reads any file
//! on disk (models named on the command line or dropped on the window).

use std::path::{Path, PathBuf};

use bevy::asset::io::AssetSourceBuilder;
use bevy::prelude::*;

/// The asset source that reads any file on disk.
pub const FILE_SOURCE: &str = "fs";

/// The folder holding `models/` and `shaders/`: `VOXEL_ART_ASSETS` if set, else the first of `BEVY_ASSET_ROOT`'s
/// and `CARGO_MANIFEST_DIR`'s `assets` (at run time, then at build time) and `assets` next to the executable
/// that has a `models` folder, else `assets` in the current folder.
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

/// The asset path for a file on disk (through the `fs` source, so any folder works).
pub fn file_asset_path(path: &Path) -> String {
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_owned());
    let text = absolute.to_string_lossy().replace('\\', "/");
    format!("{FILE_SOURCE}://{}", text.trim_start_matches('/'))
}

/// Registers the `fs` source (before `AssetPlugin` is added) and returns the `AssetPlugin` reading the asset
/// folder.
pub fn asset_plugin(app: &mut App) -> AssetPlugin {
    app.register_asset_source(FILE_SOURCE, AssetSourceBuilder::platform_default("/", None));
    AssetPlugin { file_path: asset_root().display().to_string(), ..default() }
}
