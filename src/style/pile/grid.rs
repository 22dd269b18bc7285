//! The pile's broad phase: spheres sorted into a uniform grid (counting sort) and, for every awake sphere,
//! its candidate contacts. Everything works on the spheres in cell order ("sorted" indices): a cell's spheres
//! are one contiguous range, and so are the three cells along z of an (x, y) row, so a neighbourhood is nine
//! runs of adjacent memory. Buffers are kept between steps (no allocation once warm).

use std::ops::Range;

use bevy::math::{Vec3, Vec3A};
use rayon::prelude::*;

/// The grid is capped at about this many cells: a scattered pile uses bigger cells (still correct, slower).
const MAX_CELLS: i64 = 4 << 20;

/// Spheres sorted into a uniform grid with cells at least the contact reach wide (so the 27 cells around a
/// sphere hold every sphere within reach).
#[derive(Clone, Debug, Default)]
pub(super) struct Grid {
    origin: Vec3,
    inv_cell: f32,
    dims: [i32; 3],
    /// Cell c's spheres are sorted indices `starts[c]..starts[c + 1]`.
    starts: Vec<u32>,
    /// The sphere index at each sorted index.
    pub(super) order: Vec<u32>,
    /// Cell of each sphere (scratch).
    cells: Vec<u32>,
    /// Next free sorted index per cell (scratch).
    cursor: Vec<u32>,
}

impl Grid {
    fn cell_of(&self, p: Vec3) -> [i32; 3] {
        // The grid's box holds every position, so truncation is flooring here.
        let c = (p - self.origin) * self.inv_cell;
        let clamp = |v: f32, d: i32| (v as i32).clamp(0, d - 1);
        [clamp(c.x, self.dims[0]), clamp(c.y, self.dims[1]), clamp(c.z, self.dims[2])]
    }

    fn index(&self, c: [i32; 3]) -> usize {
        ((c[0] * self.dims[1] + c[1]) * self.dims[2] + c[2]) as usize
    }

    /// Sorts `positions` into cells at least `reach` wide.
    pub(super) fn rebuild(&mut self, positions: &[Vec3], reach: f32) {
        let lo = positions.iter().fold(Vec3::splat(f32::MAX), |m, p| m.min(*p)) - Vec3::splat(reach);
        let hi = positions.iter().fold(Vec3::splat(f32::MIN), |m, p| m.max(*p)) + Vec3::splat(reach);
        let mut cell = reach;
        loop {
            let size = ((hi - lo) / cell).ceil().max(Vec3::ONE);
            self.dims = [size.x as i32, size.y as i32, size.z as i32];
            if i64::from(self.dims[0]) * i64::from(self.dims[1]) * i64::from(self.dims[2]) <= MAX_CELLS {
                break;
            }
            cell *= 2.0;
        }
        self.origin = lo;
        self.inv_cell = 1.0 / cell;
        let total = (self.dims[0] * self.dims[1] * self.dims[2]) as usize;
        let mut cells = std::mem::take(&mut self.cells);
        cells.resize(positions.len(), 0);
        cells.par_iter_mut().zip(positions.par_iter()).for_each(|(c, p)| *c = self.index(self.cell_of(*p)) as u32);
        self.starts.clear();
        self.starts.resize(total + 1, 0);
        for &c in &cells {
            self.starts[c as usize + 1] += 1;
        }
        for i in 0..total {
            self.starts[i + 1] += self.starts[i];
        }
        self.cursor.clone_from(&self.starts);
        self.order.resize(positions.len(), 0);
        for (i, &c) in cells.iter().enumerate() {
            let slot = &mut self.cursor[c as usize];
            self.order[*slot as usize] = i as u32;
            *slot += 1;
        }
        self.cells = cells;
    }

    /// Fills `sorted` with `by_sphere`'s values in cell order.
    pub(super) fn gather<T: Copy, U: From<T>>(&self, by_sphere: &[T], sorted: &mut Vec<U>) {
        sorted.clear();
        sorted.extend(self.order.iter().map(|&i| U::from(by_sphere[i as usize])));
    }

    /// Writes cell-ordered `sorted` values back by sphere.
    pub(super) fn scatter<T: Copy, U: From<T>>(&self, sorted: &[T], by_sphere: &mut [U]) {
        for (value, &i) in sorted.iter().zip(&self.order) {
            by_sphere[i as usize] = U::from(*value);
        }
    }

    /// Calls `f` with the sorted-index runs covering the 27 cells around `p` (one run per (x, y) row).
    pub(super) fn for_neighbour_runs(&self, p: Vec3, mut f: impl FnMut(Range<usize>)) {
        let c = self.cell_of(p);
        let (z0, z1) = ((c[2] - 1).max(0), (c[2] + 1).min(self.dims[2] - 1));
        for x in (c[0] - 1).max(0)..=(c[0] + 1).min(self.dims[0] - 1) {
            for y in (c[1] - 1).max(0)..=(c[1] + 1).min(self.dims[1] - 1) {
                f(self.starts[self.index([x, y, z0])] as usize..self.starts[self.index([x, y, z1]) + 1] as usize);
            }
        }
    }
}

/// For every awake sphere (sorted index), the sorted indices of the spheres closer than a reach, as
/// compressed rows (`offsets[k]..offsets[k + 1]` index `near`), in a deterministic order.
#[derive(Clone, Debug, Default)]
pub(super) struct Contacts {
    offsets: Vec<u32>,
    near: Vec<u32>,
    /// Per-piece lists filled in parallel, then joined (kept between steps).
    pieces: Vec<(Vec<u32>, Vec<u32>)>,
}

impl Contacts {
    /// Spheres per parallel piece.
    const PIECE: usize = 512;

    /// Finds the candidates of every awake sphere among `sorted` positions.
    pub(super) fn find(&mut self, sorted: &[Vec3A], asleep: &[bool], grid: &Grid, reach: f32) {
        let pieces = sorted.len().div_ceil(Self::PIECE);
        self.pieces.resize_with(pieces, Default::default);
        self.pieces.par_iter_mut().enumerate().for_each(|(piece, (counts, near))| {
            counts.clear();
            near.clear();
            for k in piece * Self::PIECE..((piece + 1) * Self::PIECE).min(sorted.len()) {
                let before = near.len();
                if !asleep[k] {
                    let xk = sorted[k];
                    grid.for_neighbour_runs(xk.into(), |run| {
                        for (j, xj) in sorted[run.clone()].iter().enumerate() {
                            let j = run.start + j;
                            if j != k && xk.distance_squared(*xj) < reach * reach {
                                near.push(j as u32);
                            }
                        }
                    });
                }
                counts.push((near.len() - before) as u32);
            }
        });
        self.offsets.clear();
        self.offsets.push(0);
        self.near.clear();
        let mut total = 0;
        for (counts, near) in &self.pieces {
            self.offsets.extend(counts.iter().map(|n| {
                total += n;
                total
            }));
            self.near.extend_from_slice(near);
        }
    }

    /// The candidates of sorted sphere `k`.
    pub(super) fn of(&self, k: usize) -> &[u32] {
        &self.near[self.offsets[k] as usize..self.offsets[k + 1] as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn candidates_are_exactly_the_spheres_within_reach() {
        // A jittered 9 × 9 × 9 block: compare with all pairs.
        let mut state = 12345u32;
        let mut jitter = || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1u32 << 24) as f32 * 0.2
        };
        let mut positions = Vec::new();
        for x in 0..9 {
            for y in 0..9 {
                for z in 0..9 {
                    positions.push(Vec3::new(x as f32 + jitter(), y as f32 + jitter(), z as f32 + jitter()) * 0.25);
                }
            }
        }
        let reach = 0.26 * 1.15;
        let mut grid = Grid::default();
        grid.rebuild(&positions, reach);
        let mut sorted: Vec<Vec3A> = Vec::new();
        grid.gather(&positions, &mut sorted);
        let asleep: Vec<bool> = (0..sorted.len()).map(|k| k % 7 == 0).collect();
        let mut contacts = Contacts::default();
        contacts.find(&sorted, &asleep, &grid, reach);
        for k in 0..sorted.len() {
            let mut found: Vec<u32> = contacts.of(k).to_vec();
            found.sort_unstable();
            let expected: Vec<u32> = if asleep[k] {
                Vec::new()
            } else {
                (0..sorted.len() as u32)
                    .filter(|&j| j as usize != k && sorted[k].distance(sorted[j as usize]) < reach)
                    .collect()
            };
            assert_eq!(found, expected, "sphere {k}");
        }
        // Every sphere appears once in the order.
        let mut seen = grid.order.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..positions.len() as u32).collect::<Vec<_>>());
    }
}
