//! The models of the corpus folder for benchmarks (included with `#[path]`).

use std::path::{Path, PathBuf};

/// The models of `dir` and of its subfolders, sorted.
pub fn corpus(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = voxel_core::files::expand_inputs(&[dir.to_path_buf()]);
    for sub in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        if sub.path().is_dir() {
            files.extend(voxel_core::files::expand_inputs(&[sub.path()]));
        }
    }
    files.sort();
    files
}
