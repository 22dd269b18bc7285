//! Timing shared by the benches `targets` and `cold` (included with `#[path]`; the including bench declares
//! `mod cpu` from tests/support/cpu.rs): medians of wall and CPU time over repeated voxelizations.

use std::time::Instant;

use voxel_core::{GridSize, TriangleSoup, VoxelizeOptions, voxelize};

/// Median wall and CPU time of some runs, in ms.
#[derive(Clone, Copy)]
pub struct Timing {
    /// Wall-clock ms.
    pub wall: f64,
    /// CPU ms summed over the process's threads.
    pub cpu: f64,
}

impl std::fmt::Display for Timing {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:.2} ({:.2})", self.wall, self.cpu)
    }
}

/// The median of `values` (the upper one of an even count).
pub fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// One warm-up voxelization, then the medians of `runs`; also the grid of the last one.
pub fn measure(soup: &TriangleSoup, options: &VoxelizeOptions, runs: usize) -> (Timing, [u32; 3]) {
    let grid = voxelize(soup, options).expect("voxelize").stats.grid;
    let (timing, last) = measure_each(std::iter::repeat_n(soup, runs), options);
    (timing, last.unwrap_or(grid))
}

/// The medians of one voxelization of each of `soups` (no warm-up); also the grid of the last one.
pub fn measure_each<'a>(
    soups: impl IntoIterator<Item = &'a TriangleSoup>,
    options: &VoxelizeOptions,
) -> (Timing, Option<[u32; 3]>) {
    let mut grid = None;
    let (mut wall, mut cpu) = (Vec::new(), Vec::new());
    for soup in soups {
        let cpu_start = crate::cpu::cpu_ns();
        let started = Instant::now();
        grid = Some(voxelize(soup, options).expect("voxelize").stats.grid);
        wall.push(started.elapsed().as_secs_f64() * 1e3);
        cpu.push(cpu_start.zip(crate::cpu::cpu_ns()).map_or(f64::NAN, |(a, b)| (b - a) as f64 / 1e6));
    }
    (Timing { wall: median(wall), cpu: median(cpu) }, grid)
}

/// Default options at `r` cells along the longest axis (`None`: the article's default grid).
pub fn options(r: Option<u32>, hollow: bool) -> VoxelizeOptions {
    let grid = r.map_or_else(GridSize::default, GridSize::Resolution);
    VoxelizeOptions { grid, hollow, ..Default::default() }
}
