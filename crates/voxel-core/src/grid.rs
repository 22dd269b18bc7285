//! The voxel grid: normalization of the model (the article's `modelSize` scaling), cell sizes, the largest
//! cell count a grid may have (the voxelizer's budget is memory: `memory.rs`), and a packed bit set over cells.

use std::borrow::Cow;

use glam::DVec3;
use rayon::prelude::*;

use crate::error::{Result, VoxelError};
use crate::float;
use crate::geom::GridTriangle;
use crate::soup::TriangleSoup;

/// The most cells a grid may have: cells are numbered with `u32`.
pub const MAX_CELLS: u64 = u32::MAX as u64;

/// How the cell size is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GridSize {
    /// Cell width in normalized model units (the article's `gridSize`, 0.24 with a model size of 9).
    Cell(f32),
    /// Cells along the longest axis of the model.
    Resolution(u32),
}

impl Default for GridSize {
    fn default() -> Self {
        GridSize::Cell(0.24)
    }
}

/// The placement of the grid in normalized model space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridSpec {
    /// Cells along x, y, z.
    pub dims: [u32; 3],
    /// Cell size along x, y, z (x and z equal; y may be taller).
    pub cell: [f32; 3],
    /// The minimum corner of cell (0, 0, 0).
    pub origin: [f32; 3],
    /// Model space = (world − `center`) · `scale`.
    pub scale: f32,
    /// The world-space centre of the model's bounding box.
    pub center: [f32; 3],
    /// World → grid coordinates, in f64 and snapped (what the voxelizer computes with; the f32 fields above
    /// describe the same placement for display).
    map: WorldToGrid,
}

/// The exact world → grid mapping: grid = snap(`pad` + (world − `lo`) · `per_world`).
///
/// A vertex arrives as f32 after its node transform, so the same shape under another node scale or
/// translation differs by rounding (≈ 2⁻²⁴ of its coordinates). Snapping every grid coordinate to a multiple
/// of `quantum`, a power of two of a cell well above that noise and well below anything visible, turns a face
/// that lies on a cell boundary or a cell centre (up to rounding) into one that lies exactly on it, the same
/// bits for every scaled or moved copy, so the shell, the fill and the hollow pass decide its ties alike.
#[derive(Clone, Copy, Debug, PartialEq)]
struct WorldToGrid {
    /// The world-space minimum corner of the model's bounding box.
    lo: DVec3,
    /// The grid coordinates of `lo` (0 along the longest axis; half the spare cells along the others).
    pad: DVec3,
    /// Grid cells per world unit along x, y, z.
    per_world: DVec3,
    /// The snapping step in cells (a power of two).
    quantum: f64,
}

impl WorldToGrid {
    /// World position → snapped grid coordinates. `p − lo` is exact (f32 operands in f64), so the only
    /// rounding before the snap is the multiplication.
    #[inline]
    fn apply(&self, p: [f32; 3]) -> DVec3 {
        let g = self.pad + (DVec3::from(p.map(f64::from)) - self.lo) * self.per_world;
        snap(g, self.quantum)
    }
}

/// `v` rounded to the nearest multiple of `quantum` (a power of two, so exact: multiplying by its reciprocal,
/// also a power of two, is dividing by it, without the division's cost).
fn snap(v: DVec3, quantum: f64) -> DVec3 {
    DVec3::from((v * quantum.recip()).to_array().map(float::round)) * quantum
}

/// The snapping step for a model whose coordinates reach `reach` cells from the world origin: the f32 noise of
/// a coordinate is about 2⁻²⁴ of it (f32 node rotations add a few times that) and the step is 48–96 times
/// that, at most 1/64 cell (beyond that the model sits so far from the origin that f32 cannot place it).
/// The exponent is taken of 1.5 · `reach` so that a model centred on the origin (reach = half its cell count,
/// a multiple of ½) never sits on a step of the power of two, where rounding noise could pick either of two
/// quanta for two copies of one shape.
fn snap_quantum(reach: f64) -> f64 {
    let exponent = (1.5 * reach).log2().floor().clamp(-40.0, 12.0) as i32;
    2f64.powi(exponent - 18)
}

impl GridSpec {
    /// Fits a grid around `soup`: the bounding-box diagonal is scaled to `model_size` and centred at the
    /// origin; cells are `width` wide (x, z) and `width * height_ratio` tall (y).
    pub fn fit(
        soup: &TriangleSoup,
        model_size: f32,
        size: GridSize,
        height_ratio: f32,
        max_cells: u64,
    ) -> Result<Self> {
        let bounds = soup.bounds().ok_or_else(|| VoxelError::Empty(String::new()))?;
        Self::fit_bounds(bounds, model_size, size, height_ratio, max_cells)
    }

    /// A grid of `dims` cells, fitted around a box of those proportions (for tests of the passes on a grid of a
    /// given shape).
    #[cfg(test)]
    pub(crate) fn of_cells(dims: [u32; 3]) -> Self {
        let cuboid = crate::shapes::cuboid([0.0; 3], dims.map(|d| d as f32));
        let size = GridSize::Resolution(dims.into_iter().max().unwrap_or(1));
        let spec = Self::fit(&TriangleSoup::from_mesh(&cuboid, [1.0; 4]), 9.0, size, 1.0, 1 << 26).unwrap();
        assert_eq!(spec.dims, dims);
        spec
    }

    /// Fits a grid around the box `bounds` (min, max) as [`GridSpec::fit`] does around a soup's bounds: for
    /// a fixed grid over every pose of an animation.
    pub fn fit_bounds(
        (lo, hi): ([f32; 3], [f32; 3]),
        model_size: f32,
        size: GridSize,
        height_ratio: f32,
        max_cells: u64,
    ) -> Result<Self> {
        if !(model_size.is_finite() && model_size > 0.0) {
            return Err(VoxelError::Parameter(format!("model size must be positive, got {model_size}")));
        }
        if !(height_ratio.is_finite() && (0.1..=10.0).contains(&height_ratio)) {
            return Err(VoxelError::Parameter(format!("cell height ratio must be in 0.1..=10, got {height_ratio}")));
        }
        let lo = DVec3::from(lo.map(f64::from));
        let hi = DVec3::from(hi.map(f64::from));
        let diag = (hi - lo).length();
        if !(diag.is_finite() && diag > 0.0) {
            return Err(VoxelError::Empty(" (all vertices coincide)".into()));
        }
        let scale = f64::from(model_size) / diag;
        let extent = (hi - lo) * scale;
        let ratio = f64::from(height_ratio);
        let width = match size {
            GridSize::Cell(w) if w.is_finite() && w > 0.0 => f64::from(w),
            GridSize::Cell(w) => return Err(VoxelError::Parameter(format!("grid size must be positive, got {w}"))),
            GridSize::Resolution(r) if (1..=65_535).contains(&r) => {
                extent.x.max(extent.z).max(extent.y / ratio) / f64::from(r)
            }
            GridSize::Resolution(r) => {
                return Err(VoxelError::Parameter(format!("resolution must be in 1..=65535, got {r}")));
            }
        };
        let cell = DVec3::new(width, width * ratio, width);
        let per_world = scale / cell;
        let span = (hi - lo) * per_world;
        let quantum = snap_quantum((lo.abs().max(hi.abs()) * per_world).max_element());
        // Snapped like the coordinates, so that an extent of R cells up to rounding holds exactly R cells.
        let n = snap(span, quantum).ceil().max(DVec3::ONE);
        let too_big = |nx: f64, ny: f64, nz: f64| VoxelError::GridTooLarge {
            nx: nx as u64,
            ny: ny as u64,
            nz: nz as u64,
            cells: (nx * ny * nz).min(u64::MAX as f64) as u64,
            budget: max_cells,
        };
        if n.x * n.y * n.z > max_cells.min(MAX_CELLS) as f64 || n.max_element() > 65_535.0 {
            return Err(too_big(n.x, n.y, n.z));
        }
        let dims = [n.x as u32, n.y as u32, n.z as u32];
        let origin = -(n * cell) / 2.0;
        let center = (lo + hi) / 2.0;
        Ok(Self {
            dims,
            cell: cell.as_vec3().to_array(),
            origin: origin.as_vec3().to_array(),
            scale: scale as f32,
            center: center.as_vec3().to_array(),
            map: WorldToGrid { lo, pad: (n - span) / 2.0, per_world, quantum },
        })
    }

    /// Total number of cells.
    pub fn cell_count(&self) -> usize {
        self.dims.iter().map(|&d| d as usize).product()
    }

    /// Linear index of cell (x, y, z): z varies fastest, so a +Z column is contiguous.
    #[inline]
    pub fn index(&self, x: u32, y: u32, z: u32) -> usize {
        (x as usize * self.dims[1] as usize + y as usize) * self.dims[2] as usize + z as usize
    }

    /// The steps of the linear index along x, y and z: [`index`](Self::index) is their sum weighted by the
    /// coordinates.
    #[inline]
    pub fn strides(&self) -> [usize; 3] {
        [self.dims[1] as usize * self.dims[2] as usize, self.dims[2] as usize, 1]
    }

    /// The cell (x, y, z) of a linear index.
    #[inline]
    pub fn coords(&self, index: usize) -> [u32; 3] {
        let nz = self.dims[2] as usize;
        let ny = self.dims[1] as usize;
        [(index / nz / ny) as u32, (index / nz % ny) as u32, (index % nz) as u32]
    }

    /// The index of the cell at `index + step`, if inside the grid.
    #[inline]
    pub fn offset(&self, index: usize, step: [i32; 3]) -> Option<usize> {
        self.neighbour(self.coords(index), step)
    }

    /// The index of the cell at `cell + step`, if inside the grid.
    #[inline]
    pub fn neighbour(&self, cell: [u32; 3], step: [i32; 3]) -> Option<usize> {
        self.step(cell, step).map(|c| self.index(c[0], c[1], c[2]))
    }

    /// The cell at `cell + step`, if inside the grid.
    #[inline]
    pub fn step(&self, cell: [u32; 3], step: [i32; 3]) -> Option<[u32; 3]> {
        let mut out = [0u32; 3];
        for a in 0..3 {
            let v = i64::from(cell[a]) + i64::from(step[a]);
            if v < 0 || v >= i64::from(self.dims[a]) {
                return None;
            }
            out[a] = v as u32;
        }
        Some(out)
    }

    /// Model-space centre of cell (x, y, z).
    pub fn cell_center(&self, c: [u32; 3]) -> [f32; 3] {
        std::array::from_fn(|a| self.origin[a] + (c[a] as f32 + 0.5) * self.cell[a])
    }

    /// World position → grid coordinates (cell (i, j, k) spans [i, i+1] etc.), in f64, snapped to a small
    /// power-of-two fraction of a cell so that scaled or moved copies of a shape map to the same coordinates.
    #[inline]
    pub fn to_grid(&self, p: [f32; 3]) -> DVec3 {
        self.map.apply(p)
    }

    /// Every triangle of `soup` in grid coordinates: each vertex placed once, the triangles the soup's own.
    pub fn grid_triangles<'a>(&self, soup: &'a TriangleSoup) -> GridTriangles<'a> {
        let vertices = soup.positions().par_iter().with_min_len(VERTICES_PER_TASK).map(|&p| self.to_grid(p)).collect();
        GridTriangles::indexed(vertices, soup.triangles())
    }
}

/// The triangle of `vertices` with corners `[a, b, c]` (indexed one by one: `array::map` is not always inlined,
/// and this runs for every triangle in every pass).
#[inline]
fn corners_of(vertices: &[DVec3], [a, b, c]: [u32; 3]) -> GridTriangle {
    [vertices[a as usize], vertices[b as usize], vertices[c as usize]]
}

/// Vertices placed on the grid per task of [`GridSpec::grid_triangles`].
const VERTICES_PER_TASK: usize = 1 << 12;

/// Triangles in grid coordinates, indexed: every vertex placed on the grid once, each triangle the indices
/// of its three corners (a soup's own, borrowed). A big model's triangles then take a vertex's 24 bytes each
/// rather than a triangle's 72 (144 MB for two million), written once and read by every pass.
#[derive(Clone, Debug)]
pub struct GridTriangles<'a> {
    vertices: Vec<DVec3>,
    corners: Cow<'a, [[u32; 3]]>,
}

impl<'a> GridTriangles<'a> {
    /// Triangles of `vertices`, three indices each.
    pub fn indexed(vertices: Vec<DVec3>, corners: &'a [[u32; 3]]) -> Self {
        Self { vertices, corners: Cow::Borrowed(corners) }
    }

    /// Triangles given whole, each with its own three vertices.
    pub fn from_triangles(tris: &[GridTriangle]) -> GridTriangles<'static> {
        let corners = (0..tris.len() as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        GridTriangles { vertices: tris.as_flattened().to_vec(), corners: Cow::Owned(corners) }
    }

    /// Triangle `t`.
    #[inline]
    pub fn get(&self, t: usize) -> GridTriangle {
        corners_of(&self.vertices, self.corners[t])
    }

    /// The number of triangles.
    pub fn len(&self) -> usize {
        self.corners.len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.corners.is_empty()
    }

    /// The triangles in order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = GridTriangle> + '_ {
        self.corners.iter().map(|&corners| corners_of(&self.vertices, corners))
    }

    /// The triangles in order, in parallel.
    pub fn par_iter(&self) -> impl IndexedParallelIterator<Item = GridTriangle> + '_ {
        self.corners.par_iter().map(|&corners| corners_of(&self.vertices, corners))
    }

    /// The vertices, each once.
    pub fn vertices(&self) -> &[DVec3] {
        &self.vertices
    }

    /// The vertex indices of every corner, three a triangle.
    pub fn corners(&self) -> &[u32] {
        self.corners.as_flattened()
    }

    /// The bytes the vertices take (the corners are the soup's).
    pub fn vertex_bytes(&self) -> usize {
        std::mem::size_of_val(self.vertices.as_slice())
    }
}

/// One bit per cell of a grid, in the grid's linear order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BitGrid {
    words: Vec<u64>,
    len: usize,
}

impl BitGrid {
    /// All cells clear.
    pub fn new(len: usize) -> Self {
        Self { words: vec![0; len.div_ceil(64)], len }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the grid has no cells.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether cell `i` is set.
    #[inline]
    pub fn get(&self, i: usize) -> bool {
        self.words[i / 64] >> (i % 64) & 1 == 1
    }

    /// Sets cell `i`.
    #[inline]
    pub fn set(&mut self, i: usize) {
        self.words[i / 64] |= 1 << (i % 64);
    }

    /// Keeps the cells set in both `self` and `other` (of the same length).
    pub fn intersect(&mut self, other: &BitGrid) {
        self.words.iter_mut().zip(&other.words).for_each(|(word, other)| *word &= other);
    }

    /// Sets the cells set in `other` (of the same length) too.
    pub fn unite(&mut self, other: &BitGrid) {
        self.words.iter_mut().zip(&other.words).for_each(|(word, other)| *word |= other);
    }

    /// Sets cells `range` (used for filled runs of a column).
    pub fn set_range(&mut self, range: std::ops::Range<usize>) {
        let mut i = range.start;
        while i < range.end {
            let (w, b) = (i / 64, i % 64);
            let n = (64 - b).min(range.end - i);
            let mask = if n == 64 { u64::MAX } else { ((1u64 << n) - 1) << b };
            self.words[w] |= mask;
            i += n;
        }
    }

    /// Number of set cells.
    pub fn count(&self) -> usize {
        self.words.iter().map(|w| w.count_ones() as usize).sum()
    }

    /// The `n` (≤ 64) cells from `start` as the low bits of a word (cell `start` in bit 0).
    #[inline]
    pub fn bits(&self, start: usize, n: usize) -> u64 {
        debug_assert!(n <= 64 && start + n <= self.len);
        if n == 0 {
            return 0;
        }
        let (w, b) = (start / 64, start % 64);
        let mut word = self.words[w] >> b;
        if b != 0 && w + 1 < self.words.len() {
            word |= self.words[w + 1] << (64 - b);
        }
        if n == 64 { word } else { word & ((1u64 << n) - 1) }
    }

    /// The maximal runs of set cells within `range`, ascending, as ranges of cell indices (a run stops at
    /// the range's ends).
    pub fn runs(&self, range: std::ops::Range<usize>) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
        let end = range.end;
        let mut at = range.start;
        std::iter::from_fn(move || {
            let start = self.next(at, end, true);
            if start == end {
                return None;
            }
            at = self.next(start, end, false);
            Some(start..at)
        })
    }

    /// The first cell at or after `from` (and before `end`, else `end`) whose bit is `set`.
    fn next(&self, mut from: usize, end: usize, set: bool) -> usize {
        while from < end {
            let n = (64 - from % 64).min(end - from);
            let word = self.bits(from, n);
            let hits = if set { word } else { !word & if n == 64 { u64::MAX } else { (1u64 << n) - 1 } };
            if hits != 0 {
                return from + hits.trailing_zeros() as usize;
            }
            from += n;
        }
        end
    }

    /// Indices of the set cells, ascending.
    pub fn ones(&self) -> impl Iterator<Item = usize> + '_ {
        self.words.iter().enumerate().flat_map(|(w, &word)| {
            let mut bits = word;
            std::iter::from_fn(move || {
                if bits == 0 {
                    return None;
                }
                let b = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                Some(w * 64 + b)
            })
        })
    }
}

/// The coordinates of cells, each from the previous one's without a division when it lies above that one in the
/// same column (as most neighbouring surface cells of an ascending list do).
pub(crate) struct AscendingCoords<'a> {
    spec: &'a GridSpec,
    /// The last cell and its coordinates.
    last: Option<(u32, [u32; 3])>,
}

impl<'a> AscendingCoords<'a> {
    /// Coordinates in `spec`'s grid, from no cell yet.
    pub fn new(spec: &'a GridSpec) -> Self {
        Self { spec, last: None }
    }

    /// The coordinates of cell `i`.
    #[inline]
    pub fn of(&mut self, i: u32) -> [u32; 3] {
        let c = match self.last {
            Some((j, mut c)) if i >= j && i - j < self.spec.dims[2] - c[2] => {
                c[2] += i - j;
                c
            }
            _ => self.spec.coords(i as usize),
        };
        self.last = Some((i, c));
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::soup::{Material, Vertex};

    #[test]
    fn snapping_multiplies_by_the_reciprocal_as_dividing_would() {
        let mut random = crate::lcg::Lcg::new(5);
        for reach in [0.3, 7.5, 64.0, 1000.0, 2048.0, 1e6] {
            let quantum = snap_quantum(reach);
            for _ in 0..10_000 {
                let v = DVec3::new(random.unit(2.0 * reach), random.unit(reach), random.unit(0.01)) - reach / 2.0;
                let divided = DVec3::from((v / quantum).to_array().map(f64::round)) * quantum;
                assert_eq!(snap(v, quantum).to_array().map(f64::to_bits), divided.to_array().map(f64::to_bits), "{v}");
            }
        }
    }

    fn unit_cube_corners() -> TriangleSoup {
        let mut soup = TriangleSoup::default();
        let m = soup.add_material(Material::default());
        let p = soup.add_part(m, "t");
        soup.push_triangle(p, [Vertex::at([0.0; 3]), Vertex::at([2.0, 0.0, 0.0]), Vertex::at([0.0, 1.0, 4.0])]);
        soup
    }

    #[test]
    fn resolution_sets_cells_along_the_longest_axis() {
        let g = GridSpec::fit(&unit_cube_corners(), 9.0, GridSize::Resolution(16), 1.0, 1 << 26).unwrap();
        assert_eq!(g.dims, [8, 4, 16]);
        let g = GridSpec::fit(&unit_cube_corners(), 9.0, GridSize::Resolution(16), 1.2, 1 << 26).unwrap();
        assert!((g.cell[1] / g.cell[0] - 1.2).abs() < 1e-6);
    }

    #[test]
    fn absurd_grids_are_refused_with_the_budget() {
        let err = GridSpec::fit(&unit_cube_corners(), 9.0, GridSize::Cell(1e-4), 1.0, 1 << 26).unwrap_err();
        assert!(matches!(err, VoxelError::GridTooLarge { .. }), "{err}");
        assert!(err.to_string().contains("exceeds the budget"));
        assert!(GridSpec::fit(&unit_cube_corners(), 9.0, GridSize::Cell(f32::NAN), 1.0, 1 << 26).is_err());
        assert!(GridSpec::fit(&unit_cube_corners(), 9.0, GridSize::Resolution(0), 1.0, 1 << 26).is_err());
    }

    #[test]
    fn index_coords_and_neighbours_round_trip() {
        let g = GridSpec::fit(&unit_cube_corners(), 9.0, GridSize::Resolution(16), 1.0, 1 << 26).unwrap();
        let i = g.index(3, 2, 7);
        assert_eq!(g.coords(i), [3, 2, 7]);
        assert_eq!(g.offset(i, [0, 0, 1]), Some(g.index(3, 2, 8)));
        assert_eq!(g.offset(g.index(0, 0, 0), [-1, 0, 0]), None);
        assert_eq!(g.offset(i, [1, -1, 1]), Some(g.index(4, 1, 8)));
    }

    #[test]
    fn bit_grid_sets_counts_and_lists() {
        let mut b = BitGrid::new(130);
        b.set(0);
        b.set(64);
        b.set_range(127..130);
        assert_eq!(b.count(), 5);
        assert_eq!(b.ones().collect::<Vec<_>>(), vec![0, 64, 127, 128, 129]);
    }

    #[test]
    fn bit_grid_reads_words_and_runs_across_word_boundaries() {
        let mut b = BitGrid::new(200);
        b.set_range(60..70);
        b.set_range(100..164);
        b.set(199);
        assert_eq!(b.bits(60, 10), 0b11_1111_1111);
        assert_eq!(b.bits(58, 4), 0b1100);
        assert_eq!(b.bits(100, 64), u64::MAX);
        assert_eq!(b.bits(136, 64), ((1u64 << 28) - 1) | (1 << 63));
        assert_eq!(b.runs(0..200).collect::<Vec<_>>(), vec![60..70, 100..164, 199..200]);
        assert_eq!(b.runs(65..120).collect::<Vec<_>>(), vec![65..70, 100..120]);
        assert_eq!(b.runs(70..100).count(), 0);
    }

    #[test]
    fn strides_and_coordinates_stepped_along_a_column_match_the_index() {
        let spec = GridSpec::of_cells([5, 3, 7]);
        assert_eq!(spec.strides(), [21, 7, 1]);
        for i in 0..105 {
            let c = spec.coords(i);
            assert_eq!((0..3).map(|a| c[a] as usize * spec.strides()[a]).sum::<usize>(), i, "cell {c:?}");
        }
        // Every cell, then every third cell, then cells straddling column ends and going back.
        for cells in
            [(0..105).collect::<Vec<u32>>(), (0..105).step_by(3).collect(), vec![5, 6, 7, 13, 14, 21, 104, 3, 0, 1]]
        {
            let mut coords = AscendingCoords::new(&spec);
            for i in cells {
                assert_eq!(coords.of(i), spec.coords(i as usize), "cell {i}");
            }
        }
    }
}
