//! The voxelization pipeline: normalize → fill and shell side by side → combine → colour → (hollow).

use std::sync::OnceLock;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use crate::color_pass::{pastel_all, surface_colors};
use crate::error::{Result, VoxelError};
use crate::fill::{reachable_from_outside, solid_fill};
use crate::grid::{BitGrid, GridSpec, GridTriangles, MAX_CELLS};
use crate::memory;
use crate::model::{VoxelModel, VoxelStats};
use crate::options::{FillMode, ShellMode, VoxelizeOptions};
use crate::orient::analyse_parts_ahead;
use crate::progress::{Progress, Settle, Stage};
use crate::shell::{Shell, shell};
use crate::soup::TriangleSoup;
use crate::visible::{visible_cells, visible_listed};

/// Voxelizes `soup` with `options`.
pub fn voxelize(soup: &TriangleSoup, options: &VoxelizeOptions) -> Result<VoxelModel> {
    voxelize_timed(soup, options).map(|(model, _)| model)
}

/// [`voxelize`], reporting each [`Stage`] it enters to `progress` and stopping with
/// [`VoxelError::Cancelled`] at the next stage once `progress` is cancelled (from another thread).
pub fn voxelize_watched(soup: &TriangleSoup, options: &VoxelizeOptions, progress: &Progress) -> Result<VoxelModel> {
    voxelize_within_timed(soup, options, None, progress).map(|(model, _)| model)
}

/// Voxelizes `soup` in the grid fitted to `bounds` (min, max) instead of the soup's own bounds, so that
/// every pose of an animation lands in the same cells ([`crate::AnimatedModel::clip_bounds`]). Parts of
/// the soup outside `bounds` are clipped at the grid's edge.
pub fn voxelize_within(
    soup: &TriangleSoup,
    options: &VoxelizeOptions,
    bounds: ([f32; 3], [f32; 3]),
) -> Result<VoxelModel> {
    voxelize_within_timed(soup, options, Some(bounds), &Progress::new()).map(|(model, _)| model)
}

/// The wall time of the passes of one voxelization (for benchmarks).
///
/// The fill and the shell run side by side (with two threads or more they overlap, so their sum can exceed
/// the voxelization's wall time); each is timed from its own start to its own end, which includes any of
/// the other's work its thread picked up while waiting, and for the fill a wait for the soup's part analysis
/// started beside them (which itself counts in neither field). Combining the two (the thin cells, the flood
/// fill) and finding the visible cells count in neither field.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PassTimes {
    /// Fitting the grid and the grid triangles, then the fill (alongside the shell).
    pub fill: Duration,
    /// The surface shell's cells and their triangles (alongside the fill).
    pub shell: Duration,
    /// The colours of the visible cells.
    pub color: Duration,
}

/// [`voxelize`], also reporting how long its passes took.
pub fn voxelize_timed(soup: &TriangleSoup, options: &VoxelizeOptions) -> Result<(VoxelModel, PassTimes)> {
    voxelize_within_timed(soup, options, None, &Progress::new())
}

/// [`voxelize_within`], also reporting how long its passes took.
fn voxelize_within_timed(
    soup: &TriangleSoup,
    options: &VoxelizeOptions,
    bounds: Option<([f32; 3], [f32; 3])>,
    progress: &Progress,
) -> Result<(VoxelModel, PassTimes)> {
    progress.enter(Stage::Placing)?;
    let started = Instant::now();
    let bvh = OnceLock::new();
    // The winding fill's part analysis depends on the soup alone: when the soup's facing shows that the
    // columns will not balance (and the soup is not a sheet facing one way, which the fill's survey finds empty
    // without it), it starts at once on the other thread, beside the grid's set-up and the shell, and the fill
    // waits for it only if it gets there first. Otherwise the fill runs it if its columns show the need, beside
    // the shell.
    // Set when the passes are done (or failed): an analysis not started by then is not needed (one thread,
    // where the join runs its halves one after the other, or a busy pool).
    let settled = AtomicBool::new(false);
    // The memory the system has available (a read of /proc/meminfo: about 40 µs, a few per cent of a small model's
    // voxelization) is read on the other thread while this one fits the grid; whichever thread gets to it first
    // reads it, the other waits for it.
    let budget = OnceLock::new();
    let budget = || *budget.get_or_init(|| memory::budget(options.max_memory));
    let (passes, ()) = rayon::join(
        || -> Result<_> {
            let _settle = Settle(&settled);
            let (spec, tris) = prepare(soup, options, bounds, budget)?;
            let prepared = started.elapsed();
            progress.enter(Stage::Filling)?;
            let ((shell, shell_time), (fill, fill_time)) = rayon::join(
                || timed(|| shell(&spec, &tris, progress)),
                || {
                    // Flood and none find the solid from the shell alone (`combine`).
                    timed(|| match options.fill {
                        FillMode::Winding | FillMode::Parity => {
                            Some(solid_fill(soup, &spec, &tris, options.fill, options.method, &bvh, progress))
                        }
                        FillMode::Flood | FillMode::None => None,
                    })
                },
            );
            Ok((spec, tris, fill, shell, prepared + fill_time, shell_time))
        },
        || {
            budget();
            if options.fill == FillMode::Winding {
                analyse_parts_ahead(soup, &settled);
            }
        },
    );
    let (spec, tris, fill, shell, fill_time, shell_time) = passes?;
    progress.enter(Stage::Coloring)?;
    let solid = combine(&spec, options, fill, &shell, &tris);
    // Without a fill the solid is the shell's cells (`combine`), which the shell lists.
    let visible = if options.fill == FillMode::None {
        visible_listed(&spec, &solid, &shell.cells)
    } else {
        visible_cells(&spec, &solid)
    };
    let coloring = Instant::now();
    let mut colors = surface_colors(soup, &spec, &tris, &shell, &visible, progress);
    let times = PassTimes { fill: fill_time, shell: shell_time, color: coloring.elapsed() };
    if options.pastel {
        pastel_all(&mut colors);
    }
    let stats = VoxelStats {
        triangles: soup.triangle_count(),
        grid: spec.dims,
        voxels: solid.count(),
        surface: shell.cells.len(),
        visible: visible.len(),
    };
    let parts = soup.parts.iter().map(|p| p.name.clone()).collect();
    let solid = (!options.hollow).then_some(solid);
    progress.enter(Stage::Done)?;
    Ok((VoxelModel::new(spec, stats, parts, solid, visible, colors), times))
}

/// The result of `f` and how long it took.
fn timed<T>(f: impl FnOnce() -> T) -> (T, Duration) {
    let started = Instant::now();
    let value = f();
    (value, started.elapsed())
}

/// Checks `soup` and `options`, fits the grid of `options` to `bounds` (the soup's own when `None`) and places
/// the soup's triangles on it, within the memory `budget` gives ([`memory::check`]).
fn prepare<'a>(
    soup: &'a TriangleSoup,
    options: &VoxelizeOptions,
    bounds: Option<([f32; 3], [f32; 3])>,
    budget: impl FnOnce() -> u64,
) -> Result<(GridSpec, GridTriangles<'a>)> {
    let bounds = bounds.or_else(|| soup.bounds()).ok_or_else(|| VoxelError::Empty(String::new()))?;
    soup.validate()?;
    if options.fill == FillMode::None && options.shell == ShellMode::None {
        return Err(VoxelError::Parameter("fill none with shell none leaves nothing to voxelize".into()));
    }
    let spec = GridSpec::fit_bounds(bounds, options.model_size, options.grid, options.cell_height_ratio, MAX_CELLS)?;
    let tris = spec.grid_triangles(soup);
    memory::check(&spec, &tris, options.fill, budget())?;
    if !tris.iter().any(|t| (t[1] - t[0]).cross(t[2] - t[0]).length_squared() > 0.0) {
        return Err(VoxelError::Empty(" (every triangle has zero area)".into()));
    }
    Ok((spec, tris))
}

/// The solid cells from the fill (`None` for the modes that have no fill pass: flood and none) and the shell of
/// `tris`, per the modes.
fn combine(
    spec: &GridSpec,
    options: &VoxelizeOptions,
    fill: Option<BitGrid>,
    shell: &Shell,
    tris: &GridTriangles,
) -> BitGrid {
    let shell_bits = || {
        let mut bits = BitGrid::new(spec.cell_count());
        for &c in &shell.cells {
            bits.set(c as usize);
        }
        bits
    };
    match fill {
        Some(mut solid) => {
            match options.shell {
                ShellMode::All => {
                    for &c in &shell.cells {
                        solid.set(c as usize);
                    }
                }
                ShellMode::Auto => {
                    for c in shell.thin_cells(spec, tris, &solid) {
                        solid.set(c as usize);
                    }
                }
                ShellMode::None => {}
            }
            solid
        }
        None if options.fill == FillMode::Flood => {
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
        None => shell_bits(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::columns::crossings_by_rasterizing;
    use crate::grid::GridSize;
    use crate::shapes::uv_sphere;

    #[test]
    fn the_long_passes_stop_once_cancelled() {
        let soup = TriangleSoup::from_mesh(&uv_sphere(1.0, 32), [0.2, 0.6, 0.9, 1.0]);
        let options = VoxelizeOptions { grid: GridSize::Resolution(32), ..Default::default() };
        let (spec, tris) = prepare(&soup, &options, None, || u64::MAX).unwrap();
        let (going, cancelled) = (Progress::new(), Progress::new());
        cancelled.cancel();
        let crossings = |progress| {
            let columns = crossings_by_rasterizing(&spec, &tris, progress);
            (0..columns.len()).map(|col| columns.column(col).len()).sum::<usize>()
        };
        assert!(crossings(&going) > 1000, "{}", crossings(&going));
        assert_eq!(crossings(&cancelled), 0, "the fill's triangles are passed over");
        let whole = shell(&spec, &tris, &going);
        assert!(whole.cells.len() > 1000);
        assert!(shell(&spec, &tris, &cancelled).cells.is_empty(), "the shell's triangles are passed over");
        let colors = |progress| surface_colors(&soup, &spec, &tris, &whole, &whole.cells, progress);
        let (coloured, left) = (colors(&going), colors(&cancelled));
        assert!(coloured.iter().all(|&(c, _)| c == [124, 203, 243, 255]), "{:?}", coloured[0]);
        assert!(left.iter().all(|&(c, _)| c == [255; 4]), "the cells are left uncoloured");
    }
}
