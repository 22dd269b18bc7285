//! Placing the voxels at home each frame: home cell + bubble wobble + repel spring, turned with the model.
//!
//! The pool's slots and their looks are walked a chunk to a task (rayon over the cores); every voxel the
//! cursor leaves alone costs one distance test and writes nothing, so its chunk is not uploaded.

use std::sync::atomic::{AtomicBool, Ordering};

use bevy::prelude::*;
use rayon::prelude::*;

use super::Style;
use crate::instancing::{GpuVoxel, GpuVoxels, Piece, Slot, Turn, VOXELS_PER_CHUNK, VoxelPool};
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
    /// Spring time step (seconds).
    pub dt: f32,
    /// Animation time for the bubble wobble (seconds, scaled by the speed setting).
    pub time: f32,
    /// Slots below this belong to the model shown; the rest are spares.
    pub in_model: usize,
    /// Bubble timings and wobble.
    pub bubbles: BubbleSettings,
}

/// What placing keeps per chunk of slots: the ball around its homes and whether a spring of it moves, so a
/// chunk the cursor cannot reach and whose voxels rest is passed over whole.
#[derive(Debug, Default)]
pub struct Chunks {
    /// The pool's home count the balls were made for.
    homes: Option<u64>,
    /// Centre and radius of the ball around each chunk's homes (the cloud's frame).
    balls: Vec<(Vec3, f32)>,
    /// A spring of the chunk moved last frame.
    moving: Vec<bool>,
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
        // Every chunk is looked at once more: its springs may be anywhere.
        self.moving = vec![true; count];
        self.homes = Some(homes);
    }
}

impl Placement {
    /// Places every voxel of `slots` at home that moves (all of them with `bubbles`, by slot; otherwise those the
    /// cursor reaches or whose spring still moves) into `looks`, over all cores, passing over the chunks
    /// `chunks` says are out of reach and at rest. Returns whether any voxel is still off its cell.
    pub fn place(
        &self,
        slots: &mut [Slot],
        bubbles: Option<&[Bubble]>,
        looks: &mut GpuVoxels,
        chunks: &mut Chunks,
    ) -> bool {
        let displaced = AtomicBool::new(false);
        let pieces = slots.par_chunks_mut(VOXELS_PER_CHUNK).zip(looks.pieces());
        pieces.zip(chunks.balls.par_iter().zip(chunks.moving.par_iter_mut())).for_each(
            |((slots, mut piece), (ball, moving))| {
                if bubbles.is_none() && !*moving && !self.reaches(*ball) {
                    return;
                }
                *moving = self.place_piece(slots, bubbles, &mut piece);
                if *moving {
                    displaced.store(true, Ordering::Relaxed);
                }
            },
        );
        displaced.into_inner()
    }

    /// Whether the cursor can push a voxel whose home lies in `ball` (centre, radius).
    fn reaches(&self, (centre, radius): (Vec3, f32)) -> bool {
        self.ray.is_some_and(|ray| away_from_ray(centre, ray).length() < self.radius + radius)
    }

    fn place_piece(&self, slots: &mut [Slot], bubbles: Option<&[Bubble]>, piece: &mut Piece<GpuVoxel>) -> bool {
        let turn = Turn::new(self.rotation);
        let mut displaced = false;
        for (i, slot) in slots.iter_mut().enumerate() {
            if piece.start + i >= self.in_model || !slot.at_home() {
                continue;
            }
            let home = &slot.home;
            let repel = &mut slot.repel;
            let bubble = bubbles.and_then(|b| b.get(piece.start + i));
            let target = repel_target(home.position, self.ray, self.radius, self.strength);
            let still = target == Vec3::ZERO && repel.is_rest();
            if still && bubble.is_none() {
                continue;
            }
            if !still {
                let next = repel.stepped(target, self.dt);
                displaced |= !next.is_rest();
                // Held at its target by a still cursor: nothing changes, nothing to write.
                if next == *repel && bubble.is_none() {
                    continue;
                }
                *repel = next;
            }
            let (wobble, grow, shown) = match bubble {
                Some(b) => {
                    let (grow, shown) = b.scale(&self.bubbles);
                    (b.wobble(self.time, home.part, self.bubbles.wobble) * home.scale.max_element(), grow, shown)
                }
                None => (Vec3::ZERO, 1.0, piece.items[i].shows()),
            };
            let look = turn.place(home.position + wobble + repel.offset, home.scale * grow, piece.items[i].color);
            piece.set(i, if shown { look } else { look.hidden() });
        }
        displaced
    }
}

/// Places the voxels at home: home cell + bubble wobble + repel offset, turned with the model; bubble scale and
/// visibility. The repel springs are stepped in the same pass, and nothing runs while nothing moves.
pub(super) fn place_at_home(
    time: Res<Time>,
    settings: Res<VoxelSettings>,
    repel: Res<RepelSettings>,
    style: Res<State<Style>>,
    timing: Res<BubbleSettings>,
    cursor: Res<CursorRay>,
    active: Res<ActiveTransition>,
    mut pool: ResMut<VoxelPool>,
    bubbles: Option<Res<Bubbles>>,
    mut looks: ResMut<GpuVoxels>,
    mut springs: ResMut<RepelActive>,
    mut chunks: Local<Chunks>,
) {
    let ray = cursor.0.filter(|_| repel.enabled);
    let bubbles = bubbles.as_ref().map(|b| &b.0[..]).filter(|_| *style.get() == Style::Bubbles);
    if bubbles.is_none() && ray.is_none() && !springs.0 {
        return;
    }
    let rotation = active.turn();
    let placement = Placement {
        rotation,
        // The cursor ray in the cloud's frame: homes and offsets live there, so idle voxels need no turning.
        ray: ray.map(|r| Ray3d { origin: rotation.inverse() * r.origin, direction: rotation.inverse() * r.direction }),
        radius: repel.radius,
        strength: repel.strength,
        dt: time.delta_secs().min(1.0 / 20.0),
        time: time.elapsed_secs() * settings.speed,
        in_model: pool.visible,
        bubbles: timing.clone(),
    };
    chunks.refresh(&pool.slots, pool.homes);
    springs.0 = placement.place(&mut pool.slots, bubbles, &mut looks, &mut chunks);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::instancing::VoxelHome;
    use crate::style::bubbles::BubbleState;

    /// `n` voxels in a row along x (one cell apart, slot = index), their looks, and bubbles if asked.
    struct Voxels {
        slots: Vec<Slot>,
        bubbles: Option<Vec<Bubble>>,
        looks: GpuVoxels,
        chunks: Chunks,
    }

    /// The look every voxel starts with (nothing placed yet).
    const UNPLACED: u32 = 0xdead_beef;

    impl Voxels {
        fn row(n: usize, bubbles: Option<BubbleState>) -> Self {
            let home = |i: usize| VoxelHome { position: Vec3::X * i as f32, scale: Vec3::ONE, part: 0 };
            let mut looks = GpuVoxels::default();
            looks.reserve(n);
            for i in 0..n {
                looks.set(i, Turn::new(Quat::IDENTITY).place(Vec3::ZERO, Vec3::ONE, UNPLACED));
            }
            Voxels {
                slots: (0..n).map(|i| Slot { home: home(i), ..Slot::default() }).collect(),
                bubbles: bubbles.map(|state| vec![Bubble { phase: 0.0, state }; n]),
                looks,
                chunks: Chunks::default(),
            }
        }

        fn place(&mut self, p: &Placement) -> bool {
            self.chunks.refresh(&self.slots, 0);
            p.place(&mut self.slots, self.bubbles.as_deref(), &mut self.looks, &mut self.chunks)
        }

        /// Whether voxel `i` was written (it moved from where it started).
        fn written(&self, i: usize) -> bool {
            self.looks.items[i].position() != Vec3::ZERO
        }
    }

    /// A cursor straight down onto x = `at`, the model turned a quarter about y.
    fn placement(at: f32, in_model: usize) -> Placement {
        Placement {
            rotation: Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
            ray: Some(Ray3d::new(Vec3::new(at, 10.0, 0.0), Dir3::NEG_Y)),
            radius: 1.5,
            strength: 0.8,
            dt: 1.0 / 60.0,
            time: 0.0,
            in_model,
            bubbles: BubbleSettings::default(),
        }
    }

    #[test]
    fn only_voxels_the_cursor_reaches_move() {
        let mut voxels = Voxels::row(6, None);
        let p = placement(2.0, 5);
        assert!(voxels.place(&p));
        for i in 0..6 {
            let reached = (1..=3).contains(&i);
            assert_eq!(voxels.written(i), reached, "voxel {i}");
            assert_eq!(voxels.slots[i].repel.is_rest(), !reached, "voxel {i}");
        }
        // Voxel 1 is pushed towards −x, voxel 3 towards +x (cloud frame); the one under the cursor sideways.
        assert!(voxels.slots[1].repel.offset.x < 0.0 && voxels.slots[3].repel.offset.x > 0.0);
        // Placed in the turned cloud: home + offset, rotated a quarter turn about y, its colour kept.
        let expected = p.rotation * (voxels.slots[3].home.position + voxels.slots[3].repel.offset);
        let look = voxels.looks.items[3];
        assert!(look.position().distance(expected) < 1e-5);
        assert!(look.x_axis[0].abs() < 1e-6 && (look.x_axis[1] + 1.0).abs() < 1e-6, "turned: {:?}", look.x_axis);
        assert_eq!(look.color, UNPLACED);
    }

    #[test]
    fn voxels_held_off_by_a_still_cursor_stop_being_rewritten() {
        let mut voxels = Voxels::row(6, None);
        let p = placement(2.0, 5);
        for _ in 0..120 {
            voxels.place(&p);
        }
        let held = voxels.slots[3].repel;
        assert!(held.velocity == Vec3::ZERO && held.offset.length() > 0.1, "{held:?}");
        let before = voxels.looks.items.clone();
        assert!(voxels.place(&p), "held voxels are still off their cells");
        assert_eq!(voxels.looks.items, before, "held voxels rewritten");
    }

    #[test]
    fn spares_and_flying_voxels_are_left_alone_and_springs_come_to_rest_without_a_cursor() {
        let mut voxels = Voxels::row(6, None);
        voxels.slots[2].flying = true;
        let p = placement(5.0, 5);
        assert!(voxels.place(&p));
        assert!(voxels.slots[5].repel.is_rest() && !voxels.written(5), "a spare slot moved");
        let mut near = Voxels::row(6, None);
        near.slots[2].flying = true;
        near.place(&placement(2.0, 5));
        assert!(near.slots[2].repel.is_rest() && !near.written(2), "a flying voxel was placed");
        let gone = Placement { ray: None, ..p };
        for _ in 0..120 {
            voxels.place(&gone);
        }
        assert!(!voxels.place(&gone), "springs still moving after 2 s");
        assert!(voxels.looks.items[4].position().distance(gone.rotation * voxels.slots[4].home.position) < 1e-5);
    }

    #[test]
    fn many_chunks_are_placed_like_one() {
        let n = 3 * VOXELS_PER_CHUNK + 17;
        let p = Placement { radius: n as f32, ..placement(n as f32 / 2.0, n) };
        let mut voxels = Voxels::row(n, None);
        voxels.place(&p);
        for i in [0, VOXELS_PER_CHUNK, n - 1] {
            let expected = p.rotation * (voxels.slots[i].home.position + voxels.slots[i].repel.offset);
            assert!(voxels.looks.items[i].position().distance(expected) < 1e-2, "voxel {i}");
            assert!(!voxels.slots[i].repel.is_rest(), "voxel {i}");
        }
    }

    #[test]
    fn chunks_out_of_the_cursors_reach_and_at_rest_are_passed_over() {
        let n = 3 * VOXELS_PER_CHUNK;
        let mut voxels = Voxels::row(n, None);
        let near_first = placement(10.0, n);
        assert!(voxels.place(&near_first));
        assert_eq!(voxels.chunks.moving, vec![true, false, false], "only the first chunk's springs move");
        // The cursor moves to the last chunk: its voxels are reached, the first chunk's springs go on.
        let near_last = placement((n - 10) as f32, n);
        assert!(voxels.place(&near_last));
        assert_eq!(voxels.chunks.moving, vec![true, false, true]);
        assert!(!voxels.slots[n - 10].repel.is_rest() && !voxels.written(VOXELS_PER_CHUNK + 5));
        // New homes make new balls: the middle chunk moved under the cursor is reached.
        for (i, slot) in voxels.slots[VOXELS_PER_CHUNK..2 * VOXELS_PER_CHUNK].iter_mut().enumerate() {
            slot.home.position = Vec3::X * (n - 10 + i % 3) as f32;
        }
        voxels.chunks.refresh(&voxels.slots, 1);
        near_last.place(&mut voxels.slots, None, &mut voxels.looks, &mut voxels.chunks);
        assert!(!voxels.slots[VOXELS_PER_CHUNK + 1].repel.is_rest(), "a rehomed chunk was passed over");
    }

    #[test]
    fn burst_bubbles_are_hidden_and_whole_ones_wobble() {
        let mut gone = Voxels::row(3, Some(BubbleState::Gone(0.5)));
        let far = Placement { ray: None, time: 0.7, ..placement(0.0, 3) };
        gone.place(&far);
        assert!(gone.looks.items[..3].iter().all(|v| !v.shows()));
        let mut whole = Voxels::row(3, Some(BubbleState::Whole));
        whole.place(&far);
        assert!(whole.looks.items[..3].iter().all(|v| v.shows()));
        let off_cell = whole.looks.items[1].position().distance(far.rotation * whole.slots[1].home.position);
        assert!(off_cell > 1e-3 && off_cell < 0.3, "wobble {off_cell}");
    }
}
