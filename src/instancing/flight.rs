//! Voxels in flight: one [`VoxelTween`] per pool slot, evaluated by the GPU. A morph writes every voxel's
//! tween once, when it starts (and its look where it lands); the vertex shaders place a voxel from its tween
//! while the frame's clock ([`GpuClock`]: seconds, the model's spin angle, the visible count) is inside it,
//! and from its look afterwards. So a morph costs the CPU nothing per frame but the clock, and the GPU buffer
//! of tweens is written once a morph. [`flown`] is the shader's curve in Rust (assets/shaders/voxel_flight.wgsl),
//! for the CPU's own questions (where is a voxel now, when a morph is re-triggered) and to test the WGSL against.

use bevy::prelude::*;
use bevy::render::storage::ShaderBuffer;
use bytemuck::{Pod, Zeroable};
use rayon::prelude::*;

use super::gpu::{GpuVoxel, Mirror, Mirrored, Piece, Record};
use super::spring::GpuSpring;
use super::{VOXELS_PER_CHUNK, VoxelMaterial, VoxelPool};

/// Back-out easing with overshoot `s` (the article's `back.out(3)`; Bevy's `BackOut` uses 1.70158).
pub fn back_out(t: f32, s: f32) -> f32 {
    let u = t.clamp(0.0, 1.0) - 1.0;
    1.0 + (s + 1.0) * u * u * u + s * u * u
}

/// What decides whether a voxel shows while it flies.
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TweenShow {
    /// A morph's voxel: the visible count (it shows while its slot is below the count).
    Count = 0,
    /// A pop: it shows throughout (its look says whether it shows once landed).
    Always = 1,
}

/// One voxel's flight (96 bytes, as the shaders read it): position (back-out) and box scale from `from` to
/// `to` in the model's frame, colour after a delay, visibility by the count or always; times in seconds after
/// `start` on the flight clock.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct VoxelTween {
    /// Start position.
    pub from: Vec3,
    /// Seconds before it moves.
    pub delay: f32,
    /// End position.
    pub to: Vec3,
    /// Seconds the move takes.
    pub duration: f32,
    /// Start box scale.
    pub from_scale: Vec3,
    /// Seconds before the colour changes.
    pub color_delay: f32,
    /// End box scale.
    pub to_scale: Vec3,
    /// Seconds the colour change takes.
    pub color_duration: f32,
    /// Start colour (sRGB RGBA8, packed).
    pub color_from: u32,
    /// End colour.
    pub color_to: u32,
    /// The flight clock's time when it began.
    pub start: f32,
    /// Seconds after `start` when every part of it is over (the look takes over).
    pub end: f32,
    /// Back-out overshoot.
    pub overshoot: f32,
    /// A [`TweenShow`].
    pub show: u32,
    /// Padding to the shader's 16-byte rows (zero).
    pub pad: [u32; 2],
}

impl VoxelTween {
    /// With its end: the last of its move, its colour change, and `also` (the spin, the visible count).
    pub fn ending(self, also: f32) -> Self {
        let end = (self.delay + self.duration).max(self.color_delay + self.color_duration).max(also);
        Self { end, ..self }
    }

    /// Position and scale `elapsed` seconds after its start.
    pub fn transform(&self, elapsed: f32) -> (Vec3, Vec3) {
        let k = back_out((elapsed - self.delay) / self.duration.max(1e-6), self.overshoot);
        (self.from.lerp(self.to, k), self.from_scale.lerp(self.to_scale, k.clamp(0.0, 1.0)))
    }

    /// Colour (packed) `elapsed` seconds after its start.
    pub fn color(&self, elapsed: f32) -> u32 {
        let t = ((elapsed - self.color_delay) / self.color_duration.max(1e-6)).clamp(0.0, 1.0);
        let (from, to) = (self.color_from.to_le_bytes(), self.color_to.to_le_bytes());
        u32::from_le_bytes(std::array::from_fn(|c| {
            (f32::from(from[c]) + (f32::from(to[c]) - f32::from(from[c])) * t).round() as u8
        }))
    }

    /// Whether slot `slot` shows while it flies at `clock`.
    pub fn shows(&self, slot: usize, clock: &GpuClock) -> bool {
        self.show != TweenShow::Count as u32 || (slot as f32) < clock.shown
    }

    /// Whether it is still in the air at clock time `time`.
    pub fn flies(&self, time: f32) -> bool {
        time - self.start < self.end
    }
}

impl Record for VoxelTween {
    /// When it is over, on the flight clock: a chunk whose weight is past has nothing in flight.
    fn weight(&self) -> f32 {
        self.start + self.end
    }

    fn bind(material: &mut VoxelMaterial, buffer: Handle<ShaderBuffer>) {
        material.extension.flights = buffer;
    }
}

/// The frame's flight clock as the shaders read it: seconds (scaled by the speed setting), the model's angle
/// about y and the visible count (slot i of a morph shows while i < `shown`), which the transition sets; and the
/// cursor in the model's frame, whose push the repel springs pull towards (placing sets it).
#[repr(C)]
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuClock {
    /// Seconds.
    pub time: f32,
    /// The model's angle about y (radians).
    pub angle: f32,
    /// The visible count.
    pub shown: f32,
    /// The cursor's reach around its ray (0: no cursor).
    pub radius: f32,
    /// The cursor ray's origin, in the model's frame.
    pub ray_origin: [f32; 3],
    /// How far the cursor pushes a voxel on its ray, as a fraction of the radius.
    pub strength: f32,
    /// The cursor ray's direction, in the model's frame.
    pub ray_direction: [f32; 3],
    /// Padding to 48 bytes (zero).
    pub pad: f32,
}

impl GpuClock {
    /// The clock at `time` with the model at `angle` and `shown` slots visible, and no cursor.
    pub fn new(time: f32, angle: f32, shown: f32) -> Self {
        Self { time, angle, shown, ..Self::default() }
    }

    /// The same clock with the cursor `ray` (in the model's frame; `None`: no cursor) reaching `radius` around
    /// it and pushing with `strength`.
    pub fn reaching(self, ray: Option<Ray3d>, radius: f32, strength: f32) -> Self {
        match ray {
            Some(ray) => Self {
                radius,
                strength,
                ray_origin: ray.origin.into(),
                ray_direction: ray.direction.as_vec3().into(),
                ..self
            },
            None => Self { radius: 0.0, strength: 0.0, ray_origin: [0.0; 3], ray_direction: [0.0; 3], ..self },
        }
    }

    /// The cursor ray (`None` without a cursor).
    pub fn ray(&self) -> Option<Ray3d> {
        let direction = Dir3::new(Vec3::from(self.ray_direction)).ok()?;
        (self.radius > 0.0).then(|| Ray3d { origin: Vec3::from(self.ray_origin), direction })
    }

    /// The cursor's push at `position` (the model's frame).
    pub fn push(&self, position: Vec3) -> Vec3 {
        super::spring::push(position, self.ray(), self.radius, self.strength)
    }
}

/// A voxel in flight as drawn at `clock`, in the model's frame: (position, box scale, colour, shows).
pub fn in_flight(tween: &VoxelTween, slot: usize, clock: &GpuClock) -> (Vec3, Vec3, u32, bool) {
    let elapsed = clock.time - tween.start;
    let (position, scale) = tween.transform(elapsed);
    (position, scale, tween.color(elapsed), tween.shows(slot, clock))
}

/// Voxel `slot` as drawn at `clock`, `look` when it is not in flight: the vertex shaders' `flown`.
pub fn flown(look: &GpuVoxel, tween: &VoxelTween, slot: usize, clock: &GpuClock) -> GpuVoxel {
    if !tween.flies(clock.time) {
        return *look;
    }
    let (position, scale, color, shows) = in_flight(tween, slot, clock);
    let placed = super::Turn::new(Quat::from_rotation_y(clock.angle)).place(position, scale, color);
    if shows { placed } else { placed.hidden() }
}

/// The voxels' flights by pool slot, the GPU buffer's mirror. A pool slot is `flying` from its tween's start
/// until every tween of its chunk is over (the GPU draws each voxel's look from its own tween's end on): landing
/// is decided a chunk at a time, from the chunk's latest end, without reading a tween.
#[derive(Resource, Debug, Default)]
pub struct VoxelTweens {
    mirror: Mirror<VoxelTween>,
    /// A flag per chunk: some slot of it may still fly.
    in_air: Vec<bool>,
}

impl Mirrored for VoxelTweens {
    type Item = VoxelTween;
    fn mirror(&self) -> &Mirror<VoxelTween> {
        &self.mirror
    }
    fn mirror_mut(&mut self) -> &mut Mirror<VoxelTween> {
        &mut self.mirror
    }
}

impl VoxelTweens {
    /// Makes room for the tweens of `slots` slots.
    pub fn reserve(&mut self, slots: usize) {
        self.mirror.reserve(slots);
        self.in_air.resize(self.mirror.items.len() / VOXELS_PER_CHUNK, false);
    }

    /// Starts `tween` on slot `slot` of `pool`.
    pub fn fly(&mut self, pool: &mut VoxelPool, slot: usize, tween: VoxelTween) {
        self.reserve(pool.slots.len());
        self.mirror.set(slot, tween);
        pool.slots[slot].flying = true;
        self.in_air[slot / VOXELS_PER_CHUNK] = true;
    }

    /// The chunks of tweens as pieces for tasks that start flights in parallel (zip them with the pool's slots
    /// chunked by [`VOXELS_PER_CHUNK`]), with each chunk's in-air flag (set it when a slot of the chunk takes off).
    pub fn pieces(&mut self) -> impl IndexedParallelIterator<Item = (Piece<'_, VoxelTween>, &mut bool)> {
        self.mirror.pieces().zip(self.in_air.par_iter_mut())
    }

    /// Slot `slot`'s tween (the last it flew).
    pub fn get(&self, slot: usize) -> Option<&VoxelTween> {
        self.mirror.items.get(slot)
    }

    /// The live flights: (slot, tween).
    pub fn flying<'a>(&'a self, pool: &'a VoxelPool) -> impl Iterator<Item = (usize, &'a VoxelTween)> + 'a {
        pool.slots.iter().zip(&self.mirror.items).enumerate().filter(|(_, (s, _))| s.flying).map(|(i, (_, t))| (i, t))
    }

    /// Lands the chunks whose tweens are all over at clock time `time`.
    pub fn land(&mut self, pool: &mut VoxelPool, time: f32) {
        for (c, slots) in pool.slots.chunks_mut(VOXELS_PER_CHUNK).enumerate() {
            if self.in_air.get(c).is_some_and(|a| *a) && self.mirror.chunk_weight(c) <= time {
                slots.iter_mut().for_each(|s| s.flying = false);
                self.in_air[c] = false;
            }
        }
    }

    /// Slot `slot`'s flight, if it is in the air at clock time `time`.
    pub fn flight(&self, pool: &VoxelPool, slot: usize, time: f32) -> Option<&VoxelTween> {
        self.get(slot).filter(|t| pool.slots[slot].flying && t.flies(time))
    }

    /// How many slots there are up to the last that shows at `clock` (searched from the end).
    pub fn showing(&self, pool: &VoxelPool, looks: &[GpuVoxel], clock: &GpuClock) -> usize {
        let shows = |i: usize| match self.flight(pool, i, clock.time) {
            Some(tween) => tween.shows(i, clock),
            None => looks[i].shows(),
        };
        (0..pool.slots.len()).rev().find(|&i| shows(i)).map_or(0, |last| last + 1)
    }

    /// Every slot of `pool` as the GPU draws it at `clock` (its flight, else its look moved by its spring).
    pub fn drawn(
        &self,
        pool: &VoxelPool,
        looks: &[GpuVoxel],
        springs: &[GpuSpring],
        clock: &GpuClock,
    ) -> Vec<GpuVoxel> {
        (0..pool.slots.len())
            .into_par_iter()
            .map(|i| match self.flight(pool, i, clock.time) {
                Some(tween) => flown(&looks[i], tween, i, clock),
                None => springs.get(i).map_or(looks[i], |s| s.sprung(&looks[i], clock)),
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn back_out_three_overshoots_and_lands_on_one() {
        assert_eq!(back_out(0.0, 3.0), 0.0);
        assert_eq!(back_out(1.0, 3.0), 1.0);
        let peak = (1..100).map(|i| back_out(i as f32 / 100.0, 3.0)).fold(0.0f32, f32::max);
        assert!(peak > 1.2, "back.out(3) peaks at {peak}");
        // Stronger than the standard 1.70158.
        let standard = (1..100).map(|i| back_out(i as f32 / 100.0, 1.70158)).fold(0.0f32, f32::max);
        assert!(peak > standard + 0.05);
        assert!((standard - 1.1).abs() < 0.01, "the standard back-out overshoots about 10 %: {standard}");
    }

    #[test]
    fn the_most_voxels_drawn_have_room_for_their_looks_and_tweens() {
        let mut pool = VoxelPool::default();
        let mut looks = super::super::GpuVoxels::default();
        super::super::grow_pool(&mut pool, &mut looks, super::super::MAX_DRAWN);
        assert!(looks.items.len() >= super::super::MAX_DRAWN && pool.slots.len() > 1_000_000);
        let mut tweens = VoxelTweens::default();
        let last = super::super::MAX_DRAWN - 1;
        tweens.fly(&mut pool, last, VoxelTween { end: 1.0, ..Default::default() });
        assert_eq!(tweens.get(last).map(|t| t.end), Some(1.0), "the last drawable slot's tween is kept");
    }

    #[test]
    fn a_tween_is_96_bytes_and_flies_from_its_start_until_its_end() {
        assert_eq!(size_of::<VoxelTween>(), 96);
        assert_eq!(size_of::<GpuClock>(), 48);
        let tween = VoxelTween {
            from: Vec3::ZERO,
            to: Vec3::X * 2.0,
            from_scale: Vec3::splat(0.1),
            to_scale: Vec3::splat(0.3),
            delay: 0.1,
            duration: 0.5,
            color_from: u32::from_le_bytes([0, 0, 0, 255]),
            color_to: u32::from_le_bytes([200, 100, 50, 255]),
            color_delay: 0.2,
            color_duration: 0.1,
            start: 10.0,
            overshoot: 3.0,
            show: TweenShow::Count as u32,
            ..Default::default()
        }
        .ending(0.8);
        assert_eq!(tween.end, 0.8, "the spin outlasts the move");
        assert!(tween.flies(10.7) && !tween.flies(10.8) && !tween.flies(11.0));
        let look = GpuVoxel { color: 7, ..Default::default() };
        let clock = |time| GpuClock::new(time, 0.0, 5.0);
        // Before its delay it sits at its start, in its start colour; at the end it has landed.
        let before = flown(&look, &tween, 3, &clock(10.05));
        assert_eq!((before.position(), before.color), (Vec3::ZERO, tween.color_from));
        assert!(before.scale().distance(Vec3::splat(0.1)) < 1e-6);
        assert_eq!(flown(&look, &tween, 3, &clock(10.8)), look);
        // Mid-colour, overshooting past its cell.
        let mid = flown(&look, &tween, 3, &clock(10.25));
        assert_eq!(mid.color.to_le_bytes(), [100, 50, 25, 255]);
        assert!(flown(&look, &tween, 3, &clock(10.45)).position().x > 2.0, "back-out overshoots");
        // The count hides a slot at or above it; the model's angle turns it.
        assert!(!flown(&look, &tween, 5, &clock(10.3)).shows());
        let turned = flown(&look, &tween, 3, &GpuClock::new(10.6, std::f32::consts::FRAC_PI_2, 5.0));
        assert!(turned.position().distance(Vec3::new(0.0, 0.0, -2.0)) < 1e-5, "{}", turned.position());
    }
}
