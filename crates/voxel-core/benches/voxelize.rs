//! `cargo bench -p voxel-core`: voxelizes every model of ../shared/models (or `VOXEL_ART_MODELS`) at
//! R = 32, 64, 128, 256 with the fast method (solid + shell + colour), the BVH column method at R = 128,
//! and the article's reference at R = 32 and 64, then prints a Markdown table (median of several runs).
//!
//! `cargo bench -p voxel-core --bench voxelize -- passes` instead prints the time of the fill, shell and
//! colour passes per model at R = 64 and 128 (medians of 7 runs), plus a cube under a node scale of 0.1 and
//! an open cube.
//!
//! `cargo bench -p voxel-core --bench voxelize -- fill-cost` prints, per model and R = 32, 64, 128, the
//! median time of the parity and the winding fill (interleaved runs in one process) and their ratio.
//!
//! `cargo bench -p voxel-core --bench voxelize -- fill-runs NAME R FILL N` loads the first model whose name
//! contains NAME and voxelizes it N times at R (or at each of a list, `32,48,64`: the app's grid slider;
//! `default`: the default cell size) with FILL (`winding` or `parity`), for an instruction count:
//! under `valgrind --tool=cachegrind --cache-sim=no` with `RAYON_NUM_THREADS=1`, (Ir at N − Ir at 0) / N is
//! one voxelization's instructions. It prints a hash of the outputs per R (to compare two builds).
//!
//! `cargo bench -p voxel-core --bench voxelize -- pass-runs NAME R N` voxelizes the first model whose name
//! contains NAME N times at R (or `default`; solid, default settings) and prints the median fill, shell and
//! colour pass times; nothing else runs, so under cachegrind (as for `fill-runs`) (Ir at N − Ir at 0) / N is one
//! voxelization's instructions.
//!
//! `cargo bench -p voxel-core --bench voxelize -- first-runs NAME R N [hollow]` voxelizes the first model whose
//! name contains NAME at R (or `default`) N times with the parity and N times with the winding fill, interleaved,
//! each run on the model loaded again (so every winding run pays the soup's part analysis, as the one-shot
//! CLI does), and prints the median and the minimum wall time of each (only the voxelize call is timed) and
//! their ratios.
//!
//! `cargo bench -p voxel-core --bench voxelize -- hashes` prints, per model, a hash of every output voxel
//! (cell, colour, part, visibility) at the default grid and R = 64, 128, 256, solid and hollow, plus the
//! default grid with the pastel remap and the shell alone (`--fill none`) at R = 128 and 256: two builds that print
//! the same lines give the same cells and colours.

use std::hash::{Hash, Hasher};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use voxel_core::shapes::cuboid;
use voxel_core::voxelize::{PassTimes, voxelize_timed};
use voxel_core::{FillMode, GridSize, Method, TriangleSoup, VoxelizeOptions, load_file, voxelize};

#[path = "../tests/support/models.rs"]
mod models;

#[path = "../tests/support/corpus.rs"]
mod corpus;
use corpus::corpus;

/// Median wall time in ms of `runs` voxelizations, and the voxel count.
fn time(soup: &TriangleSoup, r: u32, method: Method, runs: usize) -> (f64, usize) {
    let options = VoxelizeOptions { grid: GridSize::Resolution(r), method, ..Default::default() };
    let mut times = Vec::new();
    let mut voxels = 0;
    for _ in 0..runs {
        let t = Instant::now();
        let m = voxelize(soup, &options).expect("voxelize");
        times.push(t.elapsed().as_secs_f64() * 1e3);
        voxels = m.len();
    }
    times.sort_by(f64::total_cmp);
    (times[times.len() / 2], voxels)
}

/// The median of `values` in ms.
fn median_ms(mut values: Vec<Duration>) -> f64 {
    values.sort();
    values[values.len() / 2].as_secs_f64() * 1e3
}

/// The median fill, shell and colour pass times in ms.
fn pass_medians<'a>(times: impl Iterator<Item = &'a PassTimes> + Clone) -> [f64; 3] {
    let passes: [fn(&PassTimes) -> Duration; 3] = [|t| t.fill, |t| t.shell, |t| t.color];
    passes.map(|pass| median_ms(times.clone().map(pass).collect()))
}

/// Prints one row per resolution: the median fill, shell and colour pass times of `runs` voxelizations.
fn print_passes(name: &str, soup: &TriangleSoup, runs: usize) {
    for r in [64, 128] {
        let options = VoxelizeOptions { grid: GridSize::Resolution(r), ..Default::default() };
        let timed: Vec<_> = (0..runs).map(|_| voxelize_timed(soup, &options).expect("voxelize")).collect();
        let visible = timed[0].0.stats.visible;
        let [fill, shell, color] = pass_medians(timed.iter().map(|(_, t)| t));
        println!(
            "| {name} | {} | {r} | {visible} | {fill:.2} | {shell:.2} | {color:.2} | {:.2} |",
            soup.triangle_count(),
            color / shell
        );
    }
}

/// Prints one row per resolution: the median voxelize time with the parity and with the winding fill,
/// from `runs` interleaved pairs of runs (so that load on a shared machine hits both alike).
fn print_fill_cost(name: &str, soup: &TriangleSoup, runs: usize) {
    for r in [32, 64, 128] {
        let options = |fill| VoxelizeOptions { grid: GridSize::Resolution(r), fill, ..Default::default() };
        let (parity, winding) = (options(FillMode::Parity), options(FillMode::Winding));
        let run = |options: &VoxelizeOptions| {
            let t = Instant::now();
            voxelize(soup, options).expect("voxelize");
            t.elapsed()
        };
        let (parity_ms, winding_ms): (Vec<_>, Vec<_>) = (0..runs).map(|_| (run(&parity), run(&winding))).unzip();
        let (parity_ms, winding_ms) = (median_ms(parity_ms), median_ms(winding_ms));
        println!(
            "| {name} | {} | {r} | {parity_ms:.1} | {winding_ms:.1} | {:.2} |",
            soup.triangle_count(),
            winding_ms / parity_ms
        );
    }
}

/// Prints the output hashes of one model: solid and hollow at the default grid and R = 64, 128, 256, pastel at the
/// default grid, and the shell alone (`--fill none`, the equal work of `benches/open3d_compare.py`) at R = 128 and 256.
fn print_hashes(name: &str, soup: &TriangleSoup) {
    let grids = [GridSize::default(), GridSize::Resolution(64), GridSize::Resolution(128), GridSize::Resolution(256)];
    let runs = grids.iter().flat_map(|&grid| [false, true].map(|hollow| (grid, hollow, false, FillMode::Winding)));
    let shells = [128, 256].map(|r| (GridSize::Resolution(r), false, false, FillMode::None));
    let line: Vec<String> = runs
        .chain([(GridSize::default(), false, true, FillMode::Winding)])
        .chain(shells)
        .map(|(grid, hollow, pastel, fill)| {
            let options = VoxelizeOptions { grid, hollow, pastel, fill, ..Default::default() };
            let mut hasher = std::hash::DefaultHasher::new();
            voxelize(soup, &options).expect("voxelize").voxels().for_each(|v| v.hash(&mut hasher));
            format!("{:016x}", hasher.finish())
        })
        .collect();
    println!("{name}: {}", line.join(" "));
}

/// The grid of a bench argument: a resolution, or `default` (the default cell size).
fn grid_arg(r: &str) -> GridSize {
    match r {
        "default" => GridSize::default(),
        r => GridSize::Resolution(r.parse().expect("R or default")),
    }
}

/// The `N` words after the mode word at `args[at]`.
fn mode_args<'a, const N: usize>(args: &'a [String], at: usize, usage: &str) -> [&'a str; N] {
    std::array::from_fn(|k| args.get(at + 1 + k).unwrap_or_else(|| panic!("usage: {usage}")).as_str())
}

/// The first model of `files` whose path contains `name`.
fn model_named<'a>(files: &'a [PathBuf], name: &str) -> &'a std::path::Path {
    files.iter().find(|f| f.to_string_lossy().contains(name)).expect("no such model")
}

/// Prints the median wall time of `runs` first parity and first winding voxelizations of `soup` at `r`
/// (interleaved, each on a fresh copy of the soup that knows nothing of its parts yet) and their ratio.
fn print_first_runs(name: &str, file: &std::path::Path, r: &str, runs: usize, hollow: bool) {
    let options = |fill| VoxelizeOptions { grid: grid_arg(r), fill, hollow, ..Default::default() };
    let (parity, winding) = (options(FillMode::Parity), options(FillMode::Winding));
    let run = |options: &VoxelizeOptions| {
        // Loaded again: a soup as the command line has it, with no part analysis yet.
        let fresh = load_file(file).expect("load");
        let t = Instant::now();
        voxelize(&fresh, options).expect("voxelize");
        t.elapsed()
    };
    let (parity_ms, winding_ms): (Vec<_>, Vec<_>) = (0..runs).map(|_| (run(&parity), run(&winding))).unzip();
    // The minimum too: on a shared machine it is the run least disturbed by the other processes.
    let min_ms = |times: &[Duration]| times.iter().min().map_or(f64::NAN, |t| t.as_secs_f64() * 1e3);
    let (parity_min, winding_min) = (min_ms(&parity_ms), min_ms(&winding_ms));
    let (parity_ms, winding_ms) = (median_ms(parity_ms), median_ms(winding_ms));
    println!(
        "{name} R={r}{}: parity {parity_ms:.2} ms, first winding {winding_ms:.2} ms, ratio {:.3} (medians of {runs}); \
         minima {parity_min:.2} / {winding_min:.2} ms, ratio {:.3}",
        if hollow { " hollow" } else { "" },
        winding_ms / parity_ms,
        winding_min / parity_min
    );
}

/// Calls `f` with the name (relative to `dir`) and soup of every model of `files` that loads.
fn for_each_model(files: &[PathBuf], dir: &std::path::Path, f: impl Fn(&str, &TriangleSoup)) {
    for file in files {
        if let Ok(soup) = load_file(file) {
            f(&file.strip_prefix(dir).unwrap_or(file).display().to_string(), &soup);
        }
    }
}

fn main() {
    let Some(dir) = models::models_dir() else { return };
    let files = corpus(&dir);
    if files.is_empty() {
        println!("no models found in {} (set VOXEL_ART_MODELS)", dir.display());
        return;
    }
    println!("threads: {}", rayon::current_num_threads());
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "passes") {
        println!("| model | triangles | R | visible | fill ms | shell ms | colour ms | colour / shell |");
        println!("|---|---:|---:|---:|---:|---:|---:|---:|");
        for_each_model(&files, &dir, |name, soup| print_passes(name, soup, 7));
        let cube = TriangleSoup::from_mesh(&cuboid([-0.1; 3], [0.1; 3]), [1.0; 4]);
        print_passes("cube ±0.1 (a ±1 cube under node scale 0.1), built", &cube, 7);
        // Without its +x face: the middle of that side is far from every triangle (the colour's BVH query).
        let mut open = cuboid([-1.0; 3], [1.0; 3]);
        let positions = open.positions.clone();
        open.triangles.retain(|t| !t.iter().all(|&i| positions[i as usize][0] == 1.0));
        print_passes("cube without its +x face, built", &TriangleSoup::from_mesh(&open, [1.0; 4]), 7);
        return;
    }
    if let Some(at) = args.iter().position(|a| a == "fill-runs") {
        let [name, r, fill, n] = mode_args(&args, at, "fill-runs NAME R FILL N");
        let fill = if fill == "parity" { FillMode::Parity } else { FillMode::Winding };
        let options = |r: &str| VoxelizeOptions { grid: grid_arg(r), fill, ..Default::default() };
        let soup = load_file(model_named(&files, name)).expect("load");
        let resolutions: Vec<&str> = r.split(',').collect();
        let mut hashers = vec![std::hash::DefaultHasher::new(); resolutions.len()];
        for _ in 0..n.parse().expect("N") {
            for (r, hasher) in resolutions.iter().zip(&mut hashers) {
                voxelize(&soup, &options(r)).expect("voxelize").voxels().for_each(|v| v.hash(hasher));
            }
        }
        for (r, hasher) in resolutions.iter().zip(&hashers) {
            println!("R={r}: output hash {:016x}", hasher.finish());
        }
        return;
    }
    if let Some(at) = args.iter().position(|a| a == "first-runs") {
        let [name, r, n] = mode_args(&args, at, "first-runs NAME R N [hollow]");
        let hollow = args.get(at + 4).is_some_and(|a| a == "hollow");
        print_first_runs(name, model_named(&files, name), r, n.parse().expect("N"), hollow);
        return;
    }
    if let Some(at) = args.iter().position(|a| a == "pass-runs") {
        let [name, r, n] = mode_args(&args, at, "pass-runs NAME R N");
        let options = VoxelizeOptions { grid: grid_arg(r), ..Default::default() };
        let soup = load_file(model_named(&files, name)).expect("load");
        let times: Vec<PassTimes> =
            (0..n.parse().expect("N")).map(|_| voxelize_timed(&soup, &options).expect("voxelize").1).collect();
        if !times.is_empty() {
            let [fill, shell, color] = pass_medians(times.iter());
            println!("{name} R={r}: fill {fill:.2} ms, shell {shell:.2} ms, colour {color:.2} ms (medians of {n})");
        }
        return;
    }
    if args.iter().any(|a| a == "hashes") {
        for_each_model(&files, &dir, print_hashes);
        return;
    }
    if args.iter().any(|a| a == "fill-cost") {
        println!("| model | triangles | R | parity ms | winding ms | winding / parity |");
        println!("|---|---:|---:|---:|---:|---:|");
        for_each_model(&files, &dir, |name, soup| print_fill_cost(name, soup, 9));
        return;
    }
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
