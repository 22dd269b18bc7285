//! The falling style's ECS side: on entering the style (or on F) the model's voxels let go, once their morph
//! has finished, and become a [`Pile`] stepped at the fixed rate. Every solid voxel falls, the interior a hollow
//! display hides included, so the model lands as a heap with its volume (above [`FALL_CAP`] voxels, in clumps); F
//! again, another model or leaving the style sends them back to their cells (a [`Reassemble`] message: the
//! transition morphs them from where they lie).

use bevy::prelude::*;
use rayon::prelude::*;

use crate::style::ToggleFall;

use super::Style;

use crate::instancing::{
    GpuClock, GpuSprings, GpuVoxel, GpuVoxels, MAX_DRAWN, Slot, Turn, VoxelHome, VoxelPool, floor_height, grow_pool,
    pack_color, voxel_target,
};
use crate::model::{ModelLibrary, VoxelModelAsset};
use crate::schedule::StyleSystems;
use crate::settings::VoxelSettings;
use crate::transition::{ActiveTransition, Reassemble, TransitionFinished, TransitionStarted};

use super::pile::{Pile, PileParams};

/// The most bodies the pile simulates: a model with more voxels falls in clumps of neighbouring voxels (slots
/// are in Morton order, so consecutive ones are near), ⌈voxels / `FALL_CAP`⌉ a clump, each one body of the pile.
pub const FALL_CAP: usize = 25_000;

/// A voxel of the falling pile (the pile keeps them in slot order): its slot, its body in the pile and where it sits from its body (a clump's
/// voxels share a body when the model falls in clumps).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Falling {
    /// Its pool slot.
    pub slot: u32,
    /// Its body.
    pub body: u32,
    /// From the body's centre to the voxel's (zero when a voxel is its own body).
    pub offset: Vec3,
}

/// The pile in motion.
#[derive(Resource, Debug)]
pub struct FallingPile {
    /// The simulation.
    pub pile: Pile,
    /// The model the voxels belong to.
    pub model: AssetId<VoxelModelAsset>,
    /// Its voxels, in slot order.
    pub voxels: Vec<Falling>,
}

/// Whether the voxels should be falling (the style is on and F has not called them back).
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct FallRequested(pub bool);

/// The model whose morph has finished, while no other has started: the voxels rest on its cells.
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct RestingOn(pub Option<AssetId<VoxelModelAsset>>);

/// The seed of the next pile (each drop jitters differently, reproducibly).
#[derive(Resource, Debug, Default, Clone, Copy)]
pub struct PileSeed(pub u64);

/// Follows the transition's messages: the voxels rest once a morph has finished, not while one runs.
fn track_rest(
    mut started: MessageReader<TransitionStarted>,
    mut finished: MessageReader<TransitionFinished>,
    mut resting: ResMut<RestingOn>,
) {
    // Within a frame a morph starts before any finishes, so a finish read here is the latest news.
    let began = started.read().count() > 0;
    if let Some(done) = finished.read().last() {
        resting.0 = Some(done.model);
    } else if began {
        resting.0 = None;
    }
}

/// Entering the style: the voxels are to fall (once they rest).
fn request_fall(mut requested: ResMut<FallRequested>) {
    requested.0 = true;
}

/// Ends the pile: the voxels stay where they lie until the transition moves them.
fn release(commands: &mut Commands, pool: &mut VoxelPool, pile: &FallingPile) {
    for v in &pile.voxels {
        pool.slots[v.slot as usize].falling = false;
    }
    commands.remove_resource::<FallingPile>();
}

/// Leaving the style: the voxels go back to their cells.
fn reassemble_on_exit(
    mut commands: Commands,
    mut requested: ResMut<FallRequested>,
    mut pool: ResMut<VoxelPool>,
    pile: Option<Res<FallingPile>>,
    mut reassemble: MessageWriter<Reassemble>,
) {
    requested.0 = false;
    pool.held = false;
    if let Some(pile) = pile {
        release(&mut commands, &mut pool, &pile);
        reassemble.write(Reassemble);
    }
}

/// Reacts to F and model changes: lets the resting voxels go or calls them back.
fn control(
    mut commands: Commands,
    mut toggles: MessageReader<ToggleFall>,
    settings: Res<VoxelSettings>,
    library: Res<ModelLibrary>,
    models: Res<Assets<VoxelModelAsset>>,
    mut pool: ResMut<VoxelPool>,
    mut looks: ResMut<GpuVoxels>,
    mut springs: ResMut<GpuSprings>,
    clock: Res<GpuClock>,
    active: Res<ActiveTransition>,
    resting: Res<RestingOn>,
    mut requested: ResMut<FallRequested>,
    mut seed: ResMut<PileSeed>,
    pile: Option<Res<FallingPile>>,
    mut reassemble: MessageWriter<Reassemble>,
) {
    if toggles.read().count() % 2 == 1 {
        requested.0 = pile.is_none();
    }
    // An animated model's new poses wait while the voxels are to fall or lie in the pile.
    pool.held = requested.0 || pile.is_some();
    let wanted = library.current_ready(&models).map(|(id, _)| id);
    if let Some(pile) = &pile {
        // Another model (once it is ready): its morph starts from wherever the voxels lie.
        let model_changed = wanted.is_some_and(|w| w != pile.model);
        if !requested.0 || model_changed {
            release(&mut commands, &mut pool, pile);
            if model_changed {
                requested.0 = false;
            } else {
                reassemble.write(Reassemble);
            }
        }
        return;
    }
    // Let go once the shown model rests on its cells.
    let Some(id) = pool.shown.filter(|id| requested.0 && wanted == Some(*id) && resting.0 == Some(*id)) else {
        return;
    };
    // Voxels still popping (an animated model's last pose) land first.
    if pool.slots.iter().any(|s| s.flying) {
        return;
    }
    let Some(model) = models.get(id) else { return };
    // The voxels a hollow display hides fall too, from their cells, on spare slots of the pool.
    let interior: Vec<_> = if settings.hollow {
        let room = MAX_DRAWN.saturating_sub(pool.visible);
        model.voxels().filter(|v| !v.visible).take(room).map(|v| voxel_target(model, &v, settings.box_size)).collect()
    } else {
        Vec::new()
    };
    let needed = pool.visible + interior.len();
    grow_pool(&mut pool, &mut looks, needed);
    // In slot order, so the pile does not depend on anything else; a voxel the cursor pushed falls from where it
    // is.
    let turn = Turn::new(active.turn());
    let shown: Vec<(u32, Vec3)> = (0..pool.slots.len())
        .filter(|&i| !pool.slots[i].flying && looks.items[i].shows())
        .map(|i| (i as u32, springs.drawn(i, &looks.items[i], &clock).position()))
        .collect();
    if shown.is_empty() {
        return;
    }
    let first_spare = pool.visible;
    for (k, t) in interior.iter().enumerate() {
        let home = VoxelHome { position: t.position, scale: t.scale, part: t.part };
        pool.slots[first_spare + k] = Slot { home, ..Slot::default() };
        pool.rehome();
        looks.set(first_spare + k, turn.place(t.position, t.scale, pack_color(t.color)));
    }
    let members: Vec<(u32, Vec3)> = shown
        .into_iter()
        .chain(interior.iter().enumerate().map(|(k, t)| ((first_spare + k) as u32, turn.rotation * t.position)))
        .collect();
    let clump = members.len().div_ceil(FALL_CAP);
    // A clump is a body as wide as its voxels together.
    let cell = model.spec.cell.iter().copied().fold(0.0f32, f32::max) * settings.box_size * (clump as f32).cbrt();
    let params = PileParams::for_cell(cell, floor_height(model));
    let bodies = members.chunks(clump).map(|c| c[0].1).collect();
    let pile = Pile::new(bodies, params, seed.0);
    seed.0 += 1;
    let voxels = members
        .iter()
        .enumerate()
        .map(|(i, &(slot, at))| {
            let body = i / clump;
            springs.clear(slot as usize, &mut pool.slots[slot as usize]);
            pool.slots[slot as usize].falling = true;
            Falling { slot, body: body as u32, offset: at - members[body * clump].1 }
        })
        .collect();
    commands.insert_resource(FallingPile { pile, model: id, voxels });
}

/// One fixed step of the pile.
fn step(mut pile: ResMut<FallingPile>) {
    pile.pile.step();
}

/// Writes the pile's positions into the falling voxels' looks, a chunk of slots to a task (the pile's voxels
/// are in slot order).
fn sync(pile: Res<FallingPile>, mut looks: ResMut<GpuVoxels>) {
    if !pile.is_changed() {
        return;
    }
    let (voxels, positions) = (&pile.voxels, &pile.pile.positions);
    looks.pieces().for_each(|mut piece| {
        let first = voxels.partition_point(|v| (v.slot as usize) < piece.start);
        let end = piece.start + piece.items.len();
        for v in voxels[first..].iter().take_while(|v| (v.slot as usize) < end) {
            if let Some(p) = positions.get(v.body as usize) {
                let i = v.slot as usize - piece.start;
                let look = GpuVoxel { translation: (*p + v.offset).into(), ..piece.items[i] };
                piece.set(i, look);
            }
        }
    });
}

pub(super) fn plugin(app: &mut App) {
    app.init_resource::<FallRequested>();
    app.init_resource::<RestingOn>();
    app.init_resource::<PileSeed>();
    app.add_systems(OnEnter(Style::Falling), request_fall);
    app.add_systems(OnExit(Style::Falling), reassemble_on_exit);
    app.add_systems(
        Update,
        (track_rest.in_set(StyleSystems::Rest), control.run_if(in_state(Style::Falling)).in_set(StyleSystems::Control)),
    );
    app.add_systems(FixedUpdate, step.run_if(resource_exists::<FallingPile>).in_set(StyleSystems::Fall));
    app.add_systems(Update, sync.run_if(resource_exists::<FallingPile>).in_set(StyleSystems::Pile));
}
