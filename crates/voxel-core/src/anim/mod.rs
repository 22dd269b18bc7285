//! Animated models: a glTF's node tree, skins, morph targets and clips, posed at any time of a clip into the
//! world-space [`TriangleSoup`] the voxelizer reads.
//!
//! A pose is, in the glTF order: the clip's channels set node translations, rotations, scales and morph
//! weights; node transforms compose down the tree; each primitive adds its weighted morph-target deltas to
//! its base positions; a skinned primitive is then moved by linear-blend skinning (joint matrix = the joint's
//! global transform × its inverse bind matrix; the skinned node's own transform is ignored, as the
//! specification says), any other one by its node's global transform. Colours, UVs, parts and materials stay
//! those of the static import, so colours follow the surface.
//!
//! Built by [`crate::import::load_animated_file`]; [`AnimatedModel::pose_into`] reuses its buffers, so
//! posing allocates nothing after the first frame.

mod check;
mod sampler;
mod scene;

use glam::{Mat4, Quat, Vec3};

pub use sampler::{Interpolation, Sampler};
pub use scene::{Channel, Clip, ClipInfo, Influences, Instance, Node, Primitive, Skin, Target, Trs};

use crate::error::{Result, VoxelError};
use crate::soup::TriangleSoup;

/// An axis-aligned box (min, max), as [`TriangleSoup::bounds`] returns it.
pub type Bounds = ([f32; 3], [f32; 3]);

/// Poses per second sampled (besides every keyframe time) when fitting a grid to a clip.
pub const BOUNDS_SAMPLES_PER_SECOND: f32 = 30.0;

/// The most evenly spaced poses sampled for a clip's bounds (a very long clip is sampled more sparsely).
pub const MAX_BOUNDS_SAMPLES: usize = 10_000;

/// Buffers reused from pose to pose.
#[derive(Clone, Debug, Default)]
struct Scratch {
    local: Vec<Trs>,
    weights: Vec<Vec<f32>>,
    global: Vec<Mat4>,
    joints: Vec<Mat4>,
    positions: Vec<Vec3>,
    value: Vec<f32>,
}

/// A model with its animation data, posed on demand. See the module documentation.
#[derive(Clone, Debug)]
pub struct AnimatedModel {
    rest: TriangleSoup,
    nodes: Vec<Node>,
    /// Nodes ordered parents first.
    order: Vec<usize>,
    skins: Vec<Skin>,
    primitives: Vec<Primitive>,
    instances: Vec<Instance>,
    clips: Vec<ClipInfo>,
    /// The channels of each clip.
    channels: Vec<Vec<Channel>>,
    scratch: Scratch,
}

impl AnimatedModel {
    /// A model without animation: [`AnimatedModel::clips`] is empty and only the rest soup is kept.
    pub fn still(rest: TriangleSoup) -> Self {
        Self {
            rest,
            nodes: Vec::new(),
            order: Vec::new(),
            skins: Vec::new(),
            primitives: Vec::new(),
            instances: Vec::new(),
            clips: Vec::new(),
            channels: Vec::new(),
            scratch: Scratch::default(),
        }
    }

    /// Assembles a model, checking every index (parents, skins, joints, primitives, instances, channels) and
    /// that the instances cover the rest soup's corners. `rest` is the static import (its UVs, colours,
    /// parts and materials are kept; positions are replaced by each pose).
    pub fn new(
        rest: TriangleSoup,
        nodes: Vec<Node>,
        skins: Vec<Skin>,
        primitives: Vec<Primitive>,
        instances: Vec<Instance>,
        clips: Vec<Clip>,
    ) -> Result<Self> {
        let order = parents_first(&nodes)?;
        check::skins(&skins, &nodes)?;
        check::primitives(&primitives)?;
        check::instances(&instances, &nodes, &skins, &primitives, rest.vertex_count())?;
        check::clips(&clips, &nodes)?;
        let scratch = Scratch {
            local: nodes.iter().map(|n| n.rest).collect(),
            weights: nodes.iter().map(|n| n.weights.clone()).collect(),
            global: vec![Mat4::IDENTITY; nodes.len()],
            joints: Vec::new(),
            positions: Vec::new(),
            value: Vec::new(),
        };
        let (clips, channels) = clips.into_iter().map(|c| (c.info, c.channels)).unzip();
        Ok(Self { rest, nodes, order, skins, primitives, instances, clips, channels, scratch })
    }

    /// The static import (bind pose, node transforms applied), as [`crate::load_file`] returns it.
    pub fn rest_soup(&self) -> &TriangleSoup {
        &self.rest
    }

    /// The static import, taken out of the model (what a caller keeps of a file without clips).
    pub fn into_rest_soup(self) -> TriangleSoup {
        self.rest
    }

    /// The node tree (at rest), by glTF node index.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The clips; empty when the model is not animated.
    pub fn clips(&self) -> &[ClipInfo] {
        &self.clips
    }

    /// The index of the clip named `name`, else of the clip whose index `name` spells.
    pub fn find_clip(&self, name: &str) -> Option<usize> {
        self.clips
            .iter()
            .position(|c| c.name == name)
            .or_else(|| name.parse::<usize>().ok().filter(|&i| i < self.clips.len()))
    }

    /// Poses clip `clip` at `t` seconds (wrapped into the clip: `t = duration + x` poses as `t = x`) into
    /// `out`. `out` is reset to the rest soup when it does not have its shape; pass the same soup every
    /// frame and only positions are written.
    pub fn pose_into(&mut self, clip: usize, t: f32, out: &mut TriangleSoup) -> Result<()> {
        self.sample_nodes(clip, t)?;
        let s = &mut self.scratch;
        for &n in &self.order {
            let node = &self.nodes[n];
            let local = node.matrix.unwrap_or_else(|| s.local[n].matrix());
            s.global[n] = node.parent.map_or(local, |p| s.global[p] * local);
        }
        let same_shape = out.vertex_count() == self.rest.vertex_count()
            && out.parts.len() == self.rest.parts.len()
            && out.materials.len() == self.rest.materials.len();
        if !same_shape {
            out.clone_from(&self.rest);
        }
        let positions = out.positions_mut();
        for inst in &self.instances {
            let prim = &self.primitives[inst.primitive];
            let node = &self.nodes[inst.node];
            s.positions.clear();
            s.positions.extend_from_slice(&prim.positions);
            for (target, &w) in prim.targets.iter().zip(&s.weights[inst.node]) {
                if w != 0.0 {
                    s.positions.iter_mut().zip(target).for_each(|(p, d)| *p += w * *d);
                }
            }
            match (node.skin, &prim.influences) {
                (Some(skin), Some(influences)) => {
                    let skin = &self.skins[skin];
                    s.joints.clear();
                    s.joints.extend(skin.joints.iter().zip(&skin.inverse_bind).map(|(&j, ibm)| s.global[j] * *ibm));
                    skin_positions(&mut s.positions, influences, &s.joints, s.global[inst.node]);
                }
                _ => {
                    let m = s.global[inst.node];
                    s.positions.iter_mut().for_each(|p| *p = m.transform_point3(*p));
                }
            }
            let placed = &mut positions[inst.first_vertex..inst.first_vertex + prim.vertices.len()];
            for (p, &v) in placed.iter_mut().zip(&prim.vertices) {
                *p = s.positions[v as usize].to_array();
            }
        }
        Ok(())
    }

    /// Every node's local transform in clip `clip` at `t` seconds (wrapped into the clip), by node index: the
    /// rest transform where no channel animates it (a `matrix` node keeps its rest TRS here). What a scene
    /// graph that mirrors the file's nodes sets to play the clip; [`AnimatedModel::pose_into`] composes them.
    pub fn sample_nodes(&mut self, clip: usize, t: f32) -> Result<&[Trs]> {
        check_clip(&self.clips, clip)?;
        if !t.is_finite() {
            return Err(VoxelError::Parameter(format!("pose time must be finite, got {t}")));
        }
        let duration = self.clips[clip].duration;
        let t = if duration > 0.0 { t.rem_euclid(duration) } else { 0.0 };
        let s = &mut self.scratch;
        for (n, node) in self.nodes.iter().enumerate() {
            s.local[n] = node.rest;
            s.weights[n].copy_from_slice(&node.weights);
        }
        for ch in &self.channels[clip] {
            s.value.resize(ch.sampler.width(), 0.0);
            ch.sampler.sample(t, &mut s.value);
            let v = &s.value;
            let local = &mut s.local[ch.node];
            match ch.target {
                Target::Translation => local.translation = Vec3::from_slice(v),
                Target::Rotation => local.rotation = Quat::from_slice(v),
                Target::Scale => local.scale = Vec3::from_slice(v),
                Target::Weights => s.weights[ch.node].copy_from_slice(v),
            }
        }
        Ok(&s.local)
    }

    /// The union of the bounds of clip `clip`'s poses, sampled at [`BOUNDS_SAMPLES_PER_SECOND`] (at most
    /// [`MAX_BOUNDS_SAMPLES`] poses) and at every keyframe time: the box to voxelize every frame of the clip in
    /// ([`crate::voxelize::voxelize_within`]), so the grid does not move as the pose changes.
    pub fn clip_bounds(&mut self, clip: usize) -> Result<Bounds> {
        check_clip(&self.clips, clip)?;
        let duration = self.clips[clip].duration;
        let samples = ((duration * BOUNDS_SAMPLES_PER_SECOND).ceil() as usize).min(MAX_BOUNDS_SAMPLES);
        let step = (1.0 / BOUNDS_SAMPLES_PER_SECOND).max(duration / MAX_BOUNDS_SAMPLES as f32);
        let mut times: Vec<f32> = (0..=samples).map(|i| i as f32 * step).collect();
        times.retain(|&t| t <= duration);
        times.extend(self.channels[clip].iter().flat_map(|c| c.sampler.times().iter().copied()));
        times.sort_by(f32::total_cmp);
        times.dedup();
        let mut soup = TriangleSoup::default();
        let mut union: Option<Bounds> = None;
        for t in times {
            // The clip's last key time wraps to 0; pose it as the end of the clip instead.
            let t = if t >= duration { duration.next_down() } else { t };
            self.pose_into(clip, t.max(0.0), &mut soup)?;
            let Some((lo, hi)) = soup.bounds() else { continue };
            union = Some(match union {
                None => (lo, hi),
                Some((ulo, uhi)) => {
                    (std::array::from_fn(|a| ulo[a].min(lo[a])), std::array::from_fn(|a| uhi[a].max(hi[a])))
                }
            });
        }
        union.ok_or_else(|| VoxelError::Empty(String::new()))
    }
}

/// An error naming `clip` when it is not one of `clips`.
fn check_clip(clips: &[ClipInfo], clip: usize) -> Result<()> {
    if clip < clips.len() {
        Ok(())
    } else {
        Err(VoxelError::Parameter(format!("clip {clip} does not exist (the model has {})", clips.len())))
    }
}

/// Linear-blend skinning in place: each position becomes Σ wᵢ · joint\[jᵢ\] · p / Σ wᵢ (weights that do not
/// sum to 1 are normalized); vertices without weight follow `node` (their node's global transform).
fn skin_positions(positions: &mut [Vec3], influences: &Influences, joints: &[Mat4], node: Mat4) {
    let k = influences.per_vertex;
    for (v, p) in positions.iter_mut().enumerate() {
        let range = v * k..(v + 1) * k;
        let mut blended = Mat4::ZERO;
        let mut total = 0.0;
        for (&j, &w) in influences.joints[range.clone()].iter().zip(&influences.weights[range]) {
            if w != 0.0 {
                blended += joints[usize::from(j)] * w;
                total += w;
            }
        }
        *p = if total > 0.0 { blended.transform_point3(*p) / total } else { node.transform_point3(*p) };
    }
}

/// The nodes ordered so that every parent comes before its children; a cycle is an error.
fn parents_first(nodes: &[Node]) -> Result<Vec<usize>> {
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); nodes.len()];
    let mut order = Vec::with_capacity(nodes.len());
    for (n, node) in nodes.iter().enumerate() {
        match node.parent {
            Some(p) if p < nodes.len() => children[p].push(n),
            Some(p) => return Err(VoxelError::Invalid(format!("node {n} has a missing parent {p}"))),
            None => order.push(n),
        }
    }
    let mut next = 0;
    while next < order.len() {
        order.extend_from_slice(&children[order[next]]);
        next += 1;
    }
    if order.len() != nodes.len() {
        return Err(VoxelError::Invalid("the node graph has a cycle".into()));
    }
    Ok(order)
}
