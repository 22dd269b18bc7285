//! Shared helpers for the app tests.

use std::path::PathBuf;

/// The folder of third-party test models, or `None` (reason printed) when absent.
pub fn models_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("VOXEL_ART_MODELS")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/models"));
    if dir.is_dir() {
        Some(dir)
    } else {
        println!("skipped: test models not found at {} (set VOXEL_ART_MODELS)", dir.display());
        None
    }
}

/// A fresh scratch folder for one test.
pub fn scratch_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("voxel-art-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
