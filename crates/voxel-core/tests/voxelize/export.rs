//! MagicaVoxel export: written files read back with dot_vox.

use std::collections::HashSet;

use voxel_core::shapes::cuboid;
use voxel_core::vox::write_vox;
use voxel_core::{GridSize, TriangleSoup, VoxelizeOptions, voxelize};

fn read_back(model: &voxel_core::VoxelModel, name: &str) -> (dot_vox::DotVoxData, voxel_core::vox::VoxSummary) {
    let path = std::env::temp_dir().join(format!("voxel-core-test-{}-{name}.vox", std::process::id()));
    let summary = write_vox(model, &path).unwrap();
    let data = dot_vox::load(path.to_str().unwrap()).unwrap();
    std::fs::remove_file(&path).unwrap();
    (data, summary)
}

#[test]
fn a_small_model_round_trips_with_its_colors() {
    let mut soup = TriangleSoup::default();
    soup.add_mesh(&cuboid([0.0; 3], [1.0; 3]), [1.0, 0.0, 0.0, 1.0], "red");
    soup.add_mesh(&cuboid([1.0, 0.0, 0.0], [2.0, 1.0, 1.0]), [0.0, 0.0, 1.0, 1.0], "blue");
    let m = voxelize(&soup, &VoxelizeOptions { grid: GridSize::Resolution(16), ..Default::default() }).unwrap();
    let (data, summary) = read_back(&m, "small");
    assert_eq!(data.models.len(), 1);
    assert_eq!(summary.models, 1);
    let size = &data.models[0].size;
    // MagicaVoxel is z-up: our (x, y, z) grid becomes (x, z, y).
    assert_eq!([size.x, size.y, size.z], [16, 8, 8]);
    assert_eq!(data.models[0].voxels.len(), m.len());
    let colors: HashSet<[u8; 3]> = data.models[0]
        .voxels
        .iter()
        .map(|v| {
            let c = data.palette[v.i as usize];
            [c.r, c.g, c.b]
        })
        .collect();
    assert_eq!(colors, HashSet::from([[255, 0, 0], [0, 0, 255]]));
}

#[test]
fn big_grids_split_into_several_models_and_many_colors_are_quantized() {
    let cube = TriangleSoup::from_mesh(&cuboid([0.0; 3], [1.0; 3]), [1.0; 4]);
    let mut m =
        voxelize(&cube, &VoxelizeOptions { grid: GridSize::Resolution(300), hollow: true, ..Default::default() })
            .unwrap();
    // Give every voxel one of ~4000 colours.
    let mut k = 0;
    m.recolor(|_| {
        k += 1;
        [(k % 16 * 16) as u8, (k / 16 % 16 * 16) as u8, (k / 256 % 16 * 16) as u8, 255]
    });
    let (data, summary) = read_back(&m, "big");
    assert_eq!(data.models.len(), 8, "a 300³ grid spans 2×2×2 blocks of 256");
    assert!(data.models.iter().all(|md| md.size.x <= 256 && md.size.y <= 256 && md.size.z <= 256));
    assert_eq!(data.models.iter().map(|md| md.voxels.len()).sum::<usize>(), m.len());
    assert_eq!(summary.colors, 255);
    let used: HashSet<u8> = data.models.iter().flat_map(|md| md.voxels.iter().map(|v| v.i)).collect();
    assert!(used.len() <= 255 && used.len() > 200);
}
