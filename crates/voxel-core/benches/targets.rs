//! `cargo bench -p voxel-core --bench targets`: the speed targets of issue 13 on every model of
//! ../shared/models (or `VOXEL_ART_MODELS`), in one warm process: the article's default grid, solid output
//! (fill + shell + colour) at R = 64, 128 and 256, hollow output at R = 256, and the exponent k of
//! time ∝ R^k fitted over R = 64…256 (least squares on the logarithms of the CPU-time medians). Every figure
//! is the median wall time of several runs after one warm-up, with the median CPU time summed over all
//! threads in brackets (a machine shared with other builds inflates it far less). Words after `--` keep
//! only the models whose path contains one of them.
//!
//! `-- cold` instead measures what a fresh process pays before its first voxelization is as fast as the
//! next ones: it starts itself once per sample (medians of 7) and reports the thread pool's start, the first
//! voxelization, the warm median of the same soup again (its part analysis cached) and of soups the process
//! has not seen (what a fresh process's first voxelization does too), and the overhead: pool start + first −
//! warm of a new soup (the pool's threads, the first touch of the allocations and of the code), each as wall
//! time (CPU time).

use std::path::Path;
use std::process::Command;
use std::time::Instant;

use voxel_core::{GridSize, TriangleSoup, VoxelizeOptions, load_file, voxelize};

#[path = "../tests/support/models.rs"]
mod models;

#[path = "../tests/support/corpus.rs"]
mod corpus;

#[path = "../tests/support/cpu.rs"]
mod cpu;

/// The resolutions of the growth fit.
const RESOLUTIONS: [u32; 3] = [64, 128, 256];

/// Fresh processes per model in the cold table.
const COLD_SAMPLES: usize = 7;

/// The models of the cold table, with the grids they are voxelized at (`None`: the default grid).
const COLD_MODELS: [(&str, Option<u32>); 4] = [
    ("khronos-duck.glb", None),
    ("khronos-duck.glb", Some(128)),
    ("khronos-boxvertexcolors.glb", Some(128)),
    ("khronos-flighthelmet/FlightHelmet.gltf", Some(128)),
];

/// Median wall and CPU time of some runs, in ms.
#[derive(Clone, Copy)]
struct Timing {
    wall: f64,
    cpu: f64,
}

impl std::fmt::Display for Timing {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:.2} ({:.2})", self.wall, self.cpu)
    }
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// One warm-up voxelization, then the medians of `runs`; also the grid of the last one.
fn measure(soup: &TriangleSoup, options: &VoxelizeOptions, runs: usize) -> (Timing, [u32; 3]) {
    measure_each(soup, &vec![soup; runs], options)
}

/// One warm-up voxelization of `warm_up`, then the medians of one voxelization of each of `soups`; also the
/// grid of the last one.
fn measure_each(warm_up: &TriangleSoup, soups: &[&TriangleSoup], options: &VoxelizeOptions) -> (Timing, [u32; 3]) {
    let mut grid = voxelize(warm_up, options).expect("voxelize").stats.grid;
    let (mut wall, mut cpu) = (Vec::new(), Vec::new());
    for soup in soups {
        let cpu_start = cpu::cpu_ns();
        let started = Instant::now();
        grid = voxelize(soup, options).expect("voxelize").stats.grid;
        wall.push(started.elapsed().as_secs_f64() * 1e3);
        cpu.push(cpu_start.zip(cpu::cpu_ns()).map_or(f64::NAN, |(a, b)| (b - a) as f64 / 1e6));
    }
    (Timing { wall: median(wall), cpu: median(cpu) }, grid)
}

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

fn options(r: Option<u32>, hollow: bool) -> VoxelizeOptions {
    let grid = r.map_or_else(GridSize::default, GridSize::Resolution);
    VoxelizeOptions { grid, hollow, ..Default::default() }
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

/// `soup` scaled by 2^`k`: the same grid triangles exactly (the grid is fitted to the bounds), but a soup the
/// voxelizer has not seen (its part analysis is not cached).
fn scaled(soup: &TriangleSoup, k: i32) -> TriangleSoup {
    let mut scaled = soup.clone();
    for v in &mut scaled.vertices {
        v.position = v.position.map(|c| c * 2f32.powi(k));
    }
    scaled
}

/// In a fresh process: the thread pool's start, the first voxelization, the median of the next five and that
/// of five voxelizations of soups not seen before (copies scaled by powers of two), in ms of wall time, then
/// the same in CPU time.
fn cold_child(file: &Path, r: Option<u32>) {
    let soup = load_file(file).expect("load");
    let options = options(r, false);
    let (cpu_start, started) = (cpu::cpu_ns().unwrap_or(0), Instant::now());
    rayon::join(|| (), || ());
    let (pool_cpu, pool) = (cpu::cpu_ns().unwrap_or(0), started.elapsed().as_secs_f64() * 1e3);
    voxelize(&soup, &options).expect("voxelize");
    let (first_cpu, first) = (cpu::cpu_ns().unwrap_or(0), started.elapsed().as_secs_f64() * 1e3 - pool);
    let (warm, _) = measure(&soup, &options, 5);
    let copies: Vec<TriangleSoup> = (1..=5).map(|k| scaled(&soup, k)).collect();
    let (unseen, _) = measure_each(&soup, &copies.iter().collect::<Vec<_>>(), &options);
    let ms = |a: u64, b: u64| b.saturating_sub(a) as f64 / 1e6;
    let (pool_cpu_ms, first_cpu_ms) = (ms(cpu_start, pool_cpu), ms(pool_cpu, first_cpu));
    println!("{pool} {first} {} {} {pool_cpu_ms} {first_cpu_ms} {} {}", warm.wall, unseen.wall, warm.cpu, unseen.cpu);
}

/// The cold table: medians over fresh processes.
fn print_cold(dir: &Path) {
    println!(
        "| model | grid | pool start ms | first voxelization ms | warm ms, same soup | warm ms, new soup | cold overhead ms |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|");
    let exe = std::env::current_exe().expect("the bench's path");
    for (model, r) in COLD_MODELS {
        let file = dir.join(model);
        let samples: Vec<[f64; 8]> = (0..COLD_SAMPLES)
            .map(|_| {
                let mut child = Command::new(&exe);
                child.arg("cold-child").arg(&file).arg(r.map_or_else(|| "default".into(), |r| r.to_string()));
                let out = child.output().expect("run the bench again");
                let text = String::from_utf8_lossy(&out.stdout);
                let values: Vec<f64> = text.split_whitespace().filter_map(|v| v.parse().ok()).collect();
                values.try_into().unwrap_or_else(|v| panic!("cold child printed {v:?}: {text}"))
            })
            .collect();
        // Each as "wall (CPU)": a column's medians, and the overhead pool + first − warm (new soup) per sample.
        let cell = |k: usize| {
            let (wall, cpu) =
                (median(samples.iter().map(|s| s[k]).collect()), median(samples.iter().map(|s| s[k + 4]).collect()));
            Timing { wall, cpu }
        };
        let overhead = |k: usize| median(samples.iter().map(|s| s[k] + s[k + 1] - s[k + 3]).collect());
        let overhead = Timing { wall: overhead(0), cpu: overhead(4) };
        let grid = r.map_or_else(|| "default".into(), |r| format!("R={r}"));
        println!("| {model} | {grid} | {} | {} | {} | {} | {overhead} |", cell(0), cell(1), cell(2), cell(3));
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| a != "--bench").collect();
    if let [mode, file, r] = args.as_slice()
        && mode == "cold-child"
    {
        return cold_child(Path::new(file), r.parse().ok());
    }
    let Some(dir) = models::models_dir() else { return };
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!("threads: {}; load average: {}", rayon::current_num_threads(), load.trim());
    if args.iter().any(|a| a == "cold") {
        return print_cold(&dir);
    }
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
