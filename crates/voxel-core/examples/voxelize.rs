//! The headless voxelizer without the app: `cargo run --release -p voxel-core --example voxelize -- FILE …`
//! takes the arguments of `voxel-art voxelize` (what `benches/open3d_compare.py` runs, a fresh process a run).

/// mimalloc rather than the system allocator: a fresh process touches far fewer new pages (see
/// docs/benchmarks.md, "Cold process").
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    std::process::exit(voxel_core::cli::run(std::env::args_os()));
}
