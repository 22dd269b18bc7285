//! The visible cells of a solid: filled cells with an empty face neighbour, found 64 cells of a column at a
//! time with word operations on the bit grid (the work is the grid's words, R³/64, plus the output), or, where the
//! caller lists the filled cells (a solid that is the shell alone), each listed cell's neighbours one by one.

use rayon::prelude::*;

use crate::grid::{AscendingCoords, BitGrid, GridSpec};

/// Columns handed to one task.
const COLUMNS_PER_TASK: usize = 256;

/// Solid cells with an empty face neighbour (the grid's outside counts as empty), ascending.
// Out of line (called once per voxelization) so that an instruction profile can split the passes after it
// (`valgrind --tool=callgrind --dump-after=voxel_core::visible::visible_cells`).
#[inline(never)]
pub(crate) fn visible_cells(spec: &GridSpec, solid: &BitGrid) -> Vec<u32> {
    let [nx, ny, nz] = spec.dims.map(|d| d as usize);
    let columns = nx * ny;
    // Calls `words` with each word of visible cells of a task's columns (the first cell's index, the word).
    let scan = |task: usize, words: &mut dyn FnMut(usize, u64)| {
        for col in task * COLUMNS_PER_TASK..((task + 1) * COLUMNS_PER_TASK).min(columns) {
            let (x, y) = (col / ny, col % ny);
            let side_open = x == 0 || y == 0 || x + 1 == nx || y + 1 == ny;
            column_visible(solid, col * nz, nz, side_open, [ny * nz, nz], words);
        }
    };
    // Counted first, then written in place: each task writes its cells once, into its own stretch of the output
    // (lists per task and their concatenation wrote every cell twice, into twice the pages: a fresh process pays
    // a fault for each).
    let tasks = columns.div_ceil(COLUMNS_PER_TASK);
    let counts: Vec<usize> = (0..tasks)
        .into_par_iter()
        .map(|t| {
            let mut count = 0;
            scan(t, &mut |_, word| count += word.count_ones() as usize);
            count
        })
        .collect();
    let mut visible = vec![0u32; counts.iter().sum()];
    let mut stretches = Vec::with_capacity(tasks);
    let mut rest = visible.as_mut_slice();
    for &count in &counts {
        let (stretch, tail) = std::mem::take(&mut rest).split_at_mut(count);
        stretches.push(stretch);
        rest = tail;
    }
    stretches.into_par_iter().enumerate().for_each(|(t, stretch)| {
        let mut next = 0;
        scan(t, &mut |at, mut word| {
            while word != 0 {
                stretch[next] = (at + word.trailing_zeros() as usize) as u32;
                next += 1;
                word &= word - 1;
            }
        });
    });
    visible
}

/// Listed cells handed to one task of [`visible_listed`].
const LISTED_PER_TASK: usize = 4096;

/// [`visible_cells`] of a solid whose filled cells the caller has listed (`cells`, ascending): each cell's six
/// neighbours looked up one bit at a time. A solid that is a surface alone fills a few per cent of its grid, whose
/// words the word scan reads all, twice (at R=128 with `--fill none`, one thread: the milk truck's 46,129 cells in a
/// grid of 644 k, 88.4 → 86.5 M instructions a voxelization; CesiumMan's 14,698, 45.8 → 45.4 M). Each task writes
/// its visible cells to the front of its own stretch of the output, as long as its stretch of `cells`, and the
/// stretches then close up in place: one allocation, its pages touched by the tasks, where lists collected per task
/// and then joined wrote each cell into two, fresh pages on both threads.
pub(crate) fn visible_listed(spec: &GridSpec, solid: &BitGrid, cells: &[u32]) -> Vec<u32> {
    let strides = spec.strides();
    let mut visible = vec![0u32; cells.len()];
    let counts: Vec<usize> = visible
        .par_chunks_mut(LISTED_PER_TASK)
        .zip(cells.par_chunks(LISTED_PER_TASK))
        .map(|(out, chunk)| {
            let mut coords = AscendingCoords::new(spec);
            let mut count = 0;
            for &i in chunk {
                let c = coords.of(i);
                let at = i as usize;
                let open = (0..3).any(|a| {
                    c[a] == 0 || c[a] + 1 == spec.dims[a] || !solid.get(at - strides[a]) || !solid.get(at + strides[a])
                });
                // Written whether or not the cell is visible; only a visible one is kept.
                out[count] = i;
                count += usize::from(open);
            }
            count
        })
        .collect();
    let mut len = 0;
    for (task, count) in counts.into_iter().enumerate() {
        let start = task * LISTED_PER_TASK;
        visible.copy_within(start..start + count, len);
        len += count;
    }
    visible.truncate(len);
    visible
}

/// Calls `words` with each non-empty word of visible cells of the column starting at cell `base` (`nz` cells; bit
/// k of a word starting at cell `at` is cell `at + k`); `strides` are the steps to the neighbouring columns along
/// x and y, which exist unless `side_open`.
fn column_visible(
    solid: &BitGrid,
    base: usize,
    nz: usize,
    side_open: bool,
    strides: [usize; 2],
    words: &mut dyn FnMut(usize, u64),
) {
    let mut z0 = 0;
    while z0 < nz {
        let n = (nz - z0).min(64);
        let at = base + z0;
        let filled = solid.bits(at, n);
        if filled != 0 {
            let exposed = if side_open {
                filled
            } else {
                // A neighbour outside the column (above its top, below its bottom) is empty: its bit stays 0.
                let above = solid.bits(at + 1, if z0 + n < nz { n } else { n - 1 });
                let below = if z0 > 0 { solid.bits(at - 1, n) } else { solid.bits(at, n - 1) << 1 };
                let sides =
                    strides.iter().fold(u64::MAX, |acc, &s| acc & solid.bits(at - s, n) & solid.bits(at + s, n));
                filled & !(above & below & sides)
            };
            if exposed != 0 {
                words(at, exposed);
            }
        }
        z0 += n;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The visible cells by checking every cell's six neighbours one by one.
    fn visible_by_brute_force(spec: &GridSpec, solid: &BitGrid) -> Vec<u32> {
        (0..spec.cell_count())
            .filter(|&i| solid.get(i))
            .filter(|&i| {
                [[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1]]
                    .into_iter()
                    .any(|step| spec.offset(i, step).is_none_or(|j| !solid.get(j)))
            })
            .map(|i| i as u32)
            .collect()
    }

    /// A grid of `dims` cells with a pseudo-random solid from `seed`: a cell is empty where the top `64 − shift` bits
    /// of its draw are zero (one cell in 2^(64 − shift)).
    fn random_solid(dims: [u32; 3], seed: u64, shift: u32) -> (GridSpec, BitGrid) {
        let spec = GridSpec::of_cells(dims);
        let mut solid = BitGrid::new(spec.cell_count());
        let mut random = crate::lcg::Lcg::new(seed);
        for i in 0..spec.cell_count() {
            if random.next_u64() >> shift != 0 {
                solid.set(i);
            }
        }
        (spec, solid)
    }

    #[test]
    fn word_parallel_visibility_matches_the_neighbour_check() {
        // Columns of 70 cells (two words each, not word-aligned), one cell in 16 empty.
        let (spec, solid) = random_solid([5, 3, 70], 12345, 60);
        assert_eq!(visible_cells(&spec, &solid), visible_by_brute_force(&spec, &solid));
        let full = {
            let mut b = BitGrid::new(spec.cell_count());
            b.set_range(0..spec.cell_count());
            b
        };
        let shell = visible_cells(&spec, &full);
        assert_eq!(shell, visible_by_brute_force(&spec, &full));
        assert_eq!(shell.len(), 5 * 3 * 70 - 3 * 68);
    }

    #[test]
    fn listed_cells_give_the_neighbour_checks_visible_cells_across_tasks() {
        // A pseudo-random solid in a 24 × 20 × 70 grid, one cell in 8 empty: about 29,400 listed cells, eight tasks,
        // each of which keeps some of its cells and drops others (the stretches close up).
        let (spec, solid) = random_solid([24, 20, 70], 777, 61);
        let listed: Vec<u32> = (0..spec.cell_count() as u32).filter(|&i| solid.get(i as usize)).collect();
        assert!(listed.len() > 7 * LISTED_PER_TASK, "{} listed", listed.len());
        let expected = visible_by_brute_force(&spec, &solid);
        assert!(expected.len() > listed.len() / 4 && expected.len() < listed.len() * 3 / 4, "{}", expected.len());
        assert_eq!(visible_listed(&spec, &solid, &listed), expected);
        assert_eq!(
            visible_listed(&spec, &solid, &listed[..100]),
            expected[..expected.partition_point(|&c| c < listed[100])]
        );
    }
}
