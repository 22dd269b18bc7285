//! The voxelizer's output: an occupancy bit grid (one bit per cell, none for a hollow model) plus the
//! visible cells with their colours. Interior cells are counted from the bits and coloured on demand, so a
//! solid model costs R³/8 bytes plus its surface, and a hollow one only its surface.

use std::borrow::Cow;

use crate::grid::{BitGrid, GridSpec};

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
    /// Distinct colours among the output voxels.
    pub colors: usize,
}

/// A voxelized model: the grid placement, which cells are filled, and the colours of the visible ones.
///
/// The output voxels are every filled cell, or only the visible ones when the model is hollow
/// ([`VoxelModel::is_hollow`]); [`VoxelModel::voxels`] yields them ascending by (x, y, z). An interior
/// cell takes the colour and part of the nearer end of its filled run along z (both ends of a run are
/// visible cells), computed as it is yielded.
#[derive(Clone, Debug, PartialEq)]
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
        Self { spec, stats, parts, solid, visible, colors }
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
        self.visible.iter().zip(&self.colors).map(|(&i, &color)| self.voxel(self.spec.coords(i as usize), color, true))
    }

    /// Every output voxel, ascending by (x, y, z): the visible ones when hollow, else every filled cell.
    pub fn voxels(&self) -> Box<dyn Iterator<Item = Voxel> + Send + '_> {
        let Some(solid) = &self.solid else { return Box::new(self.visible_voxels()) };
        let [nx, ny, nz] = self.spec.dims.map(|d| d as usize);
        Box::new((0..nx * ny).flat_map(move |col| solid.runs(col * nz..(col + 1) * nz)).flat_map(move |run| {
            // The run's ends are its first and last visible cells.
            let first = self.visible.partition_point(|&v| (v as usize) < run.start);
            let last = self.visible.partition_point(|&v| (v as usize) < run.end) - 1;
            let mut next = first;
            // A run lies in one column: only z changes along it (no division per cell).
            let [x, y, z0] = self.spec.coords(run.start);
            run.clone().map(move |i| {
                let cell = [x, y, z0 + (i - run.start) as u32];
                if self.visible.get(next).is_some_and(|&v| v as usize == i) {
                    next += 1;
                    return self.voxel(cell, self.colors[next - 1], true);
                }
                let end = if i - run.start <= run.end - 1 - i { first } else { last };
                self.voxel(cell, self.colors[end], false)
            })
        }))
    }

    /// Recolours the visible cells (interior cells follow the ends of their runs): `f` gets each visible
    /// voxel and returns its new colour.
    pub fn recolor(&mut self, mut f: impl FnMut(&Voxel) -> [u8; 4]) {
        for k in 0..self.visible.len() {
            let v = self.voxel(self.spec.coords(self.visible[k] as usize), self.colors[k], true);
            self.colors[k].0 = f(&v);
        }
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

    /// The voxel of the cell at `cell`.
    fn voxel(&self, cell: [u32; 3], (color, part): ([u8; 4], u32), visible: bool) -> Voxel {
        Voxel { cell: cell.map(|c| c as u16), color, part, visible }
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
    fn interior_cells_take_the_colour_of_the_nearer_end_of_their_run() {
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
