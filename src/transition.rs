//! Morphs between models: every voxel flies springily from where it is to its cell in the next model
//! (the article's GSAP timings), colours flip after a random delay, the model spins and the visible count
//! follows.
//!
//! The two model-level animations, the spin and the visible count, are bevy_tweening `TweenAnim`s on
//! [`ActiveTransition`]. The per-voxel flights are not: bevy_tweening 0.16 steps every `TweenAnim` in one
//! exclusive, single-threaded system through boxed closures, measured at 14.6 ms a frame for 100k per-voxel
//! tweens against 5.0 ms for a parallel system on a component (`../shared/docs/verified-stack.md`, 2 cores).
//! Voxels are pool slots, not entities: a morph writes one [`VoxelTween`] per slot ([`VoxelTweens`]) and the
//! look where it lands, once; the GPU draws the flight from the tween at the frame's clock (the spin angle and
//! the visible count in it), so the CPU's part of a frame mid-morph is the clock and landing the voxels whose
//! flights are over.

use std::f32::consts::PI;
use std::sync::Arc;
use std::time::Duration;

use bevy::prelude::*;
use bevy_tweening::{AnimTarget, Lens, Tween, TweenAnim, TweeningPlugin};
use rayon::prelude::*;

use crate::instancing::{
    GpuClock, GpuVoxel, GpuVoxels, PLACEHOLDER_COUNT, RepelOffset, Slot, Turn, TweenShow, VOXELS_PER_CHUNK, VoxelCloud,
    VoxelHome, VoxelPool, VoxelTarget, VoxelTween, VoxelTweens, apply_targets, drawn_count, pack_color,
    placeholder_targets, targets_for,
};
use crate::model::{ModelLibrary, Recolored, VoxelModelAsset};
use crate::rng::Rng;
use crate::schedule::TransitionSystems;
use crate::settings::{SettingDrag, VoxelSettings};

/// The article's timings (all editable in the panel).
#[derive(Resource, Clone, Debug, PartialEq, Reflect)]
#[reflect(Resource)]
pub struct TransitionSettings {
    /// Position delay: up to this many seconds (× rand).
    pub max_delay: f32,
    /// Position duration: base seconds …
    pub base_duration: f32,
    /// … plus this × rand^`duration_power`.
    pub extra_duration: f32,
    /// Exponent on the random extra duration (6 in the article: most voxels are quick, a few linger).
    pub duration_power: f32,
    /// Back-out overshoot (the article's `back.out(3)`).
    pub overshoot: f32,
    /// Colour change duration.
    pub color_duration: f32,
    /// Colour delay: up to this × rand × position duration.
    pub color_delay_factor: f32,
    /// Spin angle per transition (radians).
    pub spin_angle: f32,
    /// Spin duration (quadratic-out).
    pub spin_duration: f32,
    /// Time for the visible voxel count to reach the new model's count.
    pub count_duration: f32,
    /// How voxels are matched to cells.
    pub assignment: Assignment,
}

impl Default for TransitionSettings {
    fn default() -> Self {
        Self {
            max_delay: 0.2,
            base_duration: 0.6,
            extra_duration: 0.6,
            duration_power: 6.0,
            overshoot: 3.0,
            color_duration: 0.05,
            color_delay_factor: 0.7,
            spin_angle: 1.3 * PI,
            spin_duration: 1.2,
            count_duration: 0.4,
            assignment: Assignment::Morton,
        }
    }
}

impl TransitionSettings {
    /// The same matching with every delay and duration zero and no spin: the voxels land on their cells in the
    /// frame the transition starts. Used while a voxelization setting is dragged, so the live grid shows at once.
    pub fn instant(&self) -> Self {
        Self {
            max_delay: 0.0,
            base_duration: 0.0,
            extra_duration: 0.0,
            color_duration: 0.0,
            color_delay_factor: 0.0,
            spin_angle: 0.0,
            spin_duration: 0.0,
            count_duration: 0.0,
            ..self.clone()
        }
    }
}

/// How the voxels of the pool are matched to the cells of the next model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Reflect, clap::ValueEnum)]
pub enum Assignment {
    /// Both sorted along a Z-order (Morton) curve: nearby voxels stay together (the most coherent by eye:
    /// see docs/morph-assignment.png).
    #[default]
    Morton,
    /// Both sorted bottom to top (then by angle around the vertical axis): layers flow into layers.
    Height,
    /// The voxelizer's own cell order (x-major): visibly noisier paths.
    Grid,
}

/// Sent when a transition begins (the voxels take off for `model`'s cells).
#[derive(Message, Debug, Clone, PartialEq)]
pub struct TransitionStarted {
    /// The model being morphed to.
    pub model: AssetId<VoxelModelAsset>,
}

/// Sent when every voxel of a transition has arrived.
#[derive(Message, Debug, Clone, PartialEq)]
pub struct TransitionFinished {
    /// The model now shown.
    pub model: AssetId<VoxelModelAsset>,
}

/// Morph the voxels back to the shown model's cells from wherever they are (after falling).
#[derive(Message, Debug, Clone, Copy, PartialEq, Eq)]
pub struct Reassemble;

/// The transition in progress.
#[derive(Resource, Debug, Default)]
pub struct ActiveTransition {
    /// Transitions started so far (also the random seed of the next one).
    pub count: u64,
    /// The model being morphed to, and when the last voxel arrives (seconds of transition time).
    pub running: Option<(AssetId<VoxelModelAsset>, f32)>,
    /// Seconds since the transition started (scaled by the speed setting).
    pub elapsed: f32,
    /// The cloud's angle about y (the spin tween turns it, quadratic-out).
    pub angle: f32,
    /// How many of the pool's slots show: slot i shows while i < `shown` (the visible-count tween moves it
    /// linearly from the old model's count to the new one's).
    pub shown: f32,
}

impl ActiveTransition {
    /// The model's rotation now: the cloud's, which voxel transforms are composed with.
    pub fn turn(&self) -> Quat {
        Quat::from_rotation_y(self.angle)
    }
}

/// A model-level animation of the transition: one bevy_tweening `TweenAnim` on [`ActiveTransition`], despawned
/// when the next transition starts.
#[derive(Component, Debug)]
pub struct ModelTween;

/// What a model-level tween moves: one field of [`ActiveTransition`] from one value to another.
#[derive(Clone, Copy, Debug, PartialEq)]
enum ModelLens {
    /// The cloud's angle about y (radians).
    Spin { from: f32, to: f32 },
    /// The visible voxel count.
    Count { from: f32, to: f32 },
}

impl ModelLens {
    /// Sets the field at `ratio` (0 at the start, 1 at the end, after easing), landing exactly on the end value.
    fn apply(self, active: &mut ActiveTransition, ratio: f32) {
        let lerp = |from: f32, to: f32| from * (1.0 - ratio) + to * ratio;
        match self {
            ModelLens::Spin { from, to } => active.angle = lerp(from, to),
            ModelLens::Count { from, to } => active.shown = lerp(from, to),
        }
    }
}

impl Lens<ActiveTransition> for ModelLens {
    fn lerp(&mut self, mut target: Mut<'_, ActiveTransition>, ratio: f32) {
        self.apply(&mut target, ratio);
    }
}

/// Starts a model-level tween over `seconds` of transition time (`pace` scales it by the speed setting, as the
/// voxels' tweens are); with no time to take, the field lands at once.
fn spawn_model_tween(
    commands: &mut Commands,
    active: &mut ActiveTransition,
    ease: EaseFunction,
    seconds: f32,
    lens: ModelLens,
) {
    match Duration::try_from_secs_f32(seconds) {
        Ok(duration) if !duration.is_zero() => {
            commands.spawn((
                Name::new("model tween"),
                ModelTween,
                TweenAnim::new(Tween::new(ease, duration, lens)),
                AnimTarget::resource::<ActiveTransition>(),
            ));
        }
        _ => lens.apply(active, 1.0),
    }
}

/// The model-level tweens run at the speed setting, as the voxels' do.
fn pace(settings: Res<VoxelSettings>, mut tweens: Query<&mut TweenAnim, With<ModelTween>>) {
    for mut tween in &mut tweens {
        tween.speed = f64::from(settings.speed);
    }
}

/// A 3D Morton code of a cell-ish position (10 bits per axis).
fn morton(p: Vec3, lo: Vec3, size: f32) -> u32 {
    let spread = |v: f32| {
        let mut x = ((v / size).clamp(0.0, 1.0) * 1023.0) as u32;
        x = (x | (x << 16)) & 0x0300_00ff;
        x = (x | (x << 8)) & 0x0300_f00f;
        x = (x | (x << 4)) & 0x030c_30c3;
        (x | (x << 2)) & 0x0924_9249
    };
    let q = p - lo;
    spread(q.x) | spread(q.y) << 1 | spread(q.z) << 2
}

/// Sorts targets per the assignment so slot i of the old layout flies to a nearby rank of the new one (keys
/// computed once per target, sorted in parallel; equal keys keep their order).
pub fn order_targets(targets: &mut [VoxelTarget], assignment: Assignment) {
    match assignment {
        Assignment::Grid => {}
        Assignment::Height => {
            let angle = |p: Vec3| p.z.atan2(p.x);
            sort_by_key(targets, |t| (ordered(t.position.y), ordered(angle(t.position))));
        }
        Assignment::Morton => {
            let lo = targets.iter().fold(Vec3::splat(f32::MAX), |m, t| m.min(t.position));
            let hi = targets.iter().fold(Vec3::splat(f32::MIN), |m, t| m.max(t.position));
            let size = (hi - lo).max_element().max(1e-6);
            sort_by_key(targets, |t| morton(t.position, lo, size));
        }
    }
}

/// A float's bits in an order that agrees with `f32::total_cmp`.
fn ordered(f: f32) -> u32 {
    let bits = f.to_bits();
    if bits >> 31 == 1 { !bits } else { bits | 1 << 31 }
}

/// Sorts `targets` by `key`, stably.
fn sort_by_key<K: Ord + Send>(targets: &mut [VoxelTarget], key: impl Fn(&VoxelTarget) -> K + Sync) {
    let mut keyed: Vec<(K, u32)> = targets.par_iter().enumerate().map(|(i, t)| (key(t), i as u32)).collect();
    keyed.par_sort_unstable();
    let sorted: Vec<VoxelTarget> = keyed.iter().map(|(_, i)| targets[*i as usize]).collect();
    targets.copy_from_slice(&sorted);
}

/// The layout a model is shown with (ordered per the assignment).
pub fn layout(model: &VoxelModelAsset, settings: &VoxelSettings, transition: &TransitionSettings) -> Vec<VoxelTarget> {
    let mut targets = targets_for(model, settings.box_size, settings.hollow);
    order_targets(&mut targets, transition.assignment);
    targets
}

/// What a layout depends on besides its model's contents: the model, the box size, hollow, the assignment.
type LayoutKey = (AssetId<VoxelModelAsset>, u32, bool, Assignment);

/// The last few layouts made (a morph back to a model, a recolour and the animation's map reuse them), each
/// forgotten when its model changes.
#[derive(Resource, Debug, Default)]
pub struct Layouts(Vec<(LayoutKey, Arc<[VoxelTarget]>)>);

impl Layouts {
    /// Layouts kept.
    const KEPT: usize = 3;

    /// Model `id`'s layout (`model`) with these settings, made if it is not kept.
    pub fn of(
        &mut self,
        id: AssetId<VoxelModelAsset>,
        model: &VoxelModelAsset,
        settings: &VoxelSettings,
        transition: &TransitionSettings,
    ) -> Arc<[VoxelTarget]> {
        let key = (id, settings.box_size.to_bits(), settings.hollow, transition.assignment);
        if let Some((_, kept)) = self.0.iter().find(|(k, _)| *k == key) {
            return kept.clone();
        }
        let made: Arc<[VoxelTarget]> = layout(model, settings, transition).into();
        if self.0.len() == Self::KEPT {
            self.0.remove(0);
        }
        self.0.push((key, made.clone()));
        made
    }

    /// Forgets the layouts of the models that changed or went.
    fn forget(&mut self, events: &mut MessageReader<AssetEvent<VoxelModelAsset>>) {
        for event in events.read() {
            if let AssetEvent::Modified { id } | AssetEvent::Removed { id } | AssetEvent::Unused { id } = event {
                self.forget_model(*id);
            }
        }
    }

    /// Forgets model `id`'s layouts (its colours changed this frame: its asset event comes later).
    fn forget_model(&mut self, id: AssetId<VoxelModelAsset>) {
        self.0.retain(|((model, ..), _)| *model != id);
    }
}

/// The voxel state a slot is in now: (position in the cloud's frame, scale, colour, visible).
type SlotState = (Vec3, Vec3, u32, bool);

/// Plans the tween of slot `i` from its current state to the new layout (random draws from `rng`), starting
/// at clock time `start`.
pub fn plan(
    i: usize,
    now: SlotState,
    old: &[SlotState],
    new: &[VoxelTarget],
    settings: &TransitionSettings,
    start: f32,
    rng: &mut Rng,
) -> Option<(VoxelTween, VoxelHome)> {
    let (old_count, new_count) = (old.len(), new.len());
    if i >= old_count.max(new_count) || new.is_empty() {
        return None;
    }
    let duration = settings.base_duration + settings.extra_duration * rng.f32().powf(settings.duration_power);
    let delay = settings.max_delay * rng.f32();
    let color_delay = settings.color_delay_factor * rng.f32() * duration;
    let (mut from, mut from_scale, mut color_from, _) = now;
    let (to, to_scale, color_to, part);
    if i < new_count {
        (to, to_scale, color_to, part) = (new[i].position, new[i].scale, new[i].color, new[i].part);
        if i >= old_count {
            // A voxel joining the model: it comes out of a random occupied cell of the old one and shows up as
            // the visible count grows.
            if let Some(source) = (!old.is_empty()).then(|| old[rng.below(old.len())]) {
                (from, from_scale, color_from) = (source.0, source.1, source.2);
            }
        }
    } else {
        // A surplus voxel: it flies into a random occupied cell and hides as the visible count shrinks.
        let target = new[rng.below(new_count)];
        (to, to_scale, color_to, part) = (target.position, target.scale, target.color, target.part);
    }
    // Joining and surplus voxels show or hide as the visible count passes their slot.
    let count_end = if i >= old_count.min(new_count) { settings.count_duration } else { 0.0 };
    let home = VoxelHome { position: to, scale: to_scale, part };
    let tween = VoxelTween {
        from,
        to,
        from_scale,
        to_scale,
        delay,
        duration,
        color_from,
        color_to: pack_color(color_to),
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
struct Flights<'a> {
    /// Where the voxels that show now are (slot order, up to the last that shows).
    old: &'a [SlotState],
    /// The new layout.
    new: &'a [VoxelTarget],
    /// The timings.
    settings: &'a TransitionSettings,
    /// The clock time the morph starts.
    start: f32,
    /// The model's turn once the spin is over.
    landed: Turn,
    /// The morph's random seed (each chunk of slots draws from its own generator).
    seed: u64,
}

impl Flights<'_> {
    /// Plans every slot's flight from `now` (a chunk of slots to a task): its tween, its home and the look it
    /// lands on; a slot with no part in the morph hides. Returns when the last voxel lands.
    fn plan_all(
        &self,
        pool: &mut VoxelPool,
        now: &[SlotState],
        looks: &mut GpuVoxels,
        tweens: &mut VoxelTweens,
    ) -> f32 {
        let slots = pool.slots.par_chunks_mut(VOXELS_PER_CHUNK).zip(now.par_chunks(VOXELS_PER_CHUNK));
        slots
            .zip(looks.pieces())
            .zip(tweens.pieces())
            .enumerate()
            .map(|(c, (((slots, now), mut looks), (mut flights, in_air)))| {
                let mut rng = Rng::new(self.seed ^ (c as u64).wrapping_mul(0x2545_f491_4f6c_dd1d));
                let mut end = 0.0f32;
                for (i, (slot, state)) in slots.iter_mut().zip(now).enumerate() {
                    let index = looks.start + i;
                    // The flight starts where the voxel is now, repel displacement included: that is spent.
                    slot.repel = RepelOffset::default();
                    match plan(index, *state, self.old, self.new, self.settings, self.start, &mut rng) {
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

/// Starts a transition when the wanted model differs from the one shown (once it is voxelized and the pool
/// is big enough). Every voxel starts from where it is now; a running tween is replaced, never stacked. While a
/// voxelization setting is dragged the transition is instant: `step`, next in the chain, lands every voxel.
fn start(
    mut commands: Commands,
    mut pool: ResMut<VoxelPool>,
    mut looks: ResMut<GpuVoxels>,
    mut tweens: ResMut<VoxelTweens>,
    clock: Res<GpuClock>,
    mut active: ResMut<ActiveTransition>,
    mut started: MessageWriter<TransitionStarted>,
    mut reassemble: MessageReader<Reassemble>,
    library: Res<ModelLibrary>,
    models: Res<Assets<VoxelModelAsset>>,
    settings: Res<VoxelSettings>,
    transition: Res<TransitionSettings>,
    drag: Res<SettingDrag>,
    model_tweens: Query<Entity, With<ModelTween>>,
    (mut layouts, mut changed, mut recolored): (
        ResMut<Layouts>,
        MessageReader<AssetEvent<VoxelModelAsset>>,
        MessageReader<Recolored>,
    ),
    (mut last_look, mut now): (Local<Option<(f32, bool)>>, Local<Vec<SlotState>>),
) {
    layouts.forget(&mut changed);
    recolored.read().for_each(|r| layouts.forget_model(r.model));
    let restart = reassemble.read().count() > 0;
    let Some((id, model)) = library.current_ready(&models) else { return };
    // A new box size or the hollow switch lays the model out again.
    let look = (settings.box_size, settings.hollow);
    let relook = last_look.is_some_and(|l| l != look);
    if (pool.shown == Some(id) && !relook && !restart) || pool.slots.len() < drawn_count(model, settings.hollow) {
        return;
    }
    *last_look = Some(look);
    let transition = if drag.0 { transition.instant() } else { transition.clone() };
    let new = layouts.of(id, model, &settings, &transition);
    // Where every voxel is drawn now (in flight or not), in the cloud's frame, where tweens run.
    let turn = Turn::new(active.turn());
    tweens.drawn_into(
        &pool,
        &looks.items,
        &clock,
        |v| (turn.unturn(v.position()), v.scale(), v.color, v.shows()),
        &mut now,
    );
    // Everything up to the last voxel that shows now takes part (a surplus voxel still hiding, or a
    // joining one not yet shown, is picked up where it is).
    let old_count = now.iter().rposition(|s| s.3).map_or(0, |last| last + 1);
    let flights = Flights {
        old: &now[..old_count],
        new: &new,
        settings: &transition,
        start: clock.time,
        // Each voxel lands on its look, in the model turned by the whole spin.
        landed: Turn::new(Quat::from_rotation_y(active.angle + transition.spin_angle)),
        seed: active.count.wrapping_mul(0x9e37_79b9).wrapping_add(17),
    };
    tweens.reserve(pool.slots.len());
    let end = flights.plan_all(&mut pool, &now, &mut looks, &mut tweens);
    pool.rehome();
    // The model-level tweens: the spin and the visible count (the last transition's are replaced).
    for tween in &model_tweens {
        commands.entity(tween).despawn();
    }
    let angle = active.angle;
    let spin = ModelLens::Spin { from: angle, to: angle + transition.spin_angle };
    spawn_model_tween(&mut commands, &mut active, EaseFunction::QuadraticOut, transition.spin_duration, spin);
    let count = ModelLens::Count { from: old_count as f32, to: new.len() as f32 };
    spawn_model_tween(&mut commands, &mut active, EaseFunction::Linear, transition.count_duration, count);
    pool.shown = Some(id);
    pool.visible = new.len();
    active.count += 1;
    active.running = Some((id, end));
    active.elapsed = 0.0;
    started.write(TransitionStarted { model: id });
}

/// Moves the flight clock on (after the model-level tweens: the spin and the visible count are this frame's)
/// and lands the voxels whose flights are over; the GPU draws the rest from their tweens.
fn step(
    time: Res<Time>,
    settings: Res<VoxelSettings>,
    mut active: ResMut<ActiveTransition>,
    mut finished: MessageWriter<TransitionFinished>,
    mut pool: ResMut<VoxelPool>,
    mut tweens: ResMut<VoxelTweens>,
    mut clock: ResMut<GpuClock>,
    mut cloud: Query<&mut Transform, With<VoxelCloud>>,
) {
    let dt = time.delta_secs() * settings.speed;
    if active.running.is_some() {
        active.elapsed += dt;
    }
    *clock = GpuClock::new(clock.time + dt, active.angle, active.shown);
    if let Ok(mut cloud) = cloud.single_mut() {
        cloud.rotation = active.turn();
    }
    tweens.land(&mut pool, clock.time);
    if let Some((model, end)) = active.running
        && active.elapsed >= end
    {
        active.running = None;
        finished.write(TransitionFinished { model });
    }
}

/// Placeholder boxes bob gently while nothing is voxelized yet.
fn float_placeholder(time: Res<Time>, pool: Res<VoxelPool>, mut looks: ResMut<GpuVoxels>) {
    if pool.shown.is_some() {
        return;
    }
    let t = time.elapsed_secs();
    for slot in 0..pool.slots.len().min(PLACEHOLDER_COUNT) {
        let mut look = looks.items[slot];
        let phase = slot as f32 * 0.7;
        look.translation[1] += (t * 1.5 + phase).cos() * 0.12 * time.delta_secs();
        looks.set(slot, look);
    }
}

/// The placeholder floats until the first model arrives; it is laid out once.
fn placeholder(mut pool: ResMut<VoxelPool>, mut looks: ResMut<GpuVoxels>, mut done: Local<bool>) {
    if *done || pool.shown.is_some() || pool.slots.len() < PLACEHOLDER_COUNT {
        return;
    }
    let targets = placeholder_targets(PLACEHOLDER_COUNT, 0x5eed);
    apply_targets(&mut pool, &mut looks, &targets, Turn::new(Quat::IDENTITY));
    *done = true;
}

/// Gives the voxels of the model on screen its new colours after a recolour ([`Recolored`]): slot i keeps cell i
/// of the layout (as the morph laid them) and takes that cell's colour; only looks that change are written, so
/// only their chunks are uploaded. During a morph, once it is over (its colours were planned from the old ones).
fn show_recolored(
    mut recolored: MessageReader<Recolored>,
    mut pending: Local<Option<AssetId<VoxelModelAsset>>>,
    models: Res<Assets<VoxelModelAsset>>,
    (settings, transition, active): (Res<VoxelSettings>, Res<TransitionSettings>, Res<ActiveTransition>),
    pool: Res<VoxelPool>,
    mut looks: ResMut<GpuVoxels>,
    mut layouts: ResMut<Layouts>,
) {
    // (`start`, earlier in the frame, has forgotten the recoloured models' layouts.)
    if let Some(r) = recolored.read().filter(|r| pool.shown == Some(r.model)).last() {
        *pending = Some(r.model);
    }
    if active.running.is_some() {
        return;
    }
    let Some(id) = pending.take().filter(|id| pool.shown == Some(*id)) else { return };
    let Some(model) = models.get(id) else { return };
    for (slot, target) in layouts.of(id, model, &settings, &transition).iter().enumerate().take(pool.slots.len()) {
        let look = GpuVoxel { color: pack_color(target.color), ..looks.items[slot] };
        looks.set(slot, look);
    }
}

pub(super) fn plugin(app: &mut App) {
    app.init_resource::<TransitionSettings>();
    app.init_resource::<ActiveTransition>();
    app.init_resource::<Layouts>();
    app.add_message::<TransitionStarted>();
    app.add_message::<Reassemble>();
    app.add_message::<TransitionFinished>();
    app.add_message::<Recolored>();
    app.register_type::<TransitionSettings>();
    app.add_plugins(TweeningPlugin);
    app.add_systems(
        Update,
        (
            placeholder.in_set(TransitionSystems::Placeholder),
            float_placeholder.in_set(TransitionSystems::Float),
            start.in_set(TransitionSystems::Start),
            pace.in_set(TransitionSystems::Pace),
            step.in_set(TransitionSystems::Step),
            show_recolored.in_set(TransitionSystems::Recolor),
        ),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orders_put_layers_and_neighbourhoods_together() {
        let mut t: Vec<VoxelTarget> = [[0.0, 2.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 1.0]]
            .map(|p| VoxelTarget { position: Vec3::from(p), scale: Vec3::ONE, color: [0; 4], part: 0 })
            .to_vec();
        order_targets(&mut t, Assignment::Height);
        assert_eq!(t.iter().map(|t| t.position.y).collect::<Vec<_>>(), vec![0.0, 1.0, 2.0]);
        assert_eq!(morton(Vec3::ZERO, Vec3::ZERO, 1.0), 0);
        assert!(
            morton(Vec3::new(0.01, 0.01, 0.01), Vec3::ZERO, 1.0) < morton(Vec3::new(0.9, 0.0, 0.0), Vec3::ZERO, 1.0)
        );
    }
}
