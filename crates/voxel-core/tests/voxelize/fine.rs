//! Fine grids: R = 1024 with the default memory budget on a generated scene of CI size (64 overlapping
//! spheres, 65,536 triangles), checked against a reference winding count computed here on sampled columns.

use glam::DVec3;
use voxel_core::{ShellMode, load_slice, voxelize};

use crate::common::at_resolution;
use crate::scenes;

/// The crossings of the +Z column through `(x, y)` (grid coordinates) with outward-facing `tris`: the depth of
/// each, and +1 where the surface faces up (the column leaves a part there), −1 where it faces down.
fn crossings(tris: &[[DVec3; 3]], x: f64, y: f64) -> Vec<(f64, i32)> {
    let mut out = Vec::new();
    for &[a, b, c] in tris {
        let edge = |p: DVec3, q: DVec3| (q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x);
        let (e0, e1, e2) = (edge(a, b), edge(b, c), edge(c, a));
        if (e0 > 0.0 && e1 > 0.0 && e2 > 0.0) || (e0 < 0.0 && e1 < 0.0 && e2 < 0.0) {
            let area = e0 + e1 + e2; // twice the projected area, signed by facing
            out.push(((e1 * a.z + e2 * b.z + e0 * c.z) / area, if area > 0.0 { 1 } else { -1 }));
        }
    }
    out
}

#[test]
fn a_fine_grid_matches_a_reference_winding_count_on_sampled_columns() {
    let scene = scenes::spheres(64);
    let soup = load_slice(&scenes::to_glb(&scene), None).unwrap();
    assert_eq!(soup.triangle_count(), 64 * scenes::SPHERE_TRIANGLES);
    let model = voxelize(&soup, &voxel_core::VoxelizeOptions { shell: ShellMode::None, ..at_resolution(1024) })
        .expect("R=1024 fits in memory by default");
    let spec = model.spec;
    assert_eq!(spec.dims.into_iter().max(), Some(1024));
    assert!(spec.cell_count() > 1 << 28, "{:?}", spec.dims);
    let solid = model.occupancy();
    let tris: Vec<[DVec3; 3]> =
        (0..soup.triangle_count()).map(|t| soup.triangle_positions(t).map(|p| spec.to_grid(p))).collect();
    // Columns through the centres of sampled triangles, so that every one crosses the model.
    let (mut columns, mut filled) = (0, 0);
    for t in tris.iter().step_by(tris.len() / 97) {
        let centre = (t[0] + t[1] + t[2]) / 3.0;
        let (x, y) = (centre.x.floor() as u32, centre.y.floor() as u32);
        let column = crossings(&tris, f64::from(x) + 0.5, f64::from(y) + 0.5);
        assert_eq!(column.iter().map(|c| c.1).sum::<i32>(), 0, "column ({x}, {y}) is not closed");
        for z in 0..spec.dims[2] {
            let centre = f64::from(z) + 0.5;
            let winding: i32 = column.iter().filter(|c| c.0 > centre).map(|c| c.1).sum();
            assert_eq!(solid.get(spec.index(x, y, z)), winding != 0, "cell ({x}, {y}, {z}): winding {winding}");
            filled += usize::from(winding != 0);
        }
        columns += 1;
    }
    assert!(columns >= 97 && filled > 10_000, "{columns} columns, {filled} filled cells");
}
