//! glTF 2.0 import (through the `gltf` crate) into a world-space [`TriangleSoup`].
//!
//! Handles .glb, .gltf with external buffers and images, data URIs, the default scene's node hierarchy
//! (matrix or TRS, shared meshes), triangle lists/strips/fans, KHR_mesh_quantization, KHR_draco_mesh_compression,
//! EXT_meshopt_compression and EXT_texture_webp. Files that require an extension we cannot decode are refused with
//! an error naming it; malformed files are refused with an error naming what is wrong (see the `validate` module).

mod accessor;
mod animation;
mod buffers;
mod draco;
mod materials;
mod read;
mod scene;
mod validate;
mod webp;

use std::path::Path;

use crate::error::Result;
use crate::soup::TriangleSoup;
use scene::import_with;

pub use animation::{load_animated_file, load_animated_slice};
pub use read::read_file;
pub use validate::MAX_TRIANGLES;

/// Imports a .glb or .gltf file (external buffers and images resolved next to it).
pub fn load_file(path: &Path) -> Result<TriangleSoup> {
    load_slice(&read_file(path)?, path.parent())
}

/// Imports glTF/GLB bytes; `base_dir` resolves relative URIs (none: only embedded data is allowed).
pub fn load_slice(bytes: &[u8], base_dir: Option<&Path>) -> Result<TriangleSoup> {
    import_with(bytes, base_dir, |_, builder| Ok(builder.soup))
}
