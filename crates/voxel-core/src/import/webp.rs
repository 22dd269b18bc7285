//! EXT_texture_webp: a texture whose image is WebP. The extension names the WebP image inside the texture
//! (glTF-Transform's `webp` command leaves the texture no other `source`); [`use_webp_sources`] makes it the
//! texture's source before the document is checked, and [`decode_if_webp`] decodes such images with the
//! `image` crate (pure Rust; the `gltf` crate decodes only PNG and JPEG).

use std::path::Path;

use gltf::json::{Index, Root};

use super::buffers::Buffers;
use crate::error::{Result, VoxelError};
use crate::soup::Texture;

/// The extension's name.
pub(super) const EXTENSION: &str = "EXT_texture_webp";

/// Points every texture with an EXT_texture_webp `source` at that image (a client that decodes WebP uses it,
/// the spec says, over any fallback `source`).
pub(super) fn use_webp_sources(root: &mut Root) -> Result<()> {
    let images = root.images.len();
    for (i, texture) in root.textures.iter_mut().enumerate() {
        let Some(ext) = texture.extensions.as_ref().and_then(|e| e.others.get(EXTENSION)) else {
            continue;
        };
        let source = ext.get("source").and_then(serde_json::Value::as_u64);
        match source.and_then(|s| usize::try_from(s).ok()).filter(|&s| s < images) {
            Some(image) => texture.source = Index::new(image as u32),
            None => {
                return Err(VoxelError::Invalid(format!(
                    "texture {i}: {EXTENSION} source {} is not one of the file's {images} images",
                    ext.get("source").map_or_else(|| "(none)".into(), ToString::to_string)
                )));
            }
        }
    }
    Ok(())
}

/// Whether `image` is WebP: its MIME type says so, or its URI (a data URI's type, a file's extension).
fn is_webp(source: &gltf::image::Source<'_>) -> bool {
    match source {
        gltf::image::Source::View { mime_type, .. } => *mime_type == "image/webp",
        gltf::image::Source::Uri { uri, mime_type } => {
            *mime_type == Some("image/webp")
                || uri.starts_with("data:image/webp")
                || uri.rsplit('.').next().is_some_and(|ext| ext.eq_ignore_ascii_case("webp"))
        }
    }
}

/// The texture of `image` when it is WebP (`None` otherwise): its bytes from a buffer view, a data URI or a
/// file next to `base_dir`, decoded to RGBA8.
pub(super) fn decode_if_webp(
    image: &gltf::Image<'_>,
    base_dir: Option<&Path>,
    buffers: &Buffers<'_>,
) -> Option<Result<Texture>> {
    let source = image.source();
    if !is_webp(&source) {
        return None;
    }
    let what = format!("image {}", image.index());
    let bytes = match source {
        gltf::image::Source::View { view, .. } => {
            buffers.buffer_range(view.buffer().index(), view.offset(), view.length(), &what).map(<[u8]>::to_vec)
        }
        gltf::image::Source::Uri { uri, .. } => {
            if base_dir.is_none() && !uri.starts_with("data:") {
                Err(VoxelError::MissingData(format!("{what}: {uri} (no folder to read it from)")))
            } else {
                gltf::buffer::Data::from_source(gltf::buffer::Source::Uri(uri), base_dir)
                    .map(|data| data.0)
                    .map_err(|e| VoxelError::MissingData(format!("{what}: {e}")))
            }
        }
    };
    Some(bytes.and_then(|bytes| decode(&bytes, &what)))
}

/// Decodes WebP bytes (lossy or lossless, with or without alpha) to an RGBA8 texture.
fn decode(bytes: &[u8], what: &str) -> Result<Texture> {
    let undecodable = |e: &dyn std::fmt::Display| VoxelError::MissingData(format!("{what}: undecodable WebP ({e})"));
    let mut decoder = image_webp::WebPDecoder::new(std::io::Cursor::new(bytes)).map_err(|e| undecodable(&e))?;
    let (width, height) = decoder.dimensions();
    let size = decoder.output_buffer_size().ok_or_else(|| undecodable(&"the image is too large"))?;
    let mut buf = vec![0; size];
    decoder.read_image(&mut buf).map_err(|e| undecodable(&e))?;
    let pixels = if decoder.has_alpha() {
        buf.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect()
    } else {
        buf.chunks_exact(3).map(|c| [c[0], c[1], c[2], 255]).collect()
    };
    Texture::new(width, height, pixels)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn webp_is_recognized_by_mime_type_data_uri_or_extension() {
        let uri = |uri, mime_type| is_webp(&gltf::image::Source::Uri { uri, mime_type });
        assert!(uri("tex.WEBP", None) && uri("data:image/webp;base64,AAAA", None) && uri("t", Some("image/webp")));
        assert!(!uri("tex.png", None) && !uri("data:image/png;base64,AAAA", None));
    }

    #[test]
    fn lossless_webp_decodes_to_its_pixels_and_junk_is_an_error() {
        let pixels: Vec<u8> = (0..4 * 3 * 2).map(|i| (i * 37 % 256) as u8).collect();
        let mut bytes = Vec::new();
        image_webp::WebPEncoder::new(&mut bytes).encode(&pixels, 3, 2, image_webp::ColorType::Rgba8).unwrap();
        let texture = decode(&bytes, "image 0").unwrap();
        assert_eq!((texture.width, texture.height), (3, 2));
        let want: Vec<[u8; 4]> = pixels.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
        assert_eq!(texture.rgba, want);
        let err = decode(b"RIFF\x04\0\0\0WEBPjunk", "image 3").unwrap_err().to_string();
        assert!(err.starts_with("missing or unreadable data: image 3: undecodable WebP"), "{err}");
    }
}
