//! `voxel-art`: with no subcommand, the app; `voxel-art voxelize …`, the headless voxelizer.

fn main() {
    let args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    if args.get(1).is_some_and(|a| a == "voxelize") {
        std::process::exit(voxel_core::cli::run(args.into_iter().skip(1)));
    }
    std::process::exit(voxel_art::run(args));
}
