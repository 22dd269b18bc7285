//! The voxelizer's output: an occupancy bit grid (one bit per cell, none for a hollow model) plus the
//! visible cells with their colours. Interior cells are counted from the bits and coloured on demand, so a
//! solid model costs R³/8 bytes plus its surface, and a hollow one only its surface.

use std::borrow::Cow;
use std::sync::OnceLock;

use crate::distinct;
use crate::grid::{AscendingCoords, BitGrid, GridSpec};

/// One filled cell, as the model's iterators hand it out.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Voxel {
    /// Cell coordinates (x, y, z).
    pub cell: [u16; 3],
    /// sRGB RGBA8 colour.
    pub color: [u8; 4],
    /// Index of the source part (glTF primitive instance) the colour came from.
    pub part: u32,
    /// Whether the cell has an empty face neighbour (can be seen from outside).
    pub visible: bool,
}

/// Counts describing a voxelization.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct VoxelStats {
    /// Triangles in the model.
    pub triangles: usize,
    /// Grid size in cells.
    pub grid: [u32; 3],
    /// Filled cells (solid, before any hollowing).
    pub voxels: usize,
    /// Cells a triangle touches (the surface shell).
    pub surface: usize,
    /// Filled cells with an empty face neighbour.
    pub visible: usize,
}

/// A voxelized model: the grid placement, which cells are filled, and the colours of the visible ones.
///
/// The output voxels are every filled cell, or only the visible ones when the model is hollow
/// ([`VoxelModel::is_hollow`]); [`VoxelModel::voxels`] yields them ascending by (x, y, z). An interior
/// cell takes the colour and part of the nearer end of its filled run along z (both ends of a run are
/// visible cells), computed as it is yielded.
#[derive(Clone, Debug)]
pub struct VoxelModel {
    /// Where the grid sits in normalized model space.
    pub spec: GridSpec,
    /// Counts.
    pub stats: VoxelStats,
    /// Names of the source parts (index = `Voxel::part`).
    pub parts: Vec<String>,
    /// Every filled cell by linear index; `None` when hollow (then the output is `visible`).
    solid: Option<BitGrid>,
    /// The linear indices of the visible cells, ascending.
    visible: Vec<u32>,
    /// The colour and part of each visible cell.
    colors: Vec<([u8; 4], u32)>,
    /// The distinct colours, once counted ([`VoxelModel::color_count`]).
    color_count: OnceLock<usize>,
}

/// Models are equal when their placement, counts, parts, cells and colours are: whether the colour count was asked
/// for yet does not matter.
impl PartialEq for VoxelModel {
    fn eq(&self, other: &Self) -> bool {
        let Self { spec, stats, parts, solid, visible, colors, color_count: _ } = self;
        (spec, stats, parts, solid, visible, colors)
            == (&other.spec, &other.stats, &other.parts, &other.solid, &other.visible, &other.colors)
    }
}

impl VoxelModel {
    /// A model from its parts: the solid (`None` for a hollow model) and its visible cells, ascending, with
    /// their colours and parts.
    pub(crate) fn new(
        spec: GridSpec,
        stats: VoxelStats,
        parts: Vec<String>,
        solid: Option<BitGrid>,
        visible: Vec<u32>,
        colors: Vec<([u8; 4], u32)>,
    ) -> Self {
        debug_assert_eq!(visible.len(), colors.len());
        Self { spec, stats, parts, solid, visible, colors, color_count: OnceLock::new() }
    }

    /// The number of distinct colours among the output voxels (interior voxels copy visible ones, so the visible
    /// cells hold every colour; after a palette, the distinct RGB colours it left). Counted at the first call, not
    /// by the voxelization: a caller that shows no count (an animation's frames, the app's voxels) does not pay for
    /// it (CesiumMan at R=128: 1,488 colours among 14,600 cells, 0.10–0.19 ms of a fresh process's 3.1–3.5 ms).
    pub fn color_count(&self) -> usize {
        *self.color_count.get_or_init(|| distinct::count(&self.colors))
    }

    /// Sets the count [`color_count`](Self::color_count) gives, for a recolouring that counts its own.
    pub(crate) fn set_color_count(&mut self, count: usize) {
        self.color_count = OnceLock::from(count);
    }

    /// Whether only the visible cells are output.
    pub fn is_hollow(&self) -> bool {
        self.solid.is_none()
    }

    /// The number of output voxels.
    pub fn len(&self) -> usize {
        match &self.solid {
            Some(_) => self.stats.voxels,
            None => self.visible.len(),
        }
    }

    /// Whether there is no output voxel.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The bytes the model holds: its solid's bits (one a cell, none when hollow), and for each visible cell
    /// its index, colour and part.
    pub fn memory_bytes(&self) -> usize {
        let solid = self.solid.as_ref().map_or(0, |bits| bits.len().div_ceil(64) * 8);
        let visible = self.visible.len() * size_of::<u32>() + self.colors.len() * size_of::<([u8; 4], u32)>();
        solid + visible + self.parts.iter().map(String::len).sum::<usize>()
    }

    /// The same model with only its visible cells.
    pub fn hollowed(&self) -> VoxelModel {
        VoxelModel { solid: None, ..self.clone() }
    }

    /// The output cells, one bit per cell of the grid in linear order ([`GridSpec::index`]).
    pub fn occupancy(&self) -> Cow<'_, BitGrid> {
        match &self.solid {
            Some(solid) => Cow::Borrowed(solid),
            None => {
                let mut bits = BitGrid::new(self.spec.cell_count());
                for &i in &self.visible {
                    bits.set(i as usize);
                }
                Cow::Owned(bits)
            }
        }
    }

    /// The visible voxels, ascending by (x, y, z).
    pub fn visible_voxels(&self) -> impl Iterator<Item = Voxel> + '_ {
        let mut coords = AscendingCoords::new(&self.spec);
        self.visible.iter().zip(&self.colors).map(move |(&i, &(color, part))| Voxel {
            cell: coords.of(i).map(|c| c as u16),
            color,
            part,
            visible: true,
        })
    }

    /// Every output voxel, ascending by (x, y, z): the visible ones when hollow, else every filled cell.
    pub fn voxels(&self) -> Box<dyn Iterator<Item = Voxel> + Send + '_> {
        match &self.solid {
            Some(solid) => Box::new(SolidVoxels::new(self, solid)),
            None => Box::new(self.visible_voxels()),
        }
    }

    /// Recolours the visible cells (interior cells follow the ends of their runs): `f` gets each visible
    /// voxel and returns its new colour.
    pub fn recolor(&mut self, mut f: impl FnMut(&Voxel) -> [u8; 4]) {
        let mut coords = AscendingCoords::new(&self.spec);
        for (&i, (color, part)) in self.visible.iter().zip(&mut self.colors) {
            *color = f(&Voxel { cell: coords.of(i).map(|c| c as u16), color: *color, part: *part, visible: true });
        }
        self.color_count = OnceLock::new();
    }

    /// Model-space centre of a voxel.
    pub fn center(&self, v: &Voxel) -> [f32; 3] {
        self.spec.cell_center(v.cell.map(u32::from))
    }

    /// A solid model of the given cells and colours (part 0), for tests: visibility is computed, and an
    /// interior cell's own colour is replaced by its run's.
    #[cfg(test)]
    pub(crate) fn from_cells(spec: GridSpec, cells: impl IntoIterator<Item = ([u16; 3], [u8; 4])>) -> Self {
        let mut solid = BitGrid::new(spec.cell_count());
        let mut color_of = std::collections::HashMap::new();
        for (c, color) in cells {
            let i = spec.index(u32::from(c[0]), u32::from(c[1]), u32::from(c[2]));
            solid.set(i);
            color_of.insert(i, color);
        }
        let visible = crate::visible::visible_cells(&spec, &solid);
        let colors = visible.iter().map(|i| (color_of[&(*i as usize)], 0)).collect();
        let stats = VoxelStats { grid: spec.dims, voxels: solid.count(), visible: visible.len(), ..Default::default() };
        Self::new(spec, stats, Vec::new(), Some(solid), visible, colors)
    }
}

/// The voxels of a solid model, ascending: the filled runs of each column, their cells visible or
/// interior ([`VoxelModel::voxels`]).
///
/// The visible cells are filled, so each lies in a run, and the runs come ascending: a run's first cell is
/// the next visible cell, and its last one is visible too, at most the run's length further on.
struct SolidVoxels<'a> {
    model: &'a VoxelModel,
    solid: &'a BitGrid,
    /// The column being walked (x · ny + y), its x and y, and where its next run is looked for.
    column: usize,
    xy: [u16; 2],
    scan: usize,
    /// The current run, `start..end`, and the next cell of it to yield.
    start: usize,
    end: usize,
    at: usize,
    /// Positions in `visible` of the run's first and last cells, and of the next visible cell.
    first: usize,
    last: usize,
    next: usize,
}

impl<'a> SolidVoxels<'a> {
    fn new(model: &'a VoxelModel, solid: &'a BitGrid) -> Self {
        let (xy, first, last, next) = ([0, 0], 0, 0, 0);
        Self { model, solid, column: 0, xy, scan: 0, start: 0, end: 0, at: 0, first, last, next }
    }

    /// Moves to the next run; false at the end of the grid.
    fn next_run(&mut self) -> bool {
        let [nx, ny, nz] = self.model.spec.dims.map(|d| d as usize);
        while self.column < nx * ny {
            let column_end = (self.column + 1) * nz;
            if let Some(run) = self.solid.runs(self.scan..column_end).next() {
                let visible = &self.model.visible;
                debug_assert_eq!(visible.get(self.next).map(|&v| v as usize), Some(run.start));
                let within = &visible[self.next..(self.next + run.len()).min(visible.len())];
                let last = self.next + within.partition_point(|&v| (v as usize) < run.end) - 1;
                (self.first, self.last) = (self.next, last);
                (self.start, self.end, self.at, self.scan) = (run.start, run.end, run.start, run.end);
                return true;
            }
            self.column += 1;
            self.scan = column_end;
            let [x, y] = self.xy;
            self.xy = if usize::from(y) + 1 == ny { [x + 1, 0] } else { [x, y + 1] };
        }
        false
    }
}

impl Iterator for SolidVoxels<'_> {
    type Item = Voxel;

    fn next(&mut self) -> Option<Voxel> {
        if self.at == self.end && !self.next_run() {
            return None;
        }
        let i = self.at;
        self.at += 1;
        let visible = self.model.visible.get(self.next).is_some_and(|&v| v as usize == i);
        // An interior cell takes the colour of the nearer end of its run (the lower one on a tie).
        let end = if i - self.start <= self.end - 1 - i { self.first } else { self.last };
        let (color, part) = self.model.colors[if visible { self.next } else { end }];
        self.next += usize::from(visible);
        let z = (i - self.column * self.model.spec.dims[2] as usize) as u16;
        Some(Voxel { cell: [self.xy[0], self.xy[1], z], color, part, visible })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{GridSize, TriangleSoup, shapes::cuboid};

    /// A solid block of 3 × 3 × 6 cells, each coloured by its z.
    fn block() -> VoxelModel {
        let soup = TriangleSoup::from_mesh(&cuboid([0.0; 3], [3.0, 3.0, 6.0]), [1.0; 4]);
        let spec = GridSpec::fit(&soup, 9.0, GridSize::Resolution(6), 1.0, 1 << 26).unwrap();
        assert_eq!(spec.dims, [3, 3, 6]);
        let cells = (0..3u16).flat_map(|x| (0..3u16).flat_map(move |y| (0..6u16).map(move |z| [x, y, z])));
        VoxelModel::from_cells(spec, cells.map(|c| (c, [c[2] as u8 * 10, 0, 0, 255])))
    }

    #[test]
    fn memory_counts_the_solid_bits_and_twelve_bytes_a_visible_cell() {
        let m = block();
        let parts: usize = m.parts.iter().map(String::len).sum();
        assert_eq!(m.stats.visible, 50, "3 × 3 × 6 less its 1 × 1 × 4 core");
        assert_eq!(m.hollowed().memory_bytes(), 50 * 12 + parts);
        assert_eq!(m.memory_bytes(), 8 + 50 * 12 + parts, "54 cells fit one 64-bit word");
    }

    #[test]
    fn the_colour_count_is_of_the_colours_shown_after_a_recolouring_too() {
        let mut m = block();
        assert_eq!(m.color_count(), 6, "a colour a layer");
        m.recolor(|v| [v.cell[2] as u8 % 2, 0, 0, 255]);
        assert_eq!(m.color_count(), 2, "counted again");
        m.set_color_count(9);
        assert_eq!(m.color_count(), 9);
        let fresh = VoxelModel { color_count: OnceLock::new(), ..m.clone() };
        assert_eq!(fresh, m, "the same model, its count asked for or not");
    }

    #[test]
    fn interior_cells_take_the_color_of_the_nearer_end_of_their_run() {
        let m = block();
        assert_eq!((m.len(), m.stats.visible), (54, 50));
        let all: Vec<Voxel> = m.voxels().collect();
        assert_eq!(all.len(), 54);
        assert!(all.windows(2).all(|w| w[0].cell < w[1].cell), "ascending by (x, y, z)");
        let interior: Vec<([u16; 3], u8)> = all.iter().filter(|v| !v.visible).map(|v| (v.cell, v.color[0])).collect();
        // The middle column's run is z = 0…5: z = 1, 2 are nearer (or as near as) its bottom, 3, 4 its top.
        assert_eq!(interior, vec![([1, 1, 1], 0), ([1, 1, 2], 0), ([1, 1, 3], 50), ([1, 1, 4], 50)]);
        assert!(all.iter().filter(|v| v.visible).eq(m.visible_voxels().collect::<Vec<_>>().iter()));
    }

    #[test]
    fn solid_voxels_follow_the_runs_of_every_column() {
        // 5 × 4 × 9 cells: the even-x columns have a gap at z = 4 (two runs), column (1, 1) is empty, and the
        // colour of a cell is its z and x.
        let soup = TriangleSoup::from_mesh(&cuboid([0.0; 3], [5.0, 4.0, 9.0]), [1.0; 4]);
        let spec = GridSpec::fit(&soup, 9.0, GridSize::Resolution(9), 1.0, 1 << 26).unwrap();
        assert_eq!(spec.dims, [5, 4, 9]);
        let gap = |c: [u16; 3]| c[0].is_multiple_of(2) && c[2] == 4;
        let filled = |c: [u16; 3]| !(gap(c) || c[0] == 1 && c[1] == 1);
        let cells: Vec<[u16; 3]> = (0..5u16)
            .flat_map(|x| (0..4u16).flat_map(move |y| (0..9u16).map(move |z| [x, y, z])))
            .filter(|&c| filled(c))
            .collect();
        let own = |c: [u16; 3]| [c[2] as u8 * 10 + c[0] as u8, 0, 0, 255];
        let m = VoxelModel::from_cells(spec, cells.iter().map(|&c| (c, own(c))));
        // The expected voxels: a visible cell has its own colour, an interior one that of the nearer end of
        // its run along z (the lower end on a tie).
        let expected: Vec<Voxel> = cells
            .iter()
            .map(|&c| {
                let at = |dz: i32| {
                    let z = i32::from(c[2]) + dz;
                    (0..9).contains(&z) && filled([c[0], c[1], z as u16])
                };
                let sides = [[1, 0], [-1, 0], [0, 1], [0, -1]].map(|[dx, dy]| {
                    let (x, y) = (i32::from(c[0]) + dx, i32::from(c[1]) + dy);
                    (0..5).contains(&x) && (0..4).contains(&y) && filled([x as u16, y as u16, c[2]])
                });
                let visible = !(at(-1) && at(1) && sides.iter().all(|&s| s));
                let (mut lo, mut hi) = (c[2], c[2]);
                while lo > 0 && filled([c[0], c[1], lo - 1]) {
                    lo -= 1;
                }
                while hi < 8 && filled([c[0], c[1], hi + 1]) {
                    hi += 1;
                }
                let end = if c[2] - lo <= hi - c[2] { lo } else { hi };
                let color = if visible { own(c) } else { own([c[0], c[1], end]) };
                Voxel { cell: c, color, part: 0, visible }
            })
            .collect();
        assert!(expected.iter().any(|v| !v.visible), "the test has interior cells");
        let mut voxels = m.voxels();
        assert_eq!(voxels.by_ref().collect::<Vec<_>>(), expected);
        assert_eq!(voxels.next(), None, "still none after the end");
    }

    #[test]
    fn a_hollowed_model_outputs_and_occupies_only_its_visible_cells() {
        let mut m = block().hollowed();
        assert!(m.is_hollow());
        assert_eq!(m.len(), 50);
        assert!(m.voxels().all(|v| v.visible));
        let occupied = m.occupancy();
        assert_eq!(occupied.count(), 50);
        assert!(!occupied.get(m.spec.index(1, 1, 2)));
        m.recolor(|v| [v.cell[0] as u8, 1, 2, 3]);
        assert!(m.voxels().all(|v| v.color == [v.cell[0] as u8, 1, 2, 3]));
    }
}
