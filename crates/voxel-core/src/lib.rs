//! voxel-core: fast, robust, coloured voxelization of glTF models — the library under voxel-art.
//!
//! ```text
//! .glb/.gltf ──► import ──► TriangleSoup ──► voxelize ──► VoxelModel ──► (app, .vox export, stats)
//! ```
//! No rendering types here; deterministic whatever the thread count. The `voxel-art voxelize` command line
//! (modules `cli` and `cli_animation`, with clap and indicatif) is behind the `cli` feature, off by default.

#![warn(missing_docs)]

pub mod anim;
pub mod bvh;
#[cfg(feature = "cli")]
pub mod cli;
#[cfg(feature = "cli")]
pub mod cli_animation;
pub mod color;
mod colour_pass;
pub mod error;
pub mod export;
mod fill;
pub mod geom;
pub mod glb;
pub mod grid;
pub mod import;
pub mod inputs;
mod memory;
pub mod model;
mod orient;
mod radix;
pub mod shapes;
mod shell;
pub mod soup;
mod visible;
pub mod vox;
pub mod voxelize;

#[cfg(test)]
#[path = "../tests/support/models.rs"]
mod test_models;

pub use anim::{AnimatedModel, Bounds, ClipInfo};
pub use error::{Result, VoxelError};
pub use grid::{BitGrid, GridSize, GridSpec};
pub use import::{load_animated_file, load_animated_slice, load_file, load_slice};
pub use soup::{Material, Part, Texture, TextureBinding, TriangleSoup, Vertex, Wrap};
pub use voxelize::{
    FillMode, Method, ShellMode, Voxel, VoxelModel, VoxelStats, VoxelizeOptions, voxelize,
    voxelize_within,
};
