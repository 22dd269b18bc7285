//! The visible surface of a voxel model as rectangles: the faces between a filled and an empty cell (never
//! the faces between two filled cells), merged greedily into larger rectangles where neighbouring faces
//! share a colour.
//!
//! The work follows the faces, not the grid: the exposed faces are found from the voxel list, sorted per
//! direction by (plane, row, column), cut into runs of one colour along each row, and a run extends the
//! rectangle of the row before when it spans the same columns in the same colour.

use crate::model::VoxelModel;
use crate::srgb::srgb_to_linear;

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

/// A face direction: the normal's axis and sign. Within its plane a face is addressed by the column `u`
/// (axis + 1) and the row `v` (axis + 2), so that u × v points along +axis.
#[derive(Clone, Copy, Debug)]
struct Direction {
    axis: usize,
    positive: bool,
}

impl Direction {
    const ALL: [Direction; 6] = [
        Direction { axis: 0, positive: false },
        Direction { axis: 0, positive: true },
        Direction { axis: 1, positive: false },
        Direction { axis: 1, positive: true },
        Direction { axis: 2, positive: false },
        Direction { axis: 2, positive: true },
    ];

    /// The grid point at `plane` along the axis, column `u` and row `v`.
    fn point(self, plane: u32, u: u32, v: u32) -> [u32; 3] {
        let mut p = [0; 3];
        p[self.axis] = plane;
        p[(self.axis + 1) % 3] = u;
        p[(self.axis + 2) % 3] = v;
        p
    }
}

/// A run of faces of one colour along a row: columns `u0..u1`, and the rectangle it belongs to.
#[derive(Clone, Copy, Debug)]
struct Run {
    u0: u32,
    u1: u32,
    color: [u8; 3],
    rect: usize,
}

/// A merged rectangle within a plane: columns `u0..u1`, rows `v0..v1`.
#[derive(Clone, Copy, Debug)]
struct Rect {
    plane: u32,
    u0: u32,
    u1: u32,
    v0: u32,
    v1: u32,
    color: [u8; 3],
}

/// Sort key of a face: plane, then row, then column (each below 2^17 since grids are at most 65 535 cells
/// a side).
fn face_key(plane: u32, u: u32, v: u32) -> u64 {
    u64::from(plane) << 40 | u64::from(v) << 20 | u64::from(u)
}

/// Merges the faces of one direction, sorted by [`face_key`], into rectangles.
fn merge(faces: &[(u64, [u8; 3])]) -> Vec<Rect> {
    let mut rects: Vec<Rect> = Vec::new();
    // The runs of the row before (by ascending u0) and of the current row, with the row they lie in.
    let (mut previous, mut current): (Vec<Run>, Vec<Run>) = (Vec::new(), Vec::new());
    let mut row = None;
    let mut k = 0;
    while k < faces.len() {
        let (key, color) = faces[k];
        let (plane, v, u0) = ((key >> 40) as u32, (key >> 20 & 0xF_FFFF) as u32, (key & 0xF_FFFF) as u32);
        let mut u1 = u0 + 1;
        k += 1;
        while k < faces.len() && faces[k].0 == face_key(plane, u1, v) && faces[k].1 == color {
            u1 += 1;
            k += 1;
        }
        if row != Some((plane, v)) {
            // A new row: the current one becomes the row before, if it is adjacent.
            let adjacent = row.is_some_and(|(p, r)| p == plane && r + 1 == v);
            std::mem::swap(&mut previous, &mut current);
            current.clear();
            if !adjacent {
                previous.clear();
            }
            row = Some((plane, v));
        }
        // The run below with the same columns and colour, if any, carries its rectangle up one row.
        let below =
            previous.iter().position(|r| r.u0 == u0).filter(|&i| previous[i].u1 == u1 && previous[i].color == color);
        let rect = match below {
            Some(i) => {
                let rect = previous.swap_remove(i).rect;
                rects[rect].v1 = v + 1;
                rect
            }
            None => {
                rects.push(Rect { plane, u0, u1, v0: v, v1: v + 1, color });
                rects.len() - 1
            }
        };
        current.push(Run { u0, u1, color, rect });
    }
    rects
}

/// The surface of `model`: its visible faces merged into single-coloured rectangles.
///
/// The faces are those between a voxel of the model and a cell without one, so a hollowed model (visible
/// voxels only) also gets the walls of its emptied inside; mesh the solid model for the outside alone.
/// Only the visible voxels ([`VoxelModel::visible_voxels`]) are looked at: the others have no empty face
/// neighbour.
pub fn surface(model: &VoxelModel) -> Surface {
    let spec = &model.spec;
    let filled = model.occupancy();
    let strides = [spec.dims[1] as usize * spec.dims[2] as usize, spec.dims[2] as usize, 1];
    let mut faces: [Vec<(u64, [u8; 3])>; 6] = Default::default();
    for v in model.visible_voxels() {
        let cell = v.cell.map(u32::from);
        let i = spec.index(cell[0], cell[1], cell[2]);
        let color = [v.color[0], v.color[1], v.color[2]];
        for (d, dir) in Direction::ALL.into_iter().enumerate() {
            let a = dir.axis;
            let covered = if dir.positive {
                cell[a] + 1 < spec.dims[a] && filled.get(i + strides[a])
            } else {
                cell[a] > 0 && filled.get(i - strides[a])
            };
            if covered {
                continue;
            }
            let plane = cell[dir.axis] + u32::from(dir.positive);
            faces[d].push((face_key(plane, cell[(dir.axis + 1) % 3], cell[(dir.axis + 2) % 3]), color));
        }
    }
    let mut out = Surface { quads: Vec::new(), faces: faces.iter().map(Vec::len).sum() };
    for (dir, mut faces) in Direction::ALL.into_iter().zip(faces) {
        faces.sort_unstable_by_key(|f| f.0);
        let mut normal = [0; 3];
        normal[dir.axis] = if dir.positive { 1 } else { -1 };
        for r in merge(&faces) {
            let p = |u, v| dir.point(r.plane, u, v);
            // u × v points along +axis: this loop winds counter-clockwise seen from that side.
            let ccw_from_positive = [p(r.u0, r.v0), p(r.u1, r.v0), p(r.u1, r.v1), p(r.u0, r.v1)];
            let corners = if dir.positive {
                ccw_from_positive
            } else {
                [p(r.u0, r.v0), p(r.u0, r.v1), p(r.u1, r.v1), p(r.u1, r.v0)]
            };
            out.quads.push(Quad { corners, normal, color: r.color });
        }
    }
    out
}

/// The vertex and index data of a surface in normalized model space (four vertices per rectangle).
pub struct SurfaceVertices {
    /// Corner positions.
    pub positions: Vec<[f32; 3]>,
    /// The rectangle's outward normal, per corner.
    pub normals: Vec<[f32; 3]>,
    /// The rectangle's linear RGB colour, per corner.
    pub colors: Vec<[f32; 3]>,
    /// Two triangles per rectangle.
    pub indices: Vec<u32>,
}

impl SurfaceVertices {
    /// The vertices of `surface`, the surface of `model`.
    pub fn of(model: &VoxelModel, surface: &Surface) -> Self {
        let spec = &model.spec;
        let n = surface.quads.len() * 4;
        let mut out = Self {
            positions: Vec::with_capacity(n),
            normals: Vec::with_capacity(n),
            colors: Vec::with_capacity(n),
            indices: Vec::with_capacity(surface.quads.len() * 6),
        };
        for quad in &surface.quads {
            let first = out.positions.len() as u32;
            let color = quad.color.map(srgb_to_linear);
            for corner in quad.corners {
                // In f64 so that a corner is the nearest f32 to its exact place.
                out.positions.push(std::array::from_fn(|a| {
                    (f64::from(spec.origin[a]) + f64::from(corner[a]) * f64::from(spec.cell[a])) as f32
                }));
                out.normals.push(quad.normal.map(|c| c as f32));
                out.colors.push(color);
            }
            out.indices.extend([0, 1, 2, 0, 2, 3].map(|k| first + k));
        }
        out
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use std::collections::{HashMap, HashSet};

    use super::*;
    use crate::grid::GridSpec;

    /// A model on a grid of 8k × 4k × 8k cells 0.5 wide with the given coloured cells. The grid is fitted
    /// to a box of 2k × k × 2k centred on (10, 0, -4), whose diagonal (3k) is scaled to 6k: the normalization
    /// scale is exactly 2 and the grid's origin (-2k, -k, -2k).
    pub(crate) fn model_of(k: u16, cells: impl IntoIterator<Item = ([u16; 3], [u8; 3])>) -> VoxelModel {
        let k = f32::from(k);
        let mut soup = crate::TriangleSoup::default();
        let (lo, hi) = ([10.0 - k, -0.5 * k, -4.0 - k], [10.0 + k, 0.5 * k, -4.0 + k]);
        soup.add_mesh(&crate::shapes::cuboid(lo, hi), [1.0; 4], "box");
        let spec = GridSpec::fit(&soup, 6.0 * k, crate::GridSize::Cell(0.5), 1.0, crate::grid::MAX_CELLS).unwrap();
        VoxelModel::from_cells(spec, cells.into_iter().map(|(cell, c)| (cell, [c[0], c[1], c[2], 255])))
    }

    /// Every unit face between a voxel of `model` and a cell without one: (cell, normal) → colour.
    fn faces_by_brute_force(model: &VoxelModel) -> HashMap<([i64; 3], [i32; 3]), [u8; 3]> {
        let filled: HashSet<[i64; 3]> = model.voxels().map(|v| v.cell.map(i64::from)).collect();
        let mut out = HashMap::new();
        for v in model.voxels() {
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
        let s = surface(model);
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
        let m = model_of(1, [([1, 1, 1], [9, 8, 7])]);
        let s = checked_surface(&m);
        assert_eq!((s.faces, s.quads.len()), (6, 6));
        let normals: HashSet<[i32; 3]> = s.quads.iter().map(|q| q.normal).collect();
        assert_eq!(normals.len(), 6);
    }

    #[test]
    fn a_solid_block_has_no_inner_faces_and_merges_into_six_rectangles() {
        let block = (0..4u16).flat_map(|x| (0..3u16).flat_map(move |y| (0..2u16).map(move |z| ([x, y, z], [1, 2, 3]))));
        let s = checked_surface(&model_of(1, block));
        assert_eq!(s.faces, 2 * (4 * 3 + 3 * 2 + 4 * 2));
        assert_eq!(s.quads.len(), 6);
    }

    #[test]
    fn faces_merge_only_within_one_color() {
        let two = [([0, 0, 0], [255, 0, 0]), ([1, 0, 0], [0, 0, 255])];
        let s = checked_surface(&model_of(1, two));
        assert_eq!((s.faces, s.quads.len()), (10, 10));
        let same = [([0, 0, 0], [255, 0, 0]), ([1, 0, 0], [255, 0, 0])];
        let s = checked_surface(&model_of(1, same));
        assert_eq!((s.faces, s.quads.len()), (10, 6));
    }

    #[test]
    fn a_voxelized_sphere_with_two_colors_is_covered_exactly() {
        let mut soup = crate::TriangleSoup::default();
        soup.add_mesh(&crate::shapes::uv_sphere(1.0, 24), [1.0, 0.5, 0.0, 1.0], "ball");
        let mut m = crate::voxelize(
            &soup,
            &crate::VoxelizeOptions { grid: crate::GridSize::Resolution(20), ..Default::default() },
        )
        .unwrap();
        m.recolor(|v| if v.cell[1] < 8 { [10, 200, 30, 255] } else { v.color });
        let s = checked_surface(&m);
        assert!(s.quads.len() * 2 < s.faces, "{} quads for {} faces", s.quads.len(), s.faces);
    }
}
