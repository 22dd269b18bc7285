//! The Bevy front door of the voxelizer: a loaded `Gltf` asset (nodes, meshes, materials, images) read into
//! the core's [`TriangleSoup`], the same soup the `gltf`-crate importer makes for the CLI.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use bevy::asset::AssetId;
use bevy::gltf::{Gltf, GltfMaterial, GltfMesh, GltfNode};
use bevy::image::{ImageAddressMode, ImageSampler};
use bevy::mesh::{PrimitiveTopology, UvChannel, VertexAttributeValues};
use bevy::prelude::*;
use bevy::render::render_resource::TextureFormat;
use voxel_core::{Material, Texture, TextureBinding, TriangleSoup, Vertex, Wrap};

/// The asset collections a glTF is spread over.
pub struct GltfAssets<'a> {
    /// Node assets.
    pub nodes: &'a Assets<GltfNode>,
    /// Mesh (primitive list) assets.
    pub meshes: &'a Assets<GltfMesh>,
    /// Vertex data.
    pub mesh_data: &'a Assets<Mesh>,
    /// Materials.
    pub materials: &'a Assets<GltfMaterial>,
    /// Textures.
    pub images: &'a Assets<Image>,
}

/// The deepest node hierarchy followed (a guard; the loader already refuses cycles).
const MAX_DEPTH: usize = 256;

fn wrap_of(mode: ImageAddressMode) -> Wrap {
    match mode {
        ImageAddressMode::Repeat => Wrap::Repeat,
        ImageAddressMode::MirrorRepeat => Wrap::MirroredRepeat,
        ImageAddressMode::ClampToEdge | ImageAddressMode::ClampToBorder => Wrap::ClampToEdge,
    }
}

/// An image as an sRGB RGBA8 texture (a fast path for 8-bit RGBA, per-texel conversion otherwise).
fn texture_of(image: &Image) -> Result<Texture, String> {
    let (w, h) = (image.width(), image.height());
    let texels = match (image.texture_descriptor.format, &image.data) {
        (TextureFormat::Rgba8UnormSrgb, Some(data)) if data.len() >= (w * h * 4) as usize => {
            data.chunks_exact(4).take((w * h) as usize).map(|c| [c[0], c[1], c[2], c[3]]).collect()
        }
        _ => (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| image.get_color_at(x, y).map(|c| c.to_srgba().to_u8_array()))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| format!("texture cannot be read: {e}"))?,
    };
    Texture::new(w, h, texels).map_err(|e| e.to_string())
}

fn float3(values: Option<&VertexAttributeValues>) -> Option<&Vec<[f32; 3]>> {
    match values {
        Some(VertexAttributeValues::Float32x3(v)) => Some(v),
        _ => None,
    }
}

struct Reader<'a> {
    assets: &'a GltfAssets<'a>,
    soup: TriangleSoup,
    materials: HashMap<Option<AssetId<GltfMaterial>>, (usize, bool)>,
    textures: HashMap<AssetId<Image>, Arc<Texture>>,
}

impl Reader<'_> {
    /// The soup material for `handle` and whether its texture reads the second UV set.
    fn material(&mut self, handle: Option<&Handle<GltfMaterial>>) -> Result<(usize, bool), String> {
        let key = handle.map(Handle::id);
        if let Some(&hit) = self.materials.get(&key) {
            return Ok(hit);
        }
        let gltf_material = handle.and_then(|h| self.assets.materials.get(h));
        let mut material = Material::default();
        let mut second_uv_set = false;
        if let Some(m) = gltf_material {
            material.base_color = m.base_color.to_linear().to_f32_array();
            second_uv_set = m.base_color_channel == UvChannel::Uv1;
            if let Some(image_handle) = &m.base_color_texture {
                let image = self.assets.images.get(image_handle).ok_or("a base-colour texture is not loaded")?;
                let texture = match self.textures.get(&image_handle.id()) {
                    Some(t) => t.clone(),
                    None => {
                        let t = Arc::new(texture_of(image)?);
                        self.textures.insert(image_handle.id(), t.clone());
                        t
                    }
                };
                let wrap = match &image.sampler {
                    ImageSampler::Descriptor(d) => [wrap_of(d.address_mode_u), wrap_of(d.address_mode_v)],
                    ImageSampler::Default => [Wrap::Repeat; 2],
                };
                material.texture = Some(TextureBinding { texture, wrap });
            }
        }
        let resolved = (self.soup.add_material(material), second_uv_set);
        self.materials.insert(key, resolved);
        Ok(resolved)
    }

    fn mesh(&mut self, mesh: &GltfMesh, transform: &Mat4) -> Result<(), String> {
        for (k, primitive) in mesh.primitives.iter().enumerate() {
            let name = format!("{} primitive {k}", mesh.name);
            let data =
                self.assets.mesh_data.get(&primitive.mesh).ok_or_else(|| format!("{name}: mesh data not loaded"))?;
            let topology = data.primitive_topology();
            if !matches!(topology, PrimitiveTopology::TriangleList | PrimitiveTopology::TriangleStrip) {
                continue;
            }
            let attribute = |id| data.try_attribute_option(id).map_err(|e| format!("{name}: {e}"));
            let positions = float3(attribute(Mesh::ATTRIBUTE_POSITION)?)
                .ok_or_else(|| format!("{name}: positions are not 3 floats"))?;
            let (material, second_uv_set) = self.material(primitive.material.as_ref())?;
            let uv_id = if second_uv_set { Mesh::ATTRIBUTE_UV_1 } else { Mesh::ATTRIBUTE_UV_0 };
            let uvs = match attribute(uv_id)? {
                Some(VertexAttributeValues::Float32x2(v)) => Some(v),
                _ => None,
            };
            let colors = match attribute(Mesh::ATTRIBUTE_COLOR)? {
                Some(VertexAttributeValues::Float32x4(v)) => Some(v),
                _ => None,
            };
            let indices: Vec<usize> = match data.try_indices_option().map_err(|e| format!("{name}: {e}"))? {
                Some(i) => i.iter().collect(),
                None => (0..positions.len()).collect(),
            };
            if indices.iter().any(|&i| i >= positions.len()) {
                return Err(format!("{name}: a vertex index is out of range"));
            }
            let corners: Vec<[usize; 3]> = match topology {
                PrimitiveTopology::TriangleStrip => indices
                    .windows(3)
                    .enumerate()
                    .map(|(i, w)| if i % 2 == 0 { [w[0], w[1], w[2]] } else { [w[1], w[0], w[2]] })
                    .collect(),
                _ => indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
            };
            let world: Vec<[f32; 3]> =
                positions.iter().map(|p| transform.transform_point3(Vec3::from(*p)).to_array()).collect();
            let part = self.soup.add_part(material, name);
            for tri in corners {
                self.soup.push_triangle(
                    part,
                    tri.map(|i| Vertex {
                        position: world[i],
                        uv: uvs.map_or([0.0; 2], |u| u[i]),
                        color: colors.map_or([1.0; 4], |c| c[i]),
                    }),
                );
            }
        }
        Ok(())
    }
}

/// Reads every mesh instance of the glTF's node forest (roots: nodes nobody lists as a child) with its
/// composed transform into a triangle soup.
pub fn soup_from_gltf(gltf: &Gltf, assets: &GltfAssets<'_>) -> Result<TriangleSoup, String> {
    let children: HashSet<AssetId<GltfNode>> =
        gltf.nodes.iter().filter_map(|h| assets.nodes.get(h)).flat_map(|n| n.children.iter().map(Handle::id)).collect();
    let mut stack: Vec<(Handle<GltfNode>, Mat4, usize)> = gltf
        .nodes
        .iter()
        .filter(|h| !children.contains(&h.id()))
        .rev()
        .map(|h| (h.clone(), Mat4::IDENTITY, 0))
        .collect();
    let mut reader =
        Reader { assets, soup: TriangleSoup::default(), materials: HashMap::new(), textures: HashMap::new() };
    while let Some((handle, parent, depth)) = stack.pop() {
        if depth > MAX_DEPTH {
            return Err("the node hierarchy is too deep (or recursive)".into());
        }
        let node = assets.nodes.get(&handle).ok_or("a node is not loaded")?;
        let world = parent * node.transform.to_matrix();
        if let Some(mesh) = node.mesh.as_ref().and_then(|m| assets.meshes.get(m)) {
            reader.mesh(mesh, &world)?;
        }
        for child in node.children.iter().rev() {
            stack.push((child.clone(), world, depth + 1));
        }
    }
    let soup = reader.soup;
    soup.validate().map_err(|e| e.to_string())?;
    Ok(soup)
}
