//! The nearest shell cell to many cells at once: an exact Euclidean distance transform of the shell's cells
//! (the lower envelope of parabolas of Felzenszwalb and Huttenlocher, along z, then y over the whole grid, then
//! x along the lines of the cells asked about), ties to the lower index as
//! [`ShellOctree::nearest`](super::octree::ShellOctree::nearest) breaks them. It takes time linear in the grid's
//! cells and 8 bytes a cell while it runs, so it pays where many cells far from the surface each need their
//! nearest shell cell (an open sheet's filled slab) and an octree walk a cell would cost more.
//!
//! Why the passes give the lowest index among tied cells: the squared distance is a sum over the axes, so its
//! minimum over shell cells `(x', y', z')` is a minimum over `x'` of `(x - x')²` plus the minimum over `y'` of
//! `(y - y')²` plus the minimum over `z'` of `(z - z')²`. Each pass keeps, among positions tied along its axis,
//! the lowest; an index orders cells by x, then y, then z, so that is the lowest index among tied cells.

use rayon::prelude::*;

use super::Shell;
use crate::grid::GridSpec;
use crate::radix;

/// No shell cell (along a line, or in the whole grid).
const NONE: u32 = u32::MAX;

/// For each of `cells` (linear indices, ascending), the linear index of the shell cell whose centre is nearest
/// to its centre (ties: the lower index), or `None` for an empty shell.
pub(crate) fn nearest_shell_cells(spec: &GridSpec, shell: &Shell, cells: &[u32]) -> Vec<Option<u32>> {
    let [nx, ny, nz] = spec.dims.map(|d| d as usize);
    // `distance[i]`: the squared distance from cell i to `site[i]`, the nearest shell cell found so far
    // ([`NONE`]: none yet; `site[i]` is then left as it is). Allocated as zeros, which the system maps on first
    // write: the z pass writes every distance, on every thread.
    let mut distance = vec![0; nx * ny * nz];
    let mut site = vec![0; nx * ny * nz];
    // Along z: a row's shell cells, at distance 0.
    distance.par_chunks_mut(nz).zip(site.par_chunks_mut(nz)).enumerate().for_each_init(
        Scratch::default,
        |scratch, (row, (distance, site))| {
            let first = (row * nz) as u32;
            let lo = shell.cells.partition_point(|&c| c < first);
            let own = &shell.cells[lo..lo + shell.cells[lo..].partition_point(|&c| c < first + nz as u32)];
            if own.is_empty() {
                distance.fill(NONE);
                return;
            }
            let at = |z: usize| first + z as u32;
            scratch.load(nz, |z| if own.binary_search(&at(z)).is_ok() { 0 } else { NONE }, at);
            scratch.store(distance, site, 1);
        },
    );
    // Along y, in each slab of constant x.
    distance.par_chunks_mut(ny * nz).zip(site.par_chunks_mut(ny * nz)).for_each_init(
        Scratch::default,
        |scratch, (distance, site)| {
            for z in 0..nz {
                scratch.load(ny, |y| distance[y * nz + z], |y| site[y * nz + z]);
                scratch.store(&mut distance[z..], &mut site[z..], nz);
            }
        },
    );
    // Along x, on the lines of `cells`: the cells in the order of their lines (y, z), along each line by x.
    let line_of = |&(i, _): &(u32, u32)| i % (ny * nz) as u32;
    let by_line = radix::sort_by_key(
        cells.iter().enumerate().map(|(n, &i)| (i, n as u32)).collect(),
        radix::bits_for(ny * nz),
        line_of,
    );
    let lines: Vec<&[(u32, u32)]> = by_line.chunk_by(|a, b| line_of(a) == line_of(b)).collect();
    let (distance, site) = (&distance, &site);
    let found: Vec<(u32, u32)> = lines
        .par_iter()
        .flat_map_iter(|line| {
            let mut scratch = Scratch::default();
            let start = line_of(&line[0]) as usize;
            let at = |x: usize| x * ny * nz + start;
            scratch.load(nx, |x| distance[at(x)], |x| site[at(x)]);
            line.iter().map(move |&(i, n)| (n, scratch.nearest_site(i as usize / (ny * nz))))
        })
        .collect();
    let mut nearest = vec![None; cells.len()];
    for (n, s) in found {
        nearest[n as usize] = Some(s).filter(|&s| s != NONE);
    }
    nearest
}

/// One parabola of a lower envelope: `(x - at)² + base`, lowest from `from` on (a fraction `num / den`, `den`
/// positive; `None`: from the line's start).
#[derive(Clone, Copy)]
struct Parabola {
    at: i64,
    base: i64,
    from: Option<(i64, i64)>,
}

/// One line's values and their lower envelope, reused from line to line.
#[derive(Default)]
struct Scratch {
    /// Per position: the squared distance to its nearest shell cell so far, and that cell.
    values: Vec<(u32, u32)>,
    envelope: Vec<Parabola>,
    /// The envelope's parabola lowest at the last position [`Scratch::nearest_site`] was asked about.
    cursor: usize,
}

impl Scratch {
    /// Loads a line of `n` positions (`distance(p)`, `site(p)`; [`NONE`]: no shell cell yet) and builds the
    /// lower envelope of the parabolas `(x - p)² + distance(p)`, a later parabola replacing an earlier one only
    /// where it is strictly lower.
    fn load(&mut self, n: usize, distance: impl Fn(usize) -> u32, site: impl Fn(usize) -> u32) {
        self.values.clear();
        self.values.extend((0..n).map(|p| (distance(p), site(p))));
        self.envelope.clear();
        self.cursor = 0;
        for (q, &(d, _)) in self.values.iter().enumerate() {
            if d == NONE {
                continue;
            }
            let (q, base) = (q as i64, i64::from(d));
            let from = loop {
                let Some(top) = self.envelope.last() else { break None };
                // The new parabola is strictly lower than the top one right of num / den.
                let (num, den) = (base + q * q - top.base - top.at * top.at, 2 * (q - top.at));
                match top.from {
                    // The top one is lowest nowhere (at its start it ties the one before, which is nearer).
                    Some((a, b)) if num * b <= a * den => {
                        self.envelope.pop();
                    }
                    _ => break Some((num, den)),
                }
            };
            self.envelope.push(Parabola { at: q, base, from });
        }
    }

    /// The site of the lowest parabola at `x` (ties: the nearer the line's start); after each
    /// [`Scratch::load`], asked about ascending positions.
    fn nearest_site(&mut self, x: usize) -> u32 {
        if self.envelope.is_empty() {
            return NONE;
        }
        let x = x as i64;
        while let Some(Parabola { from: Some((num, den)), .. }) = self.envelope.get(self.cursor + 1) {
            if *num >= x * den {
                break;
            }
            self.cursor += 1;
        }
        self.values[self.envelope[self.cursor].at as usize].1
    }

    /// Writes each position's nearest shell cell and its squared distance into `distance` and `site`, one
    /// position every `step` entries.
    fn store(&mut self, distance: &mut [u32], site: &mut [u32], step: usize) {
        for p in 0..self.values.len() {
            let s = self.nearest_site(p);
            if s == NONE {
                continue;
            }
            let parabola = self.envelope[self.cursor];
            let d = p as i64 - parabola.at;
            distance[p * step] = (d * d + parabola.base) as u32;
            site[p * step] = s;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::octree::ShellOctree;
    use super::*;
    use crate::grid::GridSize;
    use crate::shapes::{torus, uv_sphere};
    use crate::soup::TriangleSoup;

    /// The nearest shell cell of `cell` by measuring every shell cell (ties: the lower index).
    fn brute(spec: &GridSpec, shell: &Shell, cell: [u32; 3]) -> Option<u32> {
        let distance2 = |s: u32| {
            let c = spec.coords(s as usize);
            (0..3).map(|k| u64::from(c[k].abs_diff(cell[k])).pow(2)).sum::<u64>()
        };
        shell.cells.iter().map(|&s| (distance2(s), s)).min().map(|(_, s)| s)
    }

    #[test]
    fn every_cell_gets_the_nearest_shell_cell_with_ties_to_the_lower_index() {
        let mut soup = TriangleSoup::from_mesh(&torus(2.0, 0.5, 24), [1.0; 4]);
        soup.add_mesh(&crate::shapes::cuboid([2.5, 2.5, -0.5], [3.0, 3.0, 0.5]), [1.0; 4], "box");
        // Uneven sides: the passes' strides differ on every axis.
        let spec = GridSpec::fit(&soup, 9.0, GridSize::Resolution(23), 1.3, 1 << 26).unwrap();
        assert!(spec.dims[0] != spec.dims[1] && spec.dims[1] != spec.dims[2], "{:?}", spec.dims);
        let tris = spec.grid_triangles(&soup);
        let shell = super::super::shell(&spec, &tris, &crate::progress::Progress::new());
        let octree = ShellOctree::new(&spec, &shell);
        let every: Vec<u32> = (0..spec.cell_count() as u32).collect();
        let some: Vec<u32> = every.iter().copied().filter(|i| i % 7 < 2).collect();
        for cells in [every, some] {
            let nearest = nearest_shell_cells(&spec, &shell, &cells);
            assert_eq!(nearest.len(), cells.len());
            for (&i, &nearest) in cells.iter().zip(&nearest) {
                let cell = spec.coords(i as usize);
                assert_eq!(nearest, brute(&spec, &shell, cell), "{cell:?}");
                assert_eq!(nearest, octree.nearest(&spec, cell, None), "{cell:?}");
            }
        }
    }

    #[test]
    fn a_lone_shell_cell_is_everyones_nearest_and_no_shell_leaves_none() {
        let soup = TriangleSoup::from_mesh(&uv_sphere(1.0, 4), [1.0; 4]);
        let spec = GridSpec::fit(&soup, 9.0, GridSize::Resolution(7), 1.0, 1 << 26).unwrap();
        let lone = Shell { cells: vec![spec.index(3, 1, 5) as u32], ..Shell::default() };
        let every: Vec<u32> = (0..spec.cell_count() as u32).collect();
        assert!(nearest_shell_cells(&spec, &lone, &every).iter().all(|&s| s == Some(lone.cells[0])));
        assert!(nearest_shell_cells(&spec, &Shell::default(), &every[..5]).iter().all(Option::is_none));
    }
}
