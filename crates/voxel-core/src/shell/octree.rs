//! The nearest shell triangle to any grid point: an implicit octree over the shell cells (level k marks the
//! blocks of 2ᵏ × 2ᵏ × 2ᵏ cells holding a shell cell) walked nearest block first, pruning blocks farther than the
//! best triangle so far. Built in time linear in the shell, so a colour lookup far from the surface costs a
//! walk down the blocks near it, never a scan of the grid or of every triangle. A cell's triangles are read in
//! groups behind a box each: where many triangles much smaller than a cell lie about as far from the point as
//! the nearest (a cell under a dome of them), most groups are pruned without reading their triangles.

use glam::DVec3;
use rayon::prelude::*;

use super::Shell;
use crate::geom::{GridTriangle, distance2, farther_than};
use crate::grid::{BitGrid, GridSpec};

/// Cells of a level along x, y, z.
type Dims = [u32; 3];

/// The linear index of block `c` in a level of `dims` blocks (the grid's order: z fastest).
fn index(dims: Dims, c: [u32; 3]) -> usize {
    (c[0] as usize * dims[1] as usize + c[1] as usize) * dims[2] as usize + c[2] as usize
}

/// Positions of the shell's triangle lists per group: the lists laid end to end are cut every `GROUP`.
const GROUP: usize = 8;

/// The bounds (min, max) of a group's triangles, rounded outwards to `f32`.
type GroupBox = [[f32; 3]; 2];

/// The box of triangles `group` of `tris`.
fn group_box(tris: &[GridTriangle], group: &[u32]) -> GroupBox {
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for &t in group {
        let t = &tris[t as usize];
        lo = lo.min(t[0].min(t[1]).min(t[2]));
        hi = hi.max(t[0].max(t[1]).max(t[2]));
    }
    let down = |v: f64| {
        let f = v as f32;
        if f64::from(f) > v { f.next_down() } else { f }
    };
    let up = |v: f64| {
        let f = v as f32;
        if f64::from(f) < v { f.next_up() } else { f }
    };
    [lo.to_array().map(down), hi.to_array().map(up)]
}

/// The squared distance from `p` to box `b`.
fn box_distance2(p: DVec3, b: &GroupBox) -> f64 {
    let [lo, hi] = b.map(|c| DVec3::from_array(c.map(f64::from)));
    (lo - p).max(p - hi).max(DVec3::ZERO).length_squared()
}

/// The octree of one shell.
pub(crate) struct ShellOctree<'a> {
    shell: &'a Shell,
    /// `levels[k]`: the blocks of 2ᵏ cells per side, and which of them hold a shell cell (level 0: the cells).
    levels: Vec<(Dims, BitGrid)>,
    /// The box of each group of the shell's triangle lists (3 bytes an overlap, within the memory estimate: the
    /// shell's packed pairs it counts are freed by then).
    groups: Vec<GroupBox>,
}

impl<'a> ShellOctree<'a> {
    /// Marks the shell's cells and every block above them, up to a single block, and bounds the groups of the
    /// shell's triangles, `tris`.
    pub fn new(spec: &GridSpec, shell: &'a Shell, tris: &[GridTriangle]) -> Self {
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
        let groups = shell.tris.par_chunks(GROUP).map(|group| group_box(tris, group)).collect();
        Self { shell, levels, groups }
    }

    /// The squared distance from `p` to block `c` of level `level` (clipped to the grid).
    fn block_distance2(&self, p: DVec3, level: usize, c: [u32; 3]) -> f64 {
        let side = f64::from(1u32 << level);
        let grid = self.levels[0].0;
        let lo = DVec3::from_array(c.map(|v| f64::from(v) * side));
        let hi = DVec3::from_array(std::array::from_fn(|a| (f64::from(c[a] + 1) * side).min(f64::from(grid[a]))));
        (lo - p).max(p - hi).max(DVec3::ZERO).length_squared()
    }

    /// The shell triangle nearest to grid point `p` (ties: lower index), or `None` for an empty shell. `guess`,
    /// a shell triangle likely near `p`, only speeds the search up (the nearest so far from the start).
    pub fn nearest(&self, tris: &[GridTriangle], p: DVec3, guess: Option<usize>) -> Option<usize> {
        let top = self.levels.len() - 1;
        if !self.levels[top].1.get(0) {
            return None;
        }
        let mut best = guess.map(|t| (t, distance2(p, &tris[t])));
        let mut stack = vec![(top, [0u32; 3], 0.0)];
        while let Some((level, c, d2)) = stack.pop() {
            if best.is_some_and(|(_, b)| d2 > b) {
                continue;
            }
            if level == 0 {
                // A triangle listed in a cell may reach beyond it, but the cell holding its closest point lists
                // it too, and that cell is no farther than the triangle: nothing nearer is pruned.
                let Ok(k) = self.shell.cells.binary_search(&(index(self.levels[0].0, c) as u32)) else { continue };
                let (mut at, end) = (self.shell.offsets[k] as usize, self.shell.offsets[k + 1] as usize);
                while at < end {
                    let stop = (at / GROUP + 1) * GROUP;
                    let group = at..stop.min(end);
                    at = stop;
                    // A group's box holds each of its triangles: beyond the best by more than rounding, it holds
                    // no nearer one.
                    let d2 = box_distance2(p, &self.groups[group.start / GROUP]);
                    if best.is_some_and(|(_, b)| d2 > b + 1e-9 * (1.0 + d2)) {
                        continue;
                    }
                    for &t in &self.shell.tris[group] {
                        let t = t as usize;
                        if best.is_some_and(|(bt, b)| bt == t || farther_than(&tris[t], p, b)) {
                            continue; // already measured from another cell, or too far to be the nearest
                        }
                        let d = distance2(p, &tris[t]);
                        if best.is_none_or(|(bt, b)| d < b || (d == b && t < bt)) {
                            best = Some((t, d));
                        }
                    }
                }
                continue;
            }
            let (dims, blocks) = &self.levels[level - 1];
            let mut children = [(0, [0u32; 3], 0.0); 8];
            let mut n = 0;
            for k in 0..8u32 {
                let child = [0, 1, 2].map(|a| c[a] * 2 + (k >> a & 1));
                if (0..3).all(|a| child[a] < dims[a]) && blocks.get(index(*dims, child)) {
                    children[n] = (level - 1, child, self.block_distance2(p, level - 1, child));
                    n += 1;
                }
            }
            // Nearest last, so that it is searched first.
            children[..n].sort_unstable_by(|a, b| b.2.total_cmp(&a.2));
            stack.extend_from_slice(&children[..n]);
        }
        best.map(|(t, _)| t)
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
        let ball = TriangleSoup::from_mesh(&uv_sphere(0.4, 8), [1.0; 4]);
        soup.add_mesh(&crate::shapes::cuboid([2.5, 2.5, -0.5], [3.0, 3.0, 0.5]), [1.0; 4], "box");
        let first_copy = soup.triangle_count();
        // The ball twice: every triangle of it has an equally near twin with a higher index.
        for _ in 0..2 {
            for t in 0..ball.triangle_count() {
                soup.push_triangle(0, ball.triangle(t));
            }
        }
        let spec = GridSpec::fit(&soup, 9.0, GridSize::Resolution(24), 1.0, 1 << 26).unwrap();
        let tris = spec.grid_triangles(&soup);
        let shell = super::super::shell(&spec, &tris);
        let octree = ShellOctree::new(&spec, &shell, &tris);
        let mut tied = 0;
        for k in 0..400u32 {
            // Points spread through and around the grid (outside it too).
            let p = DVec3::new(f64::from(k % 9) * 3.3 - 2.0, f64::from(k / 9 % 7) * 3.9 - 1.5, f64::from(k / 63) * 4.1);
            let brute = (0..tris.len())
                .map(|t| (t, distance2(p, &tris[t])))
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
                .map(|(t, _)| t);
            assert_eq!(octree.nearest(&tris, p, None), brute, "{p}");
            // Any guess gives the same triangle: the one at the first point, or the nearest itself.
            assert_eq!(octree.nearest(&tris, p, Some(first_copy)), brute, "{p} from {first_copy}");
            assert_eq!(octree.nearest(&tris, p, brute), brute, "{p} from itself");
            tied += usize::from(brute.is_some_and(|t| t >= first_copy));
        }
        assert!(tied > 0, "no point was nearest to the doubled ball");
    }

    #[test]
    fn group_boxes_hold_their_triangles_after_rounding_to_f32() {
        // Corners that f32 cannot hold exactly, on both sides of the rounding.
        let tris: Vec<GridTriangle> = (0..24)
            .map(|k| {
                let v = |j: u32| f64::from(k * 3 + j) * (1.0 + 1e-12) + 0.1;
                [DVec3::new(v(0), -v(1), v(2)), DVec3::new(-v(2), v(0), v(1)), DVec3::new(v(1), v(2), -v(0))]
            })
            .collect();
        let ids: Vec<u32> = (0..24).collect();
        for group in ids.chunks(GROUP) {
            let b = group_box(&tris, group);
            let [lo, hi] = b.map(|c| DVec3::from_array(c.map(f64::from)));
            for t in group.iter().flat_map(|&t| tris[t as usize]) {
                assert!(lo.cmple(t).all() && t.cmple(hi).all(), "{t} outside {b:?}");
                assert_eq!(box_distance2(t, &b), 0.0);
            }
        }
    }

    #[test]
    fn an_empty_shell_has_no_nearest_triangle() {
        let soup = TriangleSoup::from_mesh(&uv_sphere(1.0, 4), [1.0; 4]);
        let spec = GridSpec::fit(&soup, 9.0, GridSize::Resolution(4), 1.0, 1 << 26).unwrap();
        let shell = Shell::default();
        assert_eq!(ShellOctree::new(&spec, &shell, &[]).nearest(&[], DVec3::splat(1.0), None), None);
    }
}
