//! The real third-party models of ../shared/models (skipped with a printed reason when absent).

use std::collections::HashSet;

use voxel_core::color::rgb_to_hsl;
use voxel_core::{FillMode, Method, ShellMode, VoxelizeOptions, load_file, voxelize};

use crate::common::{at_resolution, cells, model, models_dir};

/// Models closed as a whole (see SOURCES.md), loadable without Draco/meshopt.
pub(crate) const CLOSED: &[&str] = &[
    "polypizza-cherry.glb",
    "polypizza-chili-pepper.glb",
    "polypizza-bonsai.glb",
    "kenney-alien.glb",
    "kenney-craft-speederD/craft_speederD.gltf",
    "khronos-boxtextured/BoxTextured.gltf",
    "khronos-boxvertexcolors.glb",
    "khronos-duck.glb",
    "khronos-fox.glb",
];

#[test]
fn fast_equals_the_reference_cell_for_cell_on_closed_models() {
    for name in CLOSED {
        let Some(path) = model(name) else { return };
        let soup = load_file(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        for (fill, r) in
            [(FillMode::Winding, 32), (FillMode::Winding, 64), (FillMode::Parity, 32), (FillMode::Parity, 64)]
        {
            let run = |method| {
                let opts = VoxelizeOptions { method, fill, shell: ShellMode::None, ..at_resolution(r) };
                cells(&voxelize(&soup, &opts).unwrap())
            };
            let fast = run(Method::Fast);
            let reference = run(Method::Reference);
            assert!(!fast.is_empty(), "{name} {fill:?} R={r}: empty");
            // Exactly equal: both use the same exact column test and the same triangle roles, and closed
            // models give every column an even number of parity crossings and a zero winding sum (fast only
            // departs from the reference on odd columns of open meshes).
            assert_eq!(fast.symmetric_difference(&reference).count(), 0, "{name} {fill:?} R={r}");
        }
    }
}

/// Empty cells that no path of empty cells (face neighbours) from outside the grid reaches.
fn enclosed_empty_cells(m: &voxel_core::VoxelModel) -> HashSet<[u16; 3]> {
    let filled = cells(m);
    let dims = m.spec.dims.map(|d| d as i32);
    let empty = |c: [i32; 3]| (0..3).any(|k| c[k] < 0 || c[k] >= dims[k]) || !filled.contains(&c.map(|v| v as u16));
    // Flood the empty cells from a corner of a one-cell pad round the grid.
    let mut reached: HashSet<[i32; 3]> = HashSet::from([[-1; 3]]);
    let mut stack = vec![[-1; 3]];
    while let Some(c) = stack.pop() {
        for a in 0..3 {
            for d in [-1, 1] {
                let mut n = c;
                n[a] += d;
                let in_pad = (0..3).all(|k| (-1..=dims[k]).contains(&n[k]));
                if in_pad && empty(n) && reached.insert(n) {
                    stack.push(n);
                }
            }
        }
    }
    let mut enclosed = HashSet::new();
    for x in 0..dims[0] {
        for y in 0..dims[1] {
            for z in 0..dims[2] {
                if empty([x, y, z]) && !reached.contains(&[x, y, z]) {
                    enclosed.insert([x, y, z].map(|v| v as u16));
                }
            }
        }
    }
    enclosed
}

#[test]
fn the_bonsai_has_no_enclosed_empty_cells_away_from_its_surface_under_winding() {
    let Some(path) = model("polypizza-bonsai.glb") else { return };
    let soup = load_file(&path).unwrap();
    let run = |fill| voxelize(&soup, &VoxelizeOptions { fill, ..at_resolution(48) }).unwrap();
    let surface = cells(&run(FillMode::None));
    let enclosed = |fill| enclosed_empty_cells(&run(fill));
    // Parity leaves the overlaps of the bonsai's parts empty, hidden inside the model.
    let parity = enclosed(FillMode::Parity);
    assert!(parity.difference(&surface).count() > 100, "parity: {} enclosed", parity.len());
    // Winding fills them; what is left are single cells the surface grazes (centre just outside it).
    let winding = enclosed(FillMode::Winding);
    assert!(winding.len() < 20, "{} enclosed", winding.len());
    assert!(winding.is_subset(&surface), "an enclosed empty cell away from the surface");
}

#[test]
fn every_loadable_corpus_model_voxelizes_with_default_options() {
    for name in CLOSED.iter().chain(&["polypizza-egg-sunny-side-up.glb", "khronos-flighthelmet/FlightHelmet.gltf"]) {
        let Some(path) = model(name) else { return };
        let soup = load_file(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        let m = voxelize(&soup, &VoxelizeOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(m.len() > 100, "{name}: only {} voxels", m.len());
        assert!(m.stats.visible <= m.stats.voxels && m.stats.visible > 0);
        assert_eq!(m.len(), m.stats.voxels);
    }
}

#[test]
fn the_fried_eggs_white_is_kept_at_the_default_grid() {
    let Some(path) = model("polypizza-egg-sunny-side-up.glb") else { return };
    let soup = load_file(&path).unwrap();
    let footprint = |shell| {
        let m = voxelize(&soup, &VoxelizeOptions { shell, ..Default::default() }).unwrap();
        // Part 0 is the white (lambert2SG), part 1 the yolk.
        let white = m.voxels().filter(|v| v.part == 0).count();
        (m.voxels().map(|v| [v.cell[0], v.cell[2]]).collect::<HashSet<_>>().len(), white)
    };
    let (parity_only, _) = footprint(ShellMode::None);
    let (auto, white) = footprint(ShellMode::Auto);
    let (all, _) = footprint(ShellMode::All);
    // Every column the surface touches is covered by the default; parity alone (the article) loses the
    // thin rim of the white.
    assert_eq!(auto, all, "the default covers {auto} of {all} columns");
    assert!(parity_only * 100 < all * 95, "parity alone already covers {parity_only} of {all} columns");
    assert!(white > 400, "only {white} white voxels");
}

/// Fraction of voxels whose colour passes `pred`.
fn fraction(colors: &[[u8; 4]], pred: impl Fn([f32; 3]) -> bool) -> f64 {
    let n = colors.iter().filter(|c| pred(rgb_to_hsl([c[0], c[1], c[2]].map(|v| f32::from(v) / 255.0)))).count();
    n as f64 / colors.len().max(1) as f64
}

fn surface_colors(name: &str) -> Option<Vec<[u8; 4]>> {
    let soup = load_file(&model(name)?).unwrap();
    let m = voxelize(&soup, &VoxelizeOptions { hollow: true, ..at_resolution(48) }).unwrap();
    Some(m.voxels().map(|v| v.color).collect())
}

#[test]
fn vertex_colors_reach_the_voxels() {
    let Some(colors) = surface_colors("khronos-boxvertexcolors.glb") else { return };
    let distinct: HashSet<_> = colors.iter().collect();
    assert!(distinct.len() > 100, "only {} colours", distinct.len());
    // The vertex colours span the hue circle: red, green and blue voxels all exist.
    for (lo, hi) in [(0.95, 1.05), (0.36, 0.42), (0.62, 0.70)] {
        let hue_in = |h: f32| (lo..hi).contains(&h) || (lo..hi).contains(&(h + 1.0));
        assert!(fraction(&colors, |[h, s, _]| s > 0.3 && hue_in(h)) > 0.01, "no voxels with hue in {lo}..{hi}");
    }
}

#[test]
fn textured_box_voxels_carry_the_texture_not_white() {
    let Some(colors) = surface_colors("khronos-boxtextured/BoxTextured.gltf") else { return };
    let white = fraction(&colors, |[_, _, l]| l > 0.97);
    assert!(white < 0.5, "{white} of the voxels are white");
    // The Cesium logo is green on grey-white: saturated green voxels must be there.
    assert!(fraction(&colors, |[h, s, _]| s > 0.3 && (0.2..0.45).contains(&h)) > 0.05);
    assert!(colors.iter().collect::<HashSet<_>>().len() > 20);
}

#[test]
fn the_duck_is_yellow_and_orange() {
    let Some(colors) = surface_colors("khronos-duck.glb") else { return };
    let warm = fraction(&colors, |[h, s, _]| s > 0.4 && (0.02..0.18).contains(&h));
    assert!(warm > 0.8, "only {warm} of the duck is yellow/orange");
}

#[test]
fn the_cherry_has_red_and_green_voxels() {
    let Some(colors) = surface_colors("polypizza-cherry.glb") else { return };
    let red = fraction(&colors, |[h, s, _]| s > 0.5 && !(0.04..=0.96).contains(&h));
    let green = fraction(&colors, |[h, s, _]| s > 0.5 && (0.2..0.4).contains(&h));
    assert!(red > 0.4, "red {red}");
    assert!(green > 0.02, "green {green}");
}

#[test]
fn node_hierarchies_place_every_part() {
    // The alien has six meshes in a hierarchy of depth 3; each of its five materials shows up.
    let Some(path) = model("kenney-alien.glb") else { return };
    let soup = load_file(&path).unwrap();
    assert_eq!(soup.materials.len(), 5);
    let m = voxelize(&soup, &at_resolution(64)).unwrap();
    let used: HashSet<_> = m.voxels().map(|v| soup.parts[v.part as usize].material).collect();
    assert_eq!(used.len(), 5);
}

#[test]
fn every_file_of_the_corpus_voxelizes() {
    let Some(dir) = models_dir() else { return };
    let mut folders = vec![dir.clone()];
    folders.extend(std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).filter(|p| p.is_dir()));
    let files = voxel_core::files::expand_inputs(&folders);
    // The 18 models of SOURCES.md, the three compressed ones among them.
    assert!(files.len() >= 18, "only {} model files in {}", files.len(), dir.display());
    for file in &files {
        let soup = load_file(file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        let m = voxelize(&soup, &VoxelizeOptions::default()).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        assert!(m.stats.voxels > 0 && m.stats.visible > 0, "{}: {:?}", file.display(), m.stats);
    }
}
