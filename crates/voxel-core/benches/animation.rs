//! `cargo bench -p voxel-core --bench animation`: poses and voxelizes the animated models of ../shared/models
//! (or `VOXEL_ART_MODELS`) frame by frame at the default grid, in the clip's fixed grid, and prints a
//! Markdown table of medians: pose alone, voxelize alone, and both (one app frame's work).

use std::path::{Path, PathBuf};
use std::time::Instant;

use voxel_core::{TriangleSoup, VoxelizeOptions, load_animated_file, voxelize_within};

const MODELS: &[&str] = &[
    "khronos-fox.glb",
    "khronos-cesiumman.glb",
    "khronos-animatedmorphcube/AnimatedMorphCube.gltf",
    "khronos-cesiummilktruck/CesiumMilkTruck.gltf",
];

/// Frames timed per clip: the clip sampled at this many evenly spaced times.
const FRAMES: usize = 60;

fn models_dir() -> PathBuf {
    std::env::var_os("VOXEL_ART_MODELS")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/models"))
}

fn median(mut times: Vec<f64>) -> f64 {
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

fn main() {
    let dir = models_dir();
    println!("threads: {}", rayon::current_num_threads());
    println!("| model | clip | triangles | grid | pose ms | voxelize ms | pose + voxelize ms |");
    println!("|---|---|---:|---|---:|---:|---:|");
    let options = VoxelizeOptions::default();
    for name in MODELS {
        let mut model = match load_animated_file(&dir.join(name)) {
            Ok(m) => m,
            Err(e) => {
                println!("| {name} | error: {e} | | | | | |");
                continue;
            }
        };
        let clips: Vec<_> = model.clips().to_vec();
        for (clip, info) in clips.iter().enumerate() {
            let bounds = model.clip_bounds(clip).expect("bounds");
            let mut soup = TriangleSoup::default();
            let (mut pose, mut voxelize, mut both) = (Vec::new(), Vec::new(), Vec::new());
            let mut grid = [0; 3];
            // A warm-up pass, then the timed one.
            for pass in 0..2 {
                for frame in 0..FRAMES {
                    let t = info.duration * frame as f32 / FRAMES as f32;
                    let t0 = Instant::now();
                    model.pose_into(clip, t, &mut soup).expect("pose");
                    let t1 = Instant::now();
                    let voxels = voxelize_within(&soup, &options, bounds).expect("voxelize");
                    let t2 = Instant::now();
                    grid = voxels.stats.grid;
                    if pass == 1 {
                        pose.push((t1 - t0).as_secs_f64() * 1e3);
                        voxelize.push((t2 - t1).as_secs_f64() * 1e3);
                        both.push((t2 - t0).as_secs_f64() * 1e3);
                    }
                }
            }
            println!(
                "| {name} | {} | {} | {}×{}×{} | {:.3} | {:.2} | {:.2} |",
                info.name,
                soup.triangle_count(),
                grid[0],
                grid[1],
                grid[2],
                median(pose),
                median(voxelize),
                median(both)
            );
        }
    }
}
