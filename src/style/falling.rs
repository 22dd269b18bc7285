//! The falling style's ECS side: on entering the style (or on F) the shown voxels let go and become a
//! [`Pile`] stepped at a fixed rate; F again, another model or another style sends them back to their cells
//! with the transition tweens.

use bevy::prelude::*;

use crate::instancing::{VoxelCloud, VoxelPool, VoxelSlot, floor_height};
use crate::model::{ModelLibrary, VoxelModelAsset};
use crate::settings::{Style, VoxelSettings};
use crate::transition::{ActiveTransition, VoxelTween};

use super::pile::{Pile, PileParams};

/// A voxel that is part of the falling pile, with its index in it.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
pub struct Falling(pub u32);

/// The pile in motion and the voxels it moves.
#[derive(Resource, Debug)]
pub struct FallingPile {
    /// The simulation.
    pub pile: Pile,
    /// The voxel entity of each sphere.
    pub entities: Vec<Entity>,
    /// The model the voxels belong to.
    pub model: AssetId<VoxelModelAsset>,
}

/// Whether the voxels should be falling (the style is on and F has not called them back).
#[derive(Resource, Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct FallRequested(pub bool);

/// The seed of the next pile (each drop jitters differently, reproducibly).
#[derive(Resource, Debug, Default, Clone, Copy)]
pub struct PileSeed(pub u64);

/// Reacts to the style, F and model changes: lets the voxels go or calls them back.
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub(super) fn control(
    mut commands: Commands,
    keys: Res<ButtonInput<KeyCode>>,
    settings: Res<VoxelSettings>,
    library: Res<ModelLibrary>,
    models: Res<Assets<VoxelModelAsset>>,
    pool: Res<VoxelPool>,
    mut requested: ResMut<FallRequested>,
    mut active: ResMut<ActiveTransition>,
    mut seed: ResMut<PileSeed>,
    pile: Option<Res<FallingPile>>,
    voxels: Query<(Entity, &VoxelSlot, &GlobalTransform, &Visibility), (Without<VoxelTween>, Without<VoxelCloud>)>,
    falling: Query<Entity, With<Falling>>,
    mut last_style: Local<Style>,
) {
    let is_falling = settings.style == Style::Falling;
    if is_falling && *last_style != Style::Falling {
        requested.0 = true;
    }
    if !is_falling {
        requested.0 = false;
    }
    *last_style = settings.style;
    if is_falling && keys.just_pressed(KeyCode::KeyF) {
        requested.0 = pile.is_none();
    }
    let wanted = library.current_entry().and_then(|e| e.voxels.as_ref()).map(Handle::id);
    if let Some(pile) = &pile {
        let model_changed = wanted != Some(pile.model);
        if !requested.0 || model_changed {
            // Back to the cells: the transition morphs from wherever the voxels lie.
            for entity in &falling {
                commands.entity(entity).remove::<Falling>();
            }
            commands.remove_resource::<FallingPile>();
            active.restart = !model_changed;
            if model_changed {
                requested.0 = false;
            }
        }
        return;
    }
    // Let go once the shown model has settled.
    let (Some(id), true) = (pool.shown, requested.0 && active.running.is_none() && wanted == pool.shown) else {
        return;
    };
    let Some(model) = models.get(id) else { return };
    // In slot order: query order depends on how tables were rearranged, and the pile must not.
    let mut shown: Vec<(u32, Entity, Vec3)> = voxels
        .iter()
        .filter(|(_, _, _, v)| **v != Visibility::Hidden)
        .map(|(e, s, g, _)| (s.0, e, g.translation()))
        .collect();
    shown.sort_unstable_by_key(|s| s.0);
    let shown: Vec<(Entity, Vec3)> = shown.into_iter().map(|(_, e, p)| (e, p)).collect();
    if shown.is_empty() {
        return;
    }
    let cell = model.spec.cell.iter().copied().fold(0.0f32, f32::max) * settings.box_size;
    let params = PileParams::for_cell(cell, floor_height(model));
    let pile = Pile::new(shown.iter().map(|s| s.1).collect(), params, seed.0);
    seed.0 += 1;
    for (i, (entity, _)) in shown.iter().enumerate() {
        commands.entity(*entity).insert(Falling(i as u32));
    }
    commands.insert_resource(FallingPile { pile, entities: shown.into_iter().map(|s| s.0).collect(), model: id });
}

/// One fixed step of the pile.
pub(super) fn step(pile: Option<ResMut<FallingPile>>) {
    if let Some(mut pile) = pile {
        pile.pile.step();
    }
}

/// Writes the pile's positions into the falling voxels.
pub(super) fn sync(
    pile: Option<Res<FallingPile>>,
    mut voxels: Query<(&Falling, &mut Transform, &mut GlobalTransform)>,
) {
    let Some(pile) = pile else { return };
    if !pile.is_changed() {
        return;
    }
    voxels.par_iter_mut().for_each(|(falling, mut transform, mut global)| {
        if let Some(p) = pile.pile.positions.get(falling.0 as usize) {
            transform.bypass_change_detection().translation = *p;
            let mut affine = global.affine();
            affine.translation = (*p).into();
            *global = GlobalTransform::from(affine);
        }
    });
}
