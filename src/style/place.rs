//! Placing the voxels at home each frame: home cell + bubble wobble, turned with the model; and the cursor for
//! the repel springs, which the GPU draws (`instancing::spring`).
//!
//! The pool's slots, looks and springs are walked a chunk to a task (rayon over the cores), in groups of
//! [`GROUP`] slots with a ball around their homes: a group the cursor cannot reach and that has no voxel it
//! pulls, and one wholly within its reach whose voxels it all pulls, are passed over whole (nothing of them can
//! change). In the others, each voxel costs one distance test, and a record is written only for a voxel the
//! cursor catches (it comes within reach) or lets go.

use std::sync::atomic::{AtomicBool, Ordering};

use bevy::prelude::*;
use rayon::prelude::*;

use super::Style;
use crate::instancing::spring::away_from_ray;
use crate::instancing::{
    GpuClock, GpuSpring, GpuSprings, GpuVoxel, GpuVoxels, Piece, Slot, Turn, VOXELS_PER_CHUNK, VoxelPool,
};
use crate::settings::{RepelSettings, VoxelSettings};
use crate::style::CursorRay;
use crate::transition::ActiveTransition;

use super::bubbles::{Bubble, BubbleSettings, Bubbles};
use super::repel::RepelActive;

/// Slots in a group with its own ball (64: a 4 × 4 × 4 block of cells in a Morton-ordered layout).
pub const GROUP: usize = 64;

/// Groups in a chunk.
const GROUPS_PER_CHUNK: usize = VOXELS_PER_CHUNK / GROUP;

/// Everything placing needs besides the voxels: the model's turn, the cursor and the clock.
#[derive(Clone, Debug)]
pub struct Placement {
    /// The model's rotation.
    pub rotation: Quat,
    /// The cursor ray in the cloud's frame (`None`: no cursor, or repel off).
    pub ray: Option<Ray3d>,
    /// Repel radius (world units).
    pub radius: f32,
    /// The clock drawn last frame (its cursor's push is where a voxel let go now was drawn towards).
    pub last: GpuClock,
    /// The flight clock's time now (the springs' clock).
    pub now: f32,
    /// Animation time for the bubble wobble (seconds, scaled by the speed setting).
    pub time: f32,
    /// Slots below this belong to the model shown; the rest are spares.
    pub in_model: usize,
    /// Bubble timings and wobble.
    pub bubbles: BubbleSettings,
}

/// How many of a group's voxels at home the cursor pulled last frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pulled {
    /// None of them.
    None,
    /// Some of them (or not known: the group is looked at).
    Some,
    /// All of them.
    All,
}

/// What placing keeps per group of slots: the ball around its homes and how many of its voxels the cursor
/// pulls, so a group that nothing can change this frame is passed over whole.
#[derive(Debug, Default)]
pub struct Groups {
    /// The pool's home count the balls were made for.
    homes: Option<u64>,
    /// Centre and radius of the ball around each group's homes (the cloud's frame), whole chunks of groups.
    balls: Vec<(Vec3, f32)>,
    /// How many voxels of the group the cursor pulled last frame.
    pulling: Vec<Pulled>,
}

impl Groups {
    /// Makes the balls anew when the homes changed (`homes`: the pool's count of new homes).
    pub fn refresh(&mut self, slots: &[Slot], homes: u64) {
        let count = slots.len().div_ceil(VOXELS_PER_CHUNK) * GROUPS_PER_CHUNK;
        if self.homes == Some(homes) && self.balls.len() == count {
            return;
        }
        self.balls = slots
            .par_chunks(GROUP)
            .map(|group| {
                let (lo, hi) = group
                    .iter()
                    .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), s| (lo.min(s.home.position), hi.max(s.home.position)));
                ((lo + hi) / 2.0, (hi - lo).length() / 2.0)
            })
            .collect();
        // Every group is looked at once more: the cursor may pull a voxel of it. Past the last slot: groups with
        // no slot, never reached.
        let groups = self.balls.len();
        self.balls.resize(count, (Vec3::ZERO, f32::NEG_INFINITY));
        self.pulling = vec![Pulled::Some; groups];
        self.pulling.resize(count, Pulled::None);
        self.homes = Some(homes);
    }
}

impl Placement {
    /// Places every voxel at home of `slots` that moves into `looks` and `springs` (all of them with `bubbles`,
    /// by slot; otherwise the springs of those the cursor catches or lets go), over all cores, passing over the
    /// groups `groups` says are out of reach and not pulled. Returns whether the cursor pulls a voxel.
    pub fn place(
        &self,
        slots: &mut [Slot],
        bubbles: Option<&[Bubble]>,
        looks: &mut GpuVoxels,
        springs: &mut GpuSprings,
        groups: &mut Groups,
    ) -> bool {
        let pulling = AtomicBool::new(false);
        let pieces = slots.par_chunks_mut(VOXELS_PER_CHUNK).zip(looks.pieces().zip(springs.pieces()));
        let chunks = groups.balls.par_chunks(GROUPS_PER_CHUNK).zip(groups.pulling.par_chunks_mut(GROUPS_PER_CHUNK));
        pieces.zip(chunks).for_each(|((slots, (mut looks, mut springs)), (balls, pulls))| {
            for (g, (ball, pulls)) in balls.iter().zip(pulls).enumerate() {
                let range = (g * GROUP).min(slots.len())..((g + 1) * GROUP).min(slots.len());
                let unchanged = match *pulls {
                    Pulled::None => !self.reaches(*ball),
                    Pulled::Some => false,
                    Pulled::All => self.covers(*ball),
                };
                if range.is_empty() || bubbles.is_none() && unchanged {
                    continue;
                }
                let first = range.start;
                *pulls = self.place_group(&mut slots[range], first, bubbles, &mut looks, &mut springs);
                if *pulls != Pulled::None {
                    pulling.store(true, Ordering::Relaxed);
                }
            }
        });
        pulling.into_inner()
    }

    /// Whether the cursor can push a voxel whose home lies in `ball` (centre, radius).
    fn reaches(&self, (centre, radius): (Vec3, f32)) -> bool {
        self.ray.is_some_and(|ray| away_from_ray(centre, ray).length() < self.radius + radius)
    }

    /// Whether the cursor reaches every voxel whose home lies in `ball`.
    fn covers(&self, (centre, radius): (Vec3, f32)) -> bool {
        self.ray.is_some_and(|ray| away_from_ray(centre, ray).length() + radius < self.radius)
    }

    /// Whether the cursor reaches a voxel at home `position`.
    #[inline]
    fn reaches_home(&self, position: Vec3) -> bool {
        self.ray.is_some_and(|ray| away_from_ray(position, ray).length_squared() < self.radius * self.radius)
    }

    /// Places the group of `slots` starting at record `first` of the chunk's pieces; returns how many of its
    /// voxels at home the cursor pulls.
    fn place_group(
        &self,
        slots: &mut [Slot],
        first: usize,
        bubbles: Option<&[Bubble]>,
        looks: &mut Piece<GpuVoxel>,
        springs: &mut Piece<GpuSpring>,
    ) -> Pulled {
        let turn = Turn::new(self.rotation);
        let (mut at_home, mut pulled) = (0, 0);
        for (k, slot) in slots.iter_mut().enumerate() {
            let i = first + k;
            if looks.start + i >= self.in_model || !slot.at_home() {
                continue;
            }
            let spring = &mut slot.repel;
            let reached = self.reaches_home(slot.home.position);
            if reached != spring.pulled {
                *spring = if reached {
                    spring.caught(self.now)
                } else {
                    spring.let_go(self.now, self.last.push(slot.home.position))
                };
                springs.set(i, GpuSpring::from(*spring));
            }
            at_home += 1;
            pulled += usize::from(reached);
            let Some(bubble) = bubbles.and_then(|b| b.get(looks.start + i)) else { continue };
            let home = &slot.home;
            let (grow, shown) = bubble.scale(&self.bubbles);
            let wobble = bubble.wobble(self.time, home.part, self.bubbles.wobble) * home.scale.max_element();
            let look = turn.place(home.position + wobble, home.scale * grow, looks.items[i].color);
            looks.set(i, if shown { look } else { look.hidden() });
        }
        match pulled {
            0 => Pulled::None,
            n if n == at_home => Pulled::All,
            _ => Pulled::Some,
        }
    }
}

/// Places the voxels at home: home cell + bubble wobble, turned with the model; bubble scale and visibility; the
/// cursor (in the clock the GPU reads) and the springs of the voxels it catches and lets go. Nothing runs while
/// nothing moves.
pub(super) fn place_at_home(
    time: Res<Time>,
    settings: Res<VoxelSettings>,
    repel: Res<RepelSettings>,
    style: Res<State<Style>>,
    timing: Res<BubbleSettings>,
    cursor: Res<CursorRay>,
    active: Res<ActiveTransition>,
    mut clock: ResMut<GpuClock>,
    mut pool: ResMut<VoxelPool>,
    bubbles: Option<Res<Bubbles>>,
    mut looks: ResMut<GpuVoxels>,
    mut springs: ResMut<GpuSprings>,
    mut pulling: ResMut<RepelActive>,
    mut groups: Local<Groups>,
) {
    let rotation = active.turn();
    // The cursor ray in the cloud's frame: homes and offsets live there, so idle voxels need no turning.
    let ray = cursor
        .0
        .filter(|_| repel.enabled)
        .map(|r| Ray3d { origin: rotation.inverse() * r.origin, direction: rotation.inverse() * r.direction });
    let last = *clock;
    clock.set_if_neq(clock.reaching(ray, repel.radius, repel.strength));
    let bubbles = bubbles.as_ref().map(|b| &b.0[..]).filter(|_| *style.get() == Style::Bubbles);
    if bubbles.is_none() && ray.is_none() && !pulling.0 {
        return;
    }
    let placement = Placement {
        rotation,
        ray,
        radius: repel.radius,
        last,
        now: clock.time,
        time: time.elapsed_secs() * settings.speed,
        in_model: pool.visible,
        bubbles: timing.clone(),
    };
    springs.reserve(pool.slots.len());
    groups.refresh(&pool.slots, pool.homes);
    pulling.0 = placement.place(&mut pool.slots, bubbles, &mut looks, &mut springs, &mut groups);
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
        groups: Groups,
        clock: GpuClock,
        /// The spring records as of the last [`Voxels::written`].
        seen: Vec<GpuSpring>,
    }

    /// The colour every voxel has.
    const COLOR: u32 = 0xdead_beef;

    /// Frames of 1/60 s.
    const DT: f32 = 1.0 / 60.0;

    /// The cursor's strength.
    const STRENGTH: f32 = 0.8;

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
                seen: springs.items.clone(),
                springs,
                groups: Groups::default(),
                clock: GpuClock::default(),
            }
        }

        /// One frame of `p`, as `place_at_home` runs it: the clock moves on and takes the cursor.
        fn place(&mut self, p: &Placement) -> bool {
            let last = self.clock;
            self.clock = GpuClock::new(last.time + DT, 0.0, 0.0).reaching(p.ray, p.radius, STRENGTH);
            let p = Placement { now: self.clock.time, last, ..p.clone() };
            self.groups.refresh(&self.slots, 0);
            p.place(&mut self.slots, self.bubbles.as_deref(), &mut self.looks, &mut self.springs, &mut self.groups)
        }

        /// Slots whose spring records changed since the last call.
        fn written(&mut self) -> Vec<usize> {
            let now = &self.springs.items;
            let changed = (0..now.len()).filter(|&i| self.seen.get(i).is_none_or(|s| *s != now[i])).collect();
            self.seen = now.clone();
            changed
        }

        /// Where the GPU draws voxel `i` now.
        fn drawn(&self, i: usize) -> Vec3 {
            self.springs.drawn(i, &self.looks.items[i], &self.clock).position()
        }

        /// Where voxel `i` would be drawn on its cell.
        fn home(&self, i: usize) -> Vec3 {
            placement(0.0, 0).rotation * self.slots[i].home.position
        }
    }

    /// A cursor straight down onto x = `at`, the model turned a quarter about y.
    fn placement(at: f32, in_model: usize) -> Placement {
        Placement {
            rotation: Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
            ray: Some(Ray3d::new(Vec3::new(at, 10.0, 0.0), Dir3::NEG_Y)),
            radius: 1.5,
            last: GpuClock::default(),
            now: 0.0,
            time: 0.0,
            in_model,
            bubbles: BubbleSettings::default(),
        }
    }

    #[test]
    fn the_cursor_catches_the_voxels_it_reaches_and_the_gpu_pushes_them() {
        let mut voxels = Voxels::row(6, None);
        let looks = voxels.looks.items.clone();
        let p = placement(2.0, 5);
        assert!(voxels.place(&p));
        assert_eq!(voxels.written(), vec![1, 2, 3], "caught");
        assert!((0..6).all(|i| voxels.slots[i].repel.pulled == (1..=3).contains(&i)));
        assert_eq!(voxels.looks.items, looks, "repel rewrote looks");
        // Drawn where they were, then eased onto the push (cloud frame, turned a quarter about y): voxel 1
        // towards −x, voxel 3 towards +x, the one under the cursor sideways; nothing written meanwhile.
        assert!(voxels.drawn(3).distance(voxels.home(3)) < 1e-6);
        for _ in 0..60 {
            voxels.place(&p);
            assert!(voxels.written().is_empty(), "a still cursor rewrites springs");
        }
        let pushed = |v: &Voxels, i: usize| p.rotation.inverse() * (v.drawn(i) - v.home(i));
        assert!((pushed(&voxels, 1) - Vec3::new(-0.4, 0.0, 0.0)).length() < 0.01, "{}", pushed(&voxels, 1));
        assert!((pushed(&voxels, 3) - Vec3::new(0.4, 0.0, 0.0)).length() < 0.01, "{}", pushed(&voxels, 3));
        assert!((pushed(&voxels, 2).length() - 1.5 * STRENGTH).abs() < 0.01);
        assert!(voxels.drawn(0).distance(voxels.home(0)) < 1e-6 && voxels.drawn(4).distance(voxels.home(4)) < 1e-6);
    }

    #[test]
    fn a_moving_cursor_writes_only_the_voxels_it_catches_and_lets_go() {
        let mut voxels = Voxels::row(12, None);
        voxels.place(&placement(2.0, 12));
        voxels.written();
        voxels.place(&placement(3.0, 12));
        assert_eq!(voxels.written(), vec![1, 4], "voxel 4 caught, voxel 1 let go; 2 and 3 follow on the GPU");
        let pulled: Vec<usize> = (0..12).filter(|&i| voxels.slots[i].repel.pulled).collect();
        assert_eq!(pulled, vec![2, 3, 4]);
    }

    #[test]
    fn spares_and_flying_voxels_are_left_alone_and_let_go_voxels_return_home_on_the_gpu() {
        let mut voxels = Voxels::row(6, None);
        voxels.slots[2].flying = true;
        voxels.place(&placement(5.0, 5));
        assert_eq!(voxels.written(), vec![4], "a spare slot was caught");
        let mut near = Voxels::row(6, None);
        near.slots[2].flying = true;
        near.place(&placement(2.0, 5));
        assert_eq!(near.written(), vec![1, 3], "a flying voxel was caught");
        for _ in 0..60 {
            near.place(&placement(2.0, 5));
        }
        // Let go once, from where they are drawn; then the CPU writes nothing while the GPU brings them home.
        let gone = Placement { ray: None, ..placement(2.0, 5) };
        let before = near.drawn(3);
        assert!(!near.place(&gone), "still pulled without a cursor");
        assert_eq!(near.written(), vec![1, 3]);
        assert!(near.drawn(3).distance(before) < 1e-3, "jumped from {before} to {}", near.drawn(3));
        assert!(near.drawn(3).distance(near.home(3)) > 0.3);
        for _ in 0..120 {
            near.place(&gone);
            assert!(near.written().is_empty(), "springs rewritten on their way home");
        }
        for i in 0..5 {
            assert!(near.drawn(i).distance(near.home(i)) < 1e-5, "voxel {i}");
            assert!(near.slots[i].repel.rests(near.clock.time), "voxel {i}");
        }
    }

    #[test]
    fn many_chunks_are_placed_like_one() {
        let n = 3 * VOXELS_PER_CHUNK + 17;
        let p = Placement { radius: n as f32, ..placement(n as f32 / 2.0, n) };
        let mut voxels = Voxels::row(n, None);
        voxels.place(&p);
        assert_eq!(voxels.written().len(), n, "every voxel caught");
        for _ in 0..120 {
            voxels.place(&p);
        }
        for i in [0, VOXELS_PER_CHUNK, n - 1] {
            let push = voxels.clock.push(voxels.slots[i].home.position);
            assert!(voxels.drawn(i).distance(voxels.home(i) + p.rotation * push) < 1e-2, "voxel {i}");
        }
    }

    #[test]
    fn groups_out_of_reach_pulling_no_voxel_are_passed_over() {
        let n = 3 * VOXELS_PER_CHUNK;
        let mut voxels = Voxels::row(n, None);
        let pulling = |v: &Voxels| {
            (0..v.groups.pulling.len()).filter(|&g| v.groups.pulling[g] != Pulled::None).collect::<Vec<_>>()
        };
        voxels.place(&placement(10.0, n));
        assert_eq!(pulling(&voxels), vec![0], "only the first group pulls voxels");
        // The cursor moves to the last group: its voxels are caught, the first group's let go.
        assert!(voxels.place(&placement((n - 10) as f32, n)));
        assert_eq!(pulling(&voxels), vec![n / GROUP - 1]);
        assert!(!voxels.slots[10].repel.pulled && voxels.slots[n - 10].repel.pulled);
        // New homes make new balls: a middle group moved under the cursor is reached.
        for (i, slot) in voxels.slots[VOXELS_PER_CHUNK..VOXELS_PER_CHUNK + GROUP].iter_mut().enumerate() {
            slot.home.position = Vec3::X * (n - 10 + i % 2) as f32;
        }
        voxels.groups.refresh(&voxels.slots, 1);
        voxels.written();
        voxels.place(&placement((n - 10) as f32, n));
        assert_eq!(voxels.written().len(), GROUP, "a rehomed group was passed over");
    }

    #[test]
    fn a_group_within_reach_whose_voxels_are_all_pulled_is_passed_over() {
        let n = 2 * GROUP;
        let mut voxels = Voxels::row(n, None);
        // Squeezed into 0.13 along x: a cursor ray along x, 0.1 away, reaches every voxel and covers each group.
        voxels.slots.iter_mut().enumerate().for_each(|(i, s)| s.home.position = Vec3::X * i as f32 * 0.001);
        let along =
            Placement { ray: Some(Ray3d::new(Vec3::new(-10.0, 0.0, 0.1), Dir3::X)), radius: 1.0, ..placement(0.0, n) };
        voxels.place(&along);
        assert_eq!(voxels.written().len(), n, "every voxel caught");
        assert_eq!(voxels.groups.pulling[..2], [Pulled::All; 2]);
        // Nothing of a covered group can change: it is not looked at (a voxel marked let go stays so).
        voxels.slots[3].repel.pulled = false;
        voxels.place(&along);
        assert!(!voxels.slots[3].repel.pulled, "a covered group was looked at");
        // A cursor that no longer covers it looks at it again, and catches the voxel.
        voxels.place(&Placement { radius: 0.12, ..along });
        assert!(voxels.slots[3].repel.pulled);
        assert_eq!(voxels.groups.pulling[..2], [Pulled::All; 2]);
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
        let off_cell = whole.looks.items[1].position().distance(whole.home(1));
        assert!(off_cell > 1e-3 && off_cell < 0.3, "wobble {off_cell}");
    }
}
