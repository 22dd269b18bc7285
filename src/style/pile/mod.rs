//! Falling voxels: a small granular solver. Spheres fall under gravity, bounce on the floor with restitution
//! and friction, push each other apart (position-based relaxation over a uniform spatial grid) and rub (the
//! velocities of touching spheres pull towards each other, so voxels heap up instead of flowing flat). A sphere
//! that stays slow for a while falls asleep and becomes a fixed obstacle, so the pile comes to a complete rest
//! (plain relaxation jitters forever in tall stacks). Fixed time step; Jacobi-style iterations make each step
//! deterministic whatever the thread count.

mod grid;

use bevy::math::{Vec3, Vec3A};
use rayon::prelude::*;

use crate::rng::Rng;
use grid::{Contacts, Grid};

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
    /// The most separating speed (units per second) a contact correction may add beyond stopping an
    /// approach.
    pub separation_speed: f32,
    /// Fraction of the way a sphere's velocity moves to the mean of the spheres touching it, per step.
    pub contact_friction: f32,
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
            dt: crate::schedule::FIXED_STEP.as_secs_f32(),
            separation_speed: cell,
            contact_friction: 0.5,
            iterations: 6,
            sleep_speed: cell * 2.0,
            sleep_steps: 20,
        }
    }
}

/// Candidate contacts are the pairs closer than this many diameters.
const REACH: f32 = 1.15;

/// The falling spheres.
#[derive(Clone, Debug)]
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
    /// Buffers reused from step to step.
    scratch: Scratch,
}

/// A step's working data, kept so steps allocate nothing once warm. "Sorted" arrays are indexed in the
/// grid's cell order (see [`grid`]).
#[derive(Clone, Debug, Default)]
struct Scratch {
    grid: Grid,
    contacts: Contacts,
    /// Positions before this step's prediction (by sphere).
    previous: Vec<Vec3>,
    /// Whether each sphere sleeps this step (by sphere).
    asleep: Vec<bool>,
    /// Positions being relaxed, and the next iteration's (sorted).
    sorted: Vec<Vec3A>,
    next: Vec<Vec3A>,
    /// Whether each sorted sphere sleeps.
    sorted_asleep: Vec<bool>,
    /// Velocities in cell order, and after contact friction.
    sorted_velocities: Vec<Vec3A>,
    rubbed: Vec<Vec3A>,
    /// Deepest overlap left after the relaxation (sorted, then by sphere).
    deepest: Vec<f32>,
    overlap: Vec<f32>,
}

impl Pile {
    /// Spheres at `positions`, at rest, each nudged by a tiny seeded jitter so stacks topple.
    pub fn new(positions: Vec<Vec3>, params: PileParams, seed: u64) -> Self {
        let mut rng = Rng::new(seed);
        let mut jitter = || (rng.f32() - 0.5) * 0.4;
        let velocities = positions.iter().map(|_| Vec3::new(jitter(), 0.0, jitter())).collect();
        let calm = vec![0; positions.len()];
        Self { positions, velocities, params, calm, steps: 0, scratch: Scratch::default() }
    }

    /// Advances one fixed step: predict, sort into cells, find contacts, relax overlaps, wake pressed
    /// sleepers, derive velocities (capped separation, floor bounce and friction, contact friction), put calm
    /// spheres to sleep.
    pub fn step(&mut self) {
        self.steps += 1;
        let mut s = std::mem::take(&mut self.scratch);
        self.predict(&mut s);
        // Relax overlaps (Jacobi: every sphere reads the same snapshot, so the result is deterministic). The
        // contact candidates are gathered once per step (a sphere moves far less than a radius between
        // iterations): every pair closer than `REACH` diameters. Sleeping spheres are fixed obstacles
        // for the whole step: they have no list of their own and an awake sphere takes the whole correction.
        let diameter = 2.0 * self.params.radius;
        let reach = diameter * REACH;
        s.grid.rebuild(&self.positions, reach);
        s.grid.gather(&self.positions, &mut s.sorted);
        s.grid.gather(&s.asleep, &mut s.sorted_asleep);
        s.contacts.find(&s.sorted, &s.sorted_asleep, &s.grid, reach);
        for _ in 0..self.params.iterations {
            s.relax(&self.params);
        }
        s.grid.scatter(&s.sorted, &mut self.positions);
        s.overlap.resize(self.positions.len(), 0.0);
        s.grid.scatter(&s.deepest, &mut s.overlap);
        // A sleeper still pressed deeper than this after the relaxation (the awake sphere is wedged and cannot
        // get clear by itself) wakes up for the next step; a sphere overlapping less may fall asleep.
        let wake_depth = 0.06 * diameter;
        let to_wake = s.pressed_sleepers(diameter - wake_depth);
        self.velocities_from_motion(&s);
        s.rub(&mut self.velocities, &self.params);
        self.fall_asleep(&s, wake_depth);
        for i in to_wake {
            self.calm[i as usize] = 0;
        }
        self.scratch = s;
    }

    /// Gravity and damping move the awake spheres (sleeping ones stay put); nothing sinks below the floor.
    fn predict(&mut self, s: &mut Scratch) {
        let p = self.params;
        let rest = p.floor + p.radius;
        let damping = (-p.damping * p.dt).exp();
        s.previous.clone_from(&self.positions);
        s.asleep.clear();
        s.asleep.extend(self.calm.iter().map(|c| *c >= p.sleep_steps));
        self.positions.par_iter_mut().zip(self.velocities.par_iter_mut()).zip(s.asleep.par_iter()).for_each(
            |((x, v), sleeping)| {
                if *sleeping {
                    return;
                }
                v.y -= p.gravity * p.dt;
                *v *= damping;
                *x += *v * p.dt;
                x.y = x.y.max(rest);
            },
        );
    }

    /// Velocities from the corrected motion (sleepers stay still), with floor bounce and floor friction.
    fn velocities_from_motion(&mut self, s: &Scratch) {
        let p = self.params;
        let rest = p.floor + p.radius;
        self.velocities
            .par_iter_mut()
            .zip(self.positions.par_iter())
            .zip(s.previous.par_iter())
            .zip(s.asleep.par_iter())
            .for_each(|(((v, x), x0), asleep)| {
                if *asleep {
                    *v = Vec3::ZERO;
                    return;
                }
                // What the relaxation added to the predicted velocity may stop an approach, but adds at most
                // `separation_speed` on top: voxels packed closer than the spheres' diameter when they let go come
                // apart without being launched.
                let moved = (*x - *x0) / p.dt;
                let correction = moved - *v;
                let push = correction.length();
                let mut nv = if push > 1e-9 {
                    let along = correction / push;
                    *v + along * push.min((-v.dot(along)).max(0.0) + p.separation_speed)
                } else {
                    moved
                };
                if x.y <= rest + 1e-4 {
                    if v.y < 0.0 && nv.y <= 0.0 {
                        nv.y = -v.y * p.restitution;
                        if nv.y < p.gravity * p.dt * 2.0 {
                            nv.y = 0.0;
                        }
                    }
                    nv.x *= 1.0 - p.friction;
                    nv.z *= 1.0 - p.friction;
                }
                *v = nv;
            });
    }

    /// Calm spheres fall asleep (only once they overlap less than `clear`, what would wake a sleeper);
    /// sleepers have no velocity.
    fn fall_asleep(&mut self, s: &Scratch, clear: f32) {
        let p = self.params;
        self.velocities.par_iter_mut().zip(self.calm.par_iter_mut()).zip(s.overlap.par_iter()).for_each(
            |((v, calm), overlap)| {
                if *calm >= p.sleep_steps {
                    return;
                }
                if v.length() < p.sleep_speed && *overlap < clear {
                    *calm += 1;
                } else {
                    *calm = 0;
                }
                if *calm >= p.sleep_steps {
                    *v = Vec3::ZERO;
                }
            },
        );
    }

    /// The largest speed.
    pub fn max_speed(&self) -> f32 {
        self.velocities.iter().map(|v| v.length()).fold(0.0, f32::max)
    }

    /// The deepest overlap between two voxels of edge `size` (treated as spheres of that diameter), as a
    /// fraction of `size`.
    pub fn max_overlap(&self, size: f32) -> f32 {
        let mut grid = Grid::default();
        grid.rebuild(&self.positions, 2.0 * self.params.radius.max(size * 0.5));
        let mut sorted: Vec<Vec3> = Vec::new();
        grid.gather(&self.positions, &mut sorted);
        (0..sorted.len())
            .into_par_iter()
            .map(|k| {
                let mut worst = 0.0f32;
                grid.for_neighbour_runs(sorted[k], |run| {
                    for j in run.filter(|&j| j != k) {
                        worst = worst.max(size - sorted[k].distance(sorted[j]));
                    }
                });
                worst / size
            })
            .reduce(|| 0.0, f32::max)
    }
}

impl Scratch {
    /// One Jacobi relaxation iteration over the sorted positions.
    fn relax(&mut self, p: &PileParams) {
        let diameter = 2.0 * p.radius;
        let rest = p.floor + p.radius;
        // Several contacts share one correction, damped by count^0.3 (1 contact: all of it).
        let table: [f32; 32] = std::array::from_fn(|n| 1.0 / (n.max(1) as f32).powf(0.3));
        let sharing = |n: usize| table.get(n).copied().unwrap_or_else(|| 1.0 / (n as f32).powf(0.3));
        let (snapshot, asleep, contacts) = (&self.sorted, &self.sorted_asleep, &self.contacts);
        self.next.resize(snapshot.len(), Vec3A::ZERO);
        self.deepest.resize(snapshot.len(), 0.0);
        self.next.par_iter_mut().zip(self.deepest.par_iter_mut()).enumerate().for_each(|(k, (out, deepest))| {
            let xk = snapshot[k];
            let mut push = Vec3A::ZERO;
            let mut touching = 0usize;
            let mut worst = 0.0f32;
            // Branch-free over the candidates: a pair farther than a diameter adds nothing.
            for &j in contacts.of(k) {
                let j = j as usize;
                let d = xk - snapshot[j];
                let dist = d.length().max(1e-6);
                let depth = (diameter - dist).max(0.0);
                // The share of a correction a sphere takes: all of it against a sleeper (which does not give
                // way); against an awake sphere, more the higher it sits above it (up to 0.7 a diameter up,
                // 0.3 below), so a stack pushes up from the bottom instead of sinking into itself (PBD mass
                // scaling by height).
                let share = (0.5 + 0.2 * (d.y / diameter).clamp(-1.0, 1.0)).max(f32::from(u8::from(asleep[j])));
                push += d * (depth * share / dist);
                touching += usize::from(depth > 0.0);
                worst = worst.max(depth);
                // Coincident centres separate along a direction fixed by the sorted order.
                if dist <= 1e-6 {
                    push += if k < j { Vec3A::X } else { Vec3A::NEG_X } * depth * 0.5;
                }
            }
            *deepest = worst;
            *out = if touching == 0 {
                xk
            } else {
                let mut x = xk + push * sharing(touching);
                x.y = x.y.max(rest);
                x
            };
        });
        std::mem::swap(&mut self.sorted, &mut self.next);
    }

    /// Contact friction between spheres: every awake sphere's velocity moves `contact_friction` of the way to
    /// the mean velocity of the spheres touching it (sleepers count as still), so voxels resting on others
    /// stop sliding and heap up instead of flowing flat.
    fn rub(&mut self, velocities: &mut [Vec3], p: &PileParams) {
        let touch = 2.0 * p.radius * 1.02;
        self.grid.gather(velocities, &mut self.sorted_velocities);
        self.rubbed.resize(self.sorted.len(), Vec3A::ZERO);
        let (positions, asleep, contacts, before) =
            (&self.sorted, &self.sorted_asleep, &self.contacts, &self.sorted_velocities);
        self.rubbed.par_iter_mut().enumerate().for_each(|(k, out)| {
            *out = before[k];
            if asleep[k] {
                return;
            }
            let (mut sum, mut count) = (Vec3A::ZERO, 0u32);
            for &j in contacts.of(k) {
                let j = j as usize;
                if positions[k].distance_squared(positions[j]) < touch * touch {
                    sum += before[j];
                    count += 1;
                }
            }
            if count > 0 {
                *out += (sum / count as f32 - before[k]) * p.contact_friction;
            }
        });
        self.grid.scatter(&self.rubbed, velocities);
    }

    /// The sleepers (sphere indices) an awake candidate neighbour is closer to than `near` after the
    /// relaxation, in the order found (maybe repeated).
    fn pressed_sleepers(&self, near: f32) -> Vec<u32> {
        let (sorted, asleep, order) = (&self.sorted, &self.sorted_asleep, &self.grid.order);
        (0..sorted.len())
            .into_par_iter()
            .flat_map_iter(|k| {
                self.contacts
                    .of(k)
                    .iter()
                    .filter(move |&&j| {
                        asleep[j as usize] && sorted[k].distance_squared(sorted[j as usize]) < near * near
                    })
                    .map(move |&j| order[j as usize])
            })
            .collect()
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

    /// How far the widest sphere of a falling block gets from the block's axis, beyond where it started,
    /// after a second of free fall.
    fn free_fall_growth(separation_speed: f32) -> f32 {
        let cell = 0.24;
        let positions = block(8, cell, 100.0);
        let axis = |p: &Vec3| Vec3::new(p.x - 3.5 * cell, 0.0, p.z - 3.5 * cell).length();
        let before = positions.iter().map(axis).fold(0.0, f32::max);
        let params = PileParams { separation_speed, ..PileParams::for_cell(cell, 0.0) };
        let mut pile = Pile::new(positions, params, 5);
        for _ in 0..60 {
            pile.step();
        }
        pile.positions.iter().map(axis).fold(0.0, f32::max) - before
    }

    #[test]
    fn voxels_packed_closer_than_a_diameter_come_apart_without_being_launched() {
        // Voxels sit one cell apart, the spheres are a little wider: resolving that must not blow the block up.
        let capped = free_fall_growth(PileParams::for_cell(0.24, 0.0).separation_speed);
        let uncapped = free_fall_growth(f32::INFINITY);
        // Measured: 0.46 against 0.76 (of which the seeded sideways jitter, ±0.2 units/s, is up to 0.2).
        assert!(capped < 2.0 * 0.24, "the block spread {capped} in a second of free fall");
        assert!(capped < 0.7 * uncapped, "capped {capped}, uncapped {uncapped}");
    }

    /// Horizontal distance a sphere slides in half a second over a sleeping layer, thrown sideways at 1 unit/s.
    fn slide(contact_friction: f32) -> f32 {
        let cell = 0.24;
        let params = PileParams { contact_friction, ..PileParams::for_cell(cell, 0.0) };
        // A sleeping layer packed four times closer than the cells: a nearly flat surface.
        let mut positions: Vec<Vec3> = (0..60)
            .flat_map(|x| (0..12).map(move |z| Vec3::new(x as f32 * 0.25, 0.5, z as f32 * 0.25) * cell))
            .collect();
        let start = Vec3::new(2.0 * cell, 1.55 * cell, 1.5 * cell);
        positions.push(start);
        let mut pile = Pile::new(positions, params, 1);
        let n = pile.positions.len();
        pile.calm[..n - 1].fill(params.sleep_steps);
        pile.velocities[..n - 1].fill(Vec3::ZERO);
        pile.velocities[n - 1] = Vec3::X;
        for _ in 0..30 {
            pile.step();
        }
        pile.positions[n - 1].x - start.x
    }

    #[test]
    fn contact_friction_stops_a_voxel_sliding_over_others() {
        let (rough, smooth) = (slide(0.5), slide(0.0));
        assert!(smooth > 0.3 && rough < 0.5 * smooth, "slid {rough} with friction, {smooth} without");
    }
}
