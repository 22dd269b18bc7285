//! An animated model's scene as plain data: the node tree, skins, primitives with their morph targets and joint
//! influences, the primitives' instances in the soup, and the clips' channels.

use glam::{Mat4, Quat, Vec3};

use super::sampler::Sampler;

/// What a caller needs to know about a clip.
#[derive(Clone, Debug, PartialEq)]
pub struct ClipInfo {
    /// The glTF animation's name (`animation <index>` when it has none).
    pub name: String,
    /// The last keyframe time in seconds; the clip loops over `0..duration`.
    pub duration: f32,
    /// The number of channels (animated node properties).
    pub channels: usize,
}

/// The node property a channel animates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// Translation (3 values).
    Translation,
    /// Rotation quaternion x, y, z, w (4 values).
    Rotation,
    /// Scale (3 values).
    Scale,
    /// Morph-target weights (one per target of the node's mesh).
    Weights,
}

impl Target {
    /// Values per keyframe: 3, 4 for a rotation, or the node's number of morph targets for weights.
    pub fn width(self, morph_targets: usize) -> usize {
        match self {
            Target::Translation | Target::Scale => 3,
            Target::Rotation => 4,
            Target::Weights => morph_targets,
        }
    }
}

/// One animated property of one node.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// The node index.
    pub node: usize,
    /// The property.
    pub target: Target,
    /// Its keyframes.
    pub sampler: Sampler,
}

/// A clip: named channels played together.
#[derive(Clone, Debug, PartialEq)]
pub struct Clip {
    /// Name, duration, channel count.
    pub info: ClipInfo,
    /// The channels.
    pub channels: Vec<Channel>,
}

/// A node's local transform as translation, rotation and scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trs {
    /// Translation.
    pub translation: Vec3,
    /// Rotation.
    pub rotation: Quat,
    /// Scale.
    pub scale: Vec3,
}

impl Trs {
    /// The local matrix T · R · S.
    pub(crate) fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

/// A node of the tree, at rest.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    /// The parent node, `None` for a root.
    pub parent: Option<usize>,
    /// The rest transform.
    pub rest: Trs,
    /// A rest matrix that replaces `rest` (glTF `matrix` nodes, which channels may not target).
    pub matrix: Option<Mat4>,
    /// Default morph weights: the node's `weights`, else its mesh's, else zeros (one per target).
    pub weights: Vec<f32>,
    /// The skin (index into the skins) that deforms the node's mesh.
    pub skin: Option<usize>,
}

/// A skin: joint nodes and their inverse bind matrices (identity when the file gives none).
#[derive(Clone, Debug, PartialEq)]
pub struct Skin {
    /// Joint node indices.
    pub joints: Vec<usize>,
    /// One inverse bind matrix per joint.
    pub inverse_bind: Vec<Mat4>,
}

/// Per-vertex skin influences: `per_vertex` (joint, weight) pairs per vertex. Weights are normalized when
/// posing; a vertex whose weights are all zero is not skinned and follows its node.
#[derive(Clone, Debug, PartialEq)]
pub struct Influences {
    /// Influences per vertex (4, or 8 with JOINTS_1/WEIGHTS_1).
    pub per_vertex: usize,
    /// Indices into the skin's joints.
    pub joints: Vec<u16>,
    /// Weights.
    pub weights: Vec<f32>,
}

/// A mesh primitive in mesh space with what deforms it.
#[derive(Clone, Debug, PartialEq)]
pub struct Primitive {
    /// Base positions.
    pub positions: Vec<Vec3>,
    /// The vertex of each soup vertex an instance of the primitive holds, in the soup's order.
    pub vertices: Vec<u32>,
    /// POSITION deltas per morph target.
    pub targets: Vec<Vec<Vec3>>,
    /// Joints and weights, when the primitive has JOINTS_0/WEIGHTS_0.
    pub influences: Option<Influences>,
}

/// One part of the soup: a primitive placed by a node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Instance {
    /// The node.
    pub node: usize,
    /// Index into the primitives.
    pub primitive: usize,
    /// The first soup vertex of the instance.
    pub first_vertex: usize,
}
