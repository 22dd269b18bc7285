//! Solid fill: column crossings (triangle-major rasterization or BVH column queries) counted by the
//! nonzero winding rule or by parity, the article's per-point reference, and flood fill from outside.
//!
//! # The column count
//!
//! Every triangle has a [`Role`] (see [`crate::orient`], which orients the model's closed parts): a
//! winding triangle (of a closed, oriented part — or any triangle, when the file's own facing already
//! balances every column) *enters* (+1) or *leaves* (−1) when a +Z column crosses it, by whether its
//! outward side faces down or up; a triangle of a sheet that cannot be closed (open, non-manifold) counts
//! by *parity*. For a cell centre at height z_c, with the crossings at or below z_c:
//!
//! * W = the sum of the steps of the winding crossings (the winding number of the closed parts);
//! * P = the number of parity crossings, modulo 2 — or 0 in a column with an odd number of parity
//!   crossings (only open meshes give those; such a column is not filled by them, instead of being filled
//!   down to the grid's floor);
//! * the cell is inside when W + P ≠ 0.
//!
//! So closed parts fill by the nonzero rule (overlapping parts stay solid: W = 2), a cavity shell facing
//! inwards cancels its surroundings (W = 1 − 1 = 0, or P + W = 1 − 1 = 0 inside a parity solid), and
//! where only parity parts cross a column the rule is the article's parity. With every role `Parity`
//! (`FillMode::Parity`) it is exactly whole-model parity. The sums depend only on which crossings lie at
//! or below z_c, not on the order of crossings at equal depth, and the column test is exact, so the
//! winding steps add up to zero in every column (a closed part's always do; the file's facing is only used
//! as it is when they do): the count from below equals the count from above, which is what the reference
//! ([`reference_fill`]) uses.

use std::sync::OnceLock;

use glam::Vec3A;
use obvhs::aabb::Aabb;
use rayon::prelude::*;

use crate::bvh::TriangleBvh;
use crate::geom::{GridTriangle, covers_column, depth_at, edge_side, projected_orientation};
use crate::grid::{BitGrid, GridSpec};
use crate::orient::{Role, closed_parts, winding_roles};
use crate::radix::{self, Segments};
use crate::soup::TriangleSoup;
use crate::voxelize::{FillMode, Method};

/// One crossing of a +Z column (`column = x * ny + y`) with a triangle, at depth `z`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Crossing {
    /// The column.
    pub column: u32,
    /// The triangle crossed.
    pub triangle: u32,
    /// The z where the column meets the triangle.
    pub z: f64,
}

/// Every column's crossings in one flat list, sorted by column, then depth, then triangle, and which way the
/// crossed triangles face.
pub(crate) struct Columns {
    /// Crossings of column c are `crossings[starts[c]..starts[c + 1]]`.
    starts: Vec<usize>,
    crossings: Vec<Crossing>,
    /// Per triangle: whether its projection on the XY plane runs counter-clockwise, so that with its corners
    /// in the file's order it faces up (+Z). Meaningful only for triangles that some column crosses (the
    /// rasterizer leaves the others `false`).
    pub faces_up: Vec<bool>,
}

impl Columns {
    /// Indexes crossings already sorted by column (then depth, then triangle), for `count` columns.
    fn from_sorted(count: usize, crossings: Vec<Crossing>, faces_up: Vec<bool>) -> Self {
        let mut starts = vec![0; count + 1];
        for c in &crossings {
            starts[c.column as usize + 1] += 1;
        }
        for c in 0..count {
            starts[c + 1] += starts[c];
        }
        Self { starts, crossings, faces_up }
    }

    /// The number of columns.
    pub fn len(&self) -> usize {
        self.starts.len() - 1
    }

    /// The crossings of column `col`, ascending by depth.
    pub fn column(&self, col: usize) -> &[Crossing] {
        &self.crossings[self.starts[col]..self.starts[col + 1]]
    }
}

/// The order of crossings: column, depth, triangle (total, so sorting is deterministic).
fn crossing_order(a: &Crossing, b: &Crossing) -> std::cmp::Ordering {
    a.column.cmp(&b.column).then(a.z.total_cmp(&b.z)).then(a.triangle.cmp(&b.triangle))
}

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

/// Triangles per task of the rasterization: small enough that both threads share out a few big triangles
/// (a box has twelve, four of which cross every column), at most 2048.
fn triangles_per_task(count: usize) -> usize {
    count.div_ceil(rayon::current_num_threads() * 8).clamp(1, 2048)
}

/// Rows of at least this many columns are searched for the ends of their covered run instead of testing every
/// column.
const SEARCHED_ROW: usize = 8;

/// The columns of `ys` in the row of column centres x = `px` that triangle `t` covers ([`covers_column`]);
/// `ys` lies within the triangle's extent along y and `counter_clockwise` is its [`projected_orientation`].
///
/// A column is covered exactly when it lies on the inner side of all three edges: under the tie-break's
/// perturbation a point cannot lie on the outer side of all three, the other case [`covers_column`] accepts.
/// The covered columns form one run: along the row each edge's side test changes at most once (the edge
/// function is linear in y, and a tie is broken the same way all along the row). A long row is searched for
/// where each edge's side changes (a binary search of the exact test); a short one is tested column by column.
fn covered_run(t: &GridTriangle, counter_clockwise: bool, px: f64, ys: std::ops::Range<u32>) -> std::ops::Range<u32> {
    let inside = |k: usize, y: u32| edge_side(t[k], t[(k + 1) % 3], [px, f64::from(y) + 0.5]) == counter_clockwise;
    if ys.len() < SEARCHED_ROW {
        let mut covered = ys.filter(|&y| (0..3).all(|k| inside(k, y)));
        let first = covered.next();
        let last = covered.next_back().or(first);
        return first.zip(last).map_or(0..0, |(first, last)| first..last + 1);
    }
    let (mut start, mut end) = (ys.start, ys.end);
    for k in 0..3 {
        match (inside(k, start), inside(k, end - 1)) {
            (true, true) => {}
            (false, false) => return 0..0,
            // The inside columns are a prefix of start..end: find where they stop; or a suffix.
            (true, false) => end = first_where(start..end, |y| !inside(k, y)),
            (false, true) => start = first_where(start..end, |y| inside(k, y)),
        }
        if start >= end {
            return 0..0;
        }
    }
    start..end
}

/// The first `y` of `ys` where `holds(y)`, which holds from some point of `ys` on (else `ys.end`).
fn first_where(ys: std::ops::Range<u32>, holds: impl Fn(u32) -> bool) -> u32 {
    let (mut lo, mut hi) = (ys.start, ys.end);
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if holds(mid) { hi = mid } else { lo = mid + 1 }
    }
    lo
}

/// Every column crossing, triangle-major: each triangle is rasterized onto the column grid with the
/// consistent tie-break of [`covers_column`].
pub(crate) fn crossings_by_rasterizing(spec: &GridSpec, tris: &[GridTriangle]) -> Columns {
    let ny = spec.dims[1];
    let per_task = triangles_per_task(tris.len());
    let mut faces_up = vec![false; tris.len()];
    let lists: Vec<Segments<Crossing>> = tris
        .par_chunks(per_task)
        .zip(faces_up.par_chunks_mut(per_task))
        .enumerate()
        .map(|(chunk_index, (chunk, up))| {
            let mut out = Segments::default();
            for (k, t) in chunk.iter().enumerate() {
                let triangle = (chunk_index * per_task + k) as u32;
                let xs = column_range(t[0].x.min(t[1].x).min(t[2].x), t[0].x.max(t[1].x).max(t[2].x), spec.dims[0]);
                let ys = column_range(t[0].y.min(t[1].y).min(t[2].y), t[0].y.max(t[1].y).max(t[2].y), ny);
                if xs.is_empty() || ys.is_empty() {
                    continue; // no column centre under the triangle's extent
                }
                let Some(counter_clockwise) = projected_orientation(t) else { continue };
                up[k] = counter_clockwise;
                for x in xs {
                    let px = f64::from(x) + 0.5;
                    for y in covered_run(t, counter_clockwise, px, ys.clone()) {
                        let p = [px, f64::from(y) + 0.5];
                        out.push(Crossing { column: x * ny + y, triangle, z: depth_at(t, p) });
                    }
                }
            }
            out
        })
        .collect();
    // Made triangle-major: a stable sort by column keeps the triangles' order, then each column's few
    // crossings are sorted by depth.
    let count = spec.dims[0] as usize * ny as usize;
    let mut crossings = radix::sort_parts_by_key(Segments::concat(lists), radix::bits_for(count), |c| c.column);
    crossings.chunk_by_mut(|a, b| a.column == b.column).for_each(|column| column.sort_unstable_by(crossing_order));
    Columns::from_sorted(count, crossings, faces_up)
}

/// Every column crossing, column-major: one BVH query per column (a box around the column's line).
pub(crate) fn crossings_by_bvh(spec: &GridSpec, tris: &[GridTriangle], bvh: &TriangleBvh) -> Columns {
    let count = spec.dims[0] as usize * spec.dims[1] as usize;
    let crossings = (0..count)
        .into_par_iter()
        .flat_map_iter(|col| {
            let p = column_center(spec, col);
            let (x, y) = (p[0] as f32, p[1] as f32);
            let query = Aabb::new(Vec3A::new(x, y, f32::MIN), Vec3A::new(x, y, f32::MAX));
            let mut found = Vec::new();
            bvh.for_each_in_box(query, |t| {
                if covers_column(&tris[t], p) {
                    found.push(Crossing { column: col as u32, triangle: t as u32, z: depth_at(&tris[t], p) });
                }
            });
            found.sort_unstable_by(crossing_order);
            found
        })
        .collect();
    let faces_up = tris.par_iter().map(|t| projected_orientation(t) == Some(true)).collect();
    Columns::from_sorted(count, crossings, faces_up)
}

/// Whether a column's parity crossings count: only when there is an even number of them.
pub(crate) fn parity_counts(crossings: &[Crossing], roles: &[Role]) -> bool {
    crossings.iter().filter(|c| roles[c.triangle as usize] == Role::Parity).count().is_multiple_of(2)
}

/// Calls `emit` with the runs of cells of one column that are inside by the column count of the module
/// docs: cell k is inside when W + P ≠ 0 for the crossings at or below its centre k + 0.5.
fn column_runs(crossings: &[Crossing], roles: &[Role], nz: u32, mut emit: impl FnMut(std::ops::Range<u32>)) {
    let parity_counts = parity_counts(crossings, roles);
    let to_cell = |z: f64| (z - 0.5).ceil().clamp(0.0, f64::from(nz)) as u32;
    let (mut winding, mut parity) = (0i32, 0i32);
    let mut entered: Option<f64> = None;
    for c in crossings {
        match roles[c.triangle as usize] {
            Role::Parity => parity ^= i32::from(parity_counts),
            role => winding += role.step(),
        }
        let inside = winding + parity != 0;
        match entered {
            None if inside => entered = Some(c.z),
            Some(z) if !inside => {
                let run = to_cell(z)..to_cell(c.z);
                if !run.is_empty() {
                    emit(run);
                }
                entered = None;
            }
            _ => {}
        }
    }
}

/// The solid from per-column crossings and the triangles' roles.
fn fill_columns(spec: &GridSpec, columns: &Columns, roles: &[Role]) -> BitGrid {
    let nz = spec.dims[2];
    let mut grid = BitGrid::new(spec.cell_count());
    for col in 0..columns.len() {
        let base = col * nz as usize;
        column_runs(columns.column(col), roles, nz, |run| {
            grid.set_range(base + run.start as usize..base + run.end as usize);
        });
    }
    grid
}

/// The solid by the column count, with the roles of `fill` (winding or parity) and the crossings of
/// `method`; `tris` are `soup`'s triangles on the grid `spec`.
pub(crate) fn solid_fill(
    soup: &TriangleSoup,
    spec: &GridSpec,
    tris: &[GridTriangle],
    fill: FillMode,
    method: Method,
    bvh: &OnceLock<TriangleBvh>,
) -> BitGrid {
    let columns = match method {
        Method::Fast => Some(crossings_by_rasterizing(spec, tris)),
        Method::Bvh => Some(crossings_by_bvh(spec, tris, bvh.get_or_init(|| TriangleBvh::build(tris)))),
        Method::Reference => None,
    };
    let roles = match fill {
        FillMode::Winding => {
            winding_roles(columns.as_ref(), || crossings_by_rasterizing(spec, tris), || closed_parts(soup, tris))
        }
        _ => vec![Role::Parity; tris.len()],
    };
    match columns {
        Some(columns) => fill_columns(spec, &columns, &roles),
        None => reference_fill(spec, tris, &roles),
    }
}

/// The article's algorithm, kept small and obviously correct: for every cell centre, cast one +Z ray
/// against every triangle (brute force, no acceleration) and count the hits above the centre: the
/// winding number W as the sum of the hits' outward facings (+1 leaving upwards), P as the parity of the
/// parity hits; inside when W + P ≠ 0 (odd hits when every role is parity, the article's rule). It uses the
/// same robust column test as the fast paths.
fn reference_fill(spec: &GridSpec, tris: &[GridTriangle], roles: &[Role]) -> BitGrid {
    let [nx, ny, nz] = spec.dims;
    let inside: Vec<Vec<u32>> = (0..nx * ny)
        .into_par_iter()
        .map(|col| {
            let p = [f64::from(col / ny) + 0.5, f64::from(col % ny) + 0.5];
            (0..nz)
                .filter(|&k| {
                    let zc = f64::from(k) + 0.5;
                    let (mut winding, mut parity) = (0i32, 0i32);
                    for (t, role) in tris.iter().zip(roles) {
                        if covers_column(t, p) && depth_at(t, p) > zc {
                            match role {
                                Role::Parity => parity ^= 1,
                                role => winding -= role.step(),
                            }
                        }
                    }
                    winding + parity != 0
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

    /// The runs of a column whose crossings are (z, role), triangle i having the i-th role.
    fn runs(crossings: &[(f64, Role)]) -> Vec<std::ops::Range<u32>> {
        let roles: Vec<Role> = crossings.iter().map(|c| c.1).collect();
        let column: Vec<Crossing> =
            crossings.iter().enumerate().map(|(i, c)| Crossing { column: 0, triangle: i as u32, z: c.0 }).collect();
        let mut out = Vec::new();
        column_runs(&column, &roles, 10, |r| out.push(r));
        out
    }

    #[test]
    fn runs_follow_parity_and_drop_odd_columns() {
        use Role::Parity as P;
        assert_eq!(runs(&[(1.2, P), (3.7, P), (5.0, P), (6.0, P)]), vec![1..4, 5..6]);
        assert!(runs(&[(1.2, P), (3.7, P), (5.0, P)]).is_empty());
        // A crossing exactly at a centre: the centre counts as at-or-above, as in the reference (z > zc).
        assert_eq!(runs(&[(1.5, P), (3.5, P)]), vec![1..3]);
    }

    #[test]
    fn runs_follow_the_winding_number() {
        use Role::{Enters as E, Leaves as L, Parity as P};
        // Two overlapping parts: the overlap (W = 2) stays inside, where parity would empty it.
        assert_eq!(runs(&[(1.2, E), (3.2, E), (5.2, L), (7.2, L)]), vec![1..7]);
        // A cavity facing inwards inside a part: W = 1 − 1 = 0 in it.
        assert_eq!(runs(&[(1.2, E), (3.2, L), (5.2, E), (7.2, L)]), vec![1..3, 5..7]);
        // The same cavity inside a parity solid: P + W = 1 − 1 = 0.
        assert_eq!(runs(&[(1.2, P), (3.2, L), (5.2, E), (7.2, P)]), vec![1..3, 5..7]);
        // An odd parity column ignores its parity crossings but keeps the winding part.
        assert_eq!(runs(&[(0.2, P), (1.2, E), (3.2, L)]), vec![1..3]);
    }

    #[test]
    fn covered_runs_are_the_columns_that_pass_the_column_test() {
        // Corners on a lattice of half cells (edges through column centres: the tie-break) and finer ones.
        let mut state = 5u64;
        let mut next = |steps: u64| {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 33) % steps
        };
        let mut covered = 0;
        for k in 0..3000 {
            let step = [0.5, 1.0 / 64.0][k % 2];
            let t: GridTriangle = std::array::from_fn(|_| {
                let mut c = [0.0; 3];
                c.iter_mut().for_each(|c| *c = next((40.0 / step) as u64) as f64 * step);
                glam::DVec3::from_array(c)
            });
            for x in 0..40 {
                let px = f64::from(x) + 0.5;
                for ys in [0..40, 3..17, 10..14] {
                    let expected: Vec<u32> =
                        ys.clone().filter(|&y| covers_column(&t, [px, f64::from(y) + 0.5])).collect();
                    let run = projected_orientation(&t).map_or(0..0, |ccw| covered_run(&t, ccw, px, ys.clone()));
                    assert_eq!(run.collect::<Vec<_>>(), expected, "{t:?} at x = {px}, {ys:?}");
                    covered += expected.len();
                }
            }
        }
        assert!(covered > 100_000, "{covered}");
    }

    #[test]
    fn column_ranges_include_centres_on_the_boundary() {
        assert_eq!(column_range(0.5, 2.5, 10), 0..3);
        assert_eq!(column_range(0.6, 1.4, 10), 0..0);
        assert_eq!(column_range(-3.0, 30.0, 10), 0..10);
    }
}
