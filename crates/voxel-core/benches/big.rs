//! `cargo bench -p voxel-core --bench big`: big models, generated in code (no large files in the repository)
//! and written as .glb to `$TMPDIR/voxel-art-big`: 1M and 4M triangles of overlapping vertex-coloured spheres
//! (indexed `u32` primitives of 64 spheres, float VEC4 COLOR_0, no normals) and a 2M-triangle open height
//! field (one such primitive). Per scene it prints the file's size and read speed (file bytes / the median
//! time of `load_file`, warm page cache, as the CLI's `load_ms`) and, per mode and R (128, 256), the median
//! voxelize ms: `none` is `--fill none` (shell + colour: the work Open3D's surface voxelizer does), `full` the
//! default (winding fill + shell + colour). Every run voxelizes a soup loaded afresh, so it pays what the CLI's
//! one voxelization pays (the part analysis included). A hash of each output (every voxel: cell, colour,
//! part, visibility) tells two builds' outputs apart. Last, per scene, how soon a cancelled voxelization (R=256,
//! full) returns: cancelled 100 ms after it enters its fill stage, from another thread, as the app cancels a
//! stale job.
//!
//! Words after `--`: scene names to keep (e.g. `heightfield`); `runs=N` (default 3); `write DIR` writes the
//! scenes to DIR and stops (for `benches/open3d_compare.py --models DIR`).

use std::hash::{Hash, Hasher};
use std::path::Path;
use std::time::{Duration, Instant};

use voxel_core::{
    FillMode, GridSize, Progress, Stage, VoxelError, VoxelizeOptions, load_file, voxelize, voxelize_watched,
};

#[path = "../tests/support/scenes.rs"]
mod scenes;

#[allow(dead_code)] // only its median
#[path = "support/timing.rs"]
mod timing;

#[path = "../tests/support/cpu.rs"]
mod cpu;

use timing::median;

/// The resolutions measured.
const RESOLUTIONS: [u32; 2] = [128, 256];

/// Writes every scene whose name passes `keep` into `dir`; returns their paths.
fn write_scenes(dir: &Path, keep: impl Fn(&str) -> bool) -> Vec<std::path::PathBuf> {
    std::fs::create_dir_all(dir).expect("create the scenes' folder");
    let mut paths = Vec::new();
    for (name, make) in scenes::big_scenes().filter(|(name, _)| keep(name)) {
        let path = dir.join(name);
        std::fs::write(&path, scenes::to_glb(&make())).expect("write a scene");
        paths.push(path);
    }
    paths
}

/// Loads `path` and voxelizes it `runs` times per mode and R; prints a line per mode and R.
fn measure(path: &Path, runs: usize) {
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    let megabytes = std::fs::metadata(path).expect("scene written").len() as f64 / 1e6;
    let mut loads = Vec::new();
    for (mode, fill) in [("none", FillMode::None), ("full", FillMode::Winding)] {
        for r in RESOLUTIONS {
            let options = VoxelizeOptions { grid: GridSize::Resolution(r), fill, ..Default::default() };
            let mut times = Vec::new();
            let mut output = (0, 0, 0);
            for _ in 0..runs {
                let started = Instant::now();
                let soup = load_file(path).expect("load a scene");
                loads.push(started.elapsed().as_secs_f64() * 1e3);
                let started = Instant::now();
                let model = voxelize(&soup, &options).expect("voxelize a scene");
                times.push(started.elapsed().as_secs_f64() * 1e3);
                let mut hasher = std::hash::DefaultHasher::new();
                model.voxels().for_each(|v| v.hash(&mut hasher));
                output = (soup.triangle_count(), model.len(), hasher.finish());
            }
            let (triangles, voxels, hash) = output;
            println!("| {name} | {triangles} | {mode} | {r} | {:.1} | {voxels} | {hash:016x} |", median(times));
        }
    }
    let load_ms = median(loads);
    println!("| {name} | read | {megabytes:.1} MB in {load_ms:.1} ms | {:.0} MB/s |", megabytes / load_ms * 1e3);
    let stopped_ms = cancel_latency(path);
    println!("| {name} | cancelled | 100 ms into its fill stage | returned {stopped_ms:.1} ms after the cancel |");
}

/// How long a voxelization of `path` (R=256, full work) takes to return once cancelled from another thread
/// 100 ms after it enters its fill stage.
fn cancel_latency(path: &Path) -> f64 {
    let soup = load_file(path).expect("load a scene");
    let options = VoxelizeOptions { grid: GridSize::Resolution(256), ..Default::default() };
    let progress = Progress::new();
    std::thread::scope(|scope| {
        let run = scope.spawn(|| voxelize_watched(&soup, &options, &progress));
        while progress.stage() < Stage::Filling {
            std::thread::sleep(Duration::from_millis(1));
        }
        std::thread::sleep(Duration::from_millis(100));
        let cancelled = Instant::now();
        progress.cancel();
        let result = run.join().expect("the voxelization's thread");
        assert!(matches!(result, Err(VoxelError::Cancelled)), "the run ended before the cancel");
        cancelled.elapsed().as_secs_f64() * 1e3
    })
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| a != "--bench").collect();
    if let Some(at) = args.iter().position(|a| a == "write") {
        let dir = args.get(at + 1).expect("usage: write DIR");
        for path in write_scenes(Path::new(dir), |_| true) {
            println!("{}", path.display());
        }
        return;
    }
    let runs = args.iter().find_map(|a| a.strip_prefix("runs=")).map_or(3, |n| n.parse().expect("runs=N"));
    let names: Vec<&String> = args.iter().filter(|a| !a.starts_with("runs=")).collect();
    let dir = std::env::temp_dir().join("voxel-art-big");
    let paths = write_scenes(&dir, |name| names.is_empty() || names.iter().any(|n| name.contains(n.as_str())));
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!("threads: {}; load average: {}; scenes in {}", rayon::current_num_threads(), load.trim(), dir.display());
    println!("| scene | triangles | mode | R | voxelize ms (median of {runs}) | voxels | output hash |");
    println!("|---|---:|---|---:|---:|---:|---|");
    for path in paths {
        measure(&path, runs);
    }
}
