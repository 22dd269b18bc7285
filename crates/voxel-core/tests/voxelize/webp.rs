//! EXT_texture_webp: a textured model whose texture is re-encoded as WebP (built here from the corpus's
//! Duck, its texture named only inside the extension, as glTF-Transform's `webp` command writes it) gives the
//! same cells as the PNG original and the same colours.

use serde_json::{Value, json};
use voxel_core::glb::GlbBuilder;
use voxel_core::{VoxelModel, load_slice, voxelize};

use crate::common::{at_resolution, cells, glb, model};

/// The document and binary chunk of a .glb.
fn unpack(bytes: &[u8]) -> (Value, Vec<u8>) {
    let gltf = gltf::Gltf::from_slice_without_validation(bytes).unwrap();
    (serde_json::to_value(gltf.document.as_json()).unwrap(), gltf.blob.clone().unwrap())
}

/// `bytes` (a .glb whose textures' images are PNGs in buffer views) with every texture's image re-encoded by
/// `encode` (RGBA8 pixels, width, height → WebP bytes) and named only by EXT_texture_webp.
fn with_webp_textures(bytes: &[u8], encode: impl Fn(&[u8], u32, u32) -> Vec<u8>) -> Vec<u8> {
    let (mut doc, mut bin) = unpack(bytes);
    let textures = doc["textures"].as_array().unwrap().len();
    for t in 0..textures {
        let source = doc["textures"][t]["source"].as_u64().unwrap() as usize;
        let view = &doc["bufferViews"][doc["images"][source]["bufferView"].as_u64().unwrap() as usize];
        let offset = view["byteOffset"].as_u64().unwrap_or(0) as usize;
        let png = &bin[offset..offset + view["byteLength"].as_u64().unwrap() as usize];
        let rgba = image::load_from_memory(png).unwrap().into_rgba8();
        let webp = encode(rgba.as_raw(), rgba.width(), rgba.height());
        bin.resize(bin.len().next_multiple_of(4), 0);
        let views = doc["bufferViews"].as_array_mut().unwrap();
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": webp.len()}));
        let view = views.len() - 1;
        bin.extend_from_slice(&webp);
        let images = doc["images"].as_array_mut().unwrap();
        images.push(json!({"bufferView": view, "mimeType": "image/webp"}));
        let image = images.len() - 1;
        let texture = doc["textures"][t].as_object_mut().unwrap();
        texture.remove("source");
        texture.insert("extensions".into(), json!({"EXT_texture_webp": {"source": image}}));
    }
    bin.resize(bin.len().next_multiple_of(4), 0);
    doc["buffers"][0]["byteLength"] = bin.len().into();
    doc["extensionsUsed"] = json!(["EXT_texture_webp"]);
    doc["extensionsRequired"] = json!(["EXT_texture_webp"]);
    glb(&doc, &bin)
}

/// Lossless WebP by the `image-webp` crate (what `image` uses).
fn lossless(rgba: &[u8], width: u32, height: u32) -> Vec<u8> {
    let mut out = Vec::new();
    image_webp::WebPEncoder::new(&mut out).encode(rgba, width, height, image_webp::ColorType::Rgba8).unwrap();
    out
}

/// The mean sRGB colour of the visible voxels.
fn mean_color(model: &VoxelModel) -> [f64; 3] {
    let mut sum = [0.0f64; 3];
    let mut n = 0.0;
    for v in model.visible_voxels() {
        for (s, &c) in sum.iter_mut().zip(&v.color) {
            *s += f64::from(c);
        }
        n += 1.0;
    }
    sum.map(|s| s / n)
}

#[test]
fn a_lossless_webp_duck_voxelizes_like_its_png_twin() {
    let Some(path) = model("khronos-duck.glb") else { return };
    let png = std::fs::read(path).unwrap();
    let webp = with_webp_textures(&png, lossless);
    let options = at_resolution(48);
    let from_png = voxelize(&load_slice(&png, None).unwrap(), &options).unwrap();
    let from_webp = voxelize(&load_slice(&webp, None).unwrap(), &options).unwrap();
    assert_eq!(cells(&from_png), cells(&from_webp));
    let (a, b) = (mean_color(&from_png), mean_color(&from_webp));
    assert!((0..3).all(|k| (a[k] - b[k]).abs() <= 2.0), "{a:?} vs {b:?}");
    // Lossless: every voxel's colour is the same.
    assert!(from_png.voxels().eq(from_webp.voxels()));
    assert!(from_png.color_count() > 20, "textured: {}", from_png.color_count());
}

#[test]
fn a_webp_source_that_is_not_an_image_is_named() {
    let Some(path) = model("khronos-duck.glb") else { return };
    let webp = with_webp_textures(&std::fs::read(path).unwrap(), lossless);
    let (mut doc, bin) = unpack(&webp);
    doc["textures"][0]["extensions"]["EXT_texture_webp"]["source"] = 7.into();
    let err = load_slice(&glb(&doc, &bin), None).unwrap_err().to_string();
    assert!(err.contains("texture 0: EXT_texture_webp source 7 is not one of the file's 2 images"), "{err}");
}

/// A unit square textured with `image` (a file of tests/data): a .gltf whose buffer is a data URI.
fn textured_square(image: &str, webp: bool) -> Vec<u8> {
    use base64::Engine;
    let corners = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 1.0], [0.0, 0.0, 1.0]];
    let mut builder = GlbBuilder::default();
    let position = builder.accessor(
        &corners.iter().flatten().flat_map(|c| c.to_le_bytes()).collect::<Vec<u8>>(),
        json!({"componentType": 5126, "count": 4, "type": "VEC3", "min": [0.0, 0.0, 0.0], "max": [1.0, 0.0, 1.0]}),
    );
    let uv = builder.accessor(
        &corners.iter().flat_map(|[x, _, z]| [x.to_le_bytes(), z.to_le_bytes()]).flatten().collect::<Vec<u8>>(),
        json!({"componentType": 5126, "count": 4, "type": "VEC2"}),
    );
    let indices = builder.accessor(
        &[0u16, 2, 1, 0, 3, 2].iter().flat_map(|i| i.to_le_bytes()).collect::<Vec<u8>>(),
        json!({"componentType": 5123, "count": 6, "type": "SCALAR"}),
    );
    let primitive = json!({"attributes": {"POSITION": position, "TEXCOORD_0": uv}, "indices": indices, "material": 0});
    let material = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    let (mut doc, bin) = builder.one_mesh("webp test", vec![primitive], material);
    let texture = if webp { json!({"extensions": {"EXT_texture_webp": {"source": 0}}}) } else { json!({"source": 0}) };
    doc["extensionsUsed"] = if webp { json!(["EXT_texture_webp"]) } else { json!([]) };
    doc["textures"] = json!([texture]);
    doc["images"] = json!([{"uri": image}]);
    let data = base64::engine::general_purpose::STANDARD.encode(&bin);
    doc["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{data}"));
    serde_json::to_vec(&doc).unwrap()
}

#[test]
fn a_lossy_webp_file_texture_voxelizes_like_its_png_twin_within_8_of_255() {
    // Made by tools/make-webp-pattern.mjs (our own pattern; libwebp at quality 75).
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let options = at_resolution(32);
    let load = |image: &str, webp: bool| {
        let soup = load_slice(&textured_square(image, webp), Some(&data)).unwrap();
        voxelize(&soup, &options).unwrap()
    };
    let from_png = load("webp-pattern.png", false);
    let from_webp = load("webp-pattern-lossy.webp", true);
    assert_eq!(from_png.len(), 32 * 32);
    assert_eq!(cells(&from_png), cells(&from_webp));
    let (a, b) = (mean_color(&from_png), mean_color(&from_webp));
    assert!((0..3).all(|k| (a[k] - b[k]).abs() <= 8.0), "{a:?} vs {b:?}");
    assert!(from_webp.color_count() >= 4, "the four quadrants: {}", from_webp.color_count());
    // A file URI with no folder to read it from is a named error.
    let err = load_slice(&textured_square("webp-pattern-lossy.webp", true), None).unwrap_err().to_string();
    assert!(err.contains("image 0: webp-pattern-lossy.webp (no folder to read it from)"), "{err}");
}
