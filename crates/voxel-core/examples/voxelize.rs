//! The headless voxelizer without the app: `cargo run --release -p voxel-core --example voxelize -- FILE …`
//! takes the arguments of `voxel-art voxelize` (what `benches/open3d_compare.py` runs, a fresh process a run).

fn main() {
    voxel_core::cli::prepare_process();
    std::process::exit(voxel_core::cli::run(std::env::args_os()));
}
