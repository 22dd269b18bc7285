//! The conservative surface shell: every cell a triangle overlaps, with the triangles overlapping each (for
//! colour), and which of its cells carry a piece of surface the solid fill does not account for.
//!
//! The shell does not depend on the fill, so the pipeline builds both side by side; only the thin cells
//! ([`Shell::thin_cells`]) are found afterwards, from the fill.

use glam::DVec3;
use rayon::prelude::*;

use crate::geom::GridTriangle;
use crate::grid::{BitGrid, GridSpec, GridTriangles};
use crate::progress::Progress;
use crate::radix::{self, Segments};

mod cells;
pub(crate) mod distance;
pub(crate) mod octree;
use cells::CellTester;

/// Shell cells, ascending by linear index, with the triangles overlapping each (compressed rows of runs of
/// consecutive triangles: a fine mesh's neighbouring triangles mostly share their cells, and a cell crossed by
/// a sheet of tiny ones lists a few runs rather than dozens of triangles).
#[derive(Debug, Default)]
pub(crate) struct Shell {
    /// Linear indices of the cells any triangle overlaps.
    pub cells: Vec<u32>,
    /// `runs[offsets[k]..offsets[k + 1]]` overlap cell `cells[k]`, ascending.
    offsets: Vec<u32>,
    /// Runs of consecutive triangles, packed by `code`.
    runs: Vec<u32>,
    code: RunCode,
}

impl Shell {
    /// The triangles overlapping the `k`-th shell cell, `cells[k]`, ascending.
    pub fn triangles_at(&self, k: usize) -> Triangles<'_> {
        let runs = self.runs[self.offsets[k] as usize..self.offsets[k + 1] as usize].iter();
        Triangles { runs, code: self.code, next: 0, end: 0 }
    }

    /// The shell cells that a thin piece of surface passes through, ascending: cells the solid `fill`
    /// leaves empty, overlapped by a triangle of `tris` (the triangles the shell was built from) whose
    /// neighbours of the cell on either side along the triangle's normal are empty too (deterministic
    /// whatever the thread count).
    // Out of line, like `shell`, so that an instruction profile can split it from the passes around it.
    // Each triangle's normal is found again here rather than kept from the shell pass: only the cells the fill
    // leaves empty need it, far fewer than the overlaps at the default grid (measured: docs/benchmarks.md).
    #[inline(never)]
    pub fn thin_cells(&self, spec: &GridSpec, tris: &GridTriangles, fill: &BitGrid) -> Vec<u32> {
        if fill.count() == 0 {
            // Every neighbour is empty: every cell is thin (a terrain's, whose fill is empty).
            return self.cells.clone();
        }
        let thin = |k: usize| {
            let index = self.cells[k] as usize;
            if fill.get(index) {
                return false;
            }
            let c = spec.coords(index);
            // Neighbouring triangles mostly step alike (a cell crossed by a sheet of tiny triangles lists dozens):
            // a step just found not thin is not looked up again.
            let mut last = None;
            self.triangles_at(k).any(|tri| {
                let t = &tris.get(tri as usize);
                let step = normal_step((t[1] - t[0]).cross(t[2] - t[0]));
                if last.replace(step) == Some(step) {
                    return false;
                }
                [step, step.map(|s| -s)].into_iter().all(|s| !spec.neighbour(c, s).is_some_and(|n| fill.get(n)))
            })
        };
        (0..self.cells.len())
            .into_par_iter()
            .with_min_len(THIN_CHUNK)
            .filter(|&k| thin(k))
            .map(|k| self.cells[k])
            .collect()
    }
}

/// The triangles of runs of consecutive triangles, in order ([`Shell::triangles_at`]).
#[derive(Clone, Debug)]
pub(crate) struct Triangles<'a> {
    runs: std::slice::Iter<'a, u32>,
    code: RunCode,
    /// The rest of the run being walked.
    next: u32,
    end: u32,
}

impl Iterator for Triangles<'_> {
    type Item = u32;

    #[inline]
    fn next(&mut self) -> Option<u32> {
        if self.next == self.end {
            let [first, count] = self.code.triangles(*self.runs.next()?);
            (self.next, self.end) = (first, first + count);
        }
        self.next += 1;
        Some(self.next - 1)
    }
}

/// The most top bits of a cell's index that pick its slab in [`shell`] (the slabs sort side by side; a small grid
/// has fewer: [`SLAB_CELL_BITS`]).
const SLAB_BITS: u32 = 6;

/// The bits of the fewest cells a slab of [`shell`] covers: a smaller grid has fewer slabs, so that each of its
/// tasks starts fewer lists (a list's first segment is 512 bytes: at R=128 a model's 24 tasks started 1,536).
const SLAB_CELL_BITS: u32 = 16;

/// The runs below which consecutive slabs of [`shell`] sort together.
const RUNS_PER_SORT: usize = 1 << 16;

/// Shell cells per task of [`Shell::thin_cells`] (a few bit reads each: small tasks cost more than they save).
const THIN_CHUNK: usize = 4096;

/// The step to the face, edge or corner neighbour along a normal: components within half of the largest
/// one count.
fn normal_step(n: DVec3) -> [i32; 3] {
    let m = n.abs().max_element();
    [n.x, n.y, n.z].map(|c| if c.abs() >= 0.5 * m { c.signum() as i32 } else { 0 })
}

/// The axis along which the normal `n` is largest (the first of equals).
fn dominant_axis(n: DVec3) -> usize {
    let an = n.abs();
    if an.x >= an.y && an.x >= an.z {
        0
    } else if an.y >= an.z {
        1
    } else {
        2
    }
}

/// The slots of [`TaskRuns`] for open runs besides the current one: a triangle crossing cell boundaries adds to a
/// few cells, and the next triangle mostly to the same ones.
const OPEN_RUNS: usize = 16;
const _: () = assert!(OPEN_RUNS.is_power_of_two(), "`slot` takes the top bits of a hash");

/// No cell has this index (cells are numbered below [`MAX_CELLS`](crate::grid::MAX_CELLS)): the cell of no run.
const NO_CELL: u32 = u32::MAX;

/// A free slot of [`TaskRuns`].
const FREE: [u32; 3] = [NO_CELL, 0, 0];

/// One task's overlaps of [`shell`] as runs `[cell, first triangle, count]` of consecutive triangles overlapping
/// one cell, in lists by the top bits of their cell (a slab of the grid each). Open are the current run (the
/// last overlap's) and, in a slot picked by a hash of its cell, each of up to [`OPEN_RUNS`] others. A run leaves
/// for its slab's list when the triangle after its last skips its cell or another run takes its slot, so a
/// cell's runs reach its list in the order of their triangles, as the sort by cell must find them.
struct TaskRuns {
    slabs: Vec<Segments<u64>>,
    shift: u32,
    code: RunCode,
    /// The current run: its cell ([`NO_CELL`]: none), first triangle and count. (Fields of their own, which the
    /// compiler keeps in registers across a task's loop: most overlaps of a fine mesh only add one to `count`.)
    cell: u32,
    first: u32,
    count: u32,
    /// The other open runs ([`FREE`]: a free slot).
    open: [[u32; 3]; OPEN_RUNS],
}

impl TaskRuns {
    /// No runs, for slabs of 2^`shift` cells, `slab_count` of them, packed by `code`.
    fn new(slab_count: usize, shift: u32, code: RunCode) -> Self {
        let slabs = (0..slab_count).map(|_| Segments::default()).collect();
        Self { slabs, shift, code, cell: NO_CELL, first: 0, count: 0, open: [FREE; OPEN_RUNS] }
    }

    /// Adds the overlap of cell `cell` and triangle `tri` (each pair once, triangles ascending).
    #[inline]
    fn push(&mut self, cell: u32, tri: u32) {
        if cell != self.cell || self.first + self.count != tri || self.count == self.code.longest {
            self.switch(cell, tri);
        }
        self.count += 1;
    }

    /// Makes the run of `cell` that `tri` extends the current one (an empty run when none does).
    #[inline]
    fn switch(&mut self, cell: u32, tri: u32) {
        let current = [self.cell, self.first, self.count];
        if cell == self.cell {
            // The triangle after the run's last skips this cell, or the run is as long as a run can be: it is done.
            self.close(current);
        } else {
            // The current run steps aside into its slot; this cell's run, if open, steps out of its own.
            if current[0] != NO_CELL {
                let parked = std::mem::replace(&mut self.open[slot(current[0])], current);
                self.close(parked);
            }
            let run = &mut self.open[slot(cell)];
            if run[0] == cell {
                let run = std::mem::replace(run, FREE);
                if run[1] + run[2] == tri && run[2] < self.code.longest {
                    [self.cell, self.first, self.count] = run;
                    return;
                }
                self.close(run);
            }
        }
        [self.cell, self.first, self.count] = [cell, tri, 0];
    }

    /// Adds the overlap of cell `cell` and triangle `tri` as a run of its own, for a triangle of many cells (whose
    /// cells the next triangle seldom all shares: parking a run at each would cost more than it saves). The
    /// cell's open run, if any, is closed first, so that it stays ahead of this one in the cell's list.
    #[inline]
    fn push_alone(&mut self, cell: u32, tri: u32) {
        if cell == self.cell {
            self.close([self.cell, self.first, self.count]);
            (self.cell, self.count) = (NO_CELL, 0);
        } else {
            let open = &mut self.open[slot(cell)];
            if open[0] == cell {
                let run = std::mem::replace(open, FREE);
                self.close(run);
            }
        }
        self.close([cell, tri, 1]);
    }

    /// Puts `run` (unless it is [`FREE`]) in its slab's list.
    #[inline(always)]
    fn close(&mut self, run: [u32; 3]) {
        if run[0] != NO_CELL {
            self.slabs[(run[0] >> self.shift) as usize].push(self.code.pack(run));
        }
    }

    /// The lists, with every open run closed.
    fn finish(mut self) -> Vec<Segments<u64>> {
        self.close([self.cell, self.first, self.count]);
        for run in self.open {
            self.close(run);
        }
        self.slabs
    }
}

/// How a run of triangles (its first, and how many) is packed in a `u32`: the count less one above the first
/// triangle, which takes as many bits as the triangles need; the count has the bits left over, at most
/// [`RUN_BITS`] (none when the triangles need all 32: then every run is one triangle long). For the sort by cell,
/// a run's cell goes in the top half of a `u64`.
#[derive(Clone, Copy, Debug, Default)]
struct RunCode {
    /// The bits of the first triangle, and the longest run.
    triangle_bits: u32,
    longest: u32,
}

impl RunCode {
    /// The code for `triangles` triangles.
    fn new(triangles: usize) -> Self {
        let triangle_bits = radix::bits_for(triangles).max(1);
        Self { triangle_bits, longest: 1 << (u32::BITS - triangle_bits).min(RUN_BITS) }
    }

    /// The run `[cell, first, count]` packed for the sort by cell.
    #[inline]
    fn pack(&self, [cell, first, count]: [u32; 3]) -> u64 {
        let run = u64::from(count - 1) << self.triangle_bits | u64::from(first);
        u64::from(cell) << u32::BITS | run
    }

    /// The cell of a packed run.
    #[inline]
    fn cell(run: u64) -> u32 {
        (run >> u32::BITS) as u32
    }

    /// The first triangle and the count of a run (the low half of a packed one).
    #[inline]
    fn triangles(&self, run: u32) -> [u32; 2] {
        let run = u64::from(run);
        [(run & ((1 << self.triangle_bits) - 1)) as u32, (run >> self.triangle_bits) as u32 + 1]
    }
}

/// The most bits of a run's count less one (runs of up to 2¹⁶ triangles).
const RUN_BITS: u32 = 16;

/// The slot of [`TaskRuns`] of an open run of cell `cell` (a multiplicative hash: neighbouring cells, whose
/// indices differ by a row's or a layer's cells, take different slots).
#[inline]
fn slot(cell: u32) -> usize {
    (cell.wrapping_mul(0x9E37_79B1) >> (u32::BITS - OPEN_RUNS.trailing_zeros())) as usize
}

/// How much of the triangle–box test a candidate cell needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Test {
    /// No test: the cell's footprint lies outside the triangle's projection.
    Outside,
    /// The box axes and the plane: the cell's footprint lies inside the triangle's projection.
    Plane,
    /// The whole separating axis test.
    Full,
}

/// Where a unit square of the plane across a triangle's dominant axis lies against the triangle's projection
/// on that plane, by a margin far above rounding. Inside, no edge of the triangle passes over the square, and
/// a cell above it overlaps the triangle exactly when the triangle's plane crosses the cell; outside, no cell
/// above it overlaps the triangle.
struct FootprintTest {
    /// Per edge: its start (u, v), its direction (du, dv) times the projection's orientation, and the
    /// smallest value its edge function must exceed at a square's centre.
    edges: [([f64; 2], [f64; 2], f64); 3],
}

impl FootprintTest {
    /// Prepares triangle `t` projected on axes `u` and `v`; `orientation` is the sign of its projected area.
    fn new(t: &[[f64; 3]; 3], orientation: f64, u: usize, v: usize) -> Self {
        let edges = [0, 1, 2].map(|k| {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let dir = [(b[u] - a[u]) * orientation, (b[v] - a[v]) * orientation];
            // The edge function's drop from a square's centre to its worst corner, plus a margin.
            let reach = 0.5 * (dir[0].abs() + dir[1].abs());
            ([a[u], a[v]], dir, reach * (1.0 + 1e-9) + 1e-9)
        });
        Self { edges }
    }

    /// Where the square [iu, iu + 1] × [iv, iv + 1] lies: strictly inside, strictly outside one edge (then
    /// that edge's direction × the dominant axis separates the triangle from every cell above the square),
    /// or across an edge, each with the margin.
    fn place(&self, iu: u32, iv: u32) -> Test {
        let (cu, cv) = (f64::from(iu) + 0.5, f64::from(iv) + 0.5);
        let mut inside = true;
        for &(a, dir, reach) in &self.edges {
            let e = dir[0] * (cv - a[1]) - dir[1] * (cu - a[0]);
            if e < -reach {
                return Test::Outside;
            }
            inside &= e > reach;
        }
        if inside { Test::Plane } else { Test::Full }
    }
}

/// The cell holding coordinate `v` along an axis of `cells` cells (clamped to the grid).
#[inline]
fn cell_of(v: f64, cells: u32) -> u32 {
    // Clamped first, so truncation is the floor (and avoids a libm call).
    v.clamp(0.0, f64::from(cells) - 1.0) as u32
}

/// The last cell that the extent [`from`, `to`] along an axis of `cells` cells reaches with positive length:
/// the cell of `to`, or the one before when `to` is a whole number (a cell boundary) above `from` (clamped to
/// the grid). `to` is clamped to [0, `cells`] before its floor is taken, and only a `to` in that range can
/// equal its floor.
#[inline]
fn last_cell_of(from: f64, to: f64, cells: u32) -> u32 {
    let floor = to.max(0.0).min(f64::from(cells)) as u32;
    let boundary = to > from && floor > 0 && f64::from(floor) == to;
    (floor - u32::from(boundary)).min(cells - 1)
}

/// Up to this many candidate columns, a triangle's footprints are not placed against its projection. (The FlightHelmet
/// at R=128, whose triangles mostly span 2–9 columns, builds its shell in 9.5–9.7 ms warm with a limit of 2, 4 or 6,
/// where a limit of 9 took 10.7; the corpus's other models and the big scenes measured the same either way.)
const FEW_COLUMNS: u32 = 4;

/// Hands each cell that triangle `tri` overlaps to `out`, with how many cells the triangle may overlap (cells
/// half-open along every axis, so a triangle on a cell boundary lands in one cell, not two; a triangle whose extent
/// along an axis ends exactly on a cell boundary does not reach the next cell, which it would only touch along an
/// edge or at a point, so a face lying on cell boundaries gets the same cells however its coordinates were rounded
/// before the grid snapped them).
fn overlaps(spec: &GridSpec, tris: &GridTriangles, tri: usize, out: &mut impl FnMut(u32, Reach)) {
    let t = tris.get(tri);
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    if n.length_squared() <= 0.0 || n.is_nan() {
        return; // zero-area triangles add no surface
    }
    let (lo, hi) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
    let [nx, ny, nz] = spec.dims;
    // The cells of the triangle's extent.
    let first = [cell_of(lo.x, nx), cell_of(lo.y, ny), cell_of(lo.z, nz)];
    let last = [last_cell_of(lo.x, hi.x, nx), last_cell_of(lo.y, hi.y, ny), last_cell_of(lo.z, hi.z, nz)];
    let crossed = (last[0] - first[0]) + (last[1] - first[1]) + (last[2] - first[2]);
    let mut push = |c: [u32; 3], reach| out(spec.index(c[0], c[1], c[2]) as u32, reach);
    if crossed == 0 {
        // The whole triangle sits in one cell: it overlaps that cell and no other.
        push(first, Reach::Few);
        return;
    }
    let inside = lo.cmpge(DVec3::ZERO).all() && hi.cmple(DVec3::new(f64::from(nx), f64::from(ny), f64::from(nz))).all();
    if crossed == 1 && inside {
        // The triangle crosses one cell boundary, strictly (it has points on both sides of it), and lies in one
        // cell along the other axes (in the grid, not clamped onto its edge): it overlaps the cells on both sides.
        push(first, Reach::Few);
        push(last, Reach::Few);
        return;
    }
    let mut push = |c| push(c, Reach::Many);
    let d = dominant_axis(n);
    if inside && in_one_layer(first[d], last[d], hi[d], spec.dims[d]) {
        overlaps_in_layer(&t, d, [first, last], &mut push);
        return;
    }
    overlaps_across(spec, &t, n, [lo.to_array(), hi.to_array()], [first, last], &mut push);
}

/// How many cells a triangle of [`overlaps`] may overlap.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Reach {
    /// One or two: the next triangle mostly overlaps them too.
    Few,
    /// More (the triangle takes the whole test).
    Many,
}

/// Whether a triangle inside the grid whose extent along its dominant axis ends at `hi` (in cells `first` to
/// `last` of `cells`) lies in one layer of cells for [`overlaps_in_layer`]: one cell along the axis, short of the
/// layer's upper face or in the grid's top layer. (A triangle whose extent ends on a lower layer's upper face,
/// touching it, takes the whole test: there the column test puts a column that meets the triangle only on that
/// face in the layer above; the top layer has none above it.)
fn in_one_layer(first: u32, last: u32, hi: f64, cells: u32) -> bool {
    first == last && (hi < f64::from(first + 1) || first + 1 == cells)
}

/// [`overlaps`] of a triangle `t` inside the grid that lies in one layer of cells across its dominant axis `d`
/// ([`in_one_layer`]; cells `first` to `last`): the cell above a square of the plane across `d` overlaps the
/// triangle exactly when the triangle's projection on that plane meets the square (closed sets; the layer holds
/// the triangle's whole extent along `d`). Every square of the extent meets the projection's bounding box, so the
/// test is the projection's three edge normals. Grid coordinates have few enough significant bits that these
/// products and sums are exact, as in the whole test.
fn overlaps_in_layer(t: &GridTriangle, d: usize, [first, last]: [[u32; 3]; 2], push: &mut impl FnMut([u32; 3])) {
    let (u, v) = ((d + 1) % 3, (d + 2) % 3);
    let p = [t[0], t[1], t[2]].map(|w| [w[u], w[v]]);
    // Per edge: its normal in the plane, the range of the corners projected on it, and half the extent of a
    // unit square's projection.
    let edges = [0, 1, 2].map(|k| {
        let (a, b) = (p[k], p[(k + 1) % 3]);
        let m = [a[1] - b[1], b[0] - a[0]];
        let [p0, p1, p2] = p.map(|q| m[0] * q[0] + m[1] * q[1]);
        (m, p0.min(p1).min(p2), p0.max(p1).max(p2), 0.5 * (m[0].abs() + m[1].abs()))
    });
    for iu in first[u]..=last[u] {
        for iv in first[v]..=last[v] {
            let c = [f64::from(iu) + 0.5, f64::from(iv) + 0.5];
            let meets = edges.iter().all(|&(m, lo, hi, reach)| {
                let at = m[0] * c[0] + m[1] * c[1];
                lo <= at + reach && hi >= at - reach
            });
            if meets {
                let mut cell = [0; 3];
                (cell[u], cell[v], cell[d]) = (iu, iv, first[d]);
                push(cell);
            }
        }
    }
}

/// [`overlaps`] of a triangle `t` with normal `n` whose extent `lo`, `hi` spans the cells `first` to `last`
/// (across more than one cell boundary, or clamped onto the grid's edge): each candidate cell is tested, a
/// column along the dominant axis at a time.
#[inline(never)]
fn overlaps_across(
    spec: &GridSpec,
    t: &GridTriangle,
    n: DVec3,
    [lo, hi]: [[f64; 3]; 2],
    [first, last]: [[u32; 3]; 2],
    push: &mut impl FnMut([u32; 3]),
) {
    let corners = t.map(|w| w.to_array());
    let cell_of = |a: usize, v: f64| cell_of(v, spec.dims[a]);
    let last_cell_of = |a: usize, from: f64, to: f64| last_cell_of(from, to, spec.dims[a]);
    let d = dominant_axis(n);
    let (u, v) = ((d + 1) % 3, (d + 2) % 3);
    let n = n.to_array();
    // Placing the footprints pays for itself only where some lie well inside or outside the projection; a
    // triangle spanning a few columns gets the whole test everywhere (the same cells: the placement only
    // skips tests whose outcome it knows).
    let columns = (last[u] - first[u] + 1) * (last[v] - first[v] + 1);
    let inside = (columns > FEW_COLUMNS).then(|| FootprintTest::new(&corners, n[d].signum(), u, v));
    let tester = CellTester::new(t, d, lo, hi);
    let t0 = corners[0];
    for iu in first[u]..=last[u] {
        // The footprint's extent along u and v (clipped to the triangle's), and the plane's terms there.
        let us = [f64::from(iu).max(lo[u]), f64::from(iu + 1).min(hi[u])];
        let u_terms = us.map(|cu| n[u] * (cu - t0[u]));
        let Some(row) = tester.row(f64::from(iu) + 0.5) else { continue };
        for iv in first[v]..=last[v] {
            let test = inside.as_ref().map_or(Test::Full, |inside| inside.place(iu, iv));
            if test == Test::Outside {
                continue;
            }
            // Extent of the plane along the dominant axis over this cell's footprint.
            let vs = [f64::from(iv).max(lo[v]), f64::from(iv + 1).min(hi[v])];
            let mut dlo = f64::INFINITY;
            let mut dhi = f64::NEG_INFINITY;
            for u_term in u_terms {
                for cv in vs {
                    // n · (p − t0) = 0 solved for the dominant coordinate.
                    let pd = t0[d] - (u_term + n[v] * (cv - t0[v])) / n[d];
                    dlo = dlo.min(pd);
                    dhi = dhi.max(pd);
                }
            }
            let (dlo, dhi) = (dlo.max(lo[d]), dhi.min(hi[d]));
            let ids = cell_of(d, dlo)..=last_cell_of(d, dlo, dhi);
            if ids.is_empty() {
                continue;
            }
            let Some(column) = tester.column(&row, f64::from(iv) + 0.5, test == Test::Full) else { continue };
            for id in ids {
                if column.overlaps(f64::from(id) + 0.5) {
                    let mut c = [0u32; 3];
                    (c[u], c[v], c[d]) = (iu, iv, id);
                    push(c);
                }
            }
        }
    }
}

/// Computes the shell of `tris` (deterministic whatever the thread count). Once `progress` is cancelled the
/// remaining triangles are passed over: the shell is then incomplete, and the caller's next stage ends the run.
// Out of line (called once per voxelization) so that an instruction profile can split the passes at it:
// `valgrind --tool=callgrind --dump-before=voxel_core::shell::shell --dump-after=voxel_core::shell::shell`.
#[inline(never)]
pub(crate) fn shell(spec: &GridSpec, tris: &GridTriangles, progress: &Progress) -> Shell {
    // Each task's runs go to lists by the top bits of their cell (a slab of the grid each), so that the slabs
    // sort side by side, each into its own stretch of the output.
    let bits = radix::bits_for(spec.cell_count());
    let shift = bits.saturating_sub(SLAB_BITS).max(SLAB_CELL_BITS).min(bits);
    let slab_count = 1 << (bits - shift);
    // Each task runs its own loop over a stretch of triangles (split as rayon's `fold` would: a few a thread, more
    // where one thread waits for another) rather than `fold` itself, whose accumulator passes through memory at every
    // triangle: the current run's fields then stay in registers (the height field's 2 M triangles at R=128: 26 ms
    // against 43 on a 2-core VM).
    let code = RunCode::new(tris.len());
    let stretches = rayon::iter::split(0..tris.len(), |all| match all.len() {
        0 | 1 => (all, None),
        len => (all.start..all.start + len / 2, Some(all.start + len / 2..all.end)),
    });
    let mut lists: Vec<Vec<Segments<u64>>> = stretches
        .map(|stretch| {
            let mut runs = TaskRuns::new(slab_count, shift, code);
            for tri in stretch {
                if progress.is_cancelled() {
                    break;
                }
                overlaps(spec, tris, tri, &mut |cell, reach| match reach {
                    Reach::Few => runs.push(cell, tri as u32),
                    Reach::Many => runs.push_alone(cell, tri as u32),
                });
            }
            runs.finish()
        })
        .collect();
    // Per slab, the tasks' lists in the tasks' order: a cell's runs keep the triangles' order, so sorting by cell
    // alone orders them by (cell, triangle), and the sorted runs are the compressed rows' already.
    let slabs: Vec<Vec<Vec<u64>>> = (0..slab_count)
        .map(|slab| Segments::concat(lists.iter_mut().map(|task| std::mem::take(&mut task[slab])).collect()))
        .collect();
    let (cells, runs) = sorted_by_cell(slabs, shift);
    let (cells, offsets) = compressed(cells);
    Shell { cells, offsets, runs, code }
}

/// The compressed rows of ascending `cells`: each group of equal cells becomes one cell, in place, and the
/// position where each group starts, with the length last.
fn compressed(mut cells: Vec<u32>) -> (Vec<u32>, Vec<u32>) {
    let len = cells.len();
    // Room for the most offsets there can be, zeroed by the allocator (a long list gets fresh pages from the system,
    // untouched until written), where a growing list would copy itself into new ones.
    let mut offsets = vec![0u32; len + 1];
    let Some(&first) = cells.first() else { return (cells, vec![0]) };
    // Without a branch on whether a cell starts a group (cells change every few positions, unpredictably): every
    // position is written to the next slot, which only a new group's first position keeps.
    let (mut count, mut last) = (1, first);
    for k in 1..len {
        let cell = cells[k];
        (cells[count], offsets[count]) = (cell, k as u32);
        count += usize::from(cell != last);
        last = cell;
    }
    offsets[count] = len as u32;
    offsets.truncate(count + 1);
    cells.truncate(count);
    (cells, offsets)
}

/// The runs of `slabs` (slab `k` holding the runs whose cell shifted right by `shift` is `k`, each cell's in order
/// of triangles; packed by a [`RunCode`]), sorted by cell, split into their cells and their runs (the `u32` halves).
/// Consecutive slabs sort together until they hold enough runs to pay for a sort of their own, each sort on its own
/// thread into its own stretch of the lists (its first slab's first cell as key 0); its last pass writes each run's
/// halves to its position.
fn sorted_by_cell(slabs: Vec<Vec<Vec<u64>>>, shift: u32) -> (Vec<u32>, Vec<u32>) {
    let len = slabs.iter().flatten().map(Vec::len).sum();
    let (mut cells, mut runs) = (vec![0u32; len], vec![0u32; len]);
    let (mut cells_left, mut runs_left) = (cells.as_mut_slice(), runs.as_mut_slice());
    let mut sorts = Vec::new();
    let mut slabs = slabs.into_iter().enumerate();
    while let Some((first, parts)) = slabs.next() {
        let mut group = parts;
        let mut end = first + 1;
        while group.iter().map(Vec::len).sum::<usize>() < RUNS_PER_SORT {
            let Some((_, parts)) = slabs.next() else { break };
            group.extend(parts);
            end += 1;
        }
        let n = group.iter().map(Vec::len).sum();
        let (group_cells, rest) = std::mem::take(&mut cells_left).split_at_mut(n);
        cells_left = rest;
        let (group_runs, rest) = std::mem::take(&mut runs_left).split_at_mut(n);
        runs_left = rest;
        let (base, span) = ((first as u64) << shift, ((end - first) as u64) << shift);
        sorts.push((group, base, span, group_cells, group_runs));
    }
    sorts.into_par_iter().for_each(|(parts, base, span, cells, runs)| {
        radix::sort_parts_into(
            parts,
            radix::bits_for(span as usize),
            |&run| (u64::from(RunCode::cell(run)) - base) as u32,
            |at, run| (cells[at], runs[at]) = (RunCode::cell(run), run as u32),
        );
    });
    (cells, runs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::BoxTester;
    use crate::grid::GridSize;
    use crate::shapes::{torus, uv_sphere};
    use crate::soup::TriangleSoup;

    #[test]
    fn compressed_rows_keep_each_cell_once_with_where_its_group_starts() {
        let mut random = crate::lcg::Lcg::new(5);
        for len in [0, 1, 2, 7, 1000] {
            for repeats in [1, 3, 50] {
                let mut cells: Vec<u32> = (0..len).map(|_| random.below(len as u64 / repeats + 1) as u32).collect();
                cells.sort_unstable();
                let mut expected = (Vec::new(), Vec::new());
                for (k, &c) in cells.iter().enumerate() {
                    if expected.0.last() != Some(&c) {
                        expected.0.push(c);
                        expected.1.push(k as u32);
                    }
                }
                expected.1.push(len as u32);
                assert_eq!(compressed(cells), expected, "{len} cells, about {repeats} each");
            }
        }
    }

    #[test]
    fn squares_inside_the_projection_need_only_the_plane_test_and_squares_outside_none() {
        let mut random = crate::lcg::Lcg::new(7);
        let mut next = |scale: f64| random.unit(scale);
        let (mut inside_cells, mut outside_cells) = (0, 0);
        for _ in 0..200 {
            let t: GridTriangle = std::array::from_fn(|_| DVec3::new(next(12.0), next(12.0), next(12.0)));
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            let d = dominant_axis(n);
            let (u, v) = ((d + 1) % 3, (d + 2) % 3);
            let corners = t.map(|w| w.to_array());
            let (tester, inside) = (BoxTester::new(&t), FootprintTest::new(&corners, n[d].signum(), u, v));
            for (iu, iv, id) in (0..12).flat_map(|a| (0..12).flat_map(move |b| (0..12).map(move |c| (a, b, c)))) {
                let mut c = DVec3::ZERO;
                (c[u], c[v], c[d]) = (f64::from(iu) + 0.5, f64::from(iv) + 0.5, f64::from(id) + 0.5);
                let half = DVec3::splat(0.5);
                match inside.place(iu, iv) {
                    Test::Plane => {
                        inside_cells += 1;
                        assert_eq!(tester.overlaps(c, half), tester.overlaps_plane(c, half), "{t:?} at {c}");
                    }
                    Test::Outside => {
                        outside_cells += 1;
                        assert!(!tester.overlaps(c, half), "{t:?} at {c}");
                    }
                    _ => {}
                }
            }
        }
        assert!(inside_cells > 10_000 && outside_cells > 10_000, "{inside_cells} inside, {outside_cells} outside");
    }

    #[test]
    fn a_triangle_across_one_boundary_or_in_one_layer_gets_the_cells_the_whole_test_gives() {
        // Triangles of up to five cells at coordinates snapped to 1/8 of a cell (so that many corners and edges
        // lie on cell boundaries, the ties), in an 8³ grid.
        let soup = TriangleSoup::from_mesh(&crate::shapes::cuboid([0.0; 3], [1.0; 3]), [1.0; 4]);
        let spec = GridSpec::fit(&soup, 9.0, GridSize::Resolution(8), 1.0, 1 << 20).unwrap();
        assert_eq!(spec.dims, [8, 8, 8]);
        let mut random = crate::lcg::Lcg::new(3);
        let mut next = |n: u64| random.below(n);
        let (mut across_one, mut in_layer, mut in_top_layer) = (0, 0, 0);
        for _ in 0..100_000 {
            let base = [0; 3].map(|_| next(7 * 8) as f64 / 8.0);
            let reach = [10, 10, 20, 40][next(4) as usize];
            let t: GridTriangle =
                std::array::from_fn(|_| DVec3::from(base.map(|b| b + next(reach) as f64 / 8.0)).min(DVec3::splat(8.0)));
            let tris = GridTriangles::from_triangles(&[t]);
            let mut fast = Vec::new();
            overlaps(&spec, &tris, 0, &mut |cell, _| fast.push(cell));
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            if n.length_squared() == 0.0 {
                assert!(fast.is_empty());
                continue;
            }
            let (lo, hi) = (t[0].min(t[1]).min(t[2]).to_array(), t[0].max(t[1]).max(t[2]).to_array());
            let first = [0, 1, 2].map(|a| cell_of(lo[a], 8));
            let last = [0, 1, 2].map(|a| last_cell_of(lo[a], hi[a], 8));
            let d = dominant_axis(n);
            match (0..3).map(|a| last[a] - first[a]).sum::<u32>() {
                0 => continue,
                1 => across_one += 1,
                _ if in_one_layer(first[d], last[d], hi[d], 8) => {
                    in_layer += 1;
                    in_top_layer += usize::from(hi[d] == 8.0);
                }
                _ => continue,
            }
            let mut whole = Vec::new();
            overlaps_across(&spec, &t, n, [lo, hi], [first, last], &mut |c| {
                whole.push(spec.index(c[0], c[1], c[2]) as u32)
            });
            whole.sort_unstable();
            fast.sort_unstable();
            assert_eq!(fast, whole, "{t:?}");
        }
        assert!(across_one > 5_000 && in_layer > 5_000, "{across_one} across one boundary, {in_layer} in a layer");
        assert!(in_top_layer > 500, "{in_top_layer} on the grid's upper face");
    }

    #[test]
    fn extents_ending_on_a_boundary_stop_before_it() {
        assert_eq!([cell_of(-2.0, 10), cell_of(3.7, 10), cell_of(10.0, 10), cell_of(f64::NAN, 10)], [0, 3, 9, 0]);
        let cases = [
            ((0.2, 3.0), 2),      // ends on the boundary of cell 3: does not reach it
            ((0.2, 3.5), 3),      // ends inside cell 3
            ((3.0, 3.0), 3),      // a point on the boundary: the cell above it
            ((-5.0, 0.0), 0),     // ends on the grid's lower face
            ((0.5, 10.0), 9),     // ends on the grid's upper face
            ((0.5, 12.0), 9),     // beyond the grid
            ((-9.0, -3.0), 0),    // wholly below it
            ((0.0, f64::NAN), 0), // no extent
            ((0.0, 1e300), 9),    // whole, far beyond the grid
            ((0.0, f64::INFINITY), 9),
        ];
        for ((from, to), last) in cases {
            assert_eq!(last_cell_of(from, to, 10), last, "[{from}, {to}]");
        }
    }

    /// Each shell cell's triangles as the overlaps of every triangle give them: cells ascending, each cell's
    /// triangles ascending.
    fn listed_by_cell(spec: &GridSpec, tris: &GridTriangles) -> Vec<(u32, Vec<u32>)> {
        let mut pairs = Vec::new();
        for tri in 0..tris.len() {
            overlaps(spec, tris, tri, &mut |cell, _| pairs.push((cell, tri as u32)));
        }
        pairs.sort_unstable();
        let mut listed: Vec<(u32, Vec<u32>)> = Vec::new();
        for (cell, tri) in pairs {
            match listed.last_mut() {
                Some((last, tris)) if *last == cell => tris.push(tri),
                _ => listed.push((cell, vec![tri])),
            }
        }
        listed
    }

    #[test]
    fn runs_list_every_cells_triangles_in_order() {
        // A fine sphere (many triangles a cell: long runs), a coarse torus (a few cells a triangle: runs broken
        // and resumed as triangles step between neighbouring cells) and a box of a few big triangles, together.
        let mut soup = TriangleSoup::from_mesh(&uv_sphere(1.0, 160), [1.0; 4]);
        soup.add_mesh(&torus(1.6, 0.4, 24), [1.0; 4], "torus");
        soup.add_mesh(&crate::shapes::cuboid([-2.2; 3], [-1.2; 3]), [1.0; 4], "box");
        for resolution in [12, 40] {
            let spec = GridSpec::fit(&soup, 9.0, GridSize::Resolution(resolution), 1.0, 1 << 26).unwrap();
            let tris = spec.grid_triangles(&soup);
            let shell = shell(&spec, &tris, &Progress::new());
            let got: Vec<(u32, Vec<u32>)> =
                (0..shell.cells.len()).map(|k| (shell.cells[k], shell.triangles_at(k).collect())).collect();
            let expected = listed_by_cell(&spec, &tris);
            let overlaps: usize = expected.iter().map(|(_, tris)| tris.len()).sum();
            assert_eq!(got, expected, "R={resolution}");
            assert!(
                shell.runs.len() * 3 < overlaps,
                "R={resolution}: {} runs of {overlaps} overlaps",
                shell.runs.len()
            );
        }
    }

    #[test]
    fn a_run_as_long_as_its_code_allows_is_closed_and_a_new_one_begins() {
        // A code with one bit for the count (runs of at most two triangles), and one with none (runs of one).
        let codes = [RunCode { triangle_bits: 31, longest: 2 }, RunCode::new(u32::MAX as usize)];
        assert_eq!(codes[1].longest, 1);
        for code in codes {
            let mut runs = TaskRuns::new(4, 8, code);
            // Cell 5 for triangles 0..7 but 4; cell 300 (another slab) for 2..5; cell 6 for 3, 5 and 6.
            let mut pairs = Vec::new();
            for tri in 0..7 {
                for cell in [5, 300, 6] {
                    let overlaps = match cell {
                        5 => tri != 4,
                        300 => (2..5).contains(&tri),
                        _ => [3, 5, 6].contains(&tri),
                    };
                    if overlaps {
                        // Triangle 5 is one of many cells: its overlaps are runs of their own.
                        if tri == 5 {
                            runs.push_alone(cell, tri)
                        } else {
                            runs.push(cell, tri)
                        }
                        pairs.push((cell, tri));
                    }
                }
            }
            let slabs = runs.finish();
            let mut listed: Vec<(u32, u32)> = Vec::new();
            for run in slabs.into_iter().flat_map(|slab| Segments::concat(vec![slab])).flatten() {
                let [first, count] = code.triangles(run as u32);
                assert!(count <= code.longest, "{count}");
                listed.extend((first..first + count).map(|tri| (RunCode::cell(run), tri)));
            }
            // Stable by cell: each cell's triangles stay ascending.
            listed.sort_by_key(|&(cell, _)| cell);
            pairs.sort_unstable();
            assert_eq!(listed, pairs);
        }
        let code = RunCode::new(1_000);
        let run = [u32::MAX - 1, 999, 1 << RUN_BITS];
        assert_eq!(code.longest, 1 << RUN_BITS);
        assert_eq!(
            (RunCode::cell(code.pack(run)), code.triangles(code.pack(run) as u32)),
            (u32::MAX - 1, [999, 1 << RUN_BITS])
        );
    }

    #[test]
    fn thin_cells_are_the_empty_cells_with_a_triangle_whose_normal_neighbours_are_empty() {
        let soup = TriangleSoup::from_mesh(&torus(2.0, 0.7, 20), [1.0; 4]);
        let spec = GridSpec::fit(&soup, 9.0, GridSize::Resolution(16), 1.0, 1 << 26).unwrap();
        let tris = spec.grid_triangles(&soup);
        let shell = shell(&spec, &tris, &Progress::new());
        // A scattered fill: about one cell in three, the grid's faces included.
        let mut fill = BitGrid::new(spec.cell_count());
        (0..spec.cell_count()).filter(|i| (i * 2654435761) % 97 < 32).for_each(|i| fill.set(i));
        let empty = |index: Option<usize>| index.is_none_or(|i| !fill.get(i));
        let expected: Vec<u32> = (0..shell.cells.len())
            .filter(|&k| {
                let index = shell.cells[k] as usize;
                let t = |tri: u32| tris.get(tri as usize);
                let sides = |tri| {
                    let step = normal_step((t(tri)[1] - t(tri)[0]).cross(t(tri)[2] - t(tri)[0]));
                    [step, step.map(|s| -s)].map(|s| spec.offset(index, s))
                };
                !fill.get(index) && shell.triangles_at(k).any(|tri| sides(tri).into_iter().all(empty))
            })
            .map(|k| shell.cells[k])
            .collect();
        let empty_cells = shell.cells.iter().filter(|&&c| !fill.get(c as usize)).count();
        assert!(expected.len() > 20 && expected.len() + 20 < empty_cells, "{} of {empty_cells}", expected.len());
        assert_eq!(shell.thin_cells(&spec, &tris, &fill), expected);
    }

    #[test]
    fn normal_steps_pick_dominant_components() {
        assert_eq!(normal_step(DVec3::new(0.0, 2.0, 0.1)), [0, 1, 0]);
        assert_eq!(normal_step(DVec3::new(-1.0, 1.0, 0.2)), [-1, 1, 0]);
        assert_eq!(normal_step(DVec3::new(1.0, -1.0, 0.9)), [1, -1, 1]);
    }
}
