//! The nearest shell cell to any cell of the grid: an implicit octree over the shell cells (level k marks the
//! blocks of 2ᵏ × 2ᵏ × 2ᵏ cells holding a shell cell) walked nearest block first, pruning blocks farther than the
//! best cell so far. Built in time linear in the shell, so a lookup far from the surface costs a walk down the
//! blocks near it, never a scan of the grid; distances are between cell centres, in whole cells (exact).

use super::Shell;
use crate::grid::{BitGrid, GridSpec};

/// Cells of a level along x, y, z.
type Dims = [u32; 3];

/// The linear index of block `c` in a level of `dims` blocks (the grid's order: z fastest).
fn index(dims: Dims, c: [u32; 3]) -> usize {
    (c[0] as usize * dims[1] as usize + c[1] as usize) * dims[2] as usize + c[2] as usize
}

/// The squared distance between the centres of cells `a` and `b`, in cells.
#[inline]
fn distance2(a: [u32; 3], b: [u32; 3]) -> u64 {
    let d = [0, 1, 2].map(|k| u64::from(a[k].abs_diff(b[k])));
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
}

/// The octree of one shell.
pub(crate) struct ShellOctree {
    /// `levels[k]`: the blocks of 2ᵏ cells per side, and which of them hold a shell cell (level 0: the cells).
    levels: Vec<(Dims, BitGrid)>,
}

impl ShellOctree {
    /// Marks the shell's cells and every block above them, up to a single block.
    pub fn new(spec: &GridSpec, shell: &Shell) -> Self {
        let mut cells = BitGrid::new(spec.cell_count());
        for &c in &shell.cells {
            cells.set(c as usize);
        }
        let mut levels = vec![(spec.dims, cells)];
        loop {
            let (dims, below) = levels.last().expect("level 0 exists");
            if dims.iter().all(|&d| d == 1) {
                break;
            }
            let up = dims.map(|d| d.div_ceil(2));
            let mut blocks = BitGrid::new(up.iter().map(|&d| d as usize).product());
            let (ny, nz) = (dims[1] as usize, dims[2] as usize);
            for i in below.ones() {
                let c = [i / nz / ny, i / nz % ny, i % nz].map(|v| v as u32 / 2);
                blocks.set(index(up, c));
            }
            levels.push((up, blocks));
        }
        Self { levels }
    }

    /// The squared distance from the centre of `cell` to the nearest cell centre in block `c` of level `level`
    /// (clipped to the grid).
    fn block_distance2(&self, cell: [u32; 3], level: usize, c: [u32; 3]) -> u64 {
        let grid = self.levels[0].0;
        let d = [0, 1, 2].map(|a| {
            let lo = c[a] << level;
            let hi = ((c[a] + 1) << level).min(grid[a]) - 1;
            u64::from(lo.saturating_sub(cell[a]).max(cell[a].saturating_sub(hi)))
        });
        d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    }

    /// The linear index of the shell cell whose centre is nearest to `cell`'s (ties: the lower index), or
    /// `None` for an empty shell. `guess`, a shell cell likely near `cell`, only speeds the search up.
    pub fn nearest(&self, spec: &GridSpec, cell: [u32; 3], guess: Option<u32>) -> Option<u32> {
        let top = self.levels.len() - 1;
        if !self.levels[top].1.get(0) {
            return None;
        }
        let dims = self.levels[0].0;
        let mut best = guess.map(|g| (distance2(cell, spec.coords(g as usize)), g));
        // A block whose nearest centre is farther than the best, or as far but with no lower index (its first
        // cell's), holds nothing better.
        let beaten = |best: Option<(u64, u32)>, d2: u64, first: [u32; 3]| {
            best.is_some_and(|b| d2 > b.0 || (d2 == b.0 && index(dims, first) as u32 > b.1))
        };
        if top == 0 {
            return Some(0); // a grid of one cell, a shell cell
        }
        let mut stack = vec![(top, [0u32; 3], 0)];
        while let Some((level, c, d2)) = stack.pop() {
            if beaten(best, d2, c.map(|v| v << level)) {
                continue;
            }
            let (below, blocks) = &self.levels[level - 1];
            let mut children = [(0, [0u32; 3], 0); 8];
            let mut n = 0;
            for k in 0..8u32 {
                let child = [0, 1, 2].map(|a| c[a] * 2 + (k >> a & 1));
                if !((0..3).all(|a| child[a] < below[a]) && blocks.get(index(*below, child))) {
                    continue;
                }
                if level == 1 {
                    // The children are cells: measured at once.
                    let found = (distance2(cell, child), index(dims, child) as u32);
                    if best.is_none_or(|b| found < b) {
                        best = Some(found);
                    }
                } else {
                    children[n] = (level - 1, child, self.block_distance2(cell, level - 1, child));
                    n += 1;
                }
            }
            // Nearest last, so that it is searched first.
            children[..n].sort_unstable_by_key(|c| std::cmp::Reverse(c.2));
            stack.extend_from_slice(&children[..n]);
        }
        best.map(|(_, i)| i)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::GridSize;
    use crate::shapes::{torus, uv_sphere};
    use crate::soup::TriangleSoup;

    #[test]
    fn nearest_matches_brute_force_with_ties_to_the_lower_index() {
        let mut soup = TriangleSoup::from_mesh(&torus(2.0, 0.5, 24), [1.0; 4]);
        soup.add_mesh(&crate::shapes::cuboid([2.5, 2.5, -0.5], [3.0, 3.0, 0.5]), [1.0; 4], "box");
        let spec = GridSpec::fit(&soup, 9.0, GridSize::Resolution(24), 1.0, 1 << 26).unwrap();
        let tris = spec.grid_triangles(&soup);
        let shell = super::super::shell(&spec, &tris, &crate::progress::Progress::new());
        let octree = ShellOctree::new(&spec, &shell);
        let mut tied = 0;
        for i in (0..spec.cell_count() as u32).step_by(7) {
            let cell = spec.coords(i as usize);
            let by_distance = |s: u32| (distance2(cell, spec.coords(s as usize)), s);
            let nearest = shell.cells.iter().map(|&s| by_distance(s)).min().expect("a shell");
            let brute = Some(nearest.1);
            tied += usize::from(shell.cells.iter().filter(|&&s| by_distance(s).0 == nearest.0).count() > 1);
            assert_eq!(octree.nearest(&spec, cell, None), brute, "{cell:?}");
            // Any guess gives the same cell: the first shell cell, or the nearest itself.
            assert_eq!(octree.nearest(&spec, cell, Some(shell.cells[0])), brute, "{cell:?} from the first");
            assert_eq!(octree.nearest(&spec, cell, brute), brute, "{cell:?} from itself");
        }
        assert!(tied > 100, "{tied} cells with tied nearest shell cells");
    }

    #[test]
    fn an_empty_shell_has_no_nearest_cell() {
        let soup = TriangleSoup::from_mesh(&uv_sphere(1.0, 4), [1.0; 4]);
        let spec = GridSpec::fit(&soup, 9.0, GridSize::Resolution(4), 1.0, 1 << 26).unwrap();
        assert_eq!(ShellOctree::new(&spec, &Shell::default()).nearest(&spec, [1, 2, 3], None), None);
    }
}
