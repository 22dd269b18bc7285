//! glTF materials to soup [`Material`]s: base colour factor, base-colour texture, sampler, UV set.

use std::borrow::Cow;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use gltf::image::Format;
use gltf::texture::WrappingMode;
use rayon::prelude::*;

use super::buffers::Buffers;
use crate::error::{Result, VoxelError};
use crate::soup::{Material, Texture, TextureBinding, TriangleSoup, Wrap};

/// Which UV set feeds a material's base-colour texture, and its KHR_texture_transform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TexCoordSet {
    /// TEXCOORD_n index.
    pub index: u32,
    offset: [f32; 2],
    rotation: f32,
    scale: [f32; 2],
}

impl TexCoordSet {
    /// Applies the texture transform (translation * rotation * scale, as the extension specifies).
    pub fn transform(&self, uv: [f32; 2]) -> [f32; 2] {
        let (s, c) = self.rotation.sin_cos();
        let (u, v) = (uv[0] * self.scale[0], uv[1] * self.scale[1]);
        [c * u - s * v + self.offset[0], s * u + c * v + self.offset[1]]
    }
}

/// Converts glTF materials once each and shares decoded images between them.
pub(crate) struct MaterialCache {
    base_dir: Option<PathBuf>,
    by_gltf_index: HashMap<Option<usize>, (usize, Option<TexCoordSet>)>,
    /// Decoded images by glTF index (a prefetched one may hold its decoding error).
    images: HashMap<usize, Result<Arc<Texture>>>,
}

fn wrap_of(mode: WrappingMode) -> Wrap {
    match mode {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
    }
}

/// Converts decoded image pixels of any glTF-supported format to RGBA8 (16-bit channels keep their high byte,
/// float channels are clamped to [0, 1] and rounded).
fn to_rgba8(data: &gltf::image::Data) -> Result<Vec<[u8; 4]>> {
    let (channels, bytes_per) = match data.format {
        Format::R8 => (1, 1),
        Format::R8G8 => (2, 1),
        Format::R8G8B8 => (3, 1),
        Format::R8G8B8A8 => (4, 1),
        Format::R16 => (1, 2),
        Format::R16G16 => (2, 2),
        Format::R16G16B16 => (3, 2),
        Format::R16G16B16A16 => (4, 2),
        Format::R32G32B32FLOAT => (3, 4),
        Format::R32G32B32A32FLOAT => (4, 4),
    };
    let n = data.width as usize * data.height as usize;
    let Some(p) = data.pixels.get(..n * channels * bytes_per) else {
        return Err(VoxelError::Invalid("decoded image is shorter than its size".into()));
    };
    // One byte per channel first, then the channels to RGBA: each step a loop the compiler vectorizes.
    let bytes: Cow<'_, [u8]> = match bytes_per {
        1 => Cow::Borrowed(p),
        2 => Cow::Owned(p.chunks_exact(2).map(|c| (u16::from_le_bytes([c[0], c[1]]) >> 8) as u8).collect()),
        _ => Cow::Owned(
            p.chunks_exact(4)
                .map(|c| (f32::from_le_bytes([c[0], c[1], c[2], c[3]]).clamp(0.0, 1.0) * 255.0).round() as u8)
                .collect(),
        ),
    };
    Ok(match channels {
        1 => bytes.iter().map(|&l| [l, l, l, 255]).collect(),
        2 => bytes.chunks_exact(2).map(|c| [c[0], c[0], c[0], c[1]]).collect(),
        3 => bytes.chunks_exact(3).map(|c| [c[0], c[1], c[2], 255]).collect(),
        _ => bytes.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect(),
    })
}

/// Decodes `image` (embedded, data URI or a file next to `base_dir`) to an RGBA8 texture.
fn decode(image: &gltf::Image<'_>, base_dir: Option<&Path>, buffers: &Buffers<'_>) -> Result<Arc<Texture>> {
    if let Some(webp) = super::webp::decode_if_webp(image, base_dir, buffers) {
        return webp.map(Arc::new);
    }
    let source = image.source();
    let buffer_data = match &source {
        gltf::image::Source::View { view, .. } => {
            // The gltf crate slices the buffer unchecked (and never sees decoded meshopt views).
            let what = format!("image {} in buffer view {}", image.index(), view.index());
            buffers.buffer_range(view.buffer().index(), view.offset(), view.length(), &what)?;
            buffers.owned()
        }
        gltf::image::Source::Uri { .. } => &[],
    };
    let data = gltf::image::Data::from_source(source, base_dir, buffer_data)
        .map_err(|e| VoxelError::MissingData(format!("image {}: {e}", image.index())))?;
    Ok(Arc::new(Texture::new(data.width, data.height, to_rgba8(&data)?)?))
}

impl MaterialCache {
    pub fn new(base_dir: Option<&Path>) -> Self {
        Self { base_dir: base_dir.map(Path::to_owned), by_gltf_index: HashMap::new(), images: HashMap::new() }
    }

    /// The soup material index for `material` (added on first use) and the UV set its texture reads.
    pub fn resolve(
        &mut self,
        soup: &mut TriangleSoup,
        material: &gltf::Material<'_>,
        buffers: &Buffers<'_>,
    ) -> Result<(usize, Option<TexCoordSet>)> {
        if let Some(&hit) = self.by_gltf_index.get(&material.index()) {
            return Ok(hit);
        }
        let pbr = material.pbr_metallic_roughness();
        let mut out = Material { base_color: pbr.base_color_factor(), texture: None };
        let mut set = None;
        if let Some(info) = pbr.base_color_texture() {
            let texture = info.texture();
            let sampler = texture.sampler();
            let image = texture.source();
            out.texture = Some(TextureBinding {
                texture: self.image(&image, buffers)?,
                wrap: [wrap_of(sampler.wrap_s()), wrap_of(sampler.wrap_t())],
            });
            let transform = info.texture_transform();
            set = Some(TexCoordSet {
                index: transform.as_ref().and_then(|t| t.tex_coord()).unwrap_or(info.tex_coord()),
                offset: transform.as_ref().map_or([0.0; 2], |t| t.offset()),
                rotation: transform.as_ref().map_or(0.0, |t| t.rotation()),
                scale: transform.as_ref().map_or([1.0; 2], |t| t.scale()),
            });
        }
        let resolved = (soup.add_material(out), set);
        self.by_gltf_index.insert(material.index(), resolved);
        Ok(resolved)
    }

    /// Decodes, on the thread pool, the base-colour images of `primitives` (a failure is reported when a
    /// material that uses the image is resolved, as without this).
    pub fn prefetch<'a>(&mut self, primitives: impl Iterator<Item = gltf::Primitive<'a>>, buffers: &Buffers<'_>) {
        let mut wanted: Vec<gltf::Image<'_>> = primitives
            .filter_map(|prim| prim.material().pbr_metallic_roughness().base_color_texture())
            .map(|info| info.texture().source())
            .filter(|image| !self.images.contains_key(&image.index()))
            .collect();
        wanted.sort_by_key(gltf::Image::index);
        wanted.dedup_by_key(|image| image.index());
        let base_dir = self.base_dir.as_deref();
        let decode = |image: &gltf::Image<'_>| (image.index(), decode(image, base_dir, buffers));
        // One image is decoded here: handing it to a pool thread would only add the thread's wake-up.
        let decoded: Vec<(usize, Result<Arc<Texture>>)> = if wanted.len() > 1 {
            wanted.par_iter().map(decode).collect()
        } else {
            wanted.iter().map(decode).collect()
        };
        self.images.extend(decoded);
    }

    /// The texture of `image`: prefetched, else decoded now.
    fn image(&mut self, image: &gltf::Image<'_>, buffers: &Buffers<'_>) -> Result<Arc<Texture>> {
        let texture = match self.images.remove(&image.index()) {
            Some(decoded) => decoded?,
            None => decode(image, self.base_dir.as_deref(), buffers)?,
        };
        self.images.insert(image.index(), Ok(texture.clone()));
        Ok(texture)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(format: Format, pixels: Vec<u8>) -> gltf::image::Data {
        gltf::image::Data { pixels, format, width: 2, height: 1 }
    }

    #[test]
    fn every_image_format_becomes_rgba8() {
        let cases = [
            (Format::R8, vec![7, 200], [[7, 7, 7, 255], [200, 200, 200, 255]]),
            (Format::R8G8, vec![7, 8, 9, 10], [[7, 7, 7, 8], [9, 9, 9, 10]]),
            (Format::R8G8B8, vec![1, 2, 3, 4, 5, 6], [[1, 2, 3, 255], [4, 5, 6, 255]]),
            (Format::R8G8B8A8, vec![1, 2, 3, 4, 5, 6, 7, 8], [[1, 2, 3, 4], [5, 6, 7, 8]]),
            // 16-bit channels (little-endian) keep their high byte.
            (Format::R16, vec![0xff, 0x12, 0x00, 0xab], [[0x12, 0x12, 0x12, 255], [0xab, 0xab, 0xab, 255]]),
            (Format::R16G16, vec![0, 1, 0, 2, 0, 3, 0, 4], [[1, 1, 1, 2], [3, 3, 3, 4]]),
            (Format::R16G16B16, (1..=12).collect(), [[2, 4, 6, 255], [8, 10, 12, 255]]),
            (Format::R16G16B16A16, (1..=16).collect(), [[2, 4, 6, 8], [10, 12, 14, 16]]),
        ];
        for (format, pixels, want) in cases {
            assert_eq!(to_rgba8(&image(format, pixels)).unwrap(), want, "{format:?}");
        }
        // Float channels are clamped to [0, 1] and rounded.
        let floats = |v: &[f32]| v.iter().flat_map(|f| f.to_le_bytes()).collect::<Vec<u8>>();
        let rgb = floats(&[0.0, 0.5, 1.0, -1.0, 2.0, 0.1]);
        assert_eq!(to_rgba8(&image(Format::R32G32B32FLOAT, rgb)).unwrap(), [[0, 128, 255, 255], [0, 255, 26, 255]]);
        let rgba = floats(&[0.2, 0.4, 0.6, 0.8, 1.0, 1.0, 1.0, 0.0]);
        assert_eq!(
            to_rgba8(&image(Format::R32G32B32A32FLOAT, rgba)).unwrap(),
            [[51, 102, 153, 204], [255, 255, 255, 0]]
        );
    }

    #[test]
    fn an_image_shorter_than_its_size_is_refused() {
        let err = to_rgba8(&image(Format::R8G8B8, vec![1, 2, 3, 4, 5])).unwrap_err();
        assert_eq!(err.to_string(), VoxelError::Invalid("decoded image is shorter than its size".into()).to_string());
    }

    #[test]
    fn texture_transform_offsets_scales_and_rotates() {
        let set = TexCoordSet { index: 0, offset: [0.5, 0.25], rotation: 0.0, scale: [2.0, 2.0] };
        assert_eq!(set.transform([0.25, 0.25]), [1.0, 0.75]);
        let quarter =
            TexCoordSet { index: 0, offset: [0.0; 2], rotation: std::f32::consts::FRAC_PI_2, scale: [1.0; 2] };
        let r = quarter.transform([1.0, 0.0]);
        assert!((r[0]).abs() < 1e-6 && (r[1] - 1.0).abs() < 1e-6, "{r:?}");
    }
}
