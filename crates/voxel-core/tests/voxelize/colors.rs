//! Colour lookup for visible cells far from every triangle.

use voxel_core::shapes::{IndexedMesh, cuboid};
use voxel_core::{TriangleSoup, voxelize};

use crate::common::at_resolution;

#[test]
fn cells_far_from_the_surface_take_the_colour_of_the_nearest_face() {
    // A cube without its +x face, one colour per face. Parity still fills it (every z column crosses the
    // bottom and the top), so the cells of the open side are visible although no triangle is near the
    // middle of that side: each must take the colour of the nearest of the five faces.
    let cube = cuboid([-1.0; 3], [1.0; 3]);
    let palette =
        [[1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1.0], [1.0, 1.0, 0.0, 1.0], [0.0, 1.0, 1.0, 1.0]];
    let mut soup = TriangleSoup::default();
    // (part, axis, side) of each face kept: side 0 is the face at −1, side 1 the face at +1.
    let mut faces = Vec::new();
    for face in cube.triangles.chunks(2) {
        let corners = face.iter().flatten().map(|&i| cube.positions[i as usize]);
        let Some((axis, at)) = (0..3).find_map(|a| {
            let first = cube.positions[face[0][0] as usize][a];
            corners.clone().all(|p| p[a] == first).then_some((a, first))
        }) else {
            panic!("a cuboid face is axis-aligned")
        };
        if axis == 0 && at == 1.0 {
            continue;
        }
        let mesh = IndexedMesh { positions: cube.positions.clone(), triangles: face.to_vec() };
        let part = soup.add_mesh(&mesh, palette[faces.len()], "face");
        faces.push((part, axis, usize::from(at == 1.0)));
    }
    let r = 32u32;
    let m = voxelize(&soup, &at_resolution(r)).unwrap();
    assert_eq!(m.stats.voxels, (r * r * r) as usize);
    let mut far = 0;
    for v in m.voxels.iter().filter(|v| u32::from(v.cell[0]) == r - 1 && v.cell[1] > 0 && v.cell[2] > 0) {
        assert!(v.visible);
        let centre = v.cell.map(|c| f64::from(c) + 0.5);
        let distances: Vec<(f64, u32)> = faces
            .iter()
            .map(|&(part, axis, side)| (if side == 0 { centre[axis] } else { f64::from(r) - centre[axis] }, part))
            .collect();
        let mut sorted = distances.clone();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        if sorted[0].0 == sorted[1].0 {
            continue; // equally near two faces
        }
        far += usize::from(sorted[0].0 > 8.0);
        assert_eq!(v.part, sorted[0].1, "cell {:?}", v.cell);
        assert_eq!(v.color, palette[sorted[0].1 as usize].map(|c| (c * 255.0) as u8), "cell {:?}", v.cell);
    }
    // Cells more than 8 cells from every face exist (beyond any neighbourhood of shell cells).
    assert!(far > 100, "{far} far cells");
}
