//! EXT_meshopt_compression built in the test with meshoptimizer-rs's encoders: filters the corpus does not use
//! (EXPONENTIAL positions, OCTAHEDRAL normals), both index modes, a fallback buffer with no data; and damaged
//! streams, which are named errors.

use meshoptimizer_rs::Workspace;
use meshoptimizer_rs::codec::{
    ExpMode, IndexEncoding, VertexEncoding, encode_filter_exp, encode_filter_oct, encode_index_buffer,
    encode_index_sequence, encode_vertex_buffer,
};
use serde_json::{Value, json};
use voxel_core::{load_slice, voxelize};

use crate::common::{at_resolution, cells, cube_buffer, cube_document, glb};

/// One compressed view: its EXT_meshopt_compression fields and its compressed bytes.
struct Packed {
    bytes: Vec<u8>,
    count: usize,
    stride: usize,
    mode: &'static str,
    filter: &'static str,
}

fn unit_cube() -> (Vec<[f32; 3]>, Vec<u32>) {
    let mesh = voxel_core::shapes::cuboid([0.0; 3], [1.0; 3]);
    (mesh.positions, mesh.triangles.into_iter().flatten().collect())
}

/// The unit cube with EXPONENTIAL positions, OCTAHEDRAL normals and `index_mode` indices (TRIANGLES or
/// INDICES), all compressed into buffer 0, with buffer 1 the data-less fallback.
fn meshopt_cube(index_mode: &'static str, edit: impl FnOnce(&mut Value, &mut Vec<u8>)) -> Vec<u8> {
    let (positions, indices) = unit_cube();
    let mut ws = Workspace::default();
    let vertex = |raw: &[u8], count, stride, ws: &mut Workspace| {
        encode_vertex_buffer(raw, count, stride, VertexEncoding::new(0, 0).unwrap(), ws).unwrap()
    };
    let flat: Vec<f32> = positions.iter().flatten().copied().collect();
    let exp = encode_filter_exp(8, 12, 15, &flat, ExpMode::Separate, &mut ws).unwrap();
    let normals: Vec<f32> = positions
        .iter()
        .flat_map(|p| {
            let d = p.map(|c| c - 0.5);
            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            [d[0] / len, d[1] / len, d[2] / len, 1.0]
        })
        .collect();
    let oct = encode_filter_oct(8, 4, 8, &normals, &mut ws).unwrap();
    let index_bytes = match index_mode {
        "TRIANGLES" => encode_index_buffer(&indices, IndexEncoding::DEFAULT, &mut ws).unwrap(),
        _ => encode_index_sequence(&indices, IndexEncoding::DEFAULT, &mut ws).unwrap(),
    };
    let views = [
        Packed { bytes: vertex(&exp, 8, 12, &mut ws), count: 8, stride: 12, mode: "ATTRIBUTES", filter: "EXPONENTIAL" },
        Packed { bytes: vertex(&oct, 8, 4, &mut ws), count: 8, stride: 4, mode: "ATTRIBUTES", filter: "OCTAHEDRAL" },
        Packed { bytes: index_bytes, count: indices.len(), stride: 4, mode: index_mode, filter: "NONE" },
    ];
    let (mut bin, mut json_views, mut fallback_len) = (Vec::new(), Vec::new(), 0);
    for v in &views {
        let length = v.count * v.stride;
        json_views.push(json!({
            "buffer": 1, "byteOffset": fallback_len, "byteLength": length,
            "extensions": {"EXT_meshopt_compression": {
                "buffer": 0, "byteOffset": bin.len(), "byteLength": v.bytes.len(), "byteStride": v.stride,
                "count": v.count, "mode": v.mode, "filter": v.filter}}
        }));
        bin.extend_from_slice(&v.bytes);
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        fallback_len += length;
    }
    json_views[0]["byteStride"] = 12.into();
    json_views[1]["byteStride"] = 4.into();
    let mut doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["EXT_meshopt_compression", "KHR_mesh_quantization"],
        "extensionsRequired": ["EXT_meshopt_compression", "KHR_mesh_quantization"],
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2}]}],
        "buffers": [
            {"byteLength": bin.len()},
            {"byteLength": fallback_len, "extensions": {"EXT_meshopt_compression": {"fallback": true}}}
        ],
        "bufferViews": json_views,
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3", "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]},
            {"bufferView": 1, "componentType": 5120, "normalized": true, "count": 8, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5125, "count": indices.len(), "type": "SCALAR"}
        ]
    });
    edit(&mut doc, &mut bin);
    glb(&doc, &bin)
}

fn plain_cube() -> Vec<u8> {
    let (bin, positions_len, index_count) = cube_buffer();
    glb(&cube_document(bin.len(), positions_len, index_count), &bin)
}

#[test]
fn filtered_and_index_compressed_views_give_the_plain_cubes_cells() {
    let plain = load_slice(&plain_cube(), None).unwrap();
    let expected = cells(&voxelize(&plain, &at_resolution(10)).unwrap());
    assert_eq!(expected.len(), 1000);
    for mode in ["TRIANGLES", "INDICES"] {
        let soup = load_slice(&meshopt_cube(mode, |_, _| {}), None).unwrap_or_else(|e| panic!("{mode}: {e}"));
        assert_eq!(soup.triangle_count(), 12, "{mode}");
        assert_eq!(soup.bounds(), Some(([0.0; 3], [1.0; 3])), "{mode}");
        assert_eq!(cells(&voxelize(&soup, &at_resolution(10)).unwrap()), expected, "{mode}");
    }
}

#[test]
fn damaged_meshopt_streams_are_named() {
    // The position stream's bytes overwritten.
    let err = load_slice(&meshopt_cube("TRIANGLES", |_, bin| bin[..16].fill(0xff)), None).unwrap_err().to_string();
    assert!(err.contains("buffer view 0 (EXT_meshopt_compression): cannot decode"), "{err}");
    // A mode and a filter that do not exist, and a filter on indices.
    let set = |field: &'static str, value: &'static str| {
        move |doc: &mut Value, _: &mut Vec<u8>| {
            doc["bufferViews"][2]["extensions"]["EXT_meshopt_compression"][field] = value.into();
        }
    };
    let err = load_slice(&meshopt_cube("TRIANGLES", set("mode", "STRIPS")), None).unwrap_err().to_string();
    assert!(err.contains("unknown mode \"STRIPS\""), "{err}");
    let err = load_slice(&meshopt_cube("TRIANGLES", set("filter", "ZIGZAG")), None).unwrap_err().to_string();
    assert!(err.contains("unknown filter \"ZIGZAG\""), "{err}");
    let err = load_slice(&meshopt_cube("TRIANGLES", set("filter", "OCTAHEDRAL")), None).unwrap_err().to_string();
    assert!(err.contains("buffer view 2 (EXT_meshopt_compression): cannot decode"), "{err}");
    // An uncompressed view into the fallback buffer, which holds nothing.
    let err = load_slice(
        &meshopt_cube("TRIANGLES", |doc, _| {
            doc["bufferViews"][2]["extensions"] = json!({});
        }),
        None,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("run past the end of buffer 1 (0 bytes)"), "{err}");
}
