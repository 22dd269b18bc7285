//! Errors of the voxel core. Every failure on user data is one of these, never a panic.

use std::path::PathBuf;

/// Why a model could not be imported or voxelized.
#[derive(Debug, thiserror::Error)]
pub enum VoxelError {
    /// The file could not be read from disk.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file that failed.
        path: PathBuf,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// The bytes are not a valid glTF/GLB document.
    #[error("not a valid glTF file: {0}")]
    Parse(String),
    /// The file requires a glTF extension this voxelizer cannot decode.
    #[error("the file requires the glTF extension {0}, which voxel-art cannot decode (re-export the model without it)")]
    UnsupportedExtension(String),
    /// A buffer or image the document refers to is missing or unreadable.
    #[error("missing or unreadable data: {0}")]
    MissingData(String),
    /// The document is structurally wrong (bad indices, accessor sizes, recursive nodes...).
    #[error("invalid model: {0}")]
    Invalid(String),
    /// The model has no triangles to voxelize.
    #[error("the model has no triangles to voxelize{0}")]
    Empty(String),
    /// A vertex position is NaN or infinite.
    #[error("non-finite vertex position (NaN or infinity) in {0}")]
    NonFinite(String),
    /// The requested grid has more cells than the voxelizer can index ([`crate::grid::MAX_CELLS`]).
    #[error("grid {nx}x{ny}x{nz} = {cells} cells exceeds the budget of {budget} cells; use a coarser grid")]
    GridTooLarge {
        /// Cells along x.
        nx: u64,
        /// Cells along y.
        ny: u64,
        /// Cells along z.
        nz: u64,
        /// nx * ny * nz.
        cells: u64,
        /// The configured maximum.
        budget: u64,
    },
    /// The voxelization would need more memory than is available (or than the caller allows).
    #[error(
        "grid {nx}x{ny}x{nz} needs about {} MB, more than the {} MB available; use a coarser grid (or --max-memory)",
        needed.div_ceil(1_000_000),
        budget / 1_000_000
    )]
    OutOfMemory {
        /// Cells along x.
        nx: u32,
        /// Cells along y.
        ny: u32,
        /// Cells along z.
        nz: u32,
        /// The estimated peak memory in bytes.
        needed: u64,
        /// The memory available to it in bytes.
        budget: u64,
    },
    /// A parameter is out of its valid range.
    #[error("invalid parameter: {0}")]
    Parameter(String),
    /// A palette file could not be used.
    #[error("not a usable palette: {0}")]
    Palette(String),
    /// The caller cancelled the run ([`crate::progress::Progress::cancel`]).
    #[error("cancelled")]
    Cancelled,
    /// Writing an export failed.
    #[error("cannot write {path}: {reason}")]
    Export {
        /// The output path.
        path: PathBuf,
        /// What went wrong.
        reason: String,
    },
}

/// Result alias of the voxel core.
pub type Result<T, E = VoxelError> = std::result::Result<T, E>;
