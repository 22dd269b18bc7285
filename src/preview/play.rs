//! The preview tile of an animated model plays the original glTF too: the tile's scene (Bevy's glTF loader) is
//! moved node by node with the transforms the core's sampler gives for the model's clip, at the time the voxels
//! show (a tile of a model not shown keeps its own clock). Bevy's `AnimationPlayer` would need the
//! `bevy_animation` feature, which turns on a feature of `bevy_reflect` and so rebuilds all of Bevy.

use std::collections::HashMap;

use bevy::gltf::{Gltf, GltfNode};
use bevy::prelude::*;
use voxel_core::AnimatedModel;

use crate::model::ModelLibrary;
use crate::schedule::PreviewSystems;

use super::PreviewModel;

/// What plays a preview: a copy of the model's animation and the scene entity of each glTF node it moves.
#[derive(Component)]
pub struct PreviewRig {
    model: AnimatedModel,
    /// (node index, scene entity) of every node that has a TRS (a `matrix` node cannot be animated).
    targets: Vec<(usize, Entity)>,
    /// Seconds into the clip while the model is not the one shown.
    clock: f32,
}

/// A scene entity a preview rig moves.
#[derive(Component)]
pub struct PreviewJoint;

/// Rigs the preview of every animated model once its scene has spawned (nodes are found by name).
fn rig_previews(
    mut commands: Commands,
    library: Res<ModelLibrary>,
    gltfs: Res<Assets<Gltf>>,
    gltf_nodes: Res<Assets<GltfNode>>,
    previews: Query<(Entity, &PreviewModel), Without<PreviewRig>>,
    children: Query<&Children>,
    names: Query<&Name>,
) {
    for (root, preview) in &previews {
        let Some(entry) = library.entries.get(preview.0) else { continue };
        // The rig may be away in a pose job: try again next frame.
        let (Some(rig), Some(gltf)) = (entry.animation.as_ref().and_then(|a| a.rig.as_ref()), gltfs.get(&entry.gltf))
        else {
            continue;
        };
        let by_name: HashMap<&str, Entity> =
            children.iter_descendants(root).filter_map(|e| names.get(e).ok().map(|n| (n.as_str(), e))).collect();
        if by_name.is_empty() {
            continue;
        }
        let nodes = rig.model.nodes();
        let targets: Vec<(usize, Entity)> = gltf
            .nodes
            .iter()
            .filter_map(|h| gltf_nodes.get(h))
            .filter(|n| nodes.get(n.index).is_some_and(|node| node.matrix.is_none()))
            .filter_map(|n| Some((n.index, *by_name.get(n.name.as_str())?)))
            .collect();
        for (_, entity) in &targets {
            commands.entity(*entity).insert(PreviewJoint);
        }
        commands.entity(root).insert(PreviewRig { model: rig.model.clone(), targets, clock: 0.0 });
    }
}

/// Sets every rigged node's transform to the clip's at the preview's time.
fn play_previews(
    time: Res<Time>,
    library: Res<ModelLibrary>,
    mut rigs: Query<(&PreviewModel, &mut PreviewRig)>,
    mut joints: Query<&mut Transform, With<PreviewJoint>>,
) {
    for (preview, mut rig) in &mut rigs {
        let Some(playback) = library.entries.get(preview.0).and_then(|e| e.animation.as_ref()) else { continue };
        let PreviewRig { model, targets, clock } = &mut *rig;
        *clock = if preview.0 == library.current {
            playback.time
        } else if playback.playing {
            *clock + time.delta_secs() * playback.speed
        } else {
            *clock
        };
        let Ok(locals) = model.sample_nodes(playback.clip, *clock) else { continue };
        for (node, entity) in targets.iter() {
            if let (Some(local), Ok(mut transform)) = (locals.get(*node), joints.get_mut(*entity)) {
                // voxel-core and Bevy use different glam versions: through arrays.
                *transform = Transform {
                    translation: Vec3::from_array(local.translation.to_array()),
                    rotation: Quat::from_array(local.rotation.to_array()),
                    scale: Vec3::from_array(local.scale.to_array()),
                };
            }
        }
    }
}

/// The preview tiles play: rigged, then posed.
pub(super) fn systems() -> bevy::ecs::schedule::ScheduleConfigs<bevy::ecs::system::ScheduleSystem> {
    (rig_previews.in_set(PreviewSystems::Rig), play_previews.in_set(PreviewSystems::Play)).into_configs()
}
