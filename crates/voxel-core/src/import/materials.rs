//! glTF materials to soup [`Material`]s: base colour factor, base-colour texture, sampler, UV set.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use gltf::image::Format;
use gltf::texture::WrappingMode;

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
    images: HashMap<usize, Arc<Texture>>,
}

fn wrap_of(mode: WrappingMode) -> Wrap {
    match mode {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
    }
}

/// Converts decoded image pixels of any glTF-supported format to RGBA8.
fn to_rgba8(data: &gltf::image::Data) -> Result<Vec<[u8; 4]>> {
    let p = &data.pixels;
    let n = data.width as usize * data.height as usize;
    let u16_at = |i: usize| (u16::from_le_bytes([p[2 * i], p[2 * i + 1]]) >> 8) as u8;
    let f32_at = |i: usize| {
        let v = f32::from_le_bytes([p[4 * i], p[4 * i + 1], p[4 * i + 2], p[4 * i + 3]]);
        (v.clamp(0.0, 1.0) * 255.0).round() as u8
    };
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
    if p.len() < n * channels * bytes_per {
        return Err(VoxelError::Invalid("decoded image is shorter than its size".into()));
    }
    let get = |i: usize| match bytes_per {
        1 => p[i],
        2 => u16_at(i),
        _ => f32_at(i),
    };
    Ok((0..n)
        .map(|t| {
            let b = t * channels;
            match channels {
                1 => [get(b), get(b), get(b), 255],
                2 => [get(b), get(b), get(b), get(b + 1)],
                3 => [get(b), get(b + 1), get(b + 2), 255],
                _ => [get(b), get(b + 1), get(b + 2), get(b + 3)],
            }
        })
        .collect())
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
        buffers: &Buffers,
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

    fn image(&mut self, image: &gltf::Image<'_>, buffers: &Buffers) -> Result<Arc<Texture>> {
        if let Some(t) = self.images.get(&image.index()) {
            return Ok(t.clone());
        }
        let source = image.source();
        if let gltf::image::Source::View { view, .. } = &source {
            // The gltf crate slices the buffer unchecked (and never sees decoded meshopt views).
            let what = format!("image {} in buffer view {}", image.index(), view.index());
            buffers.buffer_range(view.buffer().index(), view.offset(), view.length(), &what)?;
        }
        let data = gltf::image::Data::from_source(source, self.base_dir.as_deref(), &buffers.data)
            .map_err(|e| VoxelError::MissingData(format!("image {}: {e}", image.index())))?;
        let texture = Arc::new(Texture::new(data.width, data.height, to_rgba8(&data)?)?);
        self.images.insert(image.index(), texture.clone());
        Ok(texture)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
