//! EXT_texture_webp: a textured model whose texture is re-encoded as WebP (built here from the corpus's
//! Duck, its texture named only inside the extension, as glTF-Transform's `webp` command writes it) gives the
//! same cells as the PNG original and the same colours.

use serde_json::{Value, json};
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

/// Lossless WebP by the `image` crate.
fn lossless(rgba: &[u8], width: u32, height: u32) -> Vec<u8> {
    let mut out = Vec::new();
    image::codecs::webp::WebPEncoder::new_lossless(&mut out)
        .encode(rgba, width, height, image::ExtendedColorType::Rgba8)
        .unwrap();
    out
}

/// The mean sRGB colour of the visible voxels.
fn mean_color(model: &VoxelModel) -> [f64; 3] {
    let mut sum = [0.0f64; 3];
    let mut n = 0.0;
    for v in model.visible_voxels() {
        for k in 0..3 {
            sum[k] += f64::from(v.color[k]);
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
    assert!(from_png.stats.colors > 20, "textured: {}", from_png.stats.colors);
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
