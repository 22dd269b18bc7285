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
use crate::radix;
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
                    timed(|| match options.fill {
                        FillMode::Winding | FillMode::Parity => {
                            solid_fill(soup, &spec, &tris, options.fill, options.method, &bvh, progress)
                        }
                        FillMode::Flood | FillMode::None => BitGrid::new(spec.cell_count()),
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
        // Interior voxels copy visible ones, so the visible cells hold every colour.
        colors: distinct(&colors),
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

/// The number of distinct colours among `colors`. A list of more than [`DISTINCT_SPLIT`] is split in halves whose
/// distinct colours are collected side by side, then counted together.
fn distinct(colors: &[([u8; 4], u32)]) -> usize {
    if colors.len() <= DISTINCT_SPLIT {
        return distinct_sorted(colors).len();
    }
    let (left, right) = colors.split_at(colors.len() / 2);
    let (left, right) = rayon::join(|| distinct_sorted(left), || distinct_sorted(right));
    union_count(&left, &right)
}

/// The distinct colours among `colors` (as little-endian `u32`), ascending.
fn distinct_sorted(colors: &[([u8; 4], u32)]) -> Vec<u32> {
    // Neighbouring cells often share a colour: a repeat of the colour before is passed over.
    let values = || {
        let mut last = None;
        colors.iter().map(|c| u32::from_le_bytes(c.0)).filter(move |&v| last.replace(v) != Some(v))
    };
    // Most models show a few colours (their materials, a palette of vertex colours, a texture's): a small set
    // collects them. Past `SMALL_SET` of them, or once the first `FEW_NEW` came among fewer than an eighth more values
    // (colours that hardly repeat: vertex colours varying across every face), the values are sorted.
    let mut seen = rustc_hash::FxHashSet::default();
    // The colours seen last, in slots picked by a multiplicative hash of the colour: most repeats are found there
    // before the set is asked (a textured model's cells repeat a few hundred colours in no order).
    let mut recent = [None; RECENT];
    for (count, v) in values().enumerate() {
        let slot = &mut recent[(v.wrapping_mul(0x9E37_79B9) >> (u32::BITS - RECENT.trailing_zeros())) as usize];
        if slot.replace(v) == Some(v) {
            continue;
        }
        if seen.insert(v) && (seen.len() > SMALL_SET || seen.len() == FEW_NEW && count < FEW_NEW + FEW_NEW / 8) {
            let mut all = Vec::with_capacity(colors.len());
            all.extend(values());
            let mut values = radix::sort_by_key(all, u32::BITS, |&v| v);
            values.dedup();
            return values;
        }
    }
    let mut values: Vec<u32> = seen.into_iter().collect();
    values.sort_unstable();
    values
}

/// The number of values in either of two ascending lists without repeats.
fn union_count(a: &[u32], b: &[u32]) -> usize {
    let (mut i, mut j, mut count) = (0, 0, 0);
    while i < a.len() && j < b.len() {
        let (x, y) = (a[i], b[j]);
        i += usize::from(x <= y);
        j += usize::from(y <= x);
        count += 1;
    }
    count + (a.len() - i) + (b.len() - j)
}

/// The most distinct values [`distinct_sorted`] collects in a set (a textured model shows a few thousand: CesiumMan at
/// R=128 1,488, whose count took 0.14 ms when the set stopped at 2¹⁰ and the values were sorted, 0.10 ms in the set).
const SMALL_SET: usize = 1 << 13;

/// The colours after which [`distinct_sorted`] judges whether they repeat: when they came among fewer than an eighth
/// more values, it sorts the values rather than filling its set. (The box of vertex colours, 96,776 cells of 92,495
/// colours, fresh runs of 11, the count alone: at R=128 1.97 → 1.29 ms, at R=256 7.04 → 6.15; a textured box whose
/// first cells are each of a new texel, 2,601 colours of 390,152 at R=256, 0.53 → 0.70.)
const FEW_NEW: usize = 1 << 10;

/// The slots of [`distinct_sorted`]'s recent colours (a power of two). (The milk truck at R=128, 46,129 colours of 132
/// kinds from a texture: counted in 0.12 ms rather than 0.15, warm.)
const RECENT: usize = 256;

/// Above this many colours, [`distinct`] counts the halves of the list side by side. (Fresh runs at R=128, medians of
/// 15 of the count alone, split from 2¹⁷ colours and from 2¹²: the milk truck's 46,129 colours 0.134 and 0.087 ms, the
/// duck's 60,530 0.080 and 0.046, CesiumMan's 14,698 0.142 and 0.127, the Fox's 14,054 0.027 and 0.023.)
const DISTINCT_SPLIT: usize = 1 << 12;

/// The solid cells from the fill and the shell of `tris`, per the modes.
fn combine(spec: &GridSpec, options: &VoxelizeOptions, fill: BitGrid, shell: &Shell, tris: &GridTriangles) -> BitGrid {
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
                    for c in shell.thin_cells(spec, tris, &solid) {
                        solid.set(c as usize);
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

    #[test]
    fn distinct_values_are_counted_whether_few_or_many() {
        // Runs of repeats and values seen again far apart, below and above the small set's size, in lists short
        // enough for one task and long enough to be split (the halves sharing colours, or one of a single colour).
        let check = |values: Vec<u32>, case: &str| {
            let colors: Vec<([u8; 4], u32)> = values.iter().map(|v| (v.to_le_bytes(), 0)).collect();
            let expected: std::collections::BTreeSet<u32> = values.into_iter().collect();
            if colors.len() <= DISTINCT_SPLIT {
                assert_eq!(distinct_sorted(&colors), expected.iter().copied().collect::<Vec<_>>(), "{case}");
            }
            assert_eq!(distinct(&colors), expected.len(), "{case}");
            expected.len()
        };
        let long = (2 * DISTINCT_SPLIT).max(1 << 18) as u32 + 1;
        for len in [1_000, long] {
            for kinds in [1, 7, SMALL_SET, SMALL_SET + 1, 50_000] {
                let values = (0..len).map(|k| (k / 3).wrapping_mul(2_654_435_761) % kinds as u32).collect();
                let count = check(values, &format!("{kinds} kinds of {len}"));
                assert!(len == 1_000 || (count > SMALL_SET) == (kinds > SMALL_SET), "{count} of {kinds} kinds");
            }
        }
        // Colours that hardly repeat at first (sorted once the first `FEW_NEW` are in), then repeat.
        let first_new = |kinds: u32| (0..kinds).chain(0..kinds).map(|k| k.wrapping_mul(2_654_435_761)).collect();
        assert_eq!(check(first_new(2_000), "2,000 new, then again"), 2_000);
        assert_eq!(check(first_new(5_000), "5,000 new, then again, in halves"), 5_000);
        // Opaque white is the largest value (every byte 255), and black the smallest.
        assert_eq!(check(vec![u32::MAX; 5], "white"), 1);
        assert_eq!(check(vec![3, u32::MAX, 0, u32::MAX, 3], "white, black and another"), 3);
        let halves = (0..long).map(|k| if k < long / 2 { 7 } else { k.wrapping_mul(2_654_435_761) % 50_000 });
        assert!(check(halves.collect(), "one colour, then many") > SMALL_SET);
        assert_eq!(distinct(&[]), 0);
        assert_eq!(union_count(&[1, 4, 9], &[0, 4, 5, 9, 12]), 6);
        assert_eq!(union_count(&[], &[3]), 1);
    }
}
