//! Reading files: a big file read in parallel chunks gives the soup its bytes give, with one vertex for every
//! vertex the file's triangles use (no more), and positions under the identity transform come through bit for
//! bit (a -0.0 as +0.0, as placing them in f64 gives).

use voxel_core::{load_file, load_slice};

use crate::scenes;

#[test]
fn a_file_of_several_read_chunks_loads_as_its_bytes_do() {
    let bytes = scenes::to_glb(&[scenes::height_field(500)]);
    assert!(bytes.len() > 8 << 20, "{} bytes: more than one 8 MiB chunk", bytes.len());
    let path = std::env::temp_dir().join(format!("voxel-core-read-{}.glb", std::process::id()));
    std::fs::write(&path, &bytes).unwrap();
    let from_file = load_file(&path);
    std::fs::remove_file(&path).unwrap();
    let (from_file, from_bytes) = (from_file.unwrap(), load_slice(&bytes, None).unwrap());
    assert_eq!((from_file.triangle_count(), from_file.vertex_count()), (2 * 500 * 500, 501 * 501), "shared vertices");
    assert!(from_file.corners().eq(from_bytes.corners()));
    assert_eq!(from_file.triangle_parts, from_bytes.triangle_parts);
    let last = from_file.corners().last().unwrap();
    assert_eq!((last.position[0], last.position[2]), (10.0, 10.0), "the far corner of the sheet");
}

#[test]
fn identity_placed_positions_keep_their_bits_but_for_negative_zero() {
    let triangle = |x: f32| scenes::Primitive {
        positions: vec![[x, 0.5, 0.0], [1.0, 0.0, 0.25], [0.0, 1.0, -1.5]],
        colors: vec![[1.0; 4]; 3],
        indices: vec![0, 1, 2],
    };
    for (x, expected) in [(-0.0f32, 0.0f32), (0.1, 0.1), (-3.75, -3.75)] {
        let soup = load_slice(&scenes::to_glb(&[triangle(x)]), None).unwrap();
        let corners: Vec<[u32; 3]> = soup.corners().map(|v| v.position.map(f32::to_bits)).collect();
        let want = [[expected, 0.5, 0.0], [1.0, 0.0, 0.25], [0.0, 1.0, -1.5]].map(|p| p.map(f32::to_bits));
        assert_eq!(corners, want, "x = {x:?}");
    }
}

#[test]
fn vertices_no_triangle_uses_are_left_out() {
    let (red, green, blue, grey) = ([1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1.0], [0.5; 4]);
    let primitive = scenes::Primitive {
        positions: vec![[9.0, 9.0, 9.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        colors: vec![grey, red, green, blue],
        indices: vec![3, 1, 2],
    };
    let soup = load_slice(&scenes::to_glb(&[primitive]), None).unwrap();
    assert_eq!((soup.vertex_count(), soup.triangles()), (3, &[[2, 0, 1]][..]));
    assert_eq!(soup.bounds(), Some(([0.0; 3], [1.0, 1.0, 0.0])), "the unused vertex at 9 is not in the bounds");
    let corners: Vec<([f32; 3], [f32; 4])> = soup.corners().map(|v| (v.position, v.color)).collect();
    assert_eq!(corners, [([0.0, 1.0, 0.0], blue), ([0.0; 3], red), ([1.0, 0.0, 0.0], green)]);
}
