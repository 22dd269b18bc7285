//! `voxel-art`: with no subcommand, the app; `voxel-art voxelize …`, the headless voxelizer (see
//! [`voxel_art::config::Cli`]).

fn main() {
    std::process::exit(voxel_art::run(std::env::args_os().collect()));
}
