//! The conservative surface shell: every cell a triangle overlaps, with the triangles overlapping each (for
//! colour), and which of its cells carry a piece of surface the solid fill does not account for.
//!
//! The shell does not depend on the fill, so the pipeline builds both side by side; only the thin cells
//! ([`Shell::thin_cells`]) are found afterwards, from the fill.

use glam::DVec3;
use rayon::prelude::*;

use crate::grid::{BitGrid, GridSpec, GridTriangles};
use crate::progress::Progress;
use crate::radix::{self, Segments};

mod cells;
pub(crate) mod distance;
pub(crate) mod octree;
mod overlaps;
mod runs;
use overlaps::{Reach, overlaps};
use runs::{RunCode, TaskRuns};

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

/// The runs below which consecutive slabs of [`shell`] sort together (fewer when a thread would be left without a
/// sort: [`sorted_by_cell`]).
const RUNS_PER_SORT: usize = 1 << 16;

/// Up to this many runs in all, [`sorted_by_cell`] sets aside every sort's first-pass room before the sorts start, on the
/// calling thread. Room for all the sorts at once holds 8 bytes a run more at the shell's peak than room taken by each
/// sort as it starts, two at a time on two threads (the FlightHelmet's peak RSS at R=2048 1.43 GB with room for all,
/// 1.27 GB without; at R=1024 325 and 296 MB). Below, at most 8 MB of room.
const ROOM_AHEAD_RUNS: usize = 1 << 20;

/// Stretches of triangles a thread in [`shell`]: equal counts of triangles, several a thread, so that a thread whose
/// stretches hold the larger triangles leaves some to the other. (Split as rayon splits work, the milk truck's first
/// half of its triangles, the body's larger ones, went to one thread in two stretches of 0.54 and 0.71 ms while the
/// other ran the second half in 0.6 ms; in 16 stretches its shell at R=128 takes 1.45 ms rather than 1.67, warm.)
const STRETCHES_PER_THREAD: usize = 8;

/// Shell cells per task of [`Shell::thin_cells`] (a few bit reads each: small tasks cost more than they save).
const THIN_CHUNK: usize = 4096;

/// The step to the face, edge or corner neighbour along a normal: components within half of the largest
/// one count.
fn normal_step(n: DVec3) -> [i32; 3] {
    let m = n.abs().max_element();
    [n.x, n.y, n.z].map(|c| if c.abs() >= 0.5 * m { c.signum() as i32 } else { 0 })
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
    // Each task runs its own loop over a stretch of triangles ([`STRETCHES_PER_THREAD`] equal ones a thread) rather
    // than `fold`, whose accumulator passes through memory at every triangle: the current run's fields then stay in
    // registers (the height field's 2 M triangles at R=128: 26 ms against 43 on a 2-core VM).
    let code = RunCode::new(tris.len());
    let count = (rayon::current_num_threads() * STRETCHES_PER_THREAD).min(tris.len()).max(1);
    let stretches =
        (0..count).into_par_iter().with_max_len(1).map(|k| k * tris.len() / count..(k + 1) * tris.len() / count);
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
    let (cells, offsets, runs) = sorted_by_cell(slabs, shift);
    Shell { cells, offsets, runs, code }
}

/// The compressed rows of ascending `cells` (the runs `base..` of the shell): each group of equal cells becomes one
/// cell, in place, with the position of the run where the group starts in `offsets` beside it. Returns the groups.
fn compress(cells: &mut [u32], offsets: &mut [u32], base: usize) -> usize {
    let Some(&first) = cells.first() else { return 0 };
    offsets[0] = base as u32;
    // Without a branch on whether a cell starts a group (cells change every few positions, unpredictably): every
    // position is written to the next slot, which only a new group's first position keeps.
    let (mut count, mut last) = (1, first);
    for k in 1..cells.len() {
        let cell = cells[k];
        (cells[count], offsets[count]) = (cell, (base + k) as u32);
        count += usize::from(cell != last);
        last = cell;
    }
    count
}

/// The runs of `slabs` (slab `k` holding the runs whose cell shifted right by `shift` is `k`, each cell's in order
/// of triangles; packed by a [`RunCode`]), sorted by cell, as compressed rows: the distinct cells ascending, where
/// each cell's runs start (with their count last), and the runs (the `u32` halves).
/// Consecutive slabs sort together until they hold enough runs to pay for a sort of their own, each sort on its own
/// thread into its own stretch of the lists (its first slab's first cell as key 0); its last pass writes each run's
/// halves to its position, and the same task compresses its stretch's rows (no cell spans two stretches), which
/// then close up.
fn sorted_by_cell(slabs: Vec<Vec<Vec<u64>>>, shift: u32) -> (Vec<u32>, Vec<u32>, Vec<u32>) {
    let len = slabs.iter().flatten().map(Vec::len).sum();
    // Room for the most offsets there can be, zeroed by the allocator (a long list gets fresh pages from the system,
    // untouched until written), where a growing list would copy itself into new ones.
    let (mut cells, mut offsets, mut runs) = (vec![0u32; len], vec![0u32; len + 1], vec![0u32; len]);
    // Enough runs for each thread to sort some, and no more than a sort pays for.
    let target = len.div_ceil(rayon::current_num_threads()).clamp(1, RUNS_PER_SORT);
    let (mut cells_left, mut offsets_left, mut runs_left) =
        (cells.as_mut_slice(), &mut offsets[..len], runs.as_mut_slice());
    let mut sorts = Vec::new();
    let mut slabs = slabs.into_iter().enumerate();
    let mut start = 0;
    while let Some((first, parts)) = slabs.next() {
        let count = |parts: &Vec<Vec<u64>>| parts.iter().map(Vec::len).sum::<usize>();
        let (mut n, mut group) = (count(&parts), parts);
        let mut end = first + 1;
        while n < target {
            let Some((_, parts)) = slabs.next() else { break };
            n += count(&parts);
            group.extend(parts);
            end += 1;
        }
        let (base, span) = ((first as u64) << shift, ((end - first) as u64) << shift);
        let lists = [&mut cells_left, &mut offsets_left, &mut runs_left].map(|rest| take_front(rest, n));
        // The sort's first pass goes to room from this thread's heap, which holds the pages a read freed, where the
        // other worker's own heap is fresh: a page fault a page (CesiumMan at R=128: 25,541 runs, 50 pages). A long
        // shell's sorts each take their room when they start ([`ROOM_AHEAD_RUNS`]).
        let room = if len <= ROOM_AHEAD_RUNS { Vec::with_capacity(n) } else { Vec::new() };
        sorts.push((group, base, span, start, lists, room));
        start += n;
    }
    let groups: Vec<(usize, usize)> = sorts
        .into_par_iter()
        .map(|(parts, base, span, start, [cells, offsets, runs], scratch)| {
            radix::sort_parts_into(
                parts,
                radix::bits_for(span as usize),
                |&run| (u64::from(RunCode::cell(run)) - base) as u32,
                |at, run| (cells[at], runs[at]) = (RunCode::cell(run), run as u32),
                scratch,
            );
            (start, compress(cells, offsets, start))
        })
        .collect();
    let mut count = 0;
    for (start, groups) in groups {
        cells.copy_within(start..start + groups, count);
        offsets.copy_within(start..start + groups, count);
        count += groups;
    }
    offsets[count] = len as u32;
    cells.truncate(count);
    offsets.truncate(count + 1);
    (cells, offsets, runs)
}

/// The first `n` items of `rest`, which keeps the others.
fn take_front<'a>(rest: &mut &'a mut [u32], n: usize) -> &'a mut [u32] {
    let (front, others) = std::mem::take(rest).split_at_mut(n);
    *rest = others;
    front
}

#[cfg(test)]
mod tests {
    use super::*;
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
                        expected.1.push(40 + k as u32);
                    }
                }
                let mut offsets = vec![0; len];
                let count = compress(&mut cells, &mut offsets, 40);
                assert_eq!(
                    (&cells[..count], &offsets[..count]),
                    (&expected.0[..], &expected.1[..]),
                    "{len}, {repeats}"
                );
            }
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
        // At R=64 the grid has four slabs, sorted and compressed in a stretch per thread, which then close up.
        for resolution in [12, 40, 64] {
            let spec = GridSpec::fit(&soup, 9.0, GridSize::Resolution(resolution), 1.0, 1 << 26).unwrap();
            let tris = spec.grid_triangles(&soup);
            let shell = shell(&spec, &tris, &Progress::new());
            let got: Vec<(u32, Vec<u32>)> =
                (0..shell.cells.len()).map(|k| (shell.cells[k], shell.triangles_at(k).collect())).collect();
            let expected = listed_by_cell(&spec, &tris);
            let overlaps: usize = expected.iter().map(|(_, tris)| tris.len()).sum();
            assert_eq!(got, expected, "R={resolution}");
            assert!(
                shell.runs.len() * 2 < overlaps,
                "R={resolution}: {} runs of {overlaps} overlaps",
                shell.runs.len()
            );
        }
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
