//! `cargo bench -p voxel-core --bench cold`: what a fresh process pays before its first voxelization is as
//! fast as the next ones (issue 13: "thread-pool start, first-touch of big allocations"), with the system
//! allocator's defaults, as a program embedding the library gets them (the command line keeps freed memory:
//! `cli::prepare_process`). The bench starts itself once per sample (medians
//! of 7) and reports the thread pool's start, the first voxelization, the warm median of the same soup again
//! (its part analysis cached) and of soups the process has not seen (what a fresh process's first
//! voxelization does too), and the overhead: pool start + first − warm of a new soup (the pool's threads, the
//! first touch of the allocations and of the code), each as wall time (CPU time), and the minor page faults of
//! the first voxelization (each a first touch of a 4 KiB page).

use std::path::Path;
use std::process::Command;
use std::time::Instant;

use voxel_core::{TriangleSoup, load_file, voxelize};

#[path = "../tests/support/models.rs"]
mod models;

#[path = "../tests/support/cpu.rs"]
mod cpu;

#[path = "support/timing.rs"]
mod timing;

use timing::{Timing, measure, measure_each, median, options};

/// Fresh processes per model in the cold table.
const COLD_SAMPLES: usize = 7;

/// The models of the cold table, with the grids they are voxelized at (`None`: the default grid).
const COLD_MODELS: [(&str, Option<u32>); 4] = [
    ("khronos-duck.glb", None),
    ("khronos-duck.glb", Some(128)),
    ("khronos-boxvertexcolors.glb", Some(128)),
    ("khronos-flighthelmet/FlightHelmet.gltf", Some(128)),
];

/// In a fresh process: the thread pool's start, the first voxelization, the median of the next five and that
/// of five voxelizations of soups not seen before (the model loaded again), in ms of wall time, then
/// the same in CPU time, then the first voxelization's minor page faults.
fn cold_child(file: &Path, r: Option<u32>) {
    let soup = load_file(file).expect("load");
    let options = options(r, false);
    let (cpu_start, started) = (cpu::cpu_ns().unwrap_or(0), Instant::now());
    rayon::join(|| (), || ());
    let (pool_cpu, pool) = (cpu::cpu_ns().unwrap_or(0), started.elapsed().as_secs_f64() * 1e3);
    let faults = cpu::minor_faults();
    voxelize(&soup, &options).expect("voxelize");
    let faults = cpu::minor_faults() - faults;
    let (first_cpu, first) = (cpu::cpu_ns().unwrap_or(0), started.elapsed().as_secs_f64() * 1e3 - pool);
    let (warm, _) = measure(&soup, &options, 5);
    // Loaded again: soups the voxelizer has not seen (no part analysis yet), as the importer makes them.
    let copies: Vec<TriangleSoup> = (1..=5).map(|_| load_file(file).expect("load")).collect();
    let (unseen, _) = measure_each(&copies, &options);
    let ms = |a: u64, b: u64| b.saturating_sub(a) as f64 / 1e6;
    let (pool_cpu_ms, first_cpu_ms) = (ms(cpu_start, pool_cpu), ms(pool_cpu, first_cpu));
    println!(
        "{pool} {first} {} {} {pool_cpu_ms} {first_cpu_ms} {} {} {faults}",
        warm.wall, unseen.wall, warm.cpu, unseen.cpu
    );
}

/// The cold table: medians over fresh processes.
fn print_cold(dir: &Path) {
    println!(
        "| model | grid | pool start ms | first voxelization ms | warm ms, same soup | warm ms, new soup | cold overhead ms | first voxelization's minor faults |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|");
    let exe = std::env::current_exe().expect("the bench's path");
    for (model, r) in COLD_MODELS {
        let file = dir.join(model);
        let samples: Vec<[f64; 9]> = (0..COLD_SAMPLES)
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
        let faults = median(samples.iter().map(|s| s[8]).collect());
        println!(
            "| {model} | {grid} | {} | {} | {} | {} | {overhead} | {faults} |",
            cell(0),
            cell(1),
            cell(2),
            cell(3)
        );
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
    print_cold(&dir);
}
