//! The nonzero winding fill: overlapping parts stay solid, inconsistent orientation is corrected, cavities
//! facing inwards are kept (shapes built in the test).

use std::collections::HashSet;
use std::f64::consts::PI;

use voxel_core::shapes::{IndexedMesh, cuboid, cylinder, torus, uv_sphere};
use voxel_core::{FillMode, Method, ShellMode, TriangleSoup, VoxelModel, VoxelizeOptions, voxelize};

use crate::common::{at_resolution, cells, relative_volume, tilted};

const WHITE: [f32; 4] = [1.0; 4];

/// The slab pushed into the side of the unit sphere.
const SLAB: ([f32; 3], [f32; 3]) = ([0.6, -0.35, -0.5], [1.3, 0.35, 0.5]);

/// `mesh` with every triangle's corner order reversed (facing inwards).
fn reversed(mut mesh: IndexedMesh) -> IndexedMesh {
    for t in &mut mesh.triangles {
        t.swap(1, 2);
    }
    mesh
}

/// `a` and `b` as one indexed mesh (one primitive; they share no vertex).
fn merged(mut a: IndexedMesh, b: &IndexedMesh) -> IndexedMesh {
    let base = a.positions.len() as u32;
    a.positions.extend(&b.positions);
    a.triangles.extend(b.triangles.iter().map(|t| t.map(|i| i + base)));
    a
}

/// Whether `p` lies in the union of the unit sphere and the slab, both shrunk by `margin`.
fn in_sphere_and_slab(p: [f64; 3], margin: f64) -> bool {
    let in_slab = (0..3).all(|a| p[a] > f64::from(SLAB.0[a]) + margin && p[a] < f64::from(SLAB.1[a]) - margin);
    in_slab || p.iter().map(|c| c * c).sum::<f64>().sqrt() < 1.0 - margin
}

/// The volume of the sphere ∪ slab: the sphere plus the slab's part outside it, integrated along x
/// (exactly) over a fine midpoint grid in y and z.
fn sphere_and_slab_volume() -> f64 {
    let ([x0, y0, z0], [x1, y1, z1]) = (SLAB.0.map(f64::from), SLAB.1.map(f64::from));
    let n = 2000;
    let (dy, dz) = ((y1 - y0) / f64::from(n), (z1 - z0) / f64::from(n));
    let mut outside = 0.0;
    for i in 0..n {
        for j in 0..n {
            let (y, z) = (y0 + (f64::from(i) + 0.5) * dy, z0 + (f64::from(j) + 0.5) * dz);
            let sphere_x = (1.0 - y * y - z * z).max(0.0).sqrt();
            outside += x1 - sphere_x.clamp(x0, x1);
        }
    }
    4.0 / 3.0 * PI + outside * dy * dz
}

/// The sphere and the slab (possibly reversed) as one primitive and as two.
fn sphere_and_slab(slab_reversed: bool) -> [TriangleSoup; 2] {
    let sphere = uv_sphere(1.0, 128);
    let slab = cuboid(SLAB.0, SLAB.1);
    let slab = if slab_reversed { reversed(slab) } else { slab };
    let mut two = TriangleSoup::from_mesh(&sphere, WHITE);
    two.add_mesh(&slab, WHITE, "slab");
    [TriangleSoup::from_mesh(&merged(sphere, &slab), WHITE), two]
}

fn with_fill(fill: FillMode, r: u32) -> VoxelizeOptions {
    VoxelizeOptions { fill, ..at_resolution(r) }
}

#[test]
fn a_slab_pushed_into_a_sphere_fills_the_union() {
    let union = sphere_and_slab_volume();
    for slab_reversed in [false, true] {
        for (primitives, soup) in [1, 2].iter().zip(sphere_and_slab(slab_reversed)) {
            let m = voxelize(&soup, &at_resolution(64)).unwrap();
            let rel = relative_volume(&m, union);
            assert!((rel - 1.0).abs() < 0.01, "reversed {slab_reversed}, {primitives} primitive(s): {rel}");
            // Parity empties the overlap (the test can tell the two apart).
            let parity = voxelize(&soup, &with_fill(FillMode::Parity, 64)).unwrap();
            assert!(relative_volume(&parity, union) < 0.97, "parity keeps the overlap");
        }
    }
}

#[test]
fn two_overlapping_boxes_in_one_primitive_give_exactly_the_union_cells() {
    let (a, b) = (([0.0, 0.0, 0.0], [4.0, 3.0, 3.0]), ([2.0, 1.0, 1.0], [6.0, 4.0, 4.0]));
    let soup = TriangleSoup::from_mesh(&merged(cuboid(a.0, a.1), &cuboid(b.0, b.1)), WHITE);
    // The 6 × 4 × 4 bounds at R = 12: cells 0.5 wide, every face on a cell boundary.
    let fill_only = |fill| VoxelizeOptions { shell: ShellMode::None, ..with_fill(fill, 12) };
    let m = voxelize(&soup, &fill_only(FillMode::Winding)).unwrap();
    assert_eq!(m.spec.dims, [12, 8, 8]);
    let in_box = |c: [u32; 3], (lo, hi): ([f32; 3], [f32; 3])| {
        let (lo, hi) = (m.spec.to_grid(lo), m.spec.to_grid(hi));
        (0..3).all(|k| (lo[k]..hi[k]).contains(&(f64::from(c[k]) + 0.5)))
    };
    let mut expected = HashSet::new();
    for x in 0..12 {
        for y in 0..8 {
            for z in 0..8 {
                if in_box([x, y, z], a) || in_box([x, y, z], b) {
                    expected.insert([x, y, z].map(|v| v as u16));
                }
            }
        }
    }
    assert_eq!(expected.len(), 8 * 6 * 6 * 2 - 4 * 4 * 4);
    // With the default shell too: every face lies on a cell boundary, so the shell adds nothing.
    assert_eq!(cells(&voxelize(&soup, &at_resolution(12)).unwrap()), expected);
    let got = cells(&m);
    let mut wrong: Vec<_> = got.symmetric_difference(&expected).collect();
    wrong.sort();
    assert!(wrong.is_empty(), "{} cells, {} expected; wrong: {wrong:?}", got.len(), expected.len());
    let parity = voxelize(&soup, &fill_only(FillMode::Parity)).unwrap();
    assert_eq!(parity.len(), expected.len() - 4 * 4 * 4, "parity empties the overlap");
}

#[test]
fn an_inside_out_torus_and_a_half_reversed_sphere_keep_their_volume() {
    let (major, minor) = (2.0f64, 0.6f64);
    let inside_out = reversed(tilted(torus(major as f32, minor as f32, 256), 0.5));
    let m = voxelize(&TriangleSoup::from_mesh(&inside_out, WHITE), &at_resolution(64)).unwrap();
    let rel = relative_volume(&m, 2.0 * PI * PI * major * minor * minor);
    assert!((rel - 1.0).abs() < 0.01, "inside-out torus: {rel}");
    // Every other triangle reversed, and the upper half reversed.
    let sphere = 4.0 / 3.0 * PI;
    for pattern in [|t: usize, _: usize| t.is_multiple_of(2), |t: usize, n: usize| t < n / 2] {
        let mut mesh = uv_sphere(1.0, 128);
        let n = mesh.triangles.len();
        for (t, tri) in mesh.triangles.iter_mut().enumerate() {
            if pattern(t, n) {
                tri.swap(1, 2);
            }
        }
        let m = voxelize(&TriangleSoup::from_mesh(&mesh, WHITE), &at_resolution(64)).unwrap();
        let rel = relative_volume(&m, sphere);
        assert!((rel - 1.0).abs() < 0.01, "half-reversed sphere: {rel}");
    }
}

/// Filled cells whose centre lies within `radius` of the grid's centre.
fn filled_near_centre(m: &VoxelModel, radius: f32) -> usize {
    m.voxels().filter(|v| m.center(v).iter().map(|c| c * c).sum::<f32>().sqrt() < radius).count()
}

#[test]
fn a_hollow_ball_keeps_its_cavity() {
    // Outer shell outwards, inner shell inwards: the cavity stays empty, as one primitive and as two.
    let (outer, inner) = (uv_sphere(1.0, 96), reversed(uv_sphere(0.5, 64)));
    let mut two = TriangleSoup::from_mesh(&outer, WHITE);
    two.add_mesh(&inner, WHITE, "cavity");
    let shell_volume = 4.0 / 3.0 * PI * (1.0 - 0.125);
    for soup in [TriangleSoup::from_mesh(&merged(outer.clone(), &inner), WHITE), two] {
        let m = voxelize(&soup, &at_resolution(64)).unwrap();
        let rel = relative_volume(&m, shell_volume);
        assert!((rel - 1.0).abs() < 0.01, "hollow ball: {rel}");
        // Normalized, the radius is 9 / (2√3) ≈ 2.6: nothing within 0.4 of the inner radius 1.3.
        assert_eq!(filled_near_centre(&m, 0.9), 0);
    }
    // The same cavity inside an outer shell with a hole (open: counted by parity) is kept too.
    let mut holed = outer.clone();
    holed.triangles.remove(2000);
    let m = voxelize(&TriangleSoup::from_mesh(&merged(holed, &inner), WHITE), &at_resolution(64)).unwrap();
    assert!((relative_volume(&m, shell_volume) - 1.0).abs() < 0.01);
    assert_eq!(filled_near_centre(&m, 0.9), 0);
}

#[test]
fn a_capsule_of_overlapping_parts_is_within_one_percent_of_its_volume() {
    // The spheres' equators are the cylinder's rims (shared vertices: non-manifold edges).
    let r = 0.5f32;
    let capsule = merged(
        merged(cylinder(r, -1.0, 1.0, 256), &uv_sphere(r, 128).translated([0.0, 1.0, 0.0])),
        &uv_sphere(r, 128).translated([0.0, -1.0, 0.0]),
    );
    let rf = f64::from(r);
    let volume = PI * rf * rf * 2.0 + 4.0 / 3.0 * PI * rf.powi(3);
    let rel = relative_volume(
        &voxelize(&TriangleSoup::from_mesh(&tilted(capsule.clone(), 0.4), WHITE), &at_resolution(64)).unwrap(),
        volume,
    );
    assert!((rel - 1.0).abs() < 0.01, "capsule: {rel}");
    // With an inside-out box beside it, which sends the model through the analysis of its parts.
    let with_box = merged(capsule, &reversed(cuboid([1.0, -0.5, -0.5], [2.0, 0.5, 0.5])));
    let m = voxelize(&TriangleSoup::from_mesh(&tilted(with_box, 0.4), WHITE), &at_resolution(64)).unwrap();
    let rel = relative_volume(&m, volume + 1.0);
    assert!((rel - 1.0).abs() < 0.01, "capsule and box: {rel}");
}

#[test]
fn hollow_sphere_and_slab_has_no_wall_around_an_empty_inside() {
    for fill in [FillMode::Winding, FillMode::Parity] {
        let soup = &sphere_and_slab(false)[0];
        let solid = cells(&voxelize(soup, &with_fill(fill, 64)).unwrap());
        let hollow = voxelize(soup, &VoxelizeOptions { hollow: true, ..with_fill(fill, 64) }).unwrap();
        let cell = f64::from(hollow.spec.cell[0]) / f64::from(hollow.spec.scale);
        // Kept cells with a face neighbour that is empty although it lies a cell deep inside the union.
        let walls = hollow
            .voxels()
            .filter(|v| {
                (0..3).any(|a| {
                    [-1i32, 1].into_iter().any(|d| {
                        let mut n = v.cell.map(i32::from);
                        n[a] += d;
                        let Ok(n) = n.map(u16::try_from).into_iter().collect::<Result<Vec<u16>, _>>() else {
                            return false;
                        };
                        let n = [n[0], n[1], n[2]];
                        let centre = hollow.spec.cell_center(n.map(u32::from));
                        let p: [f64; 3] =
                            std::array::from_fn(|k| f64::from(centre[k] / hollow.spec.scale + hollow.spec.center[k]));
                        !solid.contains(&n) && in_sphere_and_slab(p, cell)
                    })
                })
            })
            .count();
        match fill {
            FillMode::Winding => assert_eq!(walls, 0),
            _ => assert!(walls > 100, "parity: only {walls} walls round the empty overlap"),
        }
    }
}

/// The side of a cylinder alone (an open tube: no caps), its axis along `axis` (0, 1, 2: x, y, z), every other
/// triangle facing inwards (as files often have them: then the columns do not balance as the triangles face, and
/// the tube's sheet is found open and counts by parity; facing out, columns across it would count it closed).
fn open_tube(axis: usize) -> IndexedMesh {
    let mut tube = cylinder(0.5, -1.0, 1.0, 48);
    tube.triangles.retain(|t| !t.contains(&0) && !t.contains(&1)); // the caps' fans around vertices 0 and 1
    tube.triangles.iter_mut().step_by(2).for_each(|t| t.swap(1, 2));
    for p in &mut tube.positions {
        // Built along y: the coordinates cycled so that y lands on `axis`.
        *p = match axis {
            0 => [p[1], p[2], p[0]],
            1 => *p,
            _ => [p[2], p[0], p[1]],
        };
    }
    tube
}

#[test]
fn an_open_tube_stays_hollow_whichever_way_it_lies() {
    // Its walls pair up in the columns across it, but the columns along it find no wall: it encloses nothing.
    for axis in 0..3 {
        let soup = TriangleSoup::from_mesh(&open_tube(axis), WHITE);
        for method in [Method::Fast, Method::Bvh, Method::Reference] {
            let fill_only = VoxelizeOptions { method, shell: ShellMode::None, ..at_resolution(16) };
            assert_eq!(voxelize(&soup, &fill_only).unwrap().len(), 0, "tube along axis {axis}, {method:?}");
        }
        // With its shell: exactly the surface cells, as without a fill.
        let full = voxelize(&soup, &at_resolution(48)).unwrap();
        let surface = voxelize(&soup, &with_fill(FillMode::None, 48)).unwrap();
        assert_eq!(cells(&full), cells(&surface), "tube along axis {axis}");
        // The closed cylinder fills: about π r² h of the grid's units.
        let closed = voxelize(&TriangleSoup::from_mesh(&cylinder(0.5, -1.0, 1.0, 48), WHITE), &at_resolution(48));
        assert!(closed.unwrap().len() > 3 * full.len(), "axis {axis}");
    }
}

#[test]
fn a_rolling_open_sheet_fills_no_valley_and_no_hill() {
    // A terrain: columns across its hills cross it an even number of times, but the columns along its up axis
    // cross it once. Nothing but its surface is kept, at any grid.
    let field = crate::scenes::height_field(40);
    let mesh = IndexedMesh {
        positions: field.positions.clone(),
        triangles: field.indices.chunks(3).map(|t| [t[0], t[1], t[2]]).collect(),
    };
    let soup = TriangleSoup::from_mesh(&mesh, WHITE);
    for r in [24, 64] {
        let fill_only = voxelize(&soup, &VoxelizeOptions { shell: ShellMode::None, ..at_resolution(r) }).unwrap();
        assert_eq!(fill_only.len(), 0, "R={r}");
        let full = voxelize(&soup, &at_resolution(r)).unwrap();
        assert_eq!(full.len(), full.stats.surface, "R={r}");
        assert!(full.stats.grid[1] > 2, "the hills span several cells: {:?}", full.stats.grid);
    }
}

#[test]
fn a_box_closed_only_through_a_t_junction_fills_as_the_closed_box() {
    // Triangle [0, 4, 6] split at the middle of its box edge 0–4, which the side face's triangle [0, 5, 4] keeps
    // whole: the edges do not pair, the box is an open sheet. One bottom triangle faces inwards, so that the
    // columns do not balance as the triangles face: the sheet is analysed, found open, and counts by parity,
    // enclosed along every axis.
    let closed = cuboid([0.25; 3], [3.75, 2.75, 3.25]);
    let mut junction = closed.clone();
    junction.positions.push([0.25, 0.25, 1.75]);
    let at = junction.triangles.iter().position(|t| *t == [0, 4, 6]).unwrap();
    junction.triangles[at] = [0, 8, 6];
    junction.triangles.push([8, 4, 6]);
    let bottom = junction.triangles.iter().position(|t| *t == [0, 2, 3]).unwrap();
    junction.triangles[bottom].swap(1, 2);
    for method in [Method::Fast, Method::Bvh, Method::Reference] {
        let fill_only = VoxelizeOptions { method, shell: ShellMode::None, ..at_resolution(20) };
        let run = |mesh: &IndexedMesh| cells(&voxelize(&TriangleSoup::from_mesh(mesh, WHITE), &fill_only).unwrap());
        let box_cells = run(&closed);
        assert!(box_cells.len() > 20 * 14 * 16, "{}", box_cells.len());
        assert_eq!(run(&junction), box_cells, "{method:?}");
    }
}

/// A random number below `n` from the state `seed` (a 64-bit LCG, high bits).
fn next_below(seed: &mut u64, n: u64) -> u64 {
    *seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
    (*seed >> 33) % n
}

/// A terrain over [0, 8]² in X and Z: 9 × 9 vertices at whole x and z, heights on a lattice of quarters between 2
/// and 6 raised by `lift` (with none, cell centres fall on its quads' diagonals: the centres' lines run through
/// them), facing up or down.
fn lattice_terrain(seed: &mut u64, lift: f32, down: bool) -> IndexedMesh {
    let mut mesh = IndexedMesh { positions: Vec::new(), triangles: Vec::new() };
    for i in 0..9u32 {
        for k in 0..9u32 {
            mesh.positions.push([i as f32, 2.0 + lift + next_below(seed, 17) as f32 / 4.0, k as f32]);
        }
    }
    let at = |i: u32, k: u32| i * 9 + k;
    for (i, k) in (0..8).flat_map(|i| (0..8).map(move |k| (i, k))) {
        mesh.triangles.push([at(i, k), at(i, k + 1), at(i + 1, k)]);
        mesh.triangles.push([at(i + 1, k), at(i, k + 1), at(i + 1, k + 1)]);
    }
    if down { reversed(mesh) } else { mesh }
}

#[test]
fn terrains_and_parts_on_a_lattice_fill_alike_by_every_method() {
    // Terrains, alone or with a box (on a lattice of quarters, under, across or above them, facing either way):
    // the fast fill, which surveys the triangles first and may find the fill empty without the parts (a line
    // along the terrain's up axis crossed at most once), agrees with the BVH's and the reference's cell for cell,
    // ties included: the grid is the lattice's (whole cells), so centres lie on faces, edges and corners.
    let bounds = ([0.0; 3], [8.0; 3]);
    let fill_only = |method| VoxelizeOptions { method, shell: ShellMode::None, ..at_resolution(8) };
    let (mut empty, mut filled) = (0, 0);
    let mut seed = 17;
    for case in 0..240 {
        let mut mesh = lattice_terrain(&mut seed, [0.0, 0.0625][case % 5 / 3], case % 2 == 1);
        if case % 3 != 0 {
            let mut corner = || std::array::from_fn::<f32, 3, _>(|_| 0.25 + next_below(&mut seed, 31) as f32 / 4.0);
            let (a, b) = (corner(), corner());
            let (lo, hi) = (std::array::from_fn(|k| a[k].min(b[k])), std::array::from_fn(|k| a[k].max(b[k]) + 0.25));
            let block = cuboid(lo, hi);
            mesh = merged(mesh, &if case % 4 == 1 { reversed(block) } else { block });
        }
        let soup = TriangleSoup::from_mesh(&mesh, WHITE);
        let run = |method| cells(&voxel_core::voxelize_within(&soup, &fill_only(method), bounds).unwrap());
        let fast = run(Method::Fast);
        assert_eq!(fast, run(Method::Reference), "case {case}: fast and reference");
        assert_eq!(fast, run(Method::Bvh), "case {case}: fast and BVH");
        if fast.is_empty() { empty += 1 } else { filled += 1 }
    }
    // The grid is the lattice's: a corner of the terrain lands on its own coordinates.
    let terrain = TriangleSoup::from_mesh(&lattice_terrain(&mut seed, 0.0, false), WHITE);
    let spec = voxel_core::voxelize_within(&terrain, &fill_only(Method::Fast), bounds).unwrap().spec;
    assert_eq!(spec.to_grid([1.0, 2.25, 3.0]).to_array(), [1.0, 2.25, 3.0]);
    assert!(empty > 40 && filled > 40, "{empty} empty, {filled} filled");
}

#[test]
fn a_thin_part_whose_face_runs_through_centres_is_filled_by_its_ties_as_the_reference_fills_it() {
    // A wall leaning a little (normal (1, 0, 0.3)), so that the lines along X cross it once and the +Z columns do
    // not balance; and a thin closed prism along X whose slanted face (normal ±(0, 1, −1)) runs through the
    // centres (x, 4.5, 4.5), its inside on the side the +Z column's tie-break puts those centres (a crossing at a
    // centre's height counts below it). The lines along X through those centres are tipped the other way by their
    // own tie-break and cross nothing but the wall, so no line crosses two triangles; only the survey's look at the
    // triangles near the centres keeps it from calling the fill empty.
    let wall = IndexedMesh {
        positions: vec![[7.2, 0.0, 0.0], [7.2, 8.0, 0.0], [4.8, 0.0, 8.0], [4.8, 8.0, 8.0]],
        triangles: vec![[0, 1, 2], [2, 1, 3]],
    };
    let section = [[4.0f32, 4.0], [5.0, 5.0], [4.3, 4.9]];
    let at = |k: usize, x: f32| [x, section[k][0], section[k][1]];
    let mut prism = IndexedMesh { positions: Vec::new(), triangles: vec![[0, 1, 2], [3, 5, 4]] };
    prism.positions.extend((0..3).map(|k| at(k, 1.25)));
    prism.positions.extend((0..3).map(|k| at(k, 2.75)));
    for k in 0..3u32 {
        let next = (k + 1) % 3;
        prism.triangles.push([k, next, k + 3]);
        prism.triangles.push([next, next + 3, k + 3]);
    }
    let soup = TriangleSoup::from_mesh(&merged(wall, &prism), WHITE);
    let fill_only = |method| VoxelizeOptions { method, shell: ShellMode::None, ..at_resolution(8) };
    let run = |method| cells(&voxel_core::voxelize_within(&soup, &fill_only(method), ([0.0; 3], [8.0; 3])).unwrap());
    let reference = run(Method::Reference);
    assert_eq!(reference, [1, 2].map(|x| [x, 4, 4]).into_iter().collect::<HashSet<_>>(), "the centres on the face");
    assert_eq!(run(Method::Fast), reference);
    assert_eq!(run(Method::Bvh), reference);
}

#[test]
fn an_open_tube_that_balances_its_columns_as_it_faces_is_not_taken_for_a_height_field() {
    // A wall facing +X (the lines along X cross it once) beside an open tube along X facing out, which those lines
    // do not cross at all: no line along X crosses two triangles. But every +Z column through the tube enters and
    // leaves it as the file faces, so the file's facing stands and fills the tube's bore; the survey must see the
    // columns balance.
    let mut mesh = IndexedMesh {
        positions: vec![[6.25, 0.0, 0.0], [6.25, 8.0, 0.0], [6.25, 0.0, 8.0], [6.25, 8.0, 8.0]],
        triangles: vec![[0, 1, 2], [2, 1, 3]],
    };
    let ring = |k: u32, x: f32| {
        let a = std::f32::consts::TAU * (k % 16) as f32 / 16.0;
        [x, 4.2 + 2.1 * a.cos(), 4.1 + 2.1 * a.sin()]
    };
    for k in 0..16 {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend([ring(k, 1.25), ring(k + 1, 1.25), ring(k, 4.75), ring(k + 1, 4.75)]);
        mesh.triangles.extend([[base, base + 1, base + 2], [base + 1, base + 3, base + 2]]);
    }
    let soup = TriangleSoup::from_mesh(&mesh, WHITE);
    let fill_only = |method| VoxelizeOptions { method, shell: ShellMode::None, ..at_resolution(8) };
    let run = |method| cells(&voxel_core::voxelize_within(&soup, &fill_only(method), ([0.0; 3], [8.0; 3])).unwrap());
    let reference = run(Method::Reference);
    assert!(reference.len() >= 3 * 9, "the bore: {}", reference.len());
    assert_eq!(run(Method::Fast), reference);
    assert_eq!(run(Method::Bvh), reference);
}
