//! What shapes a voxelization: the fill, shell and method modes and [`VoxelizeOptions`], which the passes and
//! the pipeline ([`voxelize`](mod@crate::voxelize)) read.

use crate::grid::GridSize;

/// How the inside of the model is found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum FillMode {
    /// Nonzero winding number per grid column: closed parts are oriented outwards (or kept as cavities)
    /// and overlapping parts stay solid; parts that cannot be oriented count by parity (see `fill`).
    #[default]
    Winding,
    /// Ray parity per grid column over the whole model (the article's rule; exact for closed models, but
    /// the overlap of two parts counts as outside).
    Parity,
    /// Everything the outside cannot reach through the surface shell (tolerates holes below a cell).
    Flood,
    /// No interior: the surface shell only.
    None,
}

/// Which surface-shell cells join the solid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum ShellMode {
    /// Only where the fill does not already represent the surface: thin parts and open sheets.
    #[default]
    Auto,
    /// Every cell a triangle touches (overshoots the volume by about half a cell all round).
    All,
    /// None: the fill alone.
    None,
}

/// Which implementation computes the winding or parity fill (all give the same cells).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum Method {
    /// Triangle-major rasterization of the column crossings.
    #[default]
    Fast,
    /// One BVH query per column.
    Bvh,
    /// The article's algorithm: one ray per cell centre against every triangle (slow; for tests).
    Reference,
}

/// Everything that shapes a voxelization.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelizeOptions {
    /// The model's bounding-box diagonal after normalization (the article's `modelSize`).
    pub model_size: f32,
    /// Cell width or resolution.
    pub grid: GridSize,
    /// Cell height / cell width (1.2 for Lego bricks).
    pub cell_height_ratio: f32,
    /// Interior mode.
    pub fill: FillMode,
    /// Shell mode.
    pub shell: ShellMode,
    /// Keep only voxels with an empty face neighbour.
    pub hollow: bool,
    /// Fill implementation.
    pub method: Method,
    /// Apply the pastel remap to colours.
    pub pastel: bool,
    /// The most memory, in bytes, a voxelization may take (estimated before it starts: grids that need more
    /// are refused with the memory they need); `None`: what the system has available.
    pub max_memory: Option<u64>,
}

impl Default for VoxelizeOptions {
    fn default() -> Self {
        Self {
            model_size: 9.0,
            grid: GridSize::default(),
            cell_height_ratio: 1.0,
            fill: FillMode::default(),
            shell: ShellMode::default(),
            hollow: false,
            method: Method::default(),
            pastel: false,
            max_memory: None,
        }
    }
}
