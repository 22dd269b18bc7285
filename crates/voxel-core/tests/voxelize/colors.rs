//! Colour lookup for visible cells far from every triangle.

use voxel_core::shapes::{IndexedMesh, cuboid};
use voxel_core::{TriangleSoup, voxelize};

use crate::common::at_resolution;

/// Splits every triangle of `mesh` into four at its edge midpoints, `times` times (the surface is unchanged).
fn subdivided(mut mesh: IndexedMesh, times: u32) -> IndexedMesh {
    for _ in 0..times {
        let mut triangles = Vec::with_capacity(mesh.triangles.len() * 4);
        for [a, b, c] in std::mem::take(&mut mesh.triangles) {
            let mut midpoint = |i: u32, j: u32| {
                let (p, q) = (mesh.positions[i as usize], mesh.positions[j as usize]);
                mesh.positions.push(std::array::from_fn(|k| (p[k] + q[k]) / 2.0));
                mesh.positions.len() as u32 - 1
            };
            let (ab, bc, ca) = (midpoint(a, b), midpoint(b, c), midpoint(c, a));
            triangles.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        mesh.triangles = triangles;
    }
    mesh
}

#[test]
fn cells_far_from_the_surface_take_the_color_of_the_nearest_face() {
    // A cube without its +x face, one colour per face. Parity still fills it (every z column crosses the
    // bottom and the top), so the cells of the open side are visible although no triangle is near the
    // middle of that side: each must take the colour of the nearest of the five faces. Two triangles per
    // face (fewer triangles than shell cells: the lookup uses a BVH) and 2048 (more: an octree of the shell).
    let cube = cuboid([-1.0; 3], [1.0; 3]);
    let palette =
        [[1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1.0], [1.0, 1.0, 0.0, 1.0], [0.0, 1.0, 1.0, 1.0]];
    let r = 32u32;
    for splits in [0, 5] {
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
            let part = soup.add_mesh(&subdivided(mesh, splits), palette[faces.len()], "face");
            faces.push((part, axis, usize::from(at == 1.0)));
        }
        assert_eq!(soup.triangle_count(), 10 << (2 * splits));
        let m = voxelize(&soup, &at_resolution(r)).unwrap();
        assert_eq!(m.stats.voxels, (r * r * r) as usize);
        assert_eq!((soup.triangle_count() < m.stats.surface), splits == 0);
        let mut far = 0;
        for v in m.voxels().filter(|v| u32::from(v.cell[0]) == r - 1 && v.cell[1] > 0 && v.cell[2] > 0) {
            assert!(v.visible);
            let centre = v.cell.map(|c| f64::from(c) + 0.5);
            let mut distances: Vec<(f64, u32)> = faces
                .iter()
                .map(|&(part, axis, side)| (if side == 0 { centre[axis] } else { f64::from(r) - centre[axis] }, part))
                .collect();
            distances.sort_by(|a, b| a.0.total_cmp(&b.0));
            if distances[0].0 == distances[1].0 {
                continue; // equally near two faces
            }
            far += usize::from(distances[0].0 > 8.0);
            let part = distances[0].1;
            assert_eq!(v.part, part, "{splits} splits, cell {:?}", v.cell);
            assert_eq!(
                v.color,
                palette[part as usize].map(|c| (c * 255.0) as u8),
                "{splits} splits, cell {:?}",
                v.cell
            );
        }
        // Cells more than 8 cells from every face exist (beyond any neighbourhood of shell cells).
        assert!(far > 100, "{far} far cells");
    }
}
