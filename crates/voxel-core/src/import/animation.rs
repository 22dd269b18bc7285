//! Reads a glTF's animation data (node tree with rest transforms, skins, morph targets, per-vertex joints and
//! weights, clips) on top of the static import, into an [`AnimatedModel`].
//!
//! Only files with at least one animation get more than the static soup; others cost one check. Malformed
//! animation data (a sampler whose output does not match its input, a non-scalar time accessor, joint indices
//! out of range, float JOINTS, morph targets of the wrong length, a node with two parents…) is an error
//! naming the animation, skin or mesh: the caller still has [`crate::load_file`] for the static pose.
//! A skin's `skeleton` is only a hint in glTF (the joints' common root) and posing does not need it.

use std::collections::HashMap;
use std::path::Path;

use glam::{Mat4, Quat, Vec3};
use gltf::accessor::DataType;
use gltf::animation::Property;

use super::accessor;
use super::buffers::Buffers;
use super::scene::{DecodedPrimitive, PartSource, SoupBuilder, check_len, import_with};
use crate::anim::{
    AnimatedModel, Channel, Clip, ClipInfo, Influences, Instance, Interpolation, Node, Primitive, Sampler, Skin,
    Target, Trs,
};
use crate::error::{Result, VoxelError};

/// Imports a .glb or .gltf file with its animations (see [`load_animated_slice`]).
pub fn load_animated_file(path: &Path) -> Result<AnimatedModel> {
    load_animated_slice(&super::read::read_file(path)?, path.parent())
}

/// Imports glTF/GLB bytes with their animations: the static soup plus, when the file has animations, its
/// clips, node tree, skins and morph targets. A file without animations gives a model with no clips.
pub fn load_animated_slice(bytes: &[u8], base_dir: Option<&Path>) -> Result<AnimatedModel> {
    import_with(bytes, base_dir, build)
}

fn build(document: &gltf::Document, builder: SoupBuilder<'_>) -> Result<AnimatedModel> {
    let soup = builder.soup;
    if document.animations().len() == 0 {
        return Ok(AnimatedModel::still(soup));
    }
    let nodes = read_nodes(document)?;
    let skins = document.skins().map(|skin| read_skin(&skin, builder.buffers)).collect::<Result<Vec<_>>>()?;
    let mut primitives = Vec::new();
    let mut primitive_of: HashMap<(usize, usize), usize> = HashMap::new();
    let mut instances = Vec::with_capacity(builder.instances.len());
    for &PartSource { node, mesh, decoded, first_vertex } in &builder.instances {
        let primitive = match primitive_of.get(&(mesh, decoded)) {
            Some(&p) => p,
            None => {
                let decoded_prim = &builder.parts_of_mesh[&mesh][decoded];
                let gltf_mesh = document.meshes().nth(mesh).ok_or_else(|| missing("mesh", mesh))?;
                let gltf_prim = gltf_mesh
                    .primitives()
                    .nth(decoded_prim.primitive)
                    .ok_or_else(|| missing("primitive", decoded_prim.primitive))?;
                primitives.push(read_primitive(decoded_prim, &gltf_prim, builder.buffers)?);
                primitive_of.insert((mesh, decoded), primitives.len() - 1);
                primitives.len() - 1
            }
        };
        instances.push(Instance { node, primitive, first_vertex });
    }
    let clips = document
        .animations()
        .map(|animation| read_clip(&animation, &nodes, builder.buffers))
        .collect::<Result<Vec<_>>>()?;
    AnimatedModel::new(soup, nodes, skins, primitives, instances, clips)
}

fn missing(what: &str, index: usize) -> VoxelError {
    VoxelError::Invalid(format!("{what} {index} does not exist"))
}

/// Every node with its parent, rest transform, default morph weights and skin.
fn read_nodes(document: &gltf::Document) -> Result<Vec<Node>> {
    let mut parent = vec![None; document.nodes().len()];
    for node in document.nodes() {
        for child in node.children() {
            if parent[child.index()].replace(node.index()).is_some() {
                return Err(VoxelError::Invalid(format!("node {} has more than one parent", child.index())));
            }
        }
    }
    document
        .nodes()
        .map(|node| {
            let (matrix, rest) = match node.transform() {
                gltf::scene::Transform::Matrix { matrix } => (Some(Mat4::from_cols_array_2d(&matrix)), identity_trs()),
                gltf::scene::Transform::Decomposed { translation, rotation, scale } => (
                    None,
                    Trs {
                        translation: Vec3::from(translation),
                        rotation: Quat::from_array(rotation).normalize(),
                        scale: Vec3::from(scale),
                    },
                ),
            };
            if !(matrix.is_none_or(|m| m.is_finite())
                && rest.translation.is_finite()
                && rest.rotation.is_finite()
                && rest.scale.is_finite())
            {
                return Err(VoxelError::NonFinite(format!("the transform of node {}", node.index())));
            }
            let targets = node.mesh().and_then(|m| m.primitives().next()).map_or(0, |p| p.morph_targets().len());
            let weights = node
                .weights()
                .or_else(|| node.mesh().and_then(|m| m.weights()))
                .map_or_else(|| vec![0.0; targets], <[f32]>::to_vec);
            Ok(Node { parent: parent[node.index()], rest, matrix, weights, skin: node.skin().map(|s| s.index()) })
        })
        .collect()
}

fn identity_trs() -> Trs {
    Trs { translation: Vec3::ZERO, rotation: Quat::IDENTITY, scale: Vec3::ONE }
}

/// A skin's joints and inverse bind matrices (identity when absent).
fn read_skin(skin: &gltf::Skin<'_>, buffers: &Buffers<'_>) -> Result<Skin> {
    let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
    let what = format!("skin {}", skin.index());
    let inverse_bind = match skin.inverse_bind_matrices() {
        Some(acc) => {
            let matrices = accessor::read_vecs::<16>(&acc, buffers, &format!("{what} inverseBindMatrices"))?;
            if matrices.len() < joints.len() {
                return Err(VoxelError::Invalid(format!(
                    "{what}: {} inverse bind matrices for {} joints",
                    matrices.len(),
                    joints.len()
                )));
            }
            matrices.iter().take(joints.len()).map(Mat4::from_cols_array).collect()
        }
        None => vec![Mat4::IDENTITY; joints.len()],
    };
    if inverse_bind.iter().any(|m: &Mat4| !m.is_finite()) {
        return Err(VoxelError::NonFinite(format!("{what} inverse bind matrices")));
    }
    Ok(Skin { joints, inverse_bind })
}

/// A decoded primitive with its morph-target position deltas and skin influences.
fn read_primitive(
    decoded: &DecodedPrimitive<'_>,
    prim: &gltf::Primitive<'_>,
    buffers: &Buffers<'_>,
) -> Result<Primitive> {
    let name = &decoded.name;
    let count = decoded.positions.len();
    let targets = prim
        .morph_targets()
        .enumerate()
        .map(|(k, target)| match target.positions() {
            Some(acc) => {
                let deltas = accessor::read_vecs::<3>(&acc, buffers, &format!("{name} morph target {k} POSITION"))?;
                check_len(name, &format!("morph target {k}"), deltas.len(), count)?;
                if deltas.iter().flatten().any(|c| !c.is_finite()) {
                    return Err(VoxelError::NonFinite(format!("{name} morph target {k}")));
                }
                Ok(deltas.into_iter().map(Vec3::from).collect())
            }
            None => Ok(vec![Vec3::ZERO; count]),
        })
        .collect::<Result<Vec<Vec<Vec3>>>>()?;
    let mut influences: Option<Influences> = None;
    for set in 0..2 {
        let (Some(joints), Some(weights)) =
            (prim.get(&gltf::Semantic::Joints(set)), prim.get(&gltf::Semantic::Weights(set)))
        else {
            break;
        };
        if !matches!(joints.data_type(), DataType::U8 | DataType::U16) || joints.normalized() {
            return Err(VoxelError::Invalid(format!("{name}: JOINTS_{set} must be unsigned bytes or shorts")));
        }
        let joints = accessor::read_vecs::<4>(&joints, buffers, &format!("{name} JOINTS_{set}"))?;
        let weights = accessor::read_vecs::<4>(&weights, buffers, &format!("{name} WEIGHTS_{set}"))?;
        check_len(name, &format!("JOINTS_{set}"), joints.len(), count)?;
        check_len(name, &format!("WEIGHTS_{set}"), weights.len(), count)?;
        if weights.iter().flatten().any(|w| !w.is_finite() || *w < 0.0) {
            return Err(VoxelError::Invalid(format!("{name}: WEIGHTS_{set} must be finite and not negative")));
        }
        let previous = influences.take();
        let per_vertex = previous.as_ref().map_or(0, |p| p.per_vertex) + 4;
        let mut merged = Influences {
            per_vertex,
            joints: Vec::with_capacity(count * per_vertex),
            weights: Vec::with_capacity(count * per_vertex),
        };
        for v in 0..count {
            if let Some(p) = &previous {
                merged.joints.extend_from_slice(&p.joints[v * p.per_vertex..(v + 1) * p.per_vertex]);
                merged.weights.extend_from_slice(&p.weights[v * p.per_vertex..(v + 1) * p.per_vertex]);
            }
            merged.joints.extend(joints[v].map(|j| j as u16));
            merged.weights.extend_from_slice(&weights[v]);
        }
        influences = Some(merged);
    }
    Ok(Primitive {
        positions: decoded.positions.iter().map(|&p| Vec3::from(p)).collect(),
        vertices: decoded.used.clone().unwrap_or_else(|| (0..decoded.positions.len() as u32).collect()),
        targets,
        influences,
    })
}

/// One animation: its channels' samplers, checked against their nodes.
fn read_clip(animation: &gltf::Animation<'_>, nodes: &[Node], buffers: &Buffers<'_>) -> Result<Clip> {
    let name = animation.name().map_or_else(|| format!("animation {}", animation.index()), str::to_owned);
    let mut channels = Vec::new();
    for (k, channel) in animation.channels().enumerate() {
        let what = format!("animation {name} channel {k}");
        let node = channel.target().node().index();
        let sampler = channel.sampler();
        let interpolation = match sampler.interpolation() {
            gltf::animation::Interpolation::Step => Interpolation::Step,
            gltf::animation::Interpolation::Linear => Interpolation::Linear,
            gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
        };
        let times: Vec<f32> = accessor::read_vecs::<1>(&sampler.input(), buffers, &format!("{what} input"))?
            .into_iter()
            .map(|[t]| t)
            .collect();
        let output = sampler.output();
        let out_what = format!("{what} output");
        let (target, values) = match channel.target().property() {
            Property::Translation => {
                (Target::Translation, accessor::read_vecs::<3>(&output, buffers, &out_what)?.concat())
            }
            Property::Rotation => (Target::Rotation, accessor::read_vecs::<4>(&output, buffers, &out_what)?.concat()),
            Property::Scale => (Target::Scale, accessor::read_vecs::<3>(&output, buffers, &out_what)?.concat()),
            Property::MorphTargetWeights => {
                (Target::Weights, accessor::read_vecs::<1>(&output, buffers, &out_what)?.concat())
            }
        };
        let width = target.width(nodes[node].weights.len());
        if width == 0 {
            return Err(VoxelError::Invalid(format!("{what}: node {node} has no morph targets to weight")));
        }
        let sampler = Sampler::new(times, values, width, interpolation, target == Target::Rotation, &what)?;
        channels.push(Channel { node, target, sampler });
    }
    let duration = channels.iter().filter_map(|c| c.sampler.times().last()).fold(0.0f32, |a, &b| a.max(b));
    Ok(Clip { info: ClipInfo { name, duration, channels: channels.len() }, channels })
}
