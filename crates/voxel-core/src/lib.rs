//! voxel-core: fast, robust, coloured voxelization of glTF models — the library under voxel-art.
//!
//! ```text
//! .glb/.gltf ──► import ──► TriangleSoup ──► voxelize ──► VoxelModel ──► (app, .vox and glTF export, stats)
//! ```
//! No rendering types here; deterministic whatever the thread count. The `voxel-art voxelize` command line
//! (the `cli` module, with clap and indicatif) is behind the `cli` feature, off by default.
//!
//! A shape in, voxels out:
//!
//! ```
//! use voxel_core::{GridSize, TriangleSoup, VoxelizeOptions, shapes::cuboid, voxelize};
//!
//! // A unit cube, orange (linear RGBA), in a grid of 8 cells along its longest side.
//! let cube = TriangleSoup::from_mesh(&cuboid([0.0; 3], [1.0; 3]), [1.0, 0.5, 0.2, 1.0]);
//! let model = voxelize(&cube, &VoxelizeOptions { grid: GridSize::Resolution(8), ..Default::default() })?;
//! assert_eq!(model.stats.grid, [8, 8, 8]);
//! assert_eq!(model.stats.voxels, 8 * 8 * 8);
//! assert_eq!(model.stats.visible, 8 * 8 * 8 - 6 * 6 * 6); // the 6³ inside have no empty neighbour
//! assert!(model.voxels().all(|v| v.color == [255, 188, 124, 255])); // sRGB
//! # Ok::<(), voxel_core::VoxelError>(())
//! ```
//!
//! # Layers
//!
//! Top to bottom, each module imports only from the layers below it or from earlier entries of its own layer
//! (`tests/layers.rs` walks the imports and fails on any circle):
//!
//! * **Command line** (feature `cli`): `cli` (`mod.rs` parses and runs; its `animation`, `palette` and `report`
//!   below it).
//! * **Beside the pipeline**: [`anim`] (posing), [`import`] (glTF → soup: its `scene` below its `animation`),
//!   [`vox`], [`palette`] (the colour stage after sampling; reads .vox palettes), [`export`] (the glTF mesh, one
//!   animated glTF of a clip's frames, and .vox through [`vox`]), [`files`] (finding model files).
//! * **Pipeline**: [`voxelize`](mod@voxelize).
//! * **Passes**: `columns` (column crossings and how they count), `orient` (closed parts and their facing:
//!   `parts`, `soup_parts`, `edges`, `weld`), `fill`, `shell` (`cells`, `octree`), `visible`, `color_pass`, `memory` (the budget).
//! * **Leaf types**: [`error`], `float` (rounding without libm), [`geom`] (exact predicates), `radix`, [`shapes`], [`soup`] (the
//!   input), [`grid`] (the grid, its triangles, the bit grid), [`options`], [`progress`] (stages, cancelling), [`bvh`],
//!   [`color`] (sampling, sRGB, pastel),
//!   [`model`] (the output), [`glb`].
//!
//! A soup keeps one value derived from its positions, the winding fill's closed parts, in a slot whose type
//! belongs to `orient` ([`soup`] holds it without knowing it), so the app's grid changes analyse a model once.

#![warn(missing_docs)]

pub mod anim;
pub mod bvh;
#[cfg(feature = "cli")]
pub mod cli;
pub mod color;
mod color_pass;
mod columns;
mod distinct;
pub mod error;
pub mod export;
pub mod files;
mod fill;
mod float;
pub mod geom;
pub mod glb;
pub mod grid;
pub mod import;
#[cfg(test)]
mod lcg;
mod memory;
pub mod model;
pub mod options;
mod orient;
pub mod palette;
pub mod progress;
mod radix;
pub mod shapes;
mod shell;
pub mod soup;
pub mod srgb;
mod visible;
pub mod vox;
pub mod voxelize;

#[cfg(test)]
#[path = "../tests/support/models.rs"]
mod test_models;

pub use anim::{AnimatedModel, Bounds, ClipInfo};
pub use error::{Result, VoxelError};
pub use grid::{BitGrid, GridSize, GridSpec, GridTriangles};
pub use import::{load_animated_file, load_animated_slice, load_file, load_slice, read_file};
pub use model::{Voxel, VoxelModel, VoxelStats};
pub use options::{FillMode, Method, ShellMode, VoxelizeOptions};
pub use progress::{Progress, Stage};
pub use soup::{Material, Part, Texture, TextureBinding, TriangleSoup, Vertex, Wrap};
pub use voxelize::{voxelize, voxelize_watched, voxelize_within};
