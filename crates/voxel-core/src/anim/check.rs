//! The consistency checks of [`super::AnimatedModel::new`]: every index in range, every length matching, so
//! that posing never indexes out of bounds.

use super::scene::{Clip, Instance, Node, Primitive, Skin, Target};
use crate::error::{Result, VoxelError};

fn invalid(message: String) -> Result<()> {
    Err(VoxelError::Invalid(message))
}

/// One inverse bind matrix per joint, joints that exist and fit the per-vertex u16 indices; node skins exist.
pub(super) fn skins(skins: &[Skin], nodes: &[Node]) -> Result<()> {
    for (s, skin) in skins.iter().enumerate() {
        if skin.joints.len() != skin.inverse_bind.len() {
            let (joints, matrices) = (skin.joints.len(), skin.inverse_bind.len());
            return invalid(format!("skin {s}: {joints} joints but {matrices} inverse bind matrices"));
        }
        if skin.joints.len() > usize::from(u16::MAX) {
            return invalid(format!("skin {s}: {} joints (at most {} are supported)", skin.joints.len(), u16::MAX));
        }
        if let Some(j) = skin.joints.iter().find(|&&j| j >= nodes.len()) {
            return invalid(format!("skin {s}: joint node {j} does not exist"));
        }
    }
    if let Some((n, _)) = nodes.iter().enumerate().find(|(_, n)| n.skin.is_some_and(|s| s >= skins.len())) {
        return invalid(format!("node {n} refers to a missing skin"));
    }
    Ok(())
}

/// Soup vertices, morph targets and skin influences match each primitive's vertex count.
pub(super) fn primitives(primitives: &[Primitive]) -> Result<()> {
    for (p, prim) in primitives.iter().enumerate() {
        let count = prim.positions.len();
        if prim.vertices.iter().any(|&v| v as usize >= count) || prim.targets.iter().any(|t| t.len() != count) {
            return invalid(format!("primitive {p}: a vertex or morph target does not match its {count} vertices"));
        }
        if let Some(inf) = &prim.influences
            && (inf.joints.len() != count * inf.per_vertex || inf.weights.len() != inf.joints.len())
        {
            return invalid(format!("primitive {p}: skin weights do not match its {count} vertices"));
        }
    }
    Ok(())
}

/// Instances name existing nodes and primitives, carry one weight per morph target and joints within their
/// skin, and cover the rest soup's `vertices` in order.
pub(super) fn instances(
    instances: &[Instance],
    nodes: &[Node],
    skins: &[Skin],
    primitives: &[Primitive],
    vertices: usize,
) -> Result<()> {
    let mut covered = 0;
    for inst in instances {
        let (Some(node), Some(prim)) = (nodes.get(inst.node), primitives.get(inst.primitive)) else {
            let (n, p) = (inst.node, inst.primitive);
            return invalid(format!("a part refers to node {n} or primitive {p} that does not exist"));
        };
        if node.weights.len() != prim.targets.len() {
            let (n, w, t) = (inst.node, node.weights.len(), prim.targets.len());
            return invalid(format!("node {n}: {w} morph weights for {t} targets"));
        }
        if let (Some(s), Some(inf)) = (node.skin, &prim.influences) {
            let joints = skins[s].joints.len();
            if let Some(j) = inf.joints.iter().find(|&&j| usize::from(j) >= joints) {
                let n = inst.node;
                return invalid(format!("node {n}: vertex joint {j} is out of range (the skin has {joints} joints)"));
            }
        }
        if inst.first_vertex != covered {
            return invalid("the animated parts do not follow the static parts".into());
        }
        covered += prim.vertices.len();
    }
    if !instances.is_empty() && covered != vertices {
        return invalid(format!("the animated parts cover {covered} of {vertices} vertices"));
    }
    Ok(())
}

/// Channels target existing TRS nodes with samplers of the property's width.
pub(super) fn clips(clips: &[Clip], nodes: &[Node]) -> Result<()> {
    for clip in clips {
        let name = &clip.info.name;
        for ch in &clip.channels {
            let Some(node) = nodes.get(ch.node) else {
                return invalid(format!("animation {name}: a channel targets missing node {}", ch.node));
            };
            let width = ch.target.width(node.weights.len());
            if ch.sampler.width() != width {
                let (target, n, found) = (ch.target, ch.node, ch.sampler.width());
                return invalid(format!(
                    "animation {name}: a {target:?} channel of node {n} has {found} values per key, expected {width}"
                ));
            }
            if node.matrix.is_some() && ch.target != Target::Weights {
                return invalid(format!("animation {name}: node {} has a matrix and cannot be animated", ch.node));
            }
        }
    }
    Ok(())
}
