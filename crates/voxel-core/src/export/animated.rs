//! One animated glTF of a clip's voxel frames: each frame a node with its own mesh (greedy rectangles, as
//! [`super::gltf`] writes one model), all under one node that undoes the normalization, and one animation
//! whose STEP channels scale the frame shown to 1 and every other to 0, in turn. Any glTF viewer that plays
//! animations plays the frames; one that does not shows the first. The frames share the plain material and
//! one buffer.

use std::path::Path;

use gltf::json::{self, validation::Checked::Valid};

use super::Format;
use super::gltf::{Builder, ExportOptions, MeshStats};
use crate::error::{Result, VoxelError};
use crate::grid::GridSpec;
use crate::model::VoxelModel;

/// Builds an animated glTF frame by frame (each frame is meshed when it is added, so only the meshes are
/// kept).
pub struct AnimatedGltf {
    builder: Builder,
    /// The frames' nodes and times, in order.
    frames: Vec<(json::Index<json::Node>, f32)>,
    /// The frames' grid (every frame of a clip shares it): it places the whole animation.
    spec: Option<GridSpec>,
    stats: MeshStats,
    name: String,
}

impl AnimatedGltf {
    /// An empty animation named `options.name`.
    pub fn new(options: &ExportOptions) -> Self {
        Self {
            builder: Builder::new(),
            frames: Vec::new(),
            spec: None,
            stats: MeshStats::default(),
            name: options.name.clone(),
        }
    }

    /// Adds `model` as the frame shown from `time` seconds on (times ascending; the models in one grid).
    pub fn push_frame(&mut self, model: &VoxelModel, time: f32) -> Result<()> {
        if self.spec.is_some_and(|spec| spec != model.spec) {
            return Err(VoxelError::Parameter("the frames of one animated glTF must share one grid".into()));
        }
        // NaN fails this too.
        if self.frames.last().is_some_and(|&(_, last)| time.partial_cmp(&last) != Some(std::cmp::Ordering::Greater)) {
            return Err(VoxelError::Parameter(format!("frame times must ascend ({time} s)")));
        }
        let name = format!("{}-{:04}", self.name, self.frames.len());
        let (mesh, stats) = self.builder.mesh(model, &name);
        // Only the first frame shows when the animation does not play.
        let scale = if self.frames.is_empty() { None } else { Some([0.0; 3]) };
        let node = self.builder.root.push(json::Node { name: Some(name), mesh, scale, ..Default::default() });
        self.frames.push((node, time));
        self.stats.faces += stats.faces;
        self.stats.quads += stats.quads;
        self.stats.vertices += stats.vertices;
        self.spec.get_or_insert(model.spec);
        Ok(())
    }

    /// The document: the frames under one placed node and the animation `clip`, which loops after
    /// `duration` seconds (the last frame shows until then). `bytes` in the stats is 0.
    fn document(mut self, clip: &str, duration: f32) -> Result<(json::Root, Vec<u8>, MeshStats)> {
        let Some(spec) = self.spec.take() else {
            return Err(VoxelError::Parameter("an animation needs one frame or more".into()));
        };
        let last = self.frames.last().map_or(0.0, |&(_, t)| t);
        let end = if duration > last { duration } else { last + 1.0 / 30.0 };
        // One key per frame, and one at the end that repeats the first frame's (it only sets the length).
        let times: Vec<f32> = self.frames.iter().map(|&(_, t)| t).chain([end]).collect();
        let input = self.builder.scalars(&times);
        let mut animation = json::Animation {
            extensions: None,
            extras: Default::default(),
            channels: Vec::new(),
            name: Some(clip.into()),
            samplers: Vec::new(),
        };
        let count = self.frames.len();
        for (k, &(node, _)) in self.frames.iter().enumerate() {
            let scales: Vec<[f32; 3]> =
                (0..=count).map(|key| if key % count == k { [1.0; 3] } else { [0.0; 3] }).collect();
            let output = self.builder.vec3s(&scales, false, false);
            animation.channels.push(json::animation::Channel {
                sampler: json::Index::new(animation.samplers.len() as u32),
                target: json::animation::Target {
                    extensions: None,
                    extras: Default::default(),
                    node,
                    path: Valid(json::animation::Property::Scale),
                },
                extensions: None,
                extras: Default::default(),
            });
            animation.samplers.push(json::animation::Sampler {
                extensions: None,
                extras: Default::default(),
                input,
                interpolation: Valid(json::animation::Interpolation::Step),
                output,
            });
        }
        self.builder.root.push(animation);
        let children = self.frames.iter().map(|&(node, _)| node).collect();
        let name = self.name.clone();
        let root_node = self.builder.placed_node(&spec, &name, None, Some(children));
        let (root, bin) = self.builder.finish(root_node);
        Ok((root, bin, self.stats))
    }

    /// Writes the animation `clip` (looping after `duration` seconds) to `path` as .glb, or as .gltf with a
    /// .bin beside it, by `format`.
    pub fn write(self, path: &Path, format: Format, clip: &str, duration: f32) -> Result<MeshStats> {
        let (root, bin, stats) = self.document(clip, duration)?;
        match format {
            Format::Gltf => super::gltf::write_document(root, bin, stats, path),
            Format::Glb | Format::Vox => super::gltf::write_glb_document(&root, &bin, stats, path),
        }
    }
}
