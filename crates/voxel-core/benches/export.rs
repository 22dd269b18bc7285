//! `cargo bench -p voxel-core --bench export`: the glTF export of khronos-boxvertexcolors at R = 64 and
//! khronos-duck at R = 128 (default voxelization) from ../shared/models (or `VOXEL_ART_MODELS`): faces,
//! rectangles after greedy merging, triangles before and after, bytes, and the median export time (and of
//! the greedy meshing alone) of 30 runs, as a
//! Markdown table. The Duck's export has a budget of 50 ms.

use std::time::Instant;

use voxel_core::export::ExportOptions;
use voxel_core::export::gltf::to_glb;
use voxel_core::export::mesh::surface;
use voxel_core::{GridSize, VoxelizeOptions, load_file, voxelize};

#[path = "../tests/support/models.rs"]
mod models;

const RUNS: usize = 30;
const DUCK_BUDGET_MS: f64 = 50.0;

/// The median of `times`.
fn median(mut times: Vec<f64>) -> f64 {
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

/// Nanoseconds this thread has run on a CPU (Linux's schedstat), or 0 where unavailable. The export is
/// single-threaded, so this is its time on an idle core whatever else loads the machine.
fn thread_cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}

/// Median wall milliseconds of `RUNS` calls of `f`, and their mean CPU milliseconds (schedstat advances in
/// scheduler ticks, so one call's CPU time is too coarse; the total over all calls is not).
fn time<T>(mut f: impl FnMut() -> T) -> (f64, f64) {
    let mut wall = Vec::with_capacity(RUNS);
    let cpu = thread_cpu_ns();
    for _ in 0..RUNS {
        let t = Instant::now();
        std::hint::black_box(f());
        wall.push(t.elapsed().as_secs_f64() * 1e3);
    }
    (median(wall), (thread_cpu_ns() - cpu) as f64 / 1e6 / RUNS as f64)
}

fn main() {
    let Some(dir) = models::models_dir() else { return };
    println!(
        "| model | R | grid | voxels | faces | triangles before | rectangles | triangles after | .glb bytes | export ms: median wall (mean CPU) | of which meshing |"
    );
    println!("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (file, r) in [("khronos-boxvertexcolors.glb", 64), ("khronos-duck.glb", 128)] {
        let soup = match load_file(&dir.join(file)) {
            Ok(s) => s,
            Err(e) => {
                println!("| {file} | {r} | error: {e} (set VOXEL_ART_MODELS) |");
                continue;
            }
        };
        let model = voxelize(&soup, &VoxelizeOptions { grid: GridSize::Resolution(r), ..Default::default() })
            .expect("voxelize");
        let options = ExportOptions { name: file.trim_end_matches(".glb").into() };
        let (wall, cpu) = time(|| to_glb(&model, &options).expect("export"));
        let (greedy_wall, greedy_cpu) = time(|| surface(&model));
        let (bytes, s) = to_glb(&model, &options).expect("export");
        assert_eq!(bytes.len(), s.bytes);
        let [nx, ny, nz] = model.spec.dims;
        println!(
            "| {file} | {r} | {nx}×{ny}×{nz} | {} | {} | {} | {} | {} | {} | {wall:.1} ({cpu:.1}) | {greedy_wall:.1} ({greedy_cpu:.1}) |",
            model.len(),
            s.faces,
            2 * s.faces,
            s.quads,
            2 * s.quads,
            s.bytes
        );
        if file == "khronos-duck.glb" {
            let verdict = if wall <= DUCK_BUDGET_MS { "within" } else { "OVER" };
            println!(
                "\nDuck R=128 export: {wall:.1} ms wall ({cpu:.1} ms on the CPU), {verdict} the {DUCK_BUDGET_MS} ms budget"
            );
        }
    }
}
