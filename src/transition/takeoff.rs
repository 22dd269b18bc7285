//! A morph's take-off: each slot's flight is planned from where its voxel is drawn at that moment to its cell in
//! the new layout, and written once (its tween and the look it lands on). A morph of many voxels takes off a
//! batch of chunks a frame, in slot order, so no frame plans, reads or uploads more than [`CHUNKS_PER_FRAME`]
//! chunks of flights: a million voxels take off over 16 frames, each chunk from where it is when it goes.

use std::sync::Arc;

use bevy::prelude::*;
use rayon::prelude::*;

use super::TransitionSettings;
use crate::instancing::{
    GpuClock, GpuSprings, GpuVoxels, Slot, Turn, TweenShow, VOXELS_PER_CHUNK, VoxelHome, VoxelPool, VoxelTarget,
    VoxelTween, VoxelTweens, in_flight, pack_color,
};
use crate::rng::Rng;

/// Chunks of slots that take off in one frame (65,536 voxels; a morph of fewer takes off at once).
pub const CHUNKS_PER_FRAME: usize = 64;

/// The voxel state a slot is in: (position in the cloud's frame, scale, colour, visible).
pub type SlotState = (Vec3, Vec3, u32, bool);

/// Plans the tween of slot `i` from state `from` (where it is now; for a voxel joining the model, where the
/// occupied slot it comes out of is) to the new layout (random draws from `rng`), starting at clock time
/// `start`. `old_count` slots show now.
pub fn plan(
    i: usize,
    from: SlotState,
    old_count: usize,
    new: &[VoxelTarget],
    settings: &TransitionSettings,
    start: f32,
    rng: &mut Rng,
) -> Option<(VoxelTween, VoxelHome)> {
    let new_count = new.len();
    if i >= old_count.max(new_count) || new.is_empty() {
        return None;
    }
    let duration = settings.base_duration + settings.extra_duration * rng.f32().powf(settings.duration_power);
    let delay = settings.max_delay * rng.f32();
    let color_delay = settings.color_delay_factor * rng.f32() * duration;
    // A surplus voxel flies into a random occupied cell and hides as the visible count shrinks.
    let target = if i < new_count { new[i] } else { new[rng.below(new_count)] };
    // Joining and surplus voxels show or hide as the visible count passes their slot.
    let count_end = if i >= old_count.min(new_count) { settings.count_duration } else { 0.0 };
    let home = VoxelHome { position: target.position, scale: target.scale, part: target.part };
    let tween = VoxelTween {
        from: from.0,
        to: target.position,
        from_scale: from.1,
        to_scale: target.scale,
        delay,
        duration,
        color_from: from.2,
        color_to: pack_color(target.color),
        color_delay,
        color_duration: settings.color_duration,
        start,
        overshoot: settings.overshoot,
        show: TweenShow::Count as u32,
        ..Default::default()
    }
    .ending(settings.spin_duration.max(count_end));
    Some((tween, home))
}

/// Everything a morph's flights are planned from.
pub struct Flights {
    /// Slots that show when the morph begins (up to the last that shows).
    pub old_count: usize,
    /// Slots up to the last that shows or will once it lands (a voxel hidden by the visible count in flight
    /// may have a look that shows): past them, every slot stays hidden without taking part.
    pub reach: usize,
    /// The new layout.
    pub new: Arc<[VoxelTarget]>,
    /// The timings.
    pub settings: TransitionSettings,
    /// The model's turn once the spin is over: each voxel lands on its look in it.
    pub landed: Turn,
    /// The morph's random seed (each chunk of slots draws from its own generator).
    pub seed: u64,
    /// The flight clock's time when the morph began (its end is counted from it).
    pub began: f32,
}

impl Flights {
    /// The slot a voxel of slot `i` starts from: a voxel joining the model comes out of a random occupied slot.
    fn source(&self, i: usize) -> usize {
        let joins = i >= self.old_count && i < self.new.len() && self.old_count > 0;
        if joins {
            Rng::new(self.seed ^ (i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)).below(self.old_count)
        } else {
            i
        }
    }

    /// Slots that take part: every one that shows now or once landed, or has a cell in the new layout.
    fn slots(&self, pool: &VoxelPool) -> usize {
        self.reach.max(self.old_count).max(self.new.len()).min(pool.slots.len())
    }

    /// Plans the flights of the pool's slots `slots` (whole chunks, from a chunk's first slot) from their states
    /// `from` (a chunk to a task): each slot's tween, its home and the look it lands on; a slot with no part in
    /// the morph hides. Returns when the last of them lands, in seconds after `start`.
    fn plan_chunks(
        &self,
        slots: std::ops::Range<usize>,
        from: &[SlotState],
        pool: &mut VoxelPool,
        looks: &mut GpuVoxels,
        tweens: &mut VoxelTweens,
        start: f32,
    ) -> f32 {
        let chunk = slots.start / VOXELS_PER_CHUNK;
        let slots = pool.slots[slots].par_chunks_mut(VOXELS_PER_CHUNK).zip(from.par_chunks(VOXELS_PER_CHUNK));
        slots
            .zip(looks.pieces().skip(chunk))
            .zip(tweens.pieces().skip(chunk))
            .map(|(((slots, from), mut looks), (mut flights, in_air))| {
                let c = looks.start / VOXELS_PER_CHUNK;
                let mut rng = Rng::new(self.seed ^ (c as u64).wrapping_mul(0x2545_f491_4f6c_dd1d));
                let mut end = 0.0f32;
                for (i, (slot, state)) in slots.iter_mut().zip(from).enumerate() {
                    let index = looks.start + i;
                    match plan(index, *state, self.old_count, &self.new, &self.settings, start, &mut rng) {
                        Some((tween, home)) => {
                            end = end.max(tween.end);
                            *slot = Slot { home, flying: true, ..*slot };
                            *in_air = true;
                            let look = self.landed.place(tween.to, tween.to_scale, tween.color_to);
                            looks.set(i, if index < self.new.len() { look } else { look.hidden() });
                            flights.set(i, tween);
                        }
                        None => {
                            slot.flying = false;
                            let hidden = looks.items[i].hidden();
                            looks.set(i, hidden);
                        }
                    }
                }
                end
            })
            .reduce(|| 0.0, f32::max)
    }
}

/// The morph taking off: its flights and the next chunk to plan.
#[derive(Resource, Default)]
pub struct Takeoff {
    flights: Option<Flights>,
    next: usize,
    /// The states of the batch's slots (memory reused).
    from: Vec<SlotState>,
}

impl Takeoff {
    /// Starts taking off `flights` (a morph taking off still is replaced: its voxels in the air fly on from
    /// where they are).
    pub fn begin(&mut self, flights: Flights) {
        self.flights = Some(flights);
        self.next = 0;
    }

    /// Whether every slot of the morph has taken off.
    pub fn is_over(&self) -> bool {
        self.flights.is_none()
    }

    /// Plans the next [`CHUNKS_PER_FRAME`] chunks' flights from where their voxels are drawn at `clock` (the
    /// cloud turned by `turn`; a voxel the cursor pushed, where its spring has it), starting now. Returns when
    /// the last of them lands, in seconds after the morph began (0 when nothing takes off).
    pub fn next_batch(
        &mut self,
        pool: &mut VoxelPool,
        looks: &mut GpuVoxels,
        tweens: &mut VoxelTweens,
        springs: &mut GpuSprings,
        clock: &GpuClock,
        turn: Turn,
    ) -> f32 {
        let Some(flights) = &self.flights else { return 0.0 };
        let count = flights.slots(pool);
        let chunks = self.next..(self.next + CHUNKS_PER_FRAME).min(count.div_ceil(VOXELS_PER_CHUNK));
        let slots = chunks.start * VOXELS_PER_CHUNK..(chunks.end * VOXELS_PER_CHUNK).min(pool.slots.len());
        // A flight is drawn turned by the clock's angle; the states are in the cloud's frame.
        let respin = turn.rotation.inverse() * Quat::from_rotation_y(clock.angle);
        let state = |i: usize| match tweens.flight(pool, i, clock.time) {
            Some(tween) => {
                let (position, scale, color, shows) = in_flight(tween, i, clock);
                (respin * position, scale, color, shows)
            }
            None => {
                let look = looks.items[i];
                let drawn = springs.drawn(i, &look, clock);
                (turn.unturn(drawn.position()), look.scale(), look.color, look.shows())
            }
        };
        slots.clone().into_par_iter().map(|i| state(flights.source(i))).collect_into_vec(&mut self.from);
        // The flights start where the voxels are, pushed or not: their springs are spent.
        for i in slots.clone() {
            springs.clear(i, &mut pool.slots[i]);
        }
        let end = flights.plan_chunks(slots, &self.from, pool, looks, tweens, clock.time);
        let ends = clock.time - flights.began + end;
        self.next = chunks.end;
        if self.next * VOXELS_PER_CHUNK >= count {
            self.flights = None;
            pool.rehome();
        }
        ends
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::instancing::{GpuVoxel, grow_pool};

    /// `count` voxels along x at height `y`, one a slot.
    fn row(count: usize, y: f32, color: [u8; 4]) -> Vec<VoxelTarget> {
        let cell = |i: usize| Vec3::new(i as f32 * 0.01, y, 0.0);
        (0..count).map(|i| VoxelTarget { position: cell(i), scale: Vec3::splat(0.01), color, part: 0 }).collect()
    }

    #[test]
    fn a_big_morph_takes_off_a_batch_a_frame_each_from_where_it_is_then() {
        let batch = CHUNKS_PER_FRAME * VOXELS_PER_CHUNK;
        let (old_count, new_count) = (batch + 1000, 2 * batch + 10);
        let (mut pool, mut looks, mut tweens) = (VoxelPool::default(), GpuVoxels::default(), VoxelTweens::default());
        grow_pool(&mut pool, &mut looks, new_count);
        tweens.reserve(pool.slots.len());
        let turn = Turn::new(Quat::IDENTITY);
        for (i, t) in row(old_count, 1.0, [10, 20, 30, 255]).iter().enumerate() {
            looks.set(i, turn.place(t.position, t.scale, pack_color(t.color)));
        }
        let settings = TransitionSettings::default();
        let mut takeoff = Takeoff::default();
        let homes = pool.homes;
        takeoff.begin(Flights {
            old_count,
            reach: old_count,
            new: row(new_count, 3.0, [200, 0, 0, 255]).into(),
            settings: settings.clone(),
            landed: turn,
            seed: 7,
            began: 5.0,
        });
        let mut clock = GpuClock::new(5.0, 0.0, old_count as f32);
        let mut ends = Vec::new();
        for frame in 0..3 {
            assert!(!takeoff.is_over(), "frame {frame}: voxels are still to take off");
            ends.push(takeoff.next_batch(&mut pool, &mut looks, &mut tweens, &mut GpuSprings::default(), &clock, turn));
            let flying = pool.slots.iter().filter(|s| s.flying).count();
            assert_eq!(flying, ((frame + 1) * batch).min(new_count), "frame {frame}: one batch more flies");
            clock.time += 0.1;
        }
        assert!(takeoff.is_over() && pool.homes == homes + 1, "three batches, then the homes are new once");
        // Each batch starts when it goes; its end counts from the morph's start.
        let (first, second) = (tweens.get(0).unwrap(), tweens.get(batch).unwrap());
        assert_eq!((first.start, second.start), (5.0, 5.1));
        assert!(
            (ends[1] - (0.1 + (batch..2 * batch).map(|i| tweens.get(i).unwrap().end).fold(0.0, f32::max))).abs() < 1e-5
        );
        // A voxel that showed starts from its look; one joining the model comes out of an occupied slot.
        assert_eq!(second.from, Vec3::new(batch as f32 * 0.01, 1.0, 0.0));
        let joiner = tweens.get(old_count + 5).unwrap();
        // (Its slot's own look is at the origin; the occupied slot may have begun its own flight up to y = 3.)
        assert!(joiner.from.y >= 1.0 && joiner.from.x < old_count as f32 * 0.01, "{}", joiner.from);
        // Every voxel lands on its cell of the new layout, in its colour.
        let last = new_count - 1;
        assert_eq!(tweens.get(last).unwrap().to, Vec3::new(last as f32 * 0.01, 3.0, 0.0));
        assert_eq!(looks.items[last].color, pack_color([200, 0, 0, 255]));
        assert!(looks.items[new_count..].iter().all(|v: &GpuVoxel| !v.shows()), "slots past the model hide");
    }

    #[test]
    fn a_morph_of_at_most_a_batch_takes_off_at_once() {
        let (mut pool, mut looks, mut tweens) = (VoxelPool::default(), GpuVoxels::default(), VoxelTweens::default());
        grow_pool(&mut pool, &mut looks, 3000);
        tweens.reserve(pool.slots.len());
        let mut takeoff = Takeoff::default();
        let settings = TransitionSettings::default().instant();
        let new: Arc<[VoxelTarget]> = row(2000, 0.0, [1, 2, 3, 255]).into();
        let turn = Turn::new(Quat::IDENTITY);
        takeoff.begin(Flights { old_count: 0, reach: 0, new, settings, landed: turn, seed: 1, began: 0.0 });
        let end = takeoff.next_batch(
            &mut pool,
            &mut looks,
            &mut tweens,
            &mut GpuSprings::default(),
            &GpuClock::default(),
            turn,
        );
        assert!(takeoff.is_over() && end == 0.0, "an instant morph of 2,000 voxels is over in its first frame");
        assert_eq!(pool.slots.iter().filter(|s| s.flying).count(), 2000);
    }
}
