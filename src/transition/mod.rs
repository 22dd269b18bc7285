//! Morphs between models: every voxel flies springily from where it is to its cell in the next model
//! (the article's GSAP timings), colours flip after a random delay, the model spins and the visible count
//! follows.
//!
//! The two model-level animations, the spin and the visible count, are bevy_tweening `TweenAnim`s on
//! [`ActiveTransition`]. The per-voxel flights are not: bevy_tweening 0.16 steps every `TweenAnim` in one
//! exclusive, single-threaded system through boxed closures, measured at 14.6 ms a frame for 100k per-voxel
//! tweens against 5.0 ms for a parallel system on a component (`../shared/docs/verified-stack.md`, 2 cores).
//! Voxels are pool slots, not entities: a morph writes one [`VoxelTween`](crate::instancing::VoxelTween) per
//! slot and the look where it lands, once ([`takeoff`]: a batch of chunks a frame); the GPU draws the flight
//! from the tween at the frame's clock (the spin angle and the visible count in it), so the CPU's part of a
//! frame mid-morph is the clock and landing the voxels whose flights are over. The layout a model is shown with
//! comes from [`layout`].

pub mod layout;
pub mod takeoff;

use std::f32::consts::PI;
use std::time::Duration;

use bevy::prelude::*;
use bevy_tweening::{AnimTarget, Lens, Tween, TweenAnim, TweeningPlugin};

pub use layout::{Layouts, layout, order_targets};
pub use takeoff::{Flights, Takeoff};

use crate::instancing::{
    GpuClock, GpuSprings, GpuVoxel, GpuVoxels, PLACEHOLDER_COUNT, Turn, VoxelCloud, VoxelPool, VoxelTweens,
    apply_targets, drawn_count, pack_color, placeholder_targets,
};
use crate::model::{ModelLibrary, Recolored, VoxelModelAsset};
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

/// Starts a transition when the wanted model differs from the one shown (once it is voxelized, its layout is
/// made and the pool is big enough): its voxels take off from where they are ([`take_off`]); a running tween is
/// replaced, never stacked. While a voxelization setting is dragged the transition is instant: `step` lands
/// every voxel that took off.
fn start(
    mut commands: Commands,
    mut pool: ResMut<VoxelPool>,
    looks: Res<GpuVoxels>,
    mut tweens: ResMut<VoxelTweens>,
    clock: Res<GpuClock>,
    mut active: ResMut<ActiveTransition>,
    mut takeoff: ResMut<Takeoff>,
    mut started: MessageWriter<TransitionStarted>,
    mut reassemble: MessageReader<Reassemble>,
    (library, models): (Res<ModelLibrary>, Res<Assets<VoxelModelAsset>>),
    (settings, transition, drag): (Res<VoxelSettings>, Res<TransitionSettings>, Res<SettingDrag>),
    model_tweens: Query<Entity, With<ModelTween>>,
    (mut layouts, mut changed, mut recolored): (
        ResMut<Layouts>,
        MessageReader<AssetEvent<VoxelModelAsset>>,
        MessageReader<Recolored>,
    ),
    (mut last_look, mut restart): (Local<Option<(f32, bool)>>, Local<bool>),
) {
    layouts.forget(&mut changed);
    recolored.read().for_each(|r| layouts.forget_model(r.model));
    *restart |= reassemble.read().count() > 0;
    let Some((id, model)) = library.current_ready(&models) else { return };
    // A new box size or the hollow switch lays the model out again.
    let look = (settings.box_size, settings.hollow);
    let relook = last_look.is_some_and(|l| l != look);
    if (pool.shown == Some(id) && !relook && !*restart) || pool.slots.len() < drawn_count(model, settings.hollow) {
        return;
    }
    let transition = if drag.0 { transition.instant() } else { transition.clone() };
    // A big layout is sorted in a task: the morph starts once it is ready.
    let Some(new) = layouts.ready(id, model, &settings, &transition) else { return };
    (*last_look, *restart) = (Some(look), false);
    // Everything up to the last voxel that shows now takes part (a surplus voxel still hiding, or a joining one
    // not yet shown, is picked up where it is).
    let old_count = tweens.showing(&pool, &looks.items, &clock);
    let reach = looks.items[..pool.slots.len()].iter().rposition(GpuVoxel::shows).map_or(0, |last| last + 1);
    let (spin_angle, spin_duration, count_duration) =
        (transition.spin_angle, transition.spin_duration, transition.count_duration);
    let new_count = new.len();
    tweens.reserve(pool.slots.len());
    takeoff.begin(Flights {
        old_count,
        reach,
        new,
        // Each voxel lands on its look, in the model turned by the whole spin.
        landed: Turn::new(Quat::from_rotation_y(active.angle + spin_angle)),
        seed: active.count.wrapping_mul(0x9e37_79b9).wrapping_add(17),
        began: clock.time,
        settings: transition,
    });
    // The model-level tweens: the spin and the visible count (the last transition's are replaced).
    for tween in &model_tweens {
        commands.entity(tween).despawn();
    }
    let angle = active.angle;
    let spin = ModelLens::Spin { from: angle, to: angle + spin_angle };
    spawn_model_tween(&mut commands, &mut active, EaseFunction::QuadraticOut, spin_duration, spin);
    let count = ModelLens::Count { from: old_count as f32, to: new_count as f32 };
    spawn_model_tween(&mut commands, &mut active, EaseFunction::Linear, count_duration, count);
    pool.shown = Some(id);
    pool.visible = new_count;
    active.count += 1;
    active.running = Some((id, 0.0));
    active.elapsed = 0.0;
    started.write(TransitionStarted { model: id });
}

/// The next batch of the starting morph's voxels takes off (all of them when there are at most
/// [`takeoff::CHUNKS_PER_FRAME`] chunks); the morph ends when the last of them lands.
fn take_off(
    mut pool: ResMut<VoxelPool>,
    mut looks: ResMut<GpuVoxels>,
    mut tweens: ResMut<VoxelTweens>,
    mut springs: ResMut<GpuSprings>,
    clock: Res<GpuClock>,
    mut active: ResMut<ActiveTransition>,
    mut takeoff: ResMut<Takeoff>,
) {
    if takeoff.is_over() {
        return;
    }
    let turn = Turn::new(active.turn());
    let end = takeoff.next_batch(&mut pool, &mut looks, &mut tweens, &mut springs, &clock, turn);
    if let Some((_, last)) = &mut active.running {
        *last = last.max(end);
    }
}

/// Moves the flight clock on (after the model-level tweens: the spin and the visible count are this frame's)
/// and lands the voxels whose flights are over; the GPU draws the rest from their tweens. The morph is over
/// once every voxel has taken off and landed.
fn step(
    time: Res<Time>,
    settings: Res<VoxelSettings>,
    mut active: ResMut<ActiveTransition>,
    mut finished: MessageWriter<TransitionFinished>,
    mut pool: ResMut<VoxelPool>,
    mut tweens: ResMut<VoxelTweens>,
    mut clock: ResMut<GpuClock>,
    takeoff: Res<Takeoff>,
    mut cloud: Query<&mut Transform, With<VoxelCloud>>,
) {
    let dt = time.delta_secs() * settings.speed;
    if active.running.is_some() {
        active.elapsed += dt;
    }
    // The cursor stays as placing last set it (drawn last frame) until placing sets this frame's.
    *clock = GpuClock { time: clock.time + dt, angle: active.angle, shown: active.shown, ..*clock };
    if let Ok(mut cloud) = cloud.single_mut() {
        cloud.rotation = active.turn();
    }
    tweens.land(&mut pool, clock.time);
    if let Some((model, end)) = active.running
        && active.elapsed >= end
        && takeoff.is_over()
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
    app.init_resource::<Takeoff>();
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
            take_off.in_set(TransitionSystems::TakeOff),
            pace.in_set(TransitionSystems::Pace),
            step.in_set(TransitionSystems::Step),
            show_recolored.in_set(TransitionSystems::Recolor),
        ),
    );
}
