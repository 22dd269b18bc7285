//! Placing the voxels at home each frame: home cell + bubble wobble, turned with the model, and the repel springs
//! of the voxels the cursor reaches.
//!
//! The pool's slots, looks and springs are walked a chunk to a task (rayon over the cores); a chunk the cursor
//! cannot reach and that holds no voxel is passed over whole, and every voxel of a reached chunk the cursor leaves
//! alone costs one distance test and writes nothing. A voxel the cursor lets go is brought home by the GPU
//! (`instancing::spring`): its looks never change for repel, and its spring is written while it is pushed.

use std::sync::atomic::{AtomicBool, Ordering};

use bevy::prelude::*;
use rayon::prelude::*;

use super::Style;
use crate::instancing::{
    GpuClock, GpuSpring, GpuSprings, GpuVoxel, GpuVoxels, Piece, Slot, Turn, VOXELS_PER_CHUNK, VoxelPool, spring::Step,
};
use crate::settings::{RepelSettings, VoxelSettings};
use crate::style::CursorRay;
use crate::transition::ActiveTransition;

use super::bubbles::{Bubble, BubbleSettings, Bubbles};
use super::repel::{RepelActive, away_from_ray, repel_target};

/// Everything placing needs besides the voxels: the model's turn, the cursor and the clock.
#[derive(Clone, Debug)]
pub struct Placement {
    /// The model's rotation.
    pub rotation: Quat,
    /// The cursor ray in the cloud's frame (`None`: no cursor, or repel off).
    pub ray: Option<Ray3d>,
    /// Repel radius (world units).
    pub radius: f32,
    /// Repel strength (push on the ray = radius × strength).
    pub strength: f32,
    /// The flight clock's time now (the springs' clock).
    pub now: f32,
    /// The frame on that clock (the springs' pull).
    pub step: Step,
    /// Animation time for the bubble wobble (seconds, scaled by the speed setting).
    pub time: f32,
    /// Slots below this belong to the model shown; the rest are spares.
    pub in_model: usize,
    /// Bubble timings and wobble.
    pub bubbles: BubbleSettings,
}

/// What placing keeps per chunk of slots: the ball around its homes and whether it holds a voxel off its cell,
/// so a chunk the cursor cannot reach and that holds none is passed over whole.
#[derive(Debug, Default)]
pub struct Chunks {
    /// The pool's home count the balls were made for.
    homes: Option<u64>,
    /// Centre and radius of the ball around each chunk's homes (the cloud's frame).
    balls: Vec<(Vec3, f32)>,
    /// The cursor held a voxel of the chunk last frame.
    holding: Vec<bool>,
}

impl Chunks {
    /// Makes the balls anew when the homes changed (`homes`: the pool's count of new homes).
    pub fn refresh(&mut self, slots: &[Slot], homes: u64) {
        let count = slots.len().div_ceil(VOXELS_PER_CHUNK);
        if self.homes == Some(homes) && self.balls.len() == count {
            return;
        }
        self.balls = slots
            .par_chunks(VOXELS_PER_CHUNK)
            .map(|chunk| {
                let (lo, hi) = chunk
                    .iter()
                    .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), s| (lo.min(s.home.position), hi.max(s.home.position)));
                ((lo + hi) / 2.0, (hi - lo).length() / 2.0)
            })
            .collect();
        // Every chunk is looked at once more: it may hold a voxel anywhere.
        self.holding = vec![true; count];
        self.homes = Some(homes);
    }
}

impl Placement {
    /// Places every voxel at home of `slots` that moves into `looks` and `springs` (all of them with `bubbles`,
    /// by slot; otherwise the springs of those the cursor reaches or held), over all cores, passing over the
    /// chunks `chunks` says are out of reach and hold none. Returns whether the cursor holds a voxel.
    pub fn place(
        &self,
        slots: &mut [Slot],
        bubbles: Option<&[Bubble]>,
        looks: &mut GpuVoxels,
        springs: &mut GpuSprings,
        chunks: &mut Chunks,
    ) -> bool {
        let holding = AtomicBool::new(false);
        let pieces = slots.par_chunks_mut(VOXELS_PER_CHUNK).zip(looks.pieces().zip(springs.pieces()));
        pieces.zip(chunks.balls.par_iter().zip(chunks.holding.par_iter_mut())).for_each(
            |((slots, (mut looks, mut springs)), (ball, holds))| {
                if bubbles.is_none() && !*holds && !self.reaches(*ball) {
                    return;
                }
                *holds = self.place_piece(slots, bubbles, &mut looks, &mut springs);
                if *holds {
                    holding.store(true, Ordering::Relaxed);
                }
            },
        );
        holding.into_inner()
    }

    /// Whether the cursor can push a voxel whose home lies in `ball` (centre, radius).
    fn reaches(&self, (centre, radius): (Vec3, f32)) -> bool {
        self.ray.is_some_and(|ray| away_from_ray(centre, ray).length() < self.radius + radius)
    }

    /// Places one chunk; returns whether the cursor holds one of its voxels.
    fn place_piece(
        &self,
        slots: &mut [Slot],
        bubbles: Option<&[Bubble]>,
        looks: &mut Piece<GpuVoxel>,
        springs: &mut Piece<GpuSpring>,
    ) -> bool {
        let turn = Turn::new(self.rotation);
        let mut holds = false;
        for (i, slot) in slots.iter_mut().enumerate() {
            if looks.start + i >= self.in_model || !slot.at_home() {
                continue;
            }
            let target = repel_target(slot.home.position, self.ray, self.radius, self.strength);
            let spring = &mut slot.repel;
            if target != Vec3::ZERO || spring.held() {
                let next = if target == Vec3::ZERO {
                    spring.released(self.now)
                } else {
                    spring.pulled(target, self.now, self.step)
                };
                // Held at its target by a still cursor: nothing changes, nothing to write.
                if next != *spring {
                    *spring = next;
                    springs.set(i, GpuSpring::from(next));
                }
                holds |= spring.held();
            }
            let Some(bubble) = bubbles.and_then(|b| b.get(looks.start + i)) else { continue };
            let home = &slot.home;
            let (grow, shown) = bubble.scale(&self.bubbles);
            let wobble = bubble.wobble(self.time, home.part, self.bubbles.wobble) * home.scale.max_element();
            let look = turn.place(home.position + wobble, home.scale * grow, looks.items[i].color);
            looks.set(i, if shown { look } else { look.hidden() });
        }
        holds
    }
}

/// Places the voxels at home: home cell + bubble wobble, turned with the model; bubble scale and visibility; the
/// repel springs of the voxels the cursor reaches, and of those it lets go. Nothing runs while nothing moves.
pub(super) fn place_at_home(
    time: Res<Time>,
    settings: Res<VoxelSettings>,
    repel: Res<RepelSettings>,
    style: Res<State<Style>>,
    timing: Res<BubbleSettings>,
    cursor: Res<CursorRay>,
    active: Res<ActiveTransition>,
    clock: Res<GpuClock>,
    mut pool: ResMut<VoxelPool>,
    bubbles: Option<Res<Bubbles>>,
    mut looks: ResMut<GpuVoxels>,
    mut springs: ResMut<GpuSprings>,
    mut holding: ResMut<RepelActive>,
    mut chunks: Local<Chunks>,
) {
    let ray = cursor.0.filter(|_| repel.enabled);
    let bubbles = bubbles.as_ref().map(|b| &b.0[..]).filter(|_| *style.get() == Style::Bubbles);
    if bubbles.is_none() && ray.is_none() && !holding.0 {
        return;
    }
    let rotation = active.turn();
    let placement = Placement {
        rotation,
        // The cursor ray in the cloud's frame: homes and offsets live there, so idle voxels need no turning.
        ray: ray.map(|r| Ray3d { origin: rotation.inverse() * r.origin, direction: rotation.inverse() * r.direction }),
        radius: repel.radius,
        strength: repel.strength,
        now: clock.time,
        step: Step::new(time.delta_secs() * settings.speed),
        time: time.elapsed_secs() * settings.speed,
        in_model: pool.visible,
        bubbles: timing.clone(),
    };
    springs.reserve(pool.slots.len());
    chunks.refresh(&pool.slots, pool.homes);
    holding.0 = placement.place(&mut pool.slots, bubbles, &mut looks, &mut springs, &mut chunks);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::instancing::VoxelHome;
    use crate::style::bubbles::BubbleState;

    /// `n` voxels in a row along x (one cell apart, slot = index), their looks and springs, bubbles if asked, and
    /// the clock.
    struct Voxels {
        slots: Vec<Slot>,
        bubbles: Option<Vec<Bubble>>,
        looks: GpuVoxels,
        springs: GpuSprings,
        chunks: Chunks,
        now: f32,
    }

    /// The colour every voxel has.
    const COLOR: u32 = 0xdead_beef;

    impl Voxels {
        /// The row, laid out in a cloud turned as [`placement`]'s.
        fn row(n: usize, bubbles: Option<BubbleState>) -> Self {
            let home = |i: usize| VoxelHome { position: Vec3::X * i as f32, scale: Vec3::ONE, part: 0 };
            let mut looks = GpuVoxels::default();
            looks.reserve(n);
            let turn = Turn::new(placement(0.0, 0).rotation);
            for i in 0..n {
                looks.set(i, turn.place(home(i).position, Vec3::ONE, COLOR));
            }
            let mut springs = GpuSprings::default();
            springs.reserve(n);
            Voxels {
                slots: (0..n).map(|i| Slot { home: home(i), ..Slot::default() }).collect(),
                bubbles: bubbles.map(|state| vec![Bubble { phase: 0.0, state }; n]),
                looks,
                springs,
                chunks: Chunks::default(),
                now: 0.0,
            }
        }

        /// One frame of `p` (the clock moves on by its step).
        fn place(&mut self, p: &Placement) -> bool {
            self.now += p.step.dt;
            let p = Placement { now: self.now, ..p.clone() };
            self.chunks.refresh(&self.slots, 0);
            p.place(&mut self.slots, self.bubbles.as_deref(), &mut self.looks, &mut self.springs, &mut self.chunks)
        }

        /// Whether voxel `i`'s spring was written.
        fn written(&self, i: usize) -> bool {
            self.springs.items[i] != GpuSpring::default()
        }

        /// Where the GPU draws voxel `i` now.
        fn drawn(&self, i: usize) -> Vec3 {
            self.springs.items[i].sprung(&self.looks.items[i], self.now).position()
        }
    }

    /// A cursor straight down onto x = `at`, the model turned a quarter about y, frames of 1/60 s.
    fn placement(at: f32, in_model: usize) -> Placement {
        Placement {
            rotation: Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
            ray: Some(Ray3d::new(Vec3::new(at, 10.0, 0.0), Dir3::NEG_Y)),
            radius: 1.5,
            strength: 0.8,
            now: 0.0,
            step: Step::new(1.0 / 60.0),
            time: 0.0,
            in_model,
            bubbles: BubbleSettings::default(),
        }
    }

    #[test]
    fn only_voxels_the_cursor_reaches_move() {
        let mut voxels = Voxels::row(6, None);
        let looks = voxels.looks.items.clone();
        let p = placement(2.0, 5);
        voxels.place(&p);
        for i in 0..6 {
            let reached = (1..=3).contains(&i);
            assert_eq!(voxels.written(i), reached, "voxel {i}");
            assert_eq!(voxels.slots[i].repel.rests(voxels.now), !reached, "voxel {i}");
        }
        assert_eq!(voxels.looks.items, looks, "repel rewrote looks");
        // Voxel 1 is pushed towards −x, voxel 3 towards +x (cloud frame); the one under the cursor sideways.
        assert!(voxels.slots[1].repel.offset.x < 0.0 && voxels.slots[3].repel.offset.x > 0.0);
        // Drawn in the turned cloud: home + offset, rotated a quarter turn about y.
        let expected = p.rotation * (voxels.slots[3].home.position + voxels.slots[3].repel.offset);
        assert!(voxels.drawn(3).distance(expected) < 1e-3, "{} for {expected}", voxels.drawn(3));
        assert!(voxels.drawn(3).distance(voxels.looks.items[3].position()) > 1e-3, "not moved");
    }

    #[test]
    fn voxels_held_off_by_a_still_cursor_stop_being_rewritten() {
        let mut voxels = Voxels::row(6, None);
        let p = placement(2.0, 5);
        for _ in 0..120 {
            voxels.place(&p);
        }
        let held = voxels.slots[3].repel;
        assert!(held.held() && held.offset.length() > 0.1, "{held:?}");
        let before = voxels.springs.items.clone();
        assert!(voxels.place(&p), "the cursor holds voxels");
        assert_eq!(voxels.springs.items, before, "held voxels rewritten");
        assert!(voxels.drawn(3).distance(p.rotation * (voxels.slots[3].home.position + held.offset)) < 1e-3);
    }

    #[test]
    fn spares_and_flying_voxels_are_left_alone_and_let_go_voxels_return_home_on_the_gpu() {
        let mut voxels = Voxels::row(6, None);
        voxels.slots[2].flying = true;
        let p = placement(5.0, 5);
        voxels.place(&p);
        assert!(voxels.written(4) && !voxels.written(5), "a spare slot moved");
        let mut near = Voxels::row(6, None);
        near.slots[2].flying = true;
        near.place(&placement(2.0, 5));
        assert!(!near.written(2) && near.written(1), "a flying voxel was pushed");
        // Held voxels are let go once; then the CPU writes nothing while the GPU brings them home.
        for _ in 0..60 {
            near.place(&placement(2.0, 5));
        }
        let gone = Placement { ray: None, ..p };
        assert!(!near.place(&gone), "still held without a cursor");
        let let_go = near.springs.items.clone();
        let pushed = near.drawn(3).distance(gone.rotation * near.slots[3].home.position);
        assert!(pushed > 0.1, "pushed {pushed}");
        for _ in 0..120 {
            near.place(&gone);
        }
        assert_eq!(near.springs.items, let_go, "springs rewritten on their way home");
        for i in 0..5 {
            assert!(near.drawn(i).distance(gone.rotation * near.slots[i].home.position) < 1e-5, "voxel {i}");
            assert!(near.slots[i].repel.rests(near.now), "voxel {i}");
        }
    }

    #[test]
    fn many_chunks_are_placed_like_one() {
        let n = 3 * VOXELS_PER_CHUNK + 17;
        let p = Placement { radius: n as f32, ..placement(n as f32 / 2.0, n) };
        let mut voxels = Voxels::row(n, None);
        voxels.place(&p);
        for i in [0, VOXELS_PER_CHUNK, n - 1] {
            let expected = p.rotation * (voxels.slots[i].home.position + voxels.slots[i].repel.offset);
            assert!(voxels.drawn(i).distance(expected) < 1e-2, "voxel {i}");
            assert!(!voxels.slots[i].repel.rests(voxels.now), "voxel {i}");
        }
    }

    #[test]
    fn chunks_out_of_reach_holding_no_voxel_are_passed_over() {
        let n = 3 * VOXELS_PER_CHUNK;
        let mut voxels = Voxels::row(n, None);
        let near_first = placement(10.0, n);
        for _ in 0..60 {
            voxels.place(&near_first);
        }
        assert_eq!(voxels.chunks.holding, vec![true, false, false], "only the first chunk holds voxels");
        // The cursor moves to the last chunk: its voxels are reached, the first chunk's are let go.
        let near_last = placement((n - 10) as f32, n);
        assert!(!voxels.place(&near_last), "a voxel held on the first frame");
        assert_eq!(voxels.chunks.holding, vec![false, false, false]);
        let first = voxels.slots[10].repel;
        assert!(!first.held() && first.since == voxels.now && first.offset.length() > 0.1, "{first:?}");
        assert!(!voxels.slots[n - 10].repel.rests(voxels.now) && !voxels.written(VOXELS_PER_CHUNK + 5));
        // New homes make new balls: the middle chunk moved under the cursor is reached.
        for (i, slot) in voxels.slots[VOXELS_PER_CHUNK..2 * VOXELS_PER_CHUNK].iter_mut().enumerate() {
            slot.home.position = Vec3::X * (n - 10 + i % 3) as f32;
        }
        voxels.chunks.refresh(&voxels.slots, 1);
        voxels.place(&near_last);
        assert!(voxels.written(VOXELS_PER_CHUNK + 1), "a rehomed chunk was passed over");
    }

    #[test]
    fn burst_bubbles_are_hidden_and_whole_ones_wobble() {
        let mut gone = Voxels::row(3, Some(BubbleState::Gone(0.5)));
        let far = Placement { ray: None, time: 0.7, ..placement(0.0, 3) };
        gone.place(&far);
        assert!(gone.looks.items[..3].iter().all(|v| !v.shows()));
        let mut whole = Voxels::row(3, Some(BubbleState::Whole));
        whole.place(&far);
        assert!(whole.looks.items[..3].iter().all(|v| v.shows() && v.color == COLOR));
        let off_cell = whole.looks.items[1].position().distance(far.rotation * whole.slots[1].home.position);
        assert!(off_cell > 1e-3 && off_cell < 0.3, "wobble {off_cell}");
    }
}
