//! Solid fill: column parity (triangle-major rasterization or BVH column queries), the article's
//! per-point reference, and flood fill from outside.

use glam::Vec3A;
use obvhs::aabb::Aabb;
use rayon::prelude::*;

use crate::bvh::TriangleBvh;
use crate::geom::{GridTriangle, covers_column, depth_at};
use crate::grid::{BitGrid, GridSpec};

/// The z of every crossing of one column, ascending.
type Column = Vec<f64>;

/// Column centre (x, y) of column `col = x * ny + y`.
fn column_center(spec: &GridSpec, col: usize) -> [f64; 2] {
    let ny = spec.dims[1] as usize;
    [(col / ny) as f64 + 0.5, (col % ny) as f64 + 0.5]
}

/// Columns whose centres lie in the closed range [lo, hi] along one axis.
fn column_range(lo: f64, hi: f64, n: u32) -> std::ops::Range<u32> {
    let first = (lo - 0.5).ceil().max(0.0);
    let last = (hi - 0.5).floor().min(f64::from(n) - 1.0);
    if first.is_nan() || last.is_nan() || first > last {
        return 0..0;
    }
    first as u32..last as u32 + 1
}

/// Every column crossing, triangle-major: each triangle is rasterized onto the column grid with the
/// consistent tie-break of [`covers_column`]; the result is sorted by column, then depth.
pub(crate) fn crossings_by_rasterizing(spec: &GridSpec, tris: &[GridTriangle]) -> Vec<Column> {
    let ny = spec.dims[1];
    let mut pairs: Vec<(u32, f64)> = tris
        .par_chunks(2048)
        .flat_map_iter(|chunk| {
            let mut out = Vec::new();
            for t in chunk {
                let xs = column_range(t[0].x.min(t[1].x).min(t[2].x), t[0].x.max(t[1].x).max(t[2].x), spec.dims[0]);
                let ys = column_range(t[0].y.min(t[1].y).min(t[2].y), t[0].y.max(t[1].y).max(t[2].y), ny);
                for x in xs {
                    for y in ys.clone() {
                        let p = [f64::from(x) + 0.5, f64::from(y) + 0.5];
                        if covers_column(t, p) {
                            out.push((x * ny + y, depth_at(t, p)));
                        }
                    }
                }
            }
            out
        })
        .collect();
    pairs.par_sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut columns = vec![Column::new(); spec.dims[0] as usize * ny as usize];
    for (col, z) in pairs {
        columns[col as usize].push(z);
    }
    columns
}

/// Every column crossing, column-major: one BVH query per column (a box around the column's line).
pub(crate) fn crossings_by_bvh(spec: &GridSpec, tris: &[GridTriangle], bvh: &TriangleBvh) -> Vec<Column> {
    let columns = spec.dims[0] as usize * spec.dims[1] as usize;
    (0..columns)
        .into_par_iter()
        .map(|col| {
            let p = column_center(spec, col);
            let (x, y) = (p[0] as f32, p[1] as f32);
            let query = Aabb::new(Vec3A::new(x, y, f32::MIN), Vec3A::new(x, y, f32::MAX));
            let mut zs = Vec::new();
            bvh.for_each_in_box(query, |t| {
                if covers_column(&tris[t], p) {
                    zs.push(depth_at(&tris[t], p));
                }
            });
            zs.sort_unstable_by(f64::total_cmp);
            zs
        })
        .collect()
}

/// Cells of one column inside by parity: cell k is inside when an odd number of crossings lie at or below
/// its centre k + 0.5. Columns with an odd number of crossings only occur on open meshes; they are left
/// empty (the surface shell still covers them) instead of being filled down to the grid's floor.
fn column_runs(zs: &[f64], nz: u32) -> impl Iterator<Item = std::ops::Range<u32>> + '_ {
    let usable = if zs.len().is_multiple_of(2) { zs } else { &[] };
    let to_cell = move |z: f64| (z - 0.5).ceil().clamp(0.0, f64::from(nz)) as u32;
    usable.chunks_exact(2).map(move |pair| to_cell(pair[0])..to_cell(pair[1])).filter(|r| !r.is_empty())
}

/// Parity fill from per-column crossings.
pub(crate) fn fill_columns(spec: &GridSpec, columns: &[Column]) -> BitGrid {
    let nz = spec.dims[2];
    let mut grid = BitGrid::new(spec.cell_count());
    for (col, zs) in columns.iter().enumerate() {
        let base = col * nz as usize;
        for run in column_runs(zs, nz) {
            grid.set_range(base + run.start as usize..base + run.end as usize);
        }
    }
    grid
}

/// The article's algorithm, kept small and obviously correct: for every cell centre, cast one +Z ray
/// against every triangle (brute force, no acceleration) and call the cell inside when the number of hits
/// is odd. It uses the same robust column test as the fast paths.
pub fn reference_fill(spec: &GridSpec, tris: &[GridTriangle]) -> BitGrid {
    let [nx, ny, nz] = spec.dims;
    let inside: Vec<Vec<u32>> = (0..nx * ny)
        .into_par_iter()
        .map(|col| {
            let p = [f64::from(col / ny) + 0.5, f64::from(col % ny) + 0.5];
            (0..nz)
                .filter(|&k| {
                    let zc = f64::from(k) + 0.5;
                    let hits = tris.iter().filter(|t| covers_column(t, p) && depth_at(t, p) > zc).count();
                    hits % 2 == 1
                })
                .collect()
        })
        .collect();
    let mut grid = BitGrid::new(spec.cell_count());
    for (col, ks) in inside.iter().enumerate() {
        for &k in ks {
            grid.set(col * nz as usize + k as usize);
        }
    }
    grid
}

/// Cells reachable from outside the grid through cells not in `walls` (6-connected).
pub(crate) fn reachable_from_outside(spec: &GridSpec, walls: &BitGrid) -> BitGrid {
    let [nx, ny, nz] = spec.dims;
    let mut reached = BitGrid::new(spec.cell_count());
    let mut queue: Vec<usize> = Vec::new();
    let mut seed = |i: usize, reached: &mut BitGrid| {
        if !walls.get(i) && !reached.get(i) {
            reached.set(i);
            queue.push(i);
        }
    };
    for x in 0..nx {
        for y in 0..ny {
            for z in 0..nz {
                let border = x == 0 || y == 0 || z == 0 || x == nx - 1 || y == ny - 1 || z == nz - 1;
                if border {
                    seed(spec.index(x, y, z), &mut reached);
                }
            }
        }
    }
    let strides = [ny as usize * nz as usize, nz as usize, 1];
    while let Some(i) = queue.pop() {
        let c = spec.coords(i);
        for a in 0..3 {
            if c[a] > 0 {
                let j = i - strides[a];
                if !walls.get(j) && !reached.get(j) {
                    reached.set(j);
                    queue.push(j);
                }
            }
            if c[a] + 1 < spec.dims[a] {
                let j = i + strides[a];
                if !walls.get(j) && !reached.get(j) {
                    reached.set(j);
                    queue.push(j);
                }
            }
        }
    }
    reached
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_follow_parity_and_drop_odd_columns() {
        let runs: Vec<_> = column_runs(&[1.2, 3.7, 5.0, 6.0], 10).collect();
        assert_eq!(runs, vec![1..4, 5..6]);
        assert_eq!(column_runs(&[1.2, 3.7, 5.0], 10).count(), 0);
        // A crossing exactly at a centre: the centre counts as at-or-above, as in the reference (z > zc).
        let runs: Vec<_> = column_runs(&[1.5, 3.5], 10).collect();
        assert_eq!(runs, vec![1..3]);
    }

    #[test]
    fn column_ranges_include_centres_on_the_boundary() {
        assert_eq!(column_range(0.5, 2.5, 10), 0..3);
        assert_eq!(column_range(0.6, 1.4, 10), 0..0);
        assert_eq!(column_range(-3.0, 30.0, 10), 0..10);
    }
}
