//! The voxelizer's memory budget: what a voxelization will take, estimated from its grid and its triangles
//! before any of it is allocated, against what the machine has available (or a caller's limit).
//!
//! The output follows the surface, so the cells themselves cost one bit each in the solid grid (a few bits
//! while the fill, the flood or the hollow pass run); what grows with the surface are the overlaps of
//! triangles and cells (the shell's cell–triangle pairs and the fill's column crossings, each sorted once)
//! and the grid triangles. The estimate bounds each triangle's overlaps by the cells its extent spans on the
//! plane it faces most, so many tiny triangles (several to a cell) count one overlap each and a large
//! triangle its area in cells.

use glam::DVec3;
use rayon::prelude::*;

use crate::error::{Result, VoxelError};
use crate::geom::GridTriangle;
use crate::grid::{GridSpec, GridTriangles};
use crate::options::FillMode;

/// Bytes per overlap of a triangle and a cell: the shell's packed run (8; a run holds one overlap or more) and
/// its sorted cell and run (8), the fill's crossings, the visible cells with their colour and part (12 each,
/// fewer than the overlaps). Measured peaks (docs/benchmarks.md: the FlightHelmet at R=512–2048) are 70–85 % of
/// the estimate.
const BYTES_PER_OVERLAP: f64 = 32.0;

/// Bits per cell at the peak: the solid grid and one more while it is built (a flood fill adds its shell
/// and outside grids).
fn bits_per_cell(fill: FillMode) -> f64 {
    match fill {
        FillMode::Flood => 4.0,
        _ => 2.0,
    }
}

/// The bytes a voxelization of `tris` in `spec` with `fill` will take at its peak (an estimate that errs
/// high), besides the soup it reads.
pub(crate) fn estimate(spec: &GridSpec, tris: &GridTriangles, fill: FillMode) -> u64 {
    let top = DVec3::from(spec.dims.map(f64::from));
    let overlaps: f64 = tris.par_iter().with_min_len(TRIANGLES_PER_TASK).map(|t| overlaps_of(&t, top)).sum();
    bytes(spec, tris, fill, overlaps)
}

/// Triangles per task of the estimate's passes.
const TRIANGLES_PER_TASK: usize = 1 << 14;

/// The bytes of a voxelization of `tris` in `spec` with `fill` that makes `overlaps` overlaps.
fn bytes(spec: &GridSpec, tris: &GridTriangles, fill: FillMode, overlaps: f64) -> u64 {
    let vertices = tris.vertex_bytes() as f64;
    let cells = spec.cell_count() as f64 * bits_per_cell(fill) / 8.0;
    (vertices + cells + overlaps * BYTES_PER_OVERLAP) as u64
}

/// At least [`estimate`], from the largest extent of any triangle along each axis: every triangle counts as
/// many overlaps as a triangle of that extent can ([`overlaps_of`] is at most the most cells such an extent's
/// bounding box spans across an axis, plus one). One pass that only reads the corners, where [`estimate`]
/// works out each triangle's cells and normal (the height field's 2 million triangles on a 2-core VM: 5 ms against 25 ms).
fn bound(spec: &GridSpec, tris: &GridTriangles, fill: FillMode) -> u64 {
    let extent = tris
        .par_iter()
        .with_min_len(TRIANGLES_PER_TASK)
        .map(|t| t[0].max(t[1]).max(t[2]) - t[0].min(t[1]).min(t[2]))
        .reduce(|| DVec3::ZERO, DVec3::max);
    let top = DVec3::from(spec.dims.map(f64::from));
    // A triangle's extent `e` along an axis spans at most ⌊e⌋ + 2 cells (`⌊hi⌋ − ⌊lo⌋ ≤ ⌊hi − lo⌋ + 1`), and its
    // clamped cells at most the grid's cells plus one.
    let span = (extent.floor() + 2.0).min(top + 1.0);
    let across = (span.y * span.z).max(span.x * span.z).max(span.x * span.y);
    bytes(spec, tris, fill, tris.len() as f64 * (across + 1.0))
}

/// At least the cells triangle `t` overlaps in a grid of `top` cells along each axis: its extent in cells
/// across the axis its normal is nearest to (the cells of its projection's bounding box within the grid, one at
/// the least), plus one layer.
fn overlaps_of(t: &GridTriangle, top: DVec3) -> f64 {
    let lo = t[0].min(t[1]).min(t[2]);
    let hi = t[0].max(t[1]).max(t[2]);
    // Within the grid (where the shell clamps it) a coordinate is not negative: its floor is its truncation.
    let cell = |v: DVec3| v.clamp(DVec3::ZERO, top).as_uvec3().as_dvec3();
    let span = (cell(hi) - cell(lo)) + 1.0;
    let n = (t[1] - t[0]).cross(t[2] - t[0]).abs();
    let across = if n.x >= n.y && n.x >= n.z {
        span.y * span.z
    } else if n.y >= n.z {
        span.x * span.z
    } else {
        span.x * span.y
    };
    across.min(span.x * span.y * span.z) + 1.0
}

/// The memory a voxelization may use: `limit` when given, else what the system has available
/// (`MemAvailable` of /proc/meminfo; no limit where that cannot be read).
pub(crate) fn budget(limit: Option<u64>) -> u64 {
    limit.or_else(available).unwrap_or(u64::MAX)
}

/// `MemAvailable` of /proc/meminfo, in bytes.
fn available() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = meminfo.lines().find(|line| line.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Refuses a voxelization of `tris` in `spec` whose estimate exceeds `budget` bytes, naming the memory needed.
/// The estimate is worked out only when its [`bound`] does not fit (triangles of a few cells each, the most
/// common models, fit at once).
pub(crate) fn check(spec: &GridSpec, tris: &GridTriangles, fill: FillMode, budget: u64) -> Result<()> {
    if bound(spec, tris, fill) <= budget {
        return Ok(());
    }
    let needed = estimate(spec, tris, fill);
    if needed <= budget {
        return Ok(());
    }
    let [nx, ny, nz] = spec.dims;
    Err(VoxelError::OutOfMemory { nx, ny, nz, needed, budget })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::GridSize;
    use crate::shapes::uv_sphere;
    use crate::soup::TriangleSoup;

    #[test]
    fn the_estimate_follows_the_surface_and_the_cells() {
        let soup = TriangleSoup::from_mesh(&uv_sphere(1.0, 48), [1.0; 4]);
        let at = |r: u32| {
            let spec = GridSpec::fit(&soup, 9.0, GridSize::Resolution(r), 1.0, u64::from(u32::MAX)).unwrap();
            estimate(&spec, &spec.grid_triangles(&soup), FillMode::Winding) as f64
        };
        // At R=1024 the bit grids (2 bits a cell: 268 MB) and the surface (a few million overlaps).
        let fine = at(1024);
        assert!((300e6..1000e6).contains(&fine), "{fine}");
        // Four times the resolution: 64 times the cells, 16 times the surface; the estimate in between.
        let ratio = fine / at(256);
        assert!((16.0..64.0).contains(&ratio), "{ratio}");
    }

    #[test]
    fn a_budget_below_the_estimate_is_refused_with_the_memory_needed() {
        let soup = TriangleSoup::from_mesh(&uv_sphere(1.0, 16), [1.0; 4]);
        let spec = GridSpec::fit(&soup, 9.0, GridSize::Resolution(64), 1.0, u64::from(u32::MAX)).unwrap();
        let tris = spec.grid_triangles(&soup);
        let needed = estimate(&spec, &tris, FillMode::Winding);
        assert!(check(&spec, &tris, FillMode::Winding, needed).is_ok());
        let err = check(&spec, &tris, FillMode::Winding, needed - 1).unwrap_err();
        assert!(matches!(err, VoxelError::OutOfMemory { needed: n, .. } if n == needed), "{err}");
        assert!(err.to_string().contains("64x64x64"), "{err}");
    }

    #[test]
    fn the_bound_is_at_least_the_estimate_and_close_to_it_for_small_triangles() {
        let fine = TriangleSoup::from_mesh(&uv_sphere(1.0, 64), [1.0; 4]);
        let coarse = TriangleSoup::from_mesh(&crate::shapes::cuboid([0.0; 3], [1.0, 2.0, 3.0]), [1.0; 4]);
        for (soup, r) in [(&fine, 8), (&fine, 64), (&fine, 256), (&coarse, 4), (&coarse, 100)] {
            let spec = GridSpec::fit(soup, 9.0, GridSize::Resolution(r), 1.0, u64::from(u32::MAX)).unwrap();
            let tris = spec.grid_triangles(soup);
            for fill in [FillMode::Winding, FillMode::Flood] {
                let (estimate, bound) = (estimate(&spec, &tris, fill), bound(&spec, &tris, fill));
                assert!(bound >= estimate, "R={r}: {bound} < {estimate}");
                // A budget between the two: the estimate decides, so it fits; one byte below the estimate does not.
                assert!(check(&spec, &tris, fill, estimate).is_ok());
                assert!(check(&spec, &tris, fill, estimate - 1).is_err());
            }
        }
        // Triangles of a cell or less (the sphere at R=64): the bound counts each as its worst case,
        // a few overlaps, where a big box's faces count their area.
        let spec = GridSpec::fit(&fine, 9.0, GridSize::Resolution(64), 1.0, u64::from(u32::MAX)).unwrap();
        let tris = spec.grid_triangles(&fine);
        let overlaps = |total: u64| (total - bytes(&spec, &tris, FillMode::Winding, 0.0)) as f64 / BYTES_PER_OVERLAP;
        let per_triangle = overlaps(bound(&spec, &tris, FillMode::Winding)) / tris.len() as f64;
        assert!((2.0..=10.0).contains(&per_triangle), "{per_triangle}");
        assert!(overlaps(estimate(&spec, &tris, FillMode::Winding)) >= tris.len() as f64);
    }

    #[test]
    fn the_available_memory_is_read_on_linux() {
        if cfg!(target_os = "linux") {
            assert!(available().is_some_and(|bytes| bytes > 0));
        }
        assert_eq!(budget(Some(5)), 5);
    }
}
