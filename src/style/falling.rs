//! The falling style's ECS side: on entering the style (or on F) the model's voxels let go, once their morph
//! has finished, and become a [`Pile`] stepped at the fixed rate. Every solid voxel falls, the interior a hollow
//! display hides included, so the model lands as a heap with its volume (above [`FALL_CAP`] voxels, in clumps); F
//! again, another model or leaving the style sends them back to their cells (a [`Reassemble`] message: the
//! transition morphs them from where they lie).

use bevy::prelude::*;

use crate::style::ToggleFall;
use bevy::mesh::MeshTag;

use super::Style;
use crate::instancing::{
    MAX_DRAWN, RepelOffset, VoxelCloud, VoxelHome, VoxelPool, VoxelSlot, floor_height, grow_pool, pack_color,
    voxel_target, voxel_transform,
};
use crate::model::{ModelLibrary, VoxelModelAsset};
use crate::schedule::{AppSystems, StyleSystems};
use crate::settings::VoxelSettings;
use crate::transition::{ActiveTransition, Reassemble, TransitionFinished, TransitionStarted, VoxelTween};

use super::pile::{Pile, PileParams};

/// The most bodies the pile simulates: a model with more voxels falls in clumps of neighbouring voxels (slots
/// are in Morton order, so consecutive ones are near), ⌈voxels / `FALL_CAP`⌉ a clump, each one body of the pile.
pub const FALL_CAP: usize = 100_000;

/// A voxel that is part of the falling pile, with the index of its body in it.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
pub struct Falling(pub u32);

/// Where a voxel of a clump sits from its clump's body (only when the model falls in clumps).
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct ClumpOffset(pub Vec3);

/// The pile in motion.
#[derive(Resource, Debug)]
pub struct FallingPile {
    /// The simulation.
    pub pile: Pile,
    /// The model the voxels belong to.
    pub model: AssetId<VoxelModelAsset>,
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
fn release(commands: &mut Commands, falling: &Query<Entity, With<Falling>>) {
    for entity in falling {
        commands.entity(entity).remove::<(Falling, ClumpOffset)>();
    }
    commands.remove_resource::<FallingPile>();
}

/// Leaving the style: the voxels go back to their cells.
fn reassemble_on_exit(
    mut commands: Commands,
    mut requested: ResMut<FallRequested>,
    mut pool: ResMut<VoxelPool>,
    pile: Option<Res<FallingPile>>,
    falling: Query<Entity, With<Falling>>,
    mut reassemble: MessageWriter<Reassemble>,
) {
    requested.0 = false;
    pool.held = false;
    if pile.is_some() {
        release(&mut commands, &falling);
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
    active: Res<ActiveTransition>,
    resting: Res<RestingOn>,
    mut requested: ResMut<FallRequested>,
    mut seed: ResMut<PileSeed>,
    pile: Option<Res<FallingPile>>,
    voxels: Query<(Entity, &VoxelSlot, &GlobalTransform, &Visibility), (Without<VoxelTween>, Without<VoxelCloud>)>,
    tweening: Query<(), With<VoxelTween>>,
    falling: Query<Entity, With<Falling>>,
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
            release(&mut commands, &falling);
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
    if !tweening.is_empty() {
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
    if pool.slots.len() < needed {
        // The new slots exist from the next frame on.
        grow_pool(&mut commands, &mut pool, needed);
        return;
    }
    // In slot order: query order depends on how tables were rearranged, and the pile must not.
    let mut shown: Vec<(u32, Entity, Vec3)> = voxels
        .iter()
        .filter(|(_, _, _, v)| **v != Visibility::Hidden)
        .map(|(e, s, g, _)| (s.0, e, g.translation()))
        .collect();
    shown.sort_unstable_by_key(|s| s.0);
    if shown.is_empty() {
        return;
    }
    let turn = active.turn();
    let starts: Vec<Vec3> = shown.iter().map(|s| s.2).chain(interior.iter().map(|t| turn * t.position)).collect();
    let clump = starts.len().div_ceil(FALL_CAP);
    // A clump is a body as wide as its voxels together.
    let cell = model.spec.cell.iter().copied().fold(0.0f32, f32::max) * settings.box_size * (clump as f32).cbrt();
    let params = PileParams::for_cell(cell, floor_height(model));
    let bodies = starts.chunks(clump).map(|c| c[0]).collect();
    let pile = Pile::new(bodies, params, seed.0);
    seed.0 += 1;
    let place = |commands: &mut Commands, entity: Entity, i: usize| {
        let body = i / clump;
        commands.entity(entity).insert(Falling(body as u32));
        if clump > 1 {
            commands.entity(entity).insert(ClumpOffset(starts[i] - starts[body * clump]));
        }
    };
    for (i, (_, entity, _)) in shown.iter().enumerate() {
        place(&mut commands, *entity, i);
    }
    for (k, t) in interior.iter().enumerate() {
        let entity = pool.slots[pool.visible + k];
        commands.entity(entity).insert((
            voxel_transform(turn, t.position, t.scale),
            MeshTag(pack_color(t.color)),
            Visibility::Inherited,
            VoxelHome { position: t.position, scale: t.scale, part: t.part },
            RepelOffset::default(),
        ));
        place(&mut commands, entity, shown.len() + k);
    }
    commands.insert_resource(FallingPile { pile, model: id });
}

/// One fixed step of the pile.
fn step(mut pile: ResMut<FallingPile>) {
    pile.pile.step();
}

/// Writes the pile's positions into the falling voxels (their global transform too: voxels have no parent).
fn sync(
    pile: Res<FallingPile>,
    mut voxels: Query<(&Falling, Option<&ClumpOffset>, &mut Transform, &mut GlobalTransform)>,
) {
    if !pile.is_changed() {
        return;
    }
    voxels.par_iter_mut().for_each(|(falling, offset, mut transform, mut global)| {
        if let Some(p) = pile.pile.positions.get(falling.0 as usize) {
            let transform = transform.bypass_change_detection();
            transform.translation = *p + offset.map_or(Vec3::ZERO, |o| o.0);
            *global = GlobalTransform::from(*transform);
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
    app.add_systems(Update, sync.run_if(resource_exists::<FallingPile>).in_set(AppSystems::Sync));
}
