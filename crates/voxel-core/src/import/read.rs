//! A file's bytes, read at disk speed.

use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use rayon::prelude::*;

use crate::error::{Result, VoxelError};

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
