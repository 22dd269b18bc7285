//! Column crossings: where each +Z column of the grid (through the cell centres' x and y) meets the
//! triangles, found triangle-major by rasterization or column-major by BVH queries, and how a crossing counts
//! ([`Role`]). The fill ([`crate::fill`]) counts them into cells; the orientation ([`crate::orient`]) reads them
//! to decide the roles. The fill also rasterizes the parity triangles onto the columns along X and Y
//! ([`crossings_along`]), the same way with the coordinates cycled.

use std::sync::atomic::{AtomicI32, Ordering};

use glam::{DVec3, Vec3A};
use obvhs::aabb::Aabb;
use rayon::prelude::*;

use crate::bvh::TriangleBvh;
use crate::float;
use crate::geom::{GridTriangle, covers_column, depth_at, edge_side, projected_orientation};
use crate::grid::{GridSpec, GridTriangles};
use crate::progress::Progress;
use crate::radix::{self, Segments};

/// How a triangle's column crossings count.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Role {
    /// A triangle of a closed part whose outward side faces down: a column crossing it upwards enters
    /// the part (winding +1).
    Enters,
    /// A triangle of a closed part whose outward side faces up: crossing it upwards leaves (winding −1).
    Leaves,
    /// A triangle of a part that cannot be oriented: counts by parity.
    Parity,
}

impl Role {
    /// The change of the winding number when a column crosses the triangle upwards (0 for parity).
    pub fn step(self) -> i32 {
        match self {
            Role::Enters => 1,
            Role::Leaves => -1,
            Role::Parity => 0,
        }
    }

    /// The winding role of a triangle with its corner order as in the file, by whether it faces up (+Z).
    pub(crate) fn facing(faces_up: bool) -> Self {
        if faces_up { Role::Leaves } else { Role::Enters }
    }

    /// The role of the triangle with its corner order reversed.
    pub(crate) fn reversed(self) -> Self {
        match self {
            Role::Enters => Role::Leaves,
            Role::Leaves => Role::Enters,
            Role::Parity => Role::Parity,
        }
    }
}

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
pub(crate) fn column_range(lo: f64, hi: f64, n: u32) -> std::ops::Range<u32> {
    let first = float::ceil(lo - 0.5).max(0.0);
    let last = float::floor(hi - 0.5).min(f64::from(n) - 1.0);
    if first.is_nan() || last.is_nan() || first > last {
        return 0..0;
    }
    first as u32..last as u32 + 1
}

/// Triangles per task of the rasterization: small enough that both threads share out a few big triangles
/// (a box has twelve, four of which cross every column), at most 2048.
pub(crate) fn triangles_per_task(count: usize) -> usize {
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

/// Point `p` with its coordinates cycled so that `axis` comes last: `(axis + 1) % 3` as x, `(axis + 2) % 3` as y
/// (a rotation: the handedness is kept). Along Z, `p` itself.
#[inline]
pub(crate) fn cycled(p: DVec3, axis: usize) -> DVec3 {
    match axis {
        2 => p,
        _ => DVec3::new(p[(axis + 1) % 3], p[(axis + 2) % 3], p[axis]),
    }
}

/// Calls `f(x, y, counter_clockwise)` for every column of an `nx` × `ny` grid of them whose centre triangle `t`
/// covers ([`covers_column`], by rows: [`covered_run`]), `counter_clockwise` the triangle's
/// [`projected_orientation`], which it returns; `None` (and no call) when no column centre lies under its extent
/// or it is seen edge-on.
fn covered_columns(t: &GridTriangle, nx: u32, ny: u32, mut f: impl FnMut(u32, u32, bool)) -> Option<bool> {
    let xs = column_range(t[0].x.min(t[1].x).min(t[2].x), t[0].x.max(t[1].x).max(t[2].x), nx);
    let ys = column_range(t[0].y.min(t[1].y).min(t[2].y), t[0].y.max(t[1].y).max(t[2].y), ny);
    if xs.is_empty() || ys.is_empty() {
        return None;
    }
    let counter_clockwise = projected_orientation(t)?;
    for x in xs {
        for y in covered_run(t, counter_clockwise, f64::from(x) + 0.5, ys.clone()) {
            f(x, y, counter_clockwise);
        }
    }
    Some(counter_clockwise)
}

/// A number per column along one axis (those of [`crossings_along`]), added to triangle by triangle from any
/// number of threads: how many triangles cross each, or their steps.
pub(crate) struct Tally {
    axis: usize,
    /// The columns' counts, `nx` × `ny`.
    dims: [u32; 2],
    counts: Vec<AtomicI32>,
}

impl Tally {
    /// Zero in every column along `axis` of `spec`'s grid.
    pub(crate) fn new(spec: &GridSpec, axis: usize) -> Self {
        let dims = [spec.dims[(axis + 1) % 3], spec.dims[(axis + 2) % 3]];
        Self { axis, dims, counts: (0..dims[0] as usize * dims[1] as usize).map(|_| AtomicI32::new(0)).collect() }
    }

    /// Adds `f(orientation)` to every column that triangle `t` (grid coordinates) crosses, `orientation` its
    /// [`projected_orientation`] along the axis; true when one of those columns held a number other than zero.
    fn add(&self, t: &GridTriangle, f: impl Fn(bool) -> i32) -> bool {
        let mut held = false;
        covered_columns(&t.map(|c| cycled(c, self.axis)), self.dims[0], self.dims[1], |x, y, counter_clockwise| {
            let count = &self.counts[(x * self.dims[1] + y) as usize];
            held |= count.fetch_add(f(counter_clockwise), Ordering::Relaxed) != 0;
        });
        held
    }

    /// Counts the columns that triangle `t` crosses; false when one of them was crossed before (by another triangle).
    pub(crate) fn cross(&self, t: &GridTriangle) -> bool {
        !self.add(t, |_| 1)
    }

    /// Adds triangle `t`'s steps as it faces in the file ([`Role::facing`]) to the columns it crosses.
    pub(crate) fn step(&self, t: &GridTriangle) {
        self.add(t, |up| Role::facing(up).step());
    }

    /// Whether some column's number is not zero (for steps: the file's facing does not balance it).
    pub(crate) fn any(&self) -> bool {
        self.counts.iter().any(|c| c.load(Ordering::Relaxed) != 0)
    }
}

/// Every column crossing, triangle-major: each triangle is rasterized onto the column grid with the
/// consistent tie-break of [`covers_column`]. Once `progress` is cancelled the remaining triangles are passed
/// over (the caller's next stage ends the run).
pub(crate) fn crossings_by_rasterizing(spec: &GridSpec, tris: &GridTriangles, progress: &Progress) -> Columns {
    crossings_along::<2>(spec, tris, |_| true, progress)
}

/// The crossings of the columns along axis `AXIS` (0, 1 or 2) with the triangles that `keep` accepts, as
/// [`crossings_by_rasterizing`] finds those along Z: each corner [`cycled`] so that `AXIS` comes
/// last (`(AXIS + 1) % 3` as x, `(AXIS + 2) % 3` as y: column `x * ny + y` of those two, the depth along
/// `AXIS`), which keeps the triangles' handedness. `faces_up` then tells the facing along `AXIS`.
pub(crate) fn crossings_along<const AXIS: usize>(
    spec: &GridSpec,
    tris: &GridTriangles,
    keep: impl Fn(usize) -> bool + Sync,
    progress: &Progress,
) -> Columns {
    let (nx, ny) = (spec.dims[(AXIS + 1) % 3], spec.dims[(AXIS + 2) % 3]);
    let per_task = triangles_per_task(tris.len());
    let mut faces_up = vec![false; tris.len()];
    let lists: Vec<Segments<Crossing>> = faces_up
        .par_chunks_mut(per_task)
        .enumerate()
        .map(|(chunk_index, up)| {
            let mut out = Segments::default();
            for (k, up) in up.iter_mut().enumerate() {
                if progress.is_cancelled() {
                    break;
                }
                let index = chunk_index * per_task + k;
                if !keep(index) {
                    continue;
                }
                let (t, triangle) = (&tris.get(index).map(|c| cycled(c, AXIS)), index as u32);
                let covered = covered_columns(t, nx, ny, |x, y, _| {
                    let z = depth_at(t, [f64::from(x) + 0.5, f64::from(y) + 0.5]);
                    out.push(Crossing { column: x * ny + y, triangle, z });
                });
                if let Some(counter_clockwise) = covered {
                    *up = counter_clockwise;
                }
            }
            out
        })
        .collect();
    // Made triangle-major: a stable sort by column keeps the triangles' order, then each column's few
    // crossings are sorted by depth.
    let count = nx as usize * ny as usize;
    let mut crossings = radix::sort_parts_by_key(Segments::concat(lists), radix::bits_for(count), |c| c.column);
    crossings.chunk_by_mut(|a, b| a.column == b.column).for_each(|column| column.sort_unstable_by(crossing_order));
    Columns::from_sorted(count, crossings, faces_up)
}

/// Every column crossing, column-major: one BVH query per column (a box around the column's line).
pub(crate) fn crossings_by_bvh(spec: &GridSpec, tris: &GridTriangles, bvh: &TriangleBvh) -> Columns {
    let count = spec.dims[0] as usize * spec.dims[1] as usize;
    let crossings = (0..count)
        .into_par_iter()
        .flat_map_iter(|col| {
            let p = column_center(spec, col);
            let (x, y) = (p[0] as f32, p[1] as f32);
            let query = Aabb::new(Vec3A::new(x, y, f32::MIN), Vec3A::new(x, y, f32::MAX));
            let mut found = Vec::new();
            bvh.for_each_in_box(query, |t| {
                let triangle = tris.get(t);
                if covers_column(&triangle, p) {
                    found.push(Crossing { column: col as u32, triangle: t as u32, z: depth_at(&triangle, p) });
                }
            });
            found.sort_unstable_by(crossing_order);
            found
        })
        .collect();
    let faces_up = tris.par_iter().map(|t| projected_orientation(&t) == Some(true)).collect();
    Columns::from_sorted(count, crossings, faces_up)
}

/// Whether a column's parity crossings count: only when there is an even number of them.
pub(crate) fn parity_counts(crossings: &[Crossing], roles: &[Role]) -> bool {
    crossings.iter().filter(|c| roles[c.triangle as usize] == Role::Parity).count().is_multiple_of(2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn covered_runs_are_the_columns_that_pass_the_column_test() {
        // Corners on a lattice of half cells (edges through column centres: the tie-break) and finer ones.
        let mut random = crate::lcg::Lcg::new(5);
        let mut next = |steps: u64| random.below(steps);
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
