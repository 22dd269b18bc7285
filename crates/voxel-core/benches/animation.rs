//! `cargo bench -p voxel-core --bench animation`: poses and voxelizes the animated models of ../shared/models
//! (or `VOXEL_ART_MODELS`) frame by frame at the default grid, in the clip's fixed grid, and prints a
//! Markdown table of medians: pose alone, voxelize alone, and both (one app frame's work), plus the CPU time
//! per frame summed over all threads (from /proc/self/task/*/schedstat on Linux), which a machine shared
//! with other builds inflates far less than wall time. Words after `--` keep only the models whose path
//! contains one of them (`-- fox`).

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

#[path = "../tests/support/models.rs"]
mod models;

#[path = "../tests/support/cpu.rs"]
mod cpu;
use cpu::cpu_ns;

fn median(mut times: Vec<f64>) -> f64 {
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

fn main() {
    let Some(dir) = models::models_dir() else { return };
    println!("threads: {}", rayon::current_num_threads());
    println!("| model | clip | triangles | grid | pose ms | voxelize ms | pose + voxelize ms | CPU ms / frame |");
    println!("|---|---|---:|---|---:|---:|---:|---:|");
    let options = VoxelizeOptions::default();
    // cargo bench passes `--bench`; other words filter the models.
    let filters: Vec<String> = std::env::args().skip(1).filter(|a| !a.starts_with("--")).collect();
    for name in MODELS.iter().filter(|m| filters.is_empty() || filters.iter().any(|f| m.contains(f.as_str()))) {
        let mut model = match load_animated_file(&dir.join(name)) {
            Ok(m) => m,
            Err(e) => {
                println!("| {name} | error: {e} | | | | | | |");
                continue;
            }
        };
        let clips: Vec<_> = model.clips().to_vec();
        for (clip, info) in clips.iter().enumerate() {
            let bounds = model.clip_bounds(clip).expect("bounds");
            let mut soup = TriangleSoup::default();
            let (mut pose, mut voxelize, mut both) = (Vec::new(), Vec::new(), Vec::new());
            let mut grid = [0; 3];
            let mut cpu_start = None;
            // A warm-up pass, then the timed one.
            for pass in 0..2 {
                if pass == 1 {
                    cpu_start = cpu_ns();
                }
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
            let cpu = cpu_start.zip(cpu_ns()).map_or_else(
                || "–".to_owned(),
                |(start, end)| format!("{:.2}", (end - start) as f64 / 1e6 / FRAMES as f64),
            );
            println!(
                "| {name} | {} | {} | {}×{}×{} | {:.3} | {:.2} | {:.2} | {cpu} |",
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
