//! Integration tests of voxel-core: analytic shapes, the real models of ../shared/models, colours,
//! hostile input and .vox export. One test binary.

mod animated_export;
mod animation;
mod colors;
mod common;
mod compressed;
mod corpus;
mod errors;
mod export;
mod fine;
mod gltf_export;
mod meshopt;
mod progress;
mod read;
mod scale;
mod shapes;
mod webp;
mod winding;

#[path = "../support/scenes.rs"]
mod scenes;
