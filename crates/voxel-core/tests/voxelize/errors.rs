//! Hostile input: every case is a clear error, never a panic or a hang. Also the import paths that must work
//! (quantized positions, data URIs, strips).

use voxel_core::{GridSize, VoxelError, VoxelizeOptions, load_file, load_slice, voxelize};

use crate::common::{cube_buffer, cube_document, glb};

fn load_err(bytes: &[u8]) -> String {
    match load_slice(bytes, None) {
        Ok(_) => panic!("loaded without error"),
        Err(e) => e.to_string(),
    }
}

fn cube_glb(edit: impl FnOnce(&mut serde_json::Value, &mut Vec<u8>)) -> Vec<u8> {
    let (mut bin, positions_len, index_count) = cube_buffer();
    let mut doc = cube_document(bin.len(), positions_len, index_count);
    edit(&mut doc, &mut bin);
    glb(&doc, &bin)
}

#[test]
fn the_hand_built_cube_loads() {
    let soup = load_slice(&cube_glb(|_, _| {}), None).unwrap();
    assert_eq!(soup.triangle_count(), 12);
    let m = voxelize(&soup, &VoxelizeOptions { grid: GridSize::Resolution(10), ..Default::default() }).unwrap();
    assert_eq!(m.len(), 1000);
}

#[test]
fn a_missing_file_names_the_path() {
    let err = load_file("/no/such/model.glb".as_ref()).unwrap_err();
    assert!(matches!(err, VoxelError::Io { .. }));
    assert!(err.to_string().contains("/no/such/model.glb"), "{err}");
}

#[test]
fn truncated_and_random_bytes_are_parse_errors() {
    let full = cube_glb(|_, _| {});
    for cut in [0, 7, 20, full.len() / 2, full.len() - 3] {
        let err = load_err(&full[..cut]);
        assert!(err.contains("not a valid glTF") || err.contains("missing"), "cut {cut}: {err}");
    }
    let mut state = 0x2545_f491_u32;
    let noise: Vec<u8> = (0..4096)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state as u8
        })
        .collect();
    assert!(load_err(&noise).contains("not a valid glTF"));
    assert!(load_err(b"{\"asset\": 3}").contains("not a valid glTF"));
}

#[test]
fn undecodable_required_extensions_are_named() {
    for ext in ["KHR_texture_basisu", "EXT_mesh_gpu_instancing"] {
        let err = load_err(&cube_glb(|doc, _| doc["extensionsRequired"] = serde_json::json!([ext])));
        assert!(err.contains(ext) && err.contains("cannot decode"), "{err}");
    }
}

#[test]
fn an_empty_scene_has_no_triangles() {
    let err = load_err(&cube_glb(|doc, _| doc["scenes"] = serde_json::json!([{"nodes": []}])));
    assert!(err.contains("no triangles"), "{err}");
    // Points only: nothing to voxelize either.
    let err = load_err(&cube_glb(|doc, _| doc["meshes"][0]["primitives"][0]["mode"] = serde_json::json!(0)));
    assert!(err.contains("no triangles"), "{err}");
}

#[test]
fn nan_positions_are_refused() {
    let err = load_err(&cube_glb(|_, bin| bin[0..4].copy_from_slice(&f32::NAN.to_le_bytes())));
    assert!(err.contains("NaN"), "{err}");
    let err = load_err(&cube_glb(|_, bin| bin[4..8].copy_from_slice(&f32::INFINITY.to_le_bytes())));
    assert!(err.contains("non-finite"), "{err}");
}

#[test]
fn out_of_range_indices_are_refused() {
    let err = load_err(&cube_glb(|_, bin| {
        let at = bin.len() - 2;
        bin[at..].copy_from_slice(&500u16.to_le_bytes());
    }));
    assert!(err.contains("vertex index 500 is out of range"), "{err}");
    // An accessor running past its buffer view.
    let err = load_err(&cube_glb(|doc, _| doc["accessors"][0]["count"] = serde_json::json!(9999)));
    assert!(err.contains("do not fit") || err.contains("invalid"), "{err}");
    // A reference to a node that does not exist.
    let err = load_err(&cube_glb(|doc, _| doc["scenes"][0]["nodes"] = serde_json::json!([7])));
    assert!(err.contains("invalid model"), "{err}");
}

#[test]
fn a_node_that_is_its_own_ancestor_is_refused() {
    let err = load_err(&cube_glb(|doc, _| {
        doc["nodes"] = serde_json::json!([{"mesh": 0, "children": [1]}, {"children": [0]}]);
    }));
    assert!(err.contains("own ancestor"), "{err}");
    let err = load_err(&cube_glb(|doc, _| doc["nodes"] = serde_json::json!([{"mesh": 0, "children": [0]}])));
    assert!(err.contains("own ancestor"), "{err}");
}

#[test]
fn missing_buffers_are_named() {
    let err = load_err(&cube_glb(|doc, _| doc["buffers"][0]["uri"] = serde_json::json!("missing.bin")));
    assert!(err.contains("missing or unreadable data"), "{err}");
}

#[test]
fn degenerate_meshes_and_absurd_grids_are_errors() {
    // Every triangle collapsed onto one point.
    let err = load_slice(
        &cube_glb(|_, bin| {
            for v in 0..8 {
                bin[v * 12..v * 12 + 12].copy_from_slice(&[0u8; 12]);
            }
        }),
        None,
    )
    .and_then(|soup| voxelize(&soup, &VoxelizeOptions::default()))
    .unwrap_err()
    .to_string();
    assert!(err.contains("no triangles") || err.contains("coincide") || err.contains("zero area"), "{err}");
    let soup = load_slice(&cube_glb(|_, _| {}), None).unwrap();
    let err =
        voxelize(&soup, &VoxelizeOptions { grid: GridSize::Resolution(60_000), ..Default::default() }).unwrap_err();
    assert!(matches!(err, VoxelError::GridTooLarge { .. }), "{err}");
    let err = voxelize(&soup, &VoxelizeOptions { grid: GridSize::Cell(-1.0), ..Default::default() }).unwrap_err();
    assert!(err.to_string().contains("grid size must be positive"), "{err}");
}

#[test]
fn quantized_positions_with_a_dequantizing_node_scale_load() {
    // KHR_mesh_quantization: normalized i16 positions (0 or 32767) and a node scale of 2.
    let mesh = voxel_core::shapes::cuboid([0.0; 3], [1.0; 3]);
    let mut bin = Vec::new();
    for p in &mesh.positions {
        for c in p {
            bin.extend_from_slice(&((c * 32767.0) as i16).to_le_bytes());
        }
        bin.extend_from_slice(&[0, 0]); // pad each element to 4-byte alignment
    }
    let positions_len = bin.len();
    for t in &mesh.triangles {
        for &i in t {
            bin.extend_from_slice(&(i as u16).to_le_bytes());
        }
    }
    let mut doc = cube_document(bin.len(), positions_len, 36);
    doc["extensionsUsed"] = serde_json::json!(["KHR_mesh_quantization"]);
    doc["extensionsRequired"] = serde_json::json!(["KHR_mesh_quantization"]);
    doc["nodes"][0]["scale"] = serde_json::json!([2.0, 2.0, 2.0]);
    doc["bufferViews"][0]["byteStride"] = serde_json::json!(8);
    doc["accessors"][0]["componentType"] = serde_json::json!(5122);
    doc["accessors"][0]["normalized"] = serde_json::json!(true);
    let soup = load_slice(&glb(&doc, &bin), None).unwrap();
    let (lo, hi) = soup.bounds().unwrap();
    assert_eq!(lo, [0.0; 3]);
    assert_eq!(hi, [2.0; 3]);
    let m = voxelize(&soup, &VoxelizeOptions { grid: GridSize::Resolution(8), ..Default::default() }).unwrap();
    assert_eq!(m.len(), 512);
}

#[test]
fn data_uri_buffers_and_triangle_strips_load() {
    use base64::Engine as _;
    // A unit square as a 4-vertex strip in a .gltf whose buffer is a data URI.
    let mut bin = Vec::new();
    for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 1.0]] {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    let uri =
        format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bin));
    let doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": 5}]}],
        "buffers": [{"byteLength": bin.len(), "uri": uri}],
        "bufferViews": [{"buffer": 0, "byteLength": bin.len()}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0.0, 0.0, 0.0], "max": [1.0, 0.0, 1.0]}]
    });
    let soup = load_slice(&serde_json::to_vec(&doc).unwrap(), None).unwrap();
    assert_eq!(soup.triangle_count(), 2);
    let m = voxelize(&soup, &VoxelizeOptions { grid: GridSize::Resolution(10), ..Default::default() }).unwrap();
    assert_eq!(m.len(), 100);
}

/// The cube with a base-colour texture whose image is `image` (a JSON object) and an extra buffer view
/// `view` (a JSON object) for it to point at.
fn textured_cube_glb(image: serde_json::Value, view: serde_json::Value) -> Vec<u8> {
    cube_glb(|doc, _| {
        doc["bufferViews"].as_array_mut().unwrap().push(view);
        doc["images"] = serde_json::json!([image]);
        doc["textures"] = serde_json::json!([{"source": 0}]);
        doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = serde_json::json!({"index": 0});
    })
}

#[test]
fn a_position_accessor_past_the_end_is_named() {
    // The gltf crate's own validation hook indexes this accessor unchecked (gltf-json 1.4.1 mesh.rs:151).
    let err = load_err(&cube_glb(|doc, _| doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 9.into()));
    assert!(err.contains("POSITION refers to accessor 9, but the file has 2 accessors"), "{err}");
}

#[test]
fn an_image_buffer_view_past_its_buffer_is_named() {
    // gltf 1.4.1 import.rs:196 slices the buffer unchecked.
    let err = load_err(&textured_cube_glb(
        serde_json::json!({"bufferView": 2, "mimeType": "image/png"}),
        serde_json::json!({"buffer": 0, "byteOffset": 100, "byteLength": 5000}),
    ));
    assert!(err.contains("image 0 in buffer view 2: 5000 bytes at 100 run past the end of buffer 0"), "{err}");
}

#[test]
fn an_image_without_a_mime_type_or_a_source_is_named() {
    // gltf 1.4.1 image.rs:125 unwraps the MIME type of an image in a buffer view, image.rs:128 the URI.
    let view = serde_json::json!({"buffer": 0, "byteOffset": 0, "byteLength": 16});
    let err = load_err(&textured_cube_glb(serde_json::json!({"bufferView": 2}), view.clone()));
    assert!(err.contains("image 0 is in a buffer view but has no mimeType"), "{err}");
    let err = load_err(&textured_cube_glb(serde_json::json!({"bufferView": 2, "uri": "x.png"}), view.clone()));
    assert!(err.contains("image 0 is in a buffer view but has no mimeType"), "{err}");
    let err = load_err(&textured_cube_glb(serde_json::json!({"name": "nothing"}), view));
    assert!(err.contains("image 0 has neither a uri nor a bufferView"), "{err}");
}

#[test]
fn a_uri_that_does_not_percent_decode_is_named() {
    // gltf 1.4.1 import.rs:50 unwraps the percent-decoding of relative URIs.
    let err = load_err(&cube_glb(|doc, _| doc["buffers"][0]["uri"] = "%FF%FE.bin".into()));
    assert!(err.contains("buffer 0: the URI \"%FF%FE.bin\" does not percent-decode to UTF-8"), "{err}");
}

#[test]
fn gltf_1_is_named() {
    let message = "glTF 1.0 is not supported; convert it to glTF 2.0";
    // The 1.0 shape: objects keyed by id.
    let v1 = serde_json::json!({
        "asset": {"version": "1.0"},
        "scene": "defaultScene",
        "scenes": {"defaultScene": {"nodes": ["node"]}},
        "nodes": {"node": {"meshes": ["mesh"]}},
        "meshes": {"mesh": {"primitives": [{"attributes": {"POSITION": "acc"}, "mode": 4}]}},
        "accessors": {"acc": {"bufferView": "view", "byteOffset": 0, "componentType": 5126, "count": 3, "type": "VEC3"}}
    });
    assert!(load_err(&serde_json::to_vec(&v1).unwrap()).contains(message));
    // The same shape with no version, and a 2.0 shape that says 1.0.
    let mut unversioned = v1.clone();
    unversioned["asset"] = serde_json::json!({});
    assert!(load_err(&serde_json::to_vec(&unversioned).unwrap()).contains(message));
    assert!(load_err(&cube_glb(|doc, _| doc["asset"]["version"] = "1.0".into())).contains(message));
    // Binary glTF 1.0 (KHR_binary_glTF): version 1 in the GLB header.
    let mut glb_v1 = cube_glb(|_, _| {});
    glb_v1[4..8].copy_from_slice(&1u32.to_le_bytes());
    assert!(load_err(&glb_v1).contains(message));
}

#[test]
fn damaged_draco_streams_are_named() {
    let draco = |view: u32| {
        cube_glb(move |doc, _| {
            doc["extensionsRequired"] = serde_json::json!(["KHR_draco_mesh_compression"]);
            doc["meshes"][0]["primitives"][0]["extensions"] = serde_json::json!({
                "KHR_draco_mesh_compression": {"bufferView": view, "attributes": {"POSITION": 0}}
            });
        })
    };
    // The cube's raw positions are no Draco stream.
    let err = load_err(&draco(0));
    assert!(err.contains("mesh 0 primitive 0 (KHR_draco_mesh_compression): cannot decode"), "{err}");
    let err = load_err(&draco(9));
    assert!(err.contains("(KHR_draco_mesh_compression): buffer view 9 does not exist"), "{err}");
}

#[test]
fn a_huge_accessor_without_data_is_refused_before_allocating() {
    let err = load_err(&cube_glb(|doc, _| {
        doc["accessors"][0] = serde_json::json!({"componentType": 5126, "count": 1 << 25, "type": "VEC3"});
    }));
    assert!(err.contains("accessor of 33554432 elements without a buffer view is too large"), "{err}");
}

#[test]
fn a_glb_declaring_less_than_its_header_is_named() {
    // Found by the fuzz target: gltf 1.4.1 binary.rs:252 subtracts the header size from this length unchecked.
    let mut bytes = cube_glb(|_, _| {});
    bytes[8..12].copy_from_slice(&5u32.to_le_bytes());
    assert!(load_err(&bytes).contains("corrupt GLB (its header declares a length of 5 bytes)"));
}

#[test]
fn position_bounds_are_optional() {
    // glTF requires POSITION min/max, but nothing here uses them; exporters that omit them still load.
    let bytes = cube_glb(|doc, _| {
        let accessor = doc["accessors"][0].as_object_mut().unwrap();
        accessor.remove("min");
        accessor.remove("max");
    });
    assert_eq!(load_slice(&bytes, None).unwrap().triangle_count(), 12);
}
