//! Shared helpers for the app tests.

use std::path::PathBuf;

#[path = "../../crates/voxel-core/tests/support/models.rs"]
mod models;
pub use models::models_dir;

/// A fresh scratch folder for one test.
pub fn scratch_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("voxel-art-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
