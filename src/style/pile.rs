//! Falling voxels: a small granular solver. Spheres fall under gravity, bounce on the floor with restitution
//! and friction, and push each other apart (position-based relaxation over a uniform spatial grid). A sphere
//! that stays slow for a while falls asleep and becomes a fixed obstacle, so the pile comes to a complete rest
//! (plain relaxation jitters forever in tall stacks). Fixed time step; Jacobi-style iterations make each step
//! deterministic whatever the thread count.

use bevy::math::Vec3;
use rayon::prelude::*;

/// Parameters of the pile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PileParams {
    /// Collision radius: half a cell plus a small skin, so resting voxels keep a hair of space.
    pub radius: f32,
    /// Floor height (sphere centres rest at `floor + radius`).
    pub floor: f32,
    /// Gravity, units per second² (downwards).
    pub gravity: f32,
    /// Fraction of the normal speed kept when bouncing on the floor.
    pub restitution: f32,
    /// Fraction of the tangential speed lost per floor contact step.
    pub friction: f32,
    /// Velocity damping per second between spheres (granular energy loss).
    pub damping: f32,
    /// Fixed time step, seconds.
    pub dt: f32,
    /// Relaxation iterations per step.
    pub iterations: usize,
    /// Speeds below this (units per second) count as calm.
    pub sleep_speed: f32,
    /// Steps a sphere must stay calm before it falls asleep.
    pub sleep_steps: u16,
}

impl PileParams {
    /// Defaults for voxels of `cell` size above a floor at `floor`.
    pub fn for_cell(cell: f32, floor: f32) -> Self {
        Self {
            radius: cell * 0.5 * 1.06,
            floor,
            gravity: 20.0,
            restitution: 0.35,
            friction: 0.25,
            damping: 1.5,
            dt: 1.0 / 60.0,
            iterations: 4,
            sleep_speed: cell * 2.0,
            sleep_steps: 20,
        }
    }
}

/// A uniform grid over the spheres' bounding box with cell edge = one diameter (counting sort: `order`
/// lists sphere indices cell by cell, `starts[c]..starts[c + 1]` are cell c's).
struct Grid {
    origin: Vec3,
    inv_cell: f32,
    dims: [i32; 3],
    starts: Vec<u32>,
    order: Vec<u32>,
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

    fn build(positions: &[Vec3], diameter: f32) -> Self {
        let lo = positions.iter().fold(Vec3::splat(f32::MAX), |m, p| m.min(*p)) - Vec3::splat(diameter);
        let hi = positions.iter().fold(Vec3::splat(f32::MIN), |m, p| m.max(*p)) + Vec3::splat(diameter);
        // Cap the grid at ~4M cells: a scattered pile uses bigger cells (still correct, just slower).
        let mut cell = diameter;
        let mut dims;
        loop {
            let size = ((hi - lo) / cell).ceil().max(Vec3::ONE);
            dims = [size.x as i32, size.y as i32, size.z as i32];
            if (dims[0] as i64) * (dims[1] as i64) * (dims[2] as i64) <= 4 << 20 {
                break;
            }
            cell *= 2.0;
        }
        let mut grid = Grid { origin: lo, inv_cell: 1.0 / cell, dims, starts: Vec::new(), order: Vec::new() };
        let total = (dims[0] * dims[1] * dims[2]) as usize;
        let cells: Vec<usize> = positions.iter().map(|p| grid.index(grid.cell_of(*p))).collect();
        let mut counts = vec![0u32; total + 1];
        for &c in &cells {
            counts[c + 1] += 1;
        }
        for i in 0..total {
            counts[i + 1] += counts[i];
        }
        let mut fill = counts.clone();
        let mut order = vec![0u32; positions.len()];
        for (i, &c) in cells.iter().enumerate() {
            order[fill[c] as usize] = i as u32;
            fill[c] += 1;
        }
        grid.starts = counts;
        grid.order = order;
        grid
    }

    /// Calls `f` with every sphere index in the 27 cells around `p` (ascending cell, then index order). The
    /// three cells along z of each (x, y) row are adjacent in the cell order: one contiguous run per row.
    fn for_neighbours(&self, p: Vec3, mut f: impl FnMut(usize)) {
        let c = self.cell_of(p);
        let (z0, z1) = ((c[2] - 1).max(0), (c[2] + 1).min(self.dims[2] - 1));
        for x in (c[0] - 1).max(0)..=(c[0] + 1).min(self.dims[0] - 1) {
            for y in (c[1] - 1).max(0)..=(c[1] + 1).min(self.dims[1] - 1) {
                let first = self.starts[self.index([x, y, z0])] as usize;
                let last = self.starts[self.index([x, y, z1]) + 1] as usize;
                for &j in &self.order[first..last] {
                    f(j as usize);
                }
            }
        }
    }
}

/// For every awake sphere, the spheres closer than `reach` (compressed rows: `offsets[i]..offsets[i + 1]` index
/// `near`), in a deterministic order.
struct Contacts {
    offsets: Vec<u32>,
    near: Vec<u32>,
}

impl Contacts {
    fn find(positions: &[Vec3], asleep: &[bool], grid: &Grid, reach: f32) -> Self {
        const CHUNK: usize = 512;
        let chunks: Vec<(Vec<u32>, Vec<u32>)> = positions
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(c, chunk)| {
                let mut counts = Vec::with_capacity(chunk.len());
                let mut near = Vec::with_capacity(chunk.len() * 8);
                for (k, xi) in chunk.iter().enumerate() {
                    let i = c * CHUNK + k;
                    let before = near.len();
                    if asleep[i] {
                        counts.push(0);
                        continue;
                    }
                    grid.for_neighbours(*xi, |j| {
                        if j != i && xi.distance_squared(positions[j]) < reach * reach {
                            near.push(j as u32);
                        }
                    });
                    counts.push((near.len() - before) as u32);
                }
                (counts, near)
            })
            .collect();
        let mut offsets = Vec::with_capacity(positions.len() + 1);
        offsets.push(0);
        let mut near = Vec::with_capacity(chunks.iter().map(|c| c.1.len()).sum());
        for (counts, list) in chunks {
            for n in counts {
                offsets.push(offsets.last().copied().unwrap_or(0) + n);
            }
            near.extend(list);
        }
        Self { offsets, near }
    }

    fn of(&self, i: usize) -> &[u32] {
        &self.near[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }
}

/// The sleeping spheres an awake candidate neighbour is closer to than `near` (in the order found, maybe repeated).
fn pressed_sleepers(positions: &[Vec3], asleep: &[bool], candidates: &Contacts, near: f32) -> Vec<u32> {
    (0..positions.len())
        .into_par_iter()
        .flat_map_iter(|i| {
            candidates.of(i).iter().copied().filter(move |&j| asleep[j as usize] && positions[i].distance_squared(positions[j as usize]) < near * near)
        })
        .collect()
}

/// The falling spheres.
#[derive(Clone, Debug, PartialEq)]
pub struct Pile {
    /// Sphere centres.
    pub positions: Vec<Vec3>,
    /// Velocities.
    pub velocities: Vec<Vec3>,
    /// Parameters.
    pub params: PileParams,
    /// Steps each sphere has been calm (at `sleep_steps` it sleeps: fixed, velocity zero).
    pub calm: Vec<u16>,
    /// Steps taken so far.
    pub steps: u32,
}

impl Pile {
    /// Spheres at `positions`, at rest, each nudged by a tiny seeded jitter so stacks topple.
    pub fn new(positions: Vec<Vec3>, params: PileParams, seed: u64) -> Self {
        let mut state = seed ^ 0x9e37_79b9_7f4a_7c15;
        let mut jitter = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            ((state >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * 0.4
        };
        let velocities = positions.iter().map(|_| Vec3::new(jitter(), 0.0, jitter())).collect();
        let calm = vec![0; positions.len()];
        Self { positions, velocities, params, calm, steps: 0 }
    }

    /// Advances one fixed step.
    pub fn step(&mut self) {
        self.steps += 1;
        let p = self.params;
        let dt = p.dt;
        let rest = p.floor + p.radius;
        let damping = (-p.damping * dt).exp();
        let previous = self.positions.clone();
        let asleep: Vec<bool> = self.calm.iter().map(|c| *c >= p.sleep_steps).collect();
        // Predict (sleeping spheres stay put).
        self.positions.par_iter_mut().zip(self.velocities.par_iter_mut()).zip(asleep.par_iter()).for_each(|((x, v), sleeping)| {
            if *sleeping {
                return;
            }
            v.y -= p.gravity * dt;
            *v *= damping;
            *x += *v * dt;
            x.y = x.y.max(rest);
        });
        // Relax overlaps (Jacobi: every sphere reads the same snapshot, so the result is deterministic). The
        // contact candidates are gathered once per step (a sphere moves far less than a radius between
        // iterations): every pair closer than a diameter and a margin. Sleeping spheres are fixed obstacles
        // for the whole step: they have no list of their own and an awake sphere takes the whole correction.
        let diameter = 2.0 * p.radius;
        let grid = Grid::build(&self.positions, diameter);
        let candidates = Contacts::find(&self.positions, &asleep, &grid, diameter * 1.15);
        // A sleeper still pressed deeper than this after the relaxation (the awake sphere is wedged and cannot
        // get clear by itself) wakes up for the next step; a sphere overlapping less may fall asleep.
        let wake_depth = 0.06 * diameter;
        // Several contacts share one correction, damped by count^0.3 (1 contact: all of it).
        let sharing: Vec<f32> = (0..32).map(|n| 1.0 / (n.max(1) as f32).powf(0.3)).collect();
        // The share of a correction a sphere takes: all of it against a sleeper (which does not give way);
        // against an awake sphere, more the higher it sits above it (up to 0.7 a diameter up, 0.3 below), so a
        // stack pushes up from the bottom instead of sinking into itself (PBD mass scaling by height).
        let sleeper = |j: usize| f32::from(u8::from(asleep[j]));
        let mut deepest = vec![0.0f32; self.positions.len()];
        for _ in 0..p.iterations {
            let snapshot = &self.positions;
            (self.positions, deepest) = (0..snapshot.len())
                .into_par_iter()
                .map(|i| {
                    let xi = snapshot[i];
                    let mut push = Vec3::ZERO;
                    let mut contacts = 0usize;
                    let mut worst = 0.0f32;
                    // Branch-free over the candidates: a pair farther than a diameter adds nothing.
                    for &j in candidates.of(i) {
                        let j = j as usize;
                        let d = xi - snapshot[j];
                        let dist = d.length().max(1e-6);
                        let depth = (diameter - dist).max(0.0);
                        let share = (0.5 + 0.2 * (d.y / diameter).clamp(-1.0, 1.0)).max(sleeper(j));
                        push += d * (depth * share / dist);
                        contacts += usize::from(depth > 0.0);
                        worst = worst.max(depth);
                        // Coincident centres separate along a direction fixed by the index order.
                        if dist <= 1e-6 {
                            push += if i < j { Vec3::X } else { Vec3::NEG_X } * depth * 0.5;
                        }
                    }
                    if contacts == 0 {
                        return (xi, 0.0);
                    }
                    let share = sharing.get(contacts).copied().unwrap_or_else(|| 1.0 / (contacts as f32).powf(0.3));
                    let mut x = xi + push * share;
                    x.y = x.y.max(rest);
                    (x, worst)
                })
                .unzip();
        }
        let to_wake = pressed_sleepers(&self.positions, &asleep, &candidates, diameter - wake_depth);
        // Velocities from the corrected motion; floor bounce and friction; calm spheres fall asleep (only once
        // they overlap less than what would wake a sleeper).
        let clear = wake_depth;
        let sleep_steps = p.sleep_steps;
        self.velocities.par_iter_mut().zip(self.calm.par_iter_mut()).zip(self.positions.par_iter()).zip(previous.par_iter()).zip(deepest.par_iter()).for_each(|((((v, calm), x), x0), overlap)| {
            if *calm >= sleep_steps {
                *v = Vec3::ZERO;
                return;
            }
            let moved = (*x - *x0) / dt;
            let on_floor = x.y <= rest + 1e-4;
            let mut nv = moved;
            if on_floor {
                if v.y < 0.0 && nv.y <= 0.0 {
                    nv.y = -v.y * p.restitution;
                    if nv.y < p.gravity * dt * 2.0 {
                        nv.y = 0.0;
                    }
                }
                nv.x *= 1.0 - p.friction;
                nv.z *= 1.0 - p.friction;
            }
            if nv.length() < p.sleep_speed && *overlap < clear {
                *calm += 1;
            } else {
                *calm = 0;
            }
            *v = if *calm >= sleep_steps { Vec3::ZERO } else { nv };
        });
        for j in to_wake {
            self.calm[j as usize] = 0;
        }
    }

    /// The largest speed.
    pub fn max_speed(&self) -> f32 {
        self.velocities.iter().map(|v| v.length()).fold(0.0, f32::max)
    }

    /// The deepest overlap between two voxels of edge `size` (treated as spheres of that diameter), as a
    /// fraction of `size`.
    pub fn max_overlap(&self, size: f32) -> f32 {
        let diameter = size;
        let grid = Grid::build(&self.positions, 2.0 * self.params.radius);
        (0..self.positions.len())
            .into_par_iter()
            .map(|i| {
                let mut worst = 0.0f32;
                grid.for_neighbours(self.positions[i], |j| {
                    if j != i {
                        worst = worst.max(diameter - self.positions[i].distance(self.positions[j]));
                    }
                });
                worst / diameter
            })
            .reduce(|| 0.0, f32::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block(n: i32, cell: f32, base: f32) -> Vec<Vec3> {
        let mut out = Vec::new();
        for x in 0..n {
            for y in 0..n {
                for z in 0..n {
                    out.push(Vec3::new(x as f32, y as f32, z as f32) * cell + Vec3::new(0.0, base, 0.0));
                }
            }
        }
        out
    }

    #[test]
    fn a_dropped_block_comes_to_rest_on_the_floor_without_overlaps() {
        let cell = 0.24;
        let positions = block(10, cell, 3.0);
        let com_before: Vec3 = positions.iter().sum::<Vec3>() / positions.len() as f32;
        let mut pile = Pile::new(positions, PileParams::for_cell(cell, 0.0), 7);
        for _ in 0..600 {
            pile.step();
        }
        assert!(pile.max_speed() < 0.05, "still moving at {}", pile.max_speed());
        assert!(pile.positions.iter().all(|p| p.y >= pile.params.floor + pile.params.radius - 1e-4));
        assert!(pile.max_overlap(cell) < 0.05, "overlap {}", pile.max_overlap(cell));
        let com: Vec3 = pile.positions.iter().sum::<Vec3>() / pile.positions.len() as f32;
        let drift = Vec3::new(com.x - com_before.x, 0.0, com.z - com_before.z).length();
        assert!(drift < 3.0 * cell, "the pile's centre moved {drift} sideways");
        assert!(com.y < com_before.y, "it fell");
    }

    #[test]
    fn the_same_seed_gives_the_same_pile_whatever_the_threads() {
        let run = |threads: usize, seed: u64| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let mut pile = Pile::new(block(6, 0.24, 2.0), PileParams::for_cell(0.24, 0.0), seed);
                for _ in 0..200 {
                    pile.step();
                }
                pile.positions
            })
        };
        assert_eq!(run(1, 3), run(2, 3));
        assert_ne!(run(2, 3), run(2, 4));
    }
}
