//! Where the third-party test models are, shared by the core's and the app's tests (included with `#[path]`).

use std::path::PathBuf;

/// The folder of third-party test models: `VOXEL_ART_MODELS`, or `shared/models` beside the repository (found
/// from `CARGO_MANIFEST_DIR` at run time, else at build time).
///
/// `None`, with the reason printed, when the folder is absent; under CI (`CI=true`) a missing folder fails the
/// test instead, so a CI run can never pass by skipping the real models.
pub fn models_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("VOXEL_ART_MODELS").map(PathBuf::from).unwrap_or_else(|| {
        // Cargo sets the package's folder at run time too: a test binary built in another clone looks here.
        let manifest = std::env::var_os("CARGO_MANIFEST_DIR")
            .map_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")), PathBuf::from);
        let repo = manifest.ancestors().find(|d| d.join("Cargo.lock").is_file()).unwrap_or(&manifest);
        repo.join("../shared/models")
    });
    if dir.is_dir() {
        return Some(dir);
    }
    assert!(
        std::env::var("CI").as_deref() != Ok("true"),
        "test models not found at {} (CI=true: the corpus is required; set VOXEL_ART_MODELS)",
        dir.display()
    );
    println!("skipped: test models not found at {} (set VOXEL_ART_MODELS)", dir.display());
    None
}
