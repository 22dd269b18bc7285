//! The voxelization pipeline: normalize → fill → shell → combine → colour → (hollow).

use std::sync::OnceLock;
use std::time::{Duration, Instant};

use glam::DVec3;
use rayon::prelude::*;

use crate::bvh::TriangleBvh;
use crate::color::{pastel, sample};
use crate::error::{Result, VoxelError};
use crate::fill::{reachable_from_outside, solid_fill};
use crate::geom::{GridTriangle, closest_point_barycentric, distance2, point_at};
use crate::grid::{BitGrid, GridSize, GridSpec};
use crate::radix;
use crate::shell::{Shell, ShellOctree, shell};
use crate::soup::TriangleSoup;
use crate::visible::visible_cells;

pub use crate::model::{Voxel, VoxelModel, VoxelStats};

/// How the inside of the model is found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum FillMode {
    /// Nonzero winding number per grid column: closed parts are oriented outwards (or kept as cavities)
    /// and overlapping parts stay solid; parts that cannot be oriented count by parity (see `fill`).
    #[default]
    Winding,
    /// Ray parity per grid column over the whole model (the article's rule; exact for closed models, but
    /// the overlap of two parts counts as outside).
    Parity,
    /// Everything the outside cannot reach through the surface shell (tolerates holes below a cell).
    Flood,
    /// No interior: the surface shell only.
    None,
}

/// Which surface-shell cells join the solid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum ShellMode {
    /// Only where the fill does not already represent the surface: thin parts and open sheets.
    #[default]
    Auto,
    /// Every cell a triangle touches (overshoots the volume by about half a cell all round).
    All,
    /// None: the fill alone.
    None,
}

/// Which implementation computes the winding or parity fill (all give the same cells).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum Method {
    /// Triangle-major rasterization of the column crossings.
    #[default]
    Fast,
    /// One BVH query per column.
    Bvh,
    /// The article's algorithm: one ray per cell centre against every triangle (slow; for tests).
    Reference,
}

/// Everything that shapes a voxelization.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelizeOptions {
    /// The model's bounding-box diagonal after normalization (the article's `modelSize`).
    pub model_size: f32,
    /// Cell width or resolution.
    pub grid: GridSize,
    /// Cell height / cell width (1.2 for Lego bricks).
    pub cell_height_ratio: f32,
    /// Interior mode.
    pub fill: FillMode,
    /// Shell mode.
    pub shell: ShellMode,
    /// Keep only voxels with an empty face neighbour.
    pub hollow: bool,
    /// Fill implementation.
    pub method: Method,
    /// Apply the pastel remap to colours.
    pub pastel: bool,
    /// Largest grid (nx·ny·nz) accepted; the default keeps memory under about 1 GiB.
    pub max_cells: u64,
}

/// The default cell budget: 2²⁶ cells (e.g. 406³).
pub const DEFAULT_MAX_CELLS: u64 = 1 << 26;

impl Default for VoxelizeOptions {
    fn default() -> Self {
        Self {
            model_size: 9.0,
            grid: GridSize::default(),
            cell_height_ratio: 1.0,
            fill: FillMode::default(),
            shell: ShellMode::default(),
            hollow: false,
            method: Method::default(),
            pastel: false,
            max_cells: DEFAULT_MAX_CELLS,
        }
    }
}

/// Voxelizes `soup` with `options`.
pub fn voxelize(soup: &TriangleSoup, options: &VoxelizeOptions) -> Result<VoxelModel> {
    voxelize_timed(soup, options).map(|(model, _)| model)
}

/// Voxelizes `soup` in the grid fitted to `bounds` (min, max) instead of the soup's own bounds, so that
/// every pose of an animation lands in the same cells ([`crate::AnimatedModel::clip_bounds`]). Parts of
/// the soup outside `bounds` are clipped at the grid's edge.
pub fn voxelize_within(
    soup: &TriangleSoup,
    options: &VoxelizeOptions,
    bounds: ([f32; 3], [f32; 3]),
) -> Result<VoxelModel> {
    voxelize_within_timed(soup, options, bounds).map(|(model, _)| model)
}

/// The wall time of the passes of one voxelization (for benchmarks).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PassTimes {
    /// Fitting the grid, the grid triangles and the fill.
    pub fill: Duration,
    /// The surface shell.
    pub shell: Duration,
    /// The colours of the visible cells.
    pub color: Duration,
}

/// [`voxelize`], also reporting how long its passes took.
pub fn voxelize_timed(soup: &TriangleSoup, options: &VoxelizeOptions) -> Result<(VoxelModel, PassTimes)> {
    voxelize_within_timed(soup, options, soup.bounds().ok_or_else(|| VoxelError::Empty(String::new()))?)
}

/// [`voxelize_within`], also reporting how long its passes took.
fn voxelize_within_timed(
    soup: &TriangleSoup,
    options: &VoxelizeOptions,
    bounds: ([f32; 3], [f32; 3]),
) -> Result<(VoxelModel, PassTimes)> {
    soup.validate()?;
    if options.fill == FillMode::None && options.shell == ShellMode::None {
        return Err(VoxelError::Parameter("fill none with shell none leaves nothing to voxelize".into()));
    }
    let started = Instant::now();
    let spec =
        GridSpec::fit_bounds(bounds, options.model_size, options.grid, options.cell_height_ratio, options.max_cells)?;
    let tris = spec.grid_triangles(soup);
    if !tris.iter().any(|t| (t[1] - t[0]).cross(t[2] - t[0]).length_squared() > 0.0) {
        return Err(VoxelError::Empty(" (every triangle has zero area)".into()));
    }
    let bvh = OnceLock::new();
    let fill = match options.fill {
        FillMode::Winding | FillMode::Parity => solid_fill(soup, &spec, &tris, options.fill, options.method, &bvh),
        FillMode::Flood | FillMode::None => BitGrid::new(spec.cell_count()),
    };
    let filled = Instant::now();
    let shell = shell(&spec, &tris, &fill);
    let shelled = Instant::now();
    let solid = combine(&spec, options, fill, &shell);
    let visible = visible_cells(&spec, &solid);
    let coloring = Instant::now();
    let mut colors = surface_colors(soup, &spec, &tris, &shell, &visible, &bvh);
    let times = PassTimes { fill: filled - started, shell: shelled - filled, color: coloring.elapsed() };
    if options.pastel {
        colors.par_iter_mut().for_each(|(c, _)| *c = pastel(*c));
    }
    let stats = VoxelStats {
        triangles: soup.triangle_count(),
        grid: spec.dims,
        voxels: solid.count(),
        surface: shell.cells.len(),
        visible: visible.len(),
        // Interior voxels copy visible ones, so the visible cells hold every colour.
        colors: distinct(colors.iter().map(|c| u32::from_le_bytes(c.0)).collect()),
    };
    let parts = soup.parts.iter().map(|p| p.name.clone()).collect();
    let solid = (!options.hollow).then_some(solid);
    Ok((VoxelModel::new(spec, stats, parts, solid, visible, colors), times))
}

/// The number of distinct values.
fn distinct(mut values: Vec<u32>) -> usize {
    // Neighbouring cells often share a colour: drop repeats before sorting.
    values.dedup();
    let mut values = radix::sort_by_key(values, u32::BITS, |&v| v);
    values.dedup();
    values.len()
}

/// The solid cells from the fill and the shell, per the modes.
fn combine(spec: &GridSpec, options: &VoxelizeOptions, fill: BitGrid, shell: &Shell) -> BitGrid {
    let shell_bits = || {
        let mut bits = BitGrid::new(spec.cell_count());
        for &c in &shell.cells {
            bits.set(c as usize);
        }
        bits
    };
    match options.fill {
        FillMode::Winding | FillMode::Parity => {
            let mut solid = fill;
            match options.shell {
                ShellMode::All => {
                    for &c in &shell.cells {
                        solid.set(c as usize);
                    }
                }
                ShellMode::Auto => {
                    for (k, &c) in shell.cells.iter().enumerate() {
                        if shell.thin[k] {
                            solid.set(c as usize);
                        }
                    }
                }
                ShellMode::None => {}
            }
            solid
        }
        FillMode::Flood => {
            let shell_bits = shell_bits();
            let outside = reachable_from_outside(spec, &shell_bits);
            let mut solid = BitGrid::new(spec.cell_count());
            for i in 0..spec.cell_count() {
                if !outside.get(i) && (options.shell != ShellMode::None || !shell_bits.get(i)) {
                    solid.set(i);
                }
            }
            solid
        }
        FillMode::None => shell_bits(),
    }
}

/// The steps to the six face neighbours.
const FACE_STEPS: [[i32; 3]; 6] = [[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1]];

/// The nearest triangle to grid point `p` among `candidates` (ties: lower index), with the barycentric
/// weights of its closest point.
fn nearest_among(
    tris: &[GridTriangle],
    p: DVec3,
    candidates: impl Iterator<Item = usize>,
) -> Option<(usize, [f64; 3])> {
    let mut best: Option<(usize, f64, [f64; 3])> = None;
    for t in candidates {
        let w = closest_point_barycentric(p, &tris[t]);
        let d = point_at(&tris[t], w).distance_squared(p);
        if best.is_none_or(|(bt, bd, _)| d.total_cmp(&bd).then(t.cmp(&bt)).is_lt()) {
            best = Some((t, d, w));
        }
    }
    best.map(|(t, _, w)| (t, w))
}

/// The position of `target` in the ascending `cells`, if there, searched outwards from position `k` (a
/// galloping search: the cost grows with the log of the distance).
fn position_near(cells: &[u32], k: usize, target: u32) -> Option<usize> {
    let (mut lo, mut hi) = (k.min(cells.len()), k.min(cells.len()));
    let mut step = 1;
    if cells.get(k).is_some_and(|&c| c < target) {
        while hi < cells.len() && cells[hi] < target {
            (lo, hi) = (hi, (hi + step).min(cells.len()));
            step *= 2;
        }
    } else {
        while lo > 0 && cells[lo - 1] >= target {
            (hi, lo) = (lo, lo.saturating_sub(step));
            step *= 2;
        }
    }
    // Now cells[..lo] < target and cells[hi..] >= target or hi is the end.
    let at = lo + cells[lo..hi].partition_point(|&c| c < target);
    (cells.get(at) == Some(&target)).then_some(at)
}

/// Visible cells handed to one task of the colour pass.
const CELLS_PER_TASK: usize = 1024;

/// The colour and part of every visible cell: the material colour at the closest point of the nearest
/// triangle among the shell triangles of the cell, else of its face neighbours (where the surface crossing a
/// face lies), else of the whole model. Cells that far from the surface only occur where an open mesh leaves
/// a column unmatched; for them one index is built, outside the parallel loop, and each lookup walks the
/// part of it near its cell: a BVH over the triangles when they are fewer than the shell cells (a big
/// triangle spans many cells, whose boxes bound it loosely), else an octree over the shell cells (built in
/// time linear in the shell, where a BVH over many small triangles would cost more to build than the shell).
/// Both give the nearest triangle of nonzero area, ties to the lower index.
fn surface_colors(
    soup: &TriangleSoup,
    spec: &GridSpec,
    tris: &[GridTriangle],
    shell: &Shell,
    visible: &[u32],
    bvh: &OnceLock<TriangleBvh>,
) -> Vec<([u8; 4], u32)> {
    let centre = |i: u32| {
        let c = spec.coords(i as usize);
        DVec3::new(f64::from(c[0]) + 0.5, f64::from(c[1]) + 0.5, f64::from(c[2]) + 0.5)
    };
    // Visible and shell cells are both ascending: each task walks the two lists side by side, and finds a
    // neighbour's shell cell by galloping from where the walk is.
    let mut nearest: Vec<Option<(usize, [f64; 3])>> = visible
        .par_chunks(CELLS_PER_TASK)
        .flat_map_iter(|chunk| {
            let mut k = shell.cells.partition_point(|&c| c < chunk[0]);
            chunk.iter().map(move |&i| {
                while shell.cells.get(k).is_some_and(|&c| c < i) {
                    k += 1;
                }
                let own: &[u32] = if shell.cells.get(k) == Some(&i) { shell.triangles_at(k) } else { &[] };
                let p = centre(i);
                nearest_among(tris, p, own.iter().map(|&t| t as usize)).or_else(|| {
                    let faces = FACE_STEPS.into_iter().filter_map(|step| spec.offset(i as usize, step));
                    let near = faces.filter_map(|n| position_near(&shell.cells, k, n as u32));
                    nearest_among(tris, p, near.flat_map(|at| shell.triangles_at(at).iter().map(|&t| t as usize)))
                })
            })
        })
        .collect();
    if nearest.contains(&None) {
        let far: Box<dyn Fn(DVec3) -> Option<usize> + Sync> = if tris.len() < shell.cells.len() {
            let bvh = bvh.get_or_init(|| TriangleBvh::build(tris));
            let has_area = |t: &GridTriangle| (t[1] - t[0]).cross(t[2] - t[0]).length_squared() > 0.0;
            Box::new(move |p| {
                let d2 = |t: usize| if has_area(&tris[t]) { distance2(p, &tris[t]) } else { f64::INFINITY };
                bvh.nearest(p, d2).filter(|n| n.1.is_finite()).map(|n| n.0)
            })
        } else {
            let octree = ShellOctree::new(spec, shell);
            Box::new(move |p| octree.nearest(tris, p))
        };
        nearest.par_iter_mut().zip(visible).filter(|(t, _)| t.is_none()).for_each(|(t, &i)| {
            *t = far(centre(i)).map(|t| (t, closest_point_barycentric(centre(i), &tris[t])));
        });
    }
    nearest
        .par_iter()
        .map(|&t| match t {
            Some((t, w)) => (sample(soup, t, w), soup.triangle_parts[t]),
            None => ([255; 4], 0),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn galloping_finds_exactly_the_cells_present_from_any_start() {
        let cells: Vec<u32> = (0..300).map(|k| k * 8 + k % 7).collect();
        for k in 0..=cells.len() {
            for target in 0..cells[cells.len() - 1] + 5 {
                assert_eq!(
                    position_near(&cells, k, target),
                    cells.binary_search(&target).ok(),
                    "from {k} for {target}"
                );
            }
        }
        assert_eq!(position_near(&[], 0, 4), None);
    }
}
