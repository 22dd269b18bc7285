//! glTF export: the exported surface voxelizes back to the cells and colours it was made from, on the
//! corpus and on generated shapes; the command line writes .glb and .gltf.

use std::collections::HashMap;

use voxel_core::export::ExportOptions;
use voxel_core::export::gltf::to_glb;
use voxel_core::shapes::{cuboid, cylinder, dome, torus, uv_sphere};
use voxel_core::{GridSize, ShellMode, TriangleSoup, VoxelModel, VoxelizeOptions, load_file, load_slice, voxelize};

use crate::common::{at_resolution, model};
use crate::corpus::CLOSED;

/// The corpus models the importer reads besides the closed ones (Draco and meshopt files are refused by
/// design).
const OTHERS: &[&str] = &[
    "polypizza-egg-sunny-side-up.glb",
    "khronos-cesiummilktruck/CesiumMilkTruck.gltf",
    "khronos-cesiumman.glb",
    "khronos-animatedmorphcube/AnimatedMorphCube.gltf",
    "khronos-box.glb",
    "khronos-flighthelmet/FlightHelmet.gltf",
];

/// Exports `model` to .glb, voxelizes the export again at the same cell size (the resolution is the
/// longest side of the filled cells' box, no shell, default parity fill) and checks that it gives the same
/// cells, each within 2 units per colour channel.
///
/// The re-import normalizes the export's own bounds, which are the box of the filled cells, so its cell
/// (0, 0, 0) is the export's lowest filled cell `lo`: cells compare after that offset.
fn assert_round_trip(name: &str, model: &VoxelModel) {
    if let Err(e) = round_trip(name, model) {
        panic!("{e}");
    }
}

/// [`assert_round_trip`], returning the first difference.
fn round_trip(name: &str, model: &VoxelModel) -> Result<(), String> {
    let (bytes, stats) = to_glb(model, &ExportOptions { name: name.into() }).unwrap();
    let soup = load_slice(&bytes, None).unwrap_or_else(|e| panic!("{name}: the export does not load: {e}"));
    assert_eq!(soup.triangle_count(), 2 * stats.quads, "{name}");
    let lo: [u16; 3] = std::array::from_fn(|a| model.voxels().map(|v| v.cell[a]).min().unwrap());
    let hi: [u16; 3] = std::array::from_fn(|a| model.voxels().map(|v| v.cell[a]).max().unwrap());
    let sides: [u32; 3] = std::array::from_fn(|a| u32::from(hi[a] - lo[a]) + 1);
    let options = VoxelizeOptions {
        grid: GridSize::Resolution(sides.into_iter().max().unwrap()),
        cell_height_ratio: model.spec.cell[1] / model.spec.cell[0],
        shell: ShellMode::None,
        ..Default::default()
    };
    let back = voxelize(&soup, &options).map_err(|e| format!("{name}: {e}"))?;
    if back.spec.dims != sides {
        return Err(format!("{name}: the export's {sides:?} cells read back as a {:?} grid", back.spec.dims));
    }
    let rgb = |c: [u8; 4]| [c[0], c[1], c[2]];
    let expected: HashMap<[u16; 3], [u8; 3]> =
        model.voxels().map(|v| (std::array::from_fn(|a| v.cell[a] - lo[a]), rgb(v.color))).collect();
    let got: HashMap<[u16; 3], [u8; 3]> = back.voxels().map(|v| (v.cell, rgb(v.color))).collect();
    let missing = expected.keys().filter(|c| !got.contains_key(*c)).count();
    let extra = got.keys().filter(|c| !expected.contains_key(*c)).count();
    if (missing, extra) != (0, 0) {
        return Err(format!("{name}: {missing} exported cells missing, {extra} extra"));
    }
    let mut cells: Vec<_> = expected.iter().collect();
    cells.sort();
    for (cell, want) in cells {
        let have = got[cell];
        if (0..3).any(|k| want[k].abs_diff(have[k]) > 2) {
            return Err(format!("{name}: cell {cell:?} exported {want:?}, read back {have:?}"));
        }
    }
    Ok(())
}

#[test]
fn corpus_models_round_trip_through_glb() {
    let mut failures = Vec::new();
    for name in CLOSED.iter().chain(OTHERS) {
        let Some(path) = model(name) else { return };
        let soup = load_file(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        failures.extend(round_trip(name, &voxelize(&soup, &at_resolution(48)).unwrap()).err());
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn the_duck_round_trips_at_r128_and_with_lego_cells() {
    let Some(path) = model("khronos-duck.glb") else { return };
    let soup = load_file(&path).unwrap();
    assert_round_trip("duck R=128", &voxelize(&soup, &at_resolution(128)).unwrap());
    let lego = VoxelizeOptions { cell_height_ratio: 1.2, ..at_resolution(40) };
    assert_round_trip("duck lego", &voxelize(&soup, &lego).unwrap());
}

#[test]
fn generated_shapes_round_trip_through_glb() {
    let mut parts = TriangleSoup::default();
    parts.add_mesh(&cuboid([-1.0, -1.0, -1.0], [1.0, 0.2, 1.0]), [0.9, 0.1, 0.1, 1.0], "block");
    parts.add_mesh(&uv_sphere(0.8, 24).translated([0.0, 0.9, 0.0]), [0.1, 0.2, 0.9, 1.0], "ball");
    parts.add_mesh(&torus(1.0, 0.3, 32).translated([0.0, -1.0, 0.0]), [0.2, 0.8, 0.3, 1.0], "ring");
    let shapes = [
        ("cube", TriangleSoup::from_mesh(&cuboid([0.0; 3], [1.0, 2.0, 3.0]), [0.5, 0.5, 0.5, 1.0])),
        ("torus", TriangleSoup::from_mesh(&torus(1.0, 0.35, 48), [1.0, 0.6, 0.0, 1.0])),
        ("cylinder", TriangleSoup::from_mesh(&cylinder(0.5, 0.0, 3.0, 32), [0.3, 0.3, 0.8, 1.0])),
        ("open dome", TriangleSoup::from_mesh(&dome(1.0, 16, false), [0.0, 0.0, 0.0, 1.0])),
        ("three parts", parts),
    ];
    for (name, soup) in &shapes {
        for r in [1, 9, 33] {
            assert_round_trip(&format!("{name} R={r}"), &voxelize(soup, &at_resolution(r)).unwrap());
        }
        let lego = VoxelizeOptions { cell_height_ratio: 1.2, ..at_resolution(24) };
        assert_round_trip(&format!("{name} lego"), &voxelize(soup, &lego).unwrap());
    }
}

#[cfg(feature = "cli")]
#[test]
fn the_command_line_writes_glb_and_gltf_by_extension_and_folders_by_format() {
    let dir = std::env::temp_dir().join(format!("voxel-core-cli-gltf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let input = dir.join("plate.glb");
    let soup = TriangleSoup::from_mesh(&cuboid([0.0; 3], [4.0, 1.0, 2.0]), [0.2, 0.4, 0.6, 1.0]);
    std::fs::write(&input, voxel_core::glb::soup_to_glb(&soup).unwrap()).unwrap();
    let run = |args: &[&std::path::Path]| {
        let args = ["voxel-art voxelize".as_ref()].into_iter().chain(args.iter().map(|p| p.as_os_str()));
        voxel_core::cli::run(args.map(std::ffi::OsString::from))
    };
    let r8 = std::path::Path::new("-r8");
    assert_eq!(run(&[&input, r8, "--out".as_ref(), &dir.join("one.glb")]), 0);
    let one = load_file(&dir.join("one.glb")).unwrap();
    // An 8 × 2 × 4 block of one colour: six rectangles.
    assert_eq!(one.triangle_count(), 12);
    assert_eq!(run(&[&input, r8, "--out".as_ref(), &dir.join("two.gltf")]), 0);
    assert!(load_file(&dir.join("two.gltf")).unwrap().corners().eq(one.corners()));
    assert!(dir.join("two.bin").is_file());
    let out = dir.join("all");
    let args = [&input, &input, r8, "--format".as_ref(), "glb".as_ref(), "--out".as_ref(), &out];
    assert_eq!(run(&args), 0);
    assert!(load_file(&out.join("plate.glb")).unwrap().corners().eq(one.corners()));
    std::fs::remove_dir_all(&dir).unwrap();
}
