//! The same shape under any node scale or translation gives the same cells: faces that lie on cell
//! boundaries up to f32 rounding are decided alike for every copy.

use voxel_core::shapes::cuboid;
use voxel_core::{FillMode, ShellMode, TriangleSoup, VoxelModel, VoxelStats, VoxelizeOptions, load_slice, voxelize};

use crate::common::{at_resolution, cube_document, cuboid_buffer, glb};

/// The box from `lo` to `hi` on one node with the TRS properties `trs` (e.g. `{"scale": [2, 2, 2]}`),
/// imported from a .glb and voxelized with `options`.
fn voxelize_box(lo: [f32; 3], hi: [f32; 3], trs: serde_json::Value, options: &VoxelizeOptions) -> VoxelModel {
    let (bin, positions_len, index_count) = cuboid_buffer(lo, hi);
    let mut doc = cube_document(bin.len(), positions_len, index_count);
    doc["accessors"][0]["min"] = serde_json::json!(lo);
    doc["accessors"][0]["max"] = serde_json::json!(hi);
    doc["nodes"][0] = trs;
    doc["nodes"][0]["mesh"] = serde_json::json!(0);
    let soup = load_slice(&glb(&doc, &bin), None).expect("the box loads");
    voxelize(&soup, options).expect("the box voxelizes")
}

/// The scales of the issue (0.33985769748687744 is an f32 taken from a real file).
const SCALES: [f32; 6] = [1.0, 0.1, 0.339_857_7, 10.0, 1e-3, 1e3];

/// Default options, hollow, and flood fill with the full shell (which only closes if the shell does), at `r`.
fn option_sets(r: u32) -> [(&'static str, VoxelizeOptions); 3] {
    [
        ("default", at_resolution(r)),
        ("hollow", VoxelizeOptions { hollow: true, ..at_resolution(r) }),
        ("flood", VoxelizeOptions { fill: FillMode::Flood, shell: ShellMode::All, ..at_resolution(r) }),
    ]
}

/// The stats and the cells (ascending) of a voxelization.
fn outcome(m: &VoxelModel) -> (VoxelStats, Vec<[u16; 3]>) {
    (m.stats, m.voxels().map(|v| v.cell).collect())
}

#[test]
fn a_cube_gives_the_same_cells_under_any_node_scale_and_translation() {
    for r in [16u32, 64] {
        let shell = (r.pow(3) - (r - 2).pow(3)) as usize;
        for (what, options) in option_sets(r) {
            let reference = voxelize_box([-1.0; 3], [1.0; 3], serde_json::json!({}), &options);
            let expected = outcome(&reference);
            // The cube fills the grid exactly: R³ cells, its shell and its visible cells the outer layer.
            assert_eq!(
                (reference.stats.voxels, reference.stats.surface, reference.stats.visible),
                (r.pow(3) as usize, shell, shell),
                "{what} R={r}"
            );
            assert_eq!(reference.len(), if options.hollow { shell } else { r.pow(3) as usize });
            for s in SCALES {
                // Moved by a few of its own sizes, and by about a hundred (where f32 keeps 2⁻¹⁸ of its size).
                for translation in [[0.0; 3], [3.7, -1.3, 12.0], [105.25, -20.5, 7.75]].map(|t| t.map(|c| c * s)) {
                    let trs = serde_json::json!({"scale": [s, s, s], "translation": translation});
                    let m = voxelize_box([-1.0; 3], [1.0; 3], trs, &options);
                    assert_eq!(outcome(&m), expected, "{what} R={r} scale {s} moved {translation:?}");
                }
            }
        }
    }
}

#[test]
fn a_rotated_non_uniformly_scaled_box_gives_the_cells_of_the_same_box_built_axis_aligned() {
    // [-1, 1]² × [-½, ½] scaled (1, 2, 1) and turned 90° about z is [-2, 2] × [-1, 1] × [-½, ½]; the
    // quaternion's f32 components put every corner a rounding error off the grid's cell boundaries.
    let half = std::f32::consts::FRAC_1_SQRT_2;
    for r in [16u32, 64] {
        for (what, options) in option_sets(r) {
            let reference = voxelize_box([-2.0, -1.0, -0.5], [2.0, 1.0, 0.5], serde_json::json!({}), &options);
            assert_eq!(reference.spec.dims, [r, r / 2, r / 4], "{what} R={r}");
            assert_eq!(reference.stats.voxels, (r * r / 2 * r / 4) as usize, "{what} R={r}");
            let expected = outcome(&reference);
            for s in SCALES {
                let trs = serde_json::json!({
                    "scale": [s, 2.0 * s, s],
                    "rotation": [0.0, 0.0, half, half],
                    "translation": [-4.5 * s, 0.25 * s, 2.0 * s],
                });
                let m = voxelize_box([-1.0, -1.0, -0.5], [1.0, 1.0, 0.5], trs, &options);
                assert_eq!(m.spec.dims, reference.spec.dims, "{what} R={r} scale {s}");
                assert_eq!(outcome(&m), expected, "{what} R={r} scale {s}");
            }
        }
    }
}

#[test]
fn boxes_with_faces_on_inner_cell_boundaries_get_exactly_their_cells_at_any_scale() {
    // A = [-1, 1]³ and B = [3, 4] × [1.5, 2]² span a grid of 20 × 12 × 12 cells of ¼ at R=20; every face lies
    // on a cell boundary inside the grid, where the shell must not reach across the edges into the cells
    // beyond (they would join the solid as thin surface): parity gives exactly the boxes' 8³ + 4·2·2 cells.
    let r = 20;
    let boxes = |s: f32, offset: [f32; 3]| {
        let place = |mut mesh: voxel_core::shapes::IndexedMesh| {
            for p in &mut mesh.positions {
                *p = std::array::from_fn(|a| p[a] * s + offset[a] * s);
            }
            mesh
        };
        let mut soup = TriangleSoup::from_mesh(&place(cuboid([-1.0; 3], [1.0; 3])), [1.0; 4]);
        soup.add_mesh(&place(cuboid([3.0, 1.5, 1.5], [4.0, 2.0, 2.0])), [1.0; 4], "b");
        soup
    };
    for (what, options) in option_sets(r) {
        let reference = voxelize(&boxes(1.0, [0.0; 3]), &options).unwrap();
        assert_eq!(reference.spec.dims, [20, 12, 12]);
        if options.fill != FillMode::Flood {
            assert_eq!((reference.stats.voxels, reference.stats.visible), (8 * 8 * 8 + 16, 8 * 8 * 8 - 6 * 6 * 6 + 16));
        }
        let expected = outcome(&reference);
        for s in SCALES {
            for offset in [[0.0; 3], [3.7, -1.3, 12.0]] {
                let m = voxelize(&boxes(s, offset), &options).unwrap();
                assert_eq!(outcome(&m), expected, "{what} scale {s} moved {offset:?}");
            }
        }
    }
}
