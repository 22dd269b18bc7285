//! `cargo bench -p voxel-core`: voxelizes every model of ../shared/models (or `VOXEL_ART_MODELS`) at
//! R = 32, 64, 128, 256 with the fast method (solid + shell + colour), the BVH column method at R = 128,
//! and the article's reference at R = 32 and 64, then prints a Markdown table (median of several runs).

use std::path::PathBuf;
use std::time::Instant;

use voxel_core::{GridSize, Method, TriangleSoup, VoxelizeOptions, load_file, voxelize};

#[path = "../tests/support/models.rs"]
mod models;

/// Median wall time in ms of `runs` voxelizations, and the voxel count.
fn time(soup: &TriangleSoup, r: u32, method: Method, runs: usize) -> (f64, usize) {
    let options = VoxelizeOptions { grid: GridSize::Resolution(r), method, ..Default::default() };
    let mut times = Vec::new();
    let mut voxels = 0;
    for _ in 0..runs {
        let t = Instant::now();
        let m = voxelize(soup, &options).expect("voxelize");
        times.push(t.elapsed().as_secs_f64() * 1e3);
        voxels = m.voxels.len();
    }
    times.sort_by(f64::total_cmp);
    (times[times.len() / 2], voxels)
}

fn main() {
    let Some(dir) = models::models_dir() else { return };
    let mut files: Vec<PathBuf> = voxel_core::cli::expand_inputs(std::slice::from_ref(&dir));
    for sub in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
        if sub.path().is_dir() {
            files.extend(voxel_core::cli::expand_inputs(&[sub.path()]));
        }
    }
    files.sort();
    if files.is_empty() {
        println!("no models found in {} (set VOXEL_ART_MODELS)", dir.display());
        return;
    }
    println!("threads: {}", rayon::current_num_threads());
    println!(
        "| model | triangles | load ms | R | voxels | fast ms | bvh-column ms | reference ms | reference / fast |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for file in files {
        let name = file.strip_prefix(&dir).unwrap_or(&file).display().to_string();
        let t = Instant::now();
        let soup = match load_file(&file) {
            Ok(s) => s,
            Err(e) => {
                println!("| {name} | – | – | – | – | error: {e} | | | |");
                continue;
            }
        };
        let load_ms = t.elapsed().as_secs_f64() * 1e3;
        for r in [32, 64, 128, 256] {
            let (fast, voxels) = time(&soup, r, Method::Fast, if r >= 256 { 3 } else { 7 });
            let bvh = (r == 128).then(|| time(&soup, r, Method::Bvh, 5).0);
            let reference = (r <= 64).then(|| time(&soup, r, Method::Reference, 1).0);
            let cell = |v: Option<f64>| v.map_or_else(String::new, |v| format!("{v:.1}"));
            println!(
                "| {name} | {} | {load_ms:.1} | {r} | {voxels} | {fast:.1} | {} | {} | {} |",
                soup.triangle_count(),
                cell(bvh),
                cell(reference),
                reference.map_or_else(String::new, |r| format!("{:.0}×", r / fast)),
            );
        }
    }
}
