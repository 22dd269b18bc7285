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
mod scene;
mod validate;
mod webp;

use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use rayon::prelude::*;

use crate::error::{Result, VoxelError};
use crate::soup::TriangleSoup;
use scene::import_with;

pub use animation::{load_animated_file, load_animated_slice};
pub use validate::MAX_TRIANGLES;

/// Imports a .glb or .gltf file (external buffers and images resolved next to it).
pub fn load_file(path: &Path) -> Result<TriangleSoup> {
    load_slice(&read_file(path)?, path.parent())
}

/// How many bytes of a file one thread reads at a time.
const READ_CHUNK: usize = 8 << 20;

/// The bytes of the file at `path`. A regular file is read in chunks on the rayon threads (its length when
/// opened, each chunk through its own handle): a big file's pages are faulted in and copied on every core at
/// once. Anything else (a pipe, `/dev/stdin`) is read once, to its end.
pub fn read_file(path: &Path) -> Result<Vec<u8>> {
    read_chunks(path).map_err(|source| VoxelError::Io { path: path.to_owned(), source })
}

fn read_chunks(path: &Path) -> std::io::Result<Vec<u8>> {
    let metadata = std::fs::metadata(path)?;
    if !metadata.is_file() {
        return std::fs::read(path);
    }
    let length = usize::try_from(metadata.len()).map_err(std::io::Error::other)?;
    let mut bytes = vec![0; length];
    bytes.par_chunks_mut(READ_CHUNK).enumerate().try_for_each(|(i, chunk)| {
        let mut file = std::fs::File::open(path)?;
        file.seek(SeekFrom::Start((i * READ_CHUNK) as u64))?;
        file.read_exact(chunk)
    })?;
    Ok(bytes)
}

/// Imports glTF/GLB bytes; `base_dir` resolves relative URIs (none: only embedded data is allowed).
pub fn load_slice(bytes: &[u8], base_dir: Option<&Path>) -> Result<TriangleSoup> {
    import_with(bytes, base_dir, |_, builder| Ok(builder.soup))
}
