//! `voxel-art`: with no subcommand, the app; `voxel-art voxelize …`, the headless voxelizer (see
//! [`voxel_art::config::Cli`]).

/// mimalloc rather than the system allocator: a fresh `voxelize` process touches far fewer new pages (see
/// docs/benchmarks.md, "Cold process").
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    std::process::exit(voxel_art::run(std::env::args_os().collect()));
}
