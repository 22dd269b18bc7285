//! The visible surface of a voxel model as rectangles: the faces between a filled and an empty cell (never
//! the faces between two filled cells), merged greedily into larger rectangles where neighbouring faces
//! share a colour (block-mesh's `greedy_quads`, Lysenko's greedy meshing).

use block_mesh::ndshape::{RuntimeShape, Shape};
use block_mesh::{GreedyQuadsBuffer, MergeVoxel, RIGHT_HANDED_Y_UP_CONFIG, VoxelVisibility, greedy_quads};

use crate::error::{Result, VoxelError};
use crate::voxelize::VoxelModel;

/// A cell as the mesher sees it: empty, or filled with an sRGB colour. Faces merge only within one colour,
/// so every rectangle is a single colour (vertex colours interpolated over it stay exact).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Cell(Option<[u8; 3]>);

impl block_mesh::Voxel for Cell {
    fn get_visibility(&self) -> VoxelVisibility {
        if self.0.is_some() { VoxelVisibility::Opaque } else { VoxelVisibility::Empty }
    }
}

impl MergeVoxel for Cell {
    type MergeValue = Option<[u8; 3]>;

    fn merge_value(&self) -> Self::MergeValue {
        self.0
    }
}

/// One rectangle of the surface, all of one colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Quad {
    /// Corners in grid units (cell (x, y, z) spans [x, x + 1] × [y, y + 1] × [z, z + 1]), in
    /// counter-clockwise order seen from outside the solid.
    pub corners: [[u32; 3]; 4],
    /// The outward normal: a unit step along one axis.
    pub normal: [i32; 3],
    /// The sRGB colour of the filled cells behind the rectangle.
    pub color: [u8; 3],
}

impl Quad {
    /// Cell faces the rectangle covers.
    pub fn area(&self) -> usize {
        let side = |a: [u32; 3], b: [u32; 3]| (0..3).map(|k| a[k].abs_diff(b[k]) as usize).sum::<usize>();
        side(self.corners[0], self.corners[1]) * side(self.corners[1], self.corners[2])
    }
}

/// The surface of a voxel model.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Surface {
    /// The merged rectangles.
    pub quads: Vec<Quad>,
    /// Cell faces between a filled and an empty cell (the rectangles' total area): two triangles each
    /// without merging.
    pub faces: usize,
}

/// Orders a rectangle's corners (block-mesh's `[min u min v, max u min v, min u max v, max u max v]`)
/// counter-clockwise around `normal`.
fn counter_clockwise(c: [[u32; 3]; 4], normal: [i32; 3]) -> [[u32; 3]; 4] {
    let loop_ = [c[0], c[1], c[3], c[2]];
    let d = |a: [u32; 3], b: [u32; 3]| std::array::from_fn::<i64, 3, _>(|k| i64::from(b[k]) - i64::from(a[k]));
    let (u, v) = (d(loop_[0], loop_[1]), d(loop_[0], loop_[3]));
    let cross = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
    let facing: i64 = (0..3).map(|k| cross[k] * i64::from(normal[k])).sum();
    if facing > 0 { loop_ } else { [c[0], c[2], c[3], c[1]] }
}

/// The surface of `model`: its visible faces merged into single-coloured rectangles.
///
/// The faces are those between a voxel of the model and a cell without one, so a hollowed model (visible
/// voxels only) also gets the walls of its emptied inside; mesh the solid model for the outside alone.
pub fn surface(model: &VoxelModel) -> Result<Surface> {
    // One empty cell of padding all round: block-mesh reads each cell's neighbours without bounds checks.
    let padded = model.spec.dims.map(|d| u64::from(d) + 2);
    let size = padded.iter().product::<u64>();
    if size > u64::from(u32::MAX) {
        let [nx, ny, nz] = model.spec.dims;
        return Err(VoxelError::Parameter(format!("grid {nx}x{ny}x{nz} is too large to mesh (over 2^32 cells)")));
    }
    let shape = RuntimeShape::<u32, 3>::new(padded.map(|d| d as u32));
    let mut cells = vec![Cell(None); size as usize];
    for v in &model.voxels {
        let c = v.cell.map(|c| u32::from(c) + 1);
        cells[shape.linearize(c) as usize] = Cell(Some([v.color[0], v.color[1], v.color[2]]));
    }
    let faces = &RIGHT_HANDED_Y_UP_CONFIG.faces;
    let mut buffer = GreedyQuadsBuffer::new(cells.len());
    greedy_quads(&cells, &shape, [0; 3], padded.map(|d| d as u32 - 1), faces, &mut buffer);
    let mut out = Surface::default();
    for (group, face) in buffer.quads.groups.iter().zip(faces) {
        let normal = face.signed_normal().to_array();
        for quad in group {
            let Cell(Some(color)) = cells[shape.linearize(quad.minimum) as usize] else {
                unreachable!("block-mesh starts every quad on a filled cell");
            };
            let corners = face.quad_corners(quad).map(|c| c.to_array().map(|k| k - 1));
            out.faces += (quad.width * quad.height) as usize;
            out.quads.push(Quad { corners: counter_clockwise(corners, normal), normal, color });
        }
    }
    Ok(out)
}

#[cfg(test)]
pub(crate) mod tests {
    use std::collections::{HashMap, HashSet};

    use super::*;
    use crate::grid::GridSpec;
    use crate::voxelize::Voxel;

    /// A model of `dims` cells 0.5 wide with the given coloured cells.
    pub(crate) fn model_of(dims: [u32; 3], cells: impl IntoIterator<Item = ([u16; 3], [u8; 3])>) -> VoxelModel {
        let spec = GridSpec {
            dims,
            cell: [0.5; 3],
            origin: dims.map(|d| -0.25 * d as f32),
            scale: 2.0,
            center: [10.0, 0.0, -4.0],
        };
        let voxels = cells
            .into_iter()
            .map(|(cell, c)| Voxel { cell, color: [c[0], c[1], c[2], 255], part: 0, visible: true })
            .collect();
        VoxelModel { spec, voxels, stats: Default::default(), parts: Vec::new() }
    }

    /// Every unit face between a voxel of `model` and a cell without one: (cell, normal) → colour.
    fn faces_by_brute_force(model: &VoxelModel) -> HashMap<([i64; 3], [i32; 3]), [u8; 3]> {
        let filled: HashSet<[i64; 3]> = model.voxels.iter().map(|v| v.cell.map(i64::from)).collect();
        let mut out = HashMap::new();
        for v in &model.voxels {
            let c = v.cell.map(i64::from);
            for axis in 0..3 {
                for sign in [-1, 1] {
                    let mut n = [0; 3];
                    n[axis] = sign;
                    if !filled.contains(&std::array::from_fn(|k| c[k] + i64::from(n[k]))) {
                        out.insert((c, n), [v.color[0], v.color[1], v.color[2]]);
                    }
                }
            }
        }
        out
    }

    /// The unit faces a rectangle covers, keyed like [`faces_by_brute_force`].
    fn unit_faces(q: &Quad) -> Vec<([i64; 3], [i32; 3])> {
        let lo: [i64; 3] = std::array::from_fn(|a| q.corners.iter().map(|c| i64::from(c[a])).min().unwrap());
        let hi: [i64; 3] = std::array::from_fn(|a| q.corners.iter().map(|c| i64::from(c[a])).max().unwrap());
        let axis = q.normal.iter().position(|&n| n != 0).unwrap();
        // The filled cell lies behind the face: below the plane for a positive normal.
        let layer = if q.normal[axis] > 0 { lo[axis] - 1 } else { lo[axis] };
        let range = |a: usize| if a == axis { layer..layer + 1 } else { lo[a]..hi[a] };
        let mut out = Vec::new();
        for x in range(0) {
            for y in range(1) {
                for z in range(2) {
                    out.push(([x, y, z], q.normal));
                }
            }
        }
        out
    }

    /// Checks that the rectangles cover every visible face exactly once, in its cell's colour, wound
    /// counter-clockwise seen from outside; returns the surface.
    fn checked_surface(model: &VoxelModel) -> Surface {
        let s = surface(model).unwrap();
        let expected = faces_by_brute_force(model);
        let mut covered = HashMap::new();
        for q in &s.quads {
            let [a, b, _, d] = q.corners.map(|c| c.map(i64::from));
            let (u, v) = ([0, 1, 2].map(|k| b[k] - a[k]), [0, 1, 2].map(|k| d[k] - a[k]));
            let cross = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
            assert!((0..3).map(|k| cross[k] * i64::from(q.normal[k])).sum::<i64>() > 0, "{q:?} winds clockwise");
            assert_eq!(unit_faces(q).len(), q.area());
            for face in unit_faces(q) {
                assert!(covered.insert(face, q.color).is_none(), "{face:?} covered twice");
            }
        }
        assert_eq!(covered, expected);
        assert_eq!(s.faces, expected.len());
        s
    }

    #[test]
    fn one_voxel_is_six_unit_squares_facing_out() {
        let m = model_of([3, 3, 3], [([1, 1, 1], [9, 8, 7])]);
        let s = checked_surface(&m);
        assert_eq!((s.faces, s.quads.len()), (6, 6));
        let normals: HashSet<[i32; 3]> = s.quads.iter().map(|q| q.normal).collect();
        assert_eq!(normals.len(), 6);
    }

    #[test]
    fn a_solid_block_has_no_inner_faces_and_merges_into_six_rectangles() {
        let block = (0..4u16).flat_map(|x| (0..3u16).flat_map(move |y| (0..2u16).map(move |z| ([x, y, z], [1, 2, 3]))));
        let s = checked_surface(&model_of([4, 3, 2], block));
        assert_eq!(s.faces, 2 * (4 * 3 + 3 * 2 + 4 * 2));
        assert_eq!(s.quads.len(), 6);
    }

    #[test]
    fn faces_merge_only_within_one_colour() {
        let two = [([0, 0, 0], [255, 0, 0]), ([1, 0, 0], [0, 0, 255])];
        let s = checked_surface(&model_of([2, 1, 1], two));
        assert_eq!((s.faces, s.quads.len()), (10, 10));
        let same = [([0, 0, 0], [255, 0, 0]), ([1, 0, 0], [255, 0, 0])];
        let s = checked_surface(&model_of([2, 1, 1], same));
        assert_eq!((s.faces, s.quads.len()), (10, 6));
    }

    #[test]
    fn a_voxelized_sphere_with_two_colours_is_covered_exactly() {
        let mut soup = crate::TriangleSoup::default();
        soup.add_mesh(&crate::shapes::uv_sphere(1.0, 24), [1.0, 0.5, 0.0, 1.0], "ball");
        let mut m = crate::voxelize(
            &soup,
            &crate::VoxelizeOptions { grid: crate::GridSize::Resolution(20), ..Default::default() },
        )
        .unwrap();
        for v in &mut m.voxels {
            if v.cell[1] < 8 {
                v.color = [10, 200, 30, 255];
            }
        }
        let s = checked_surface(&m);
        assert!(s.quads.len() * 2 < s.faces, "{} quads for {} faces", s.quads.len(), s.faces);
    }
}
