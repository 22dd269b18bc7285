//! `cargo bench -p voxel-core --bench targets`: the speed targets of issue 13 on every model of
//! ../shared/models (or `VOXEL_ART_MODELS`), in one warm process: the article's default grid, solid output
//! (fill + shell + colour) at R = 64, 128 and 256, hollow output at R = 256, and the exponent k of
//! time ∝ R^k fitted over R = 64…256 (least squares on the logarithms of the CPU-time medians). Every figure
//! is the median wall time of several runs after one warm-up, with the median CPU time summed over all
//! threads in brackets (a machine shared with other builds inflates it far less). Words after `--` keep
//! only the models whose path contains one of them.
//!
//! What a fresh process pays before its first voxelization is as fast as the next ones is the `cold` bench.

use voxel_core::{TriangleSoup, load_file};

#[path = "../tests/support/models.rs"]
mod models;

#[path = "../tests/support/corpus.rs"]
mod corpus;

#[path = "../tests/support/cpu.rs"]
mod cpu;

#[path = "support/timing.rs"]
mod timing;

use timing::{Timing, measure, options};

/// The resolutions of the growth fit.
const RESOLUTIONS: [u32; 3] = [64, 128, 256];

/// The slope of ln t over ln r (least squares).
fn exponent(rs: &[u32], ts: &[f64]) -> f64 {
    let xs: Vec<f64> = rs.iter().map(|&r| f64::from(r).ln()).collect();
    let ys: Vec<f64> = ts.iter().map(|t| t.ln()).collect();
    let n = xs.len() as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

/// One row of the targets table.
fn print_targets(name: &str, soup: &TriangleSoup) {
    let (default, grid) = measure(soup, &options(None, false), 21);
    let solid: Vec<Timing> =
        RESOLUTIONS.iter().map(|&r| measure(soup, &options(Some(r), false), if r < 256 { 9 } else { 5 }).0).collect();
    let (hollow, _) = measure(soup, &options(Some(256), true), 5);
    let k = exponent(&RESOLUTIONS, &solid.iter().map(|t| t.cpu).collect::<Vec<_>>());
    let k_hollow = {
        let hollow_cpu: Vec<f64> =
            [64, 128].iter().map(|&r| measure(soup, &options(Some(r), true), 5).0.cpu).chain([hollow.cpu]).collect();
        exponent(&RESOLUTIONS, &hollow_cpu)
    };
    println!(
        "| {name} | {} | {}×{}×{} | {default} | {} | {} | {} | {k:.2} | {hollow} | {k_hollow:.2} |",
        soup.triangle_count(),
        grid[0],
        grid[1],
        grid[2],
        solid[0],
        solid[1],
        solid[2]
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| a != "--bench").collect();
    let Some(dir) = models::models_dir() else { return };
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!("threads: {}; load average: {}", rayon::current_num_threads(), load.trim());
    println!(
        "| model | triangles | default grid | default ms | R=64 ms | R=128 ms | R=256 ms | exponent | R=256 hollow ms | hollow exponent |"
    );
    println!("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|");
    for file in corpus::corpus(&dir) {
        let name = file.strip_prefix(&dir).unwrap_or(&file).display().to_string();
        if !args.is_empty() && !args.iter().any(|a| name.contains(a.as_str())) {
            continue;
        }
        match load_file(&file) {
            Ok(soup) => print_targets(&name, &soup),
            Err(e) => println!("| {name} | error: {e} |"),
        }
    }
}
