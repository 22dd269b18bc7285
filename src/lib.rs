//! voxel-art: turns glTF/GLB models into animated voxel art (Bevy app over the `voxel-core` library).

pub use voxel_core as voxel;

/// Runs the app with command-line `args` (the first is the program name); returns the exit status.
pub fn run(_args: Vec<std::ffi::OsString>) -> i32 {
    eprintln!("the interactive app is not built yet; use `voxel-art voxelize <FILE>...`");
    2
}
