//! glTF 2.0 export (.glb, or .gltf + .bin) of a voxel model's surface: one mesh of the greedy rectangles
//! with POSITION, NORMAL, linear COLOR_0 and indices, a plain white material, and one node whose transform
//! undoes the normalization, so the export sits where the original model sat, at its scale.

use std::collections::BTreeMap;
use std::path::Path;

use gltf::json::{self, validation::Checked::Valid, validation::USize64};

use super::mesh::{SurfaceVertices, surface};
use crate::error::{Result, VoxelError};
use crate::grid::GridSpec;
use crate::model::VoxelModel;

/// What a glTF export is named inside the file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ExportOptions {
    /// The name of the mesh and its node (e.g. the source model's file stem).
    pub name: String,
}

impl Default for ExportOptions {
    fn default() -> Self {
        Self { name: "voxels".into() }
    }
}

/// What a glTF export holds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct MeshStats {
    /// Cell faces between a filled and an empty cell: `2 × faces` triangles without merging.
    pub faces: usize,
    /// Rectangles after greedy merging: `2 × quads` triangles.
    pub quads: usize,
    /// Vertices (four per rectangle).
    pub vertices: usize,
    /// Bytes written (.gltf: the JSON and the .bin together).
    pub bytes: usize,
}

/// The glTF document and its binary buffer (not yet given a URI or packed).
struct Document {
    root: json::Root,
    bin: Vec<u8>,
    stats: MeshStats,
}

/// Accumulates a glTF document: its binary buffer, views, accessors, meshes and their shared material.
pub(super) struct Builder {
    pub root: json::Root,
    pub bin: Vec<u8>,
    /// The plain material every mesh uses, once the first mesh is added.
    material: Option<json::Index<json::Material>>,
}

impl Builder {
    /// An empty document naming voxel-art as its generator.
    pub fn new() -> Self {
        let asset = json::Asset {
            generator: Some(format!("voxel-art {}", env!("CARGO_PKG_VERSION"))),
            version: "2.0".into(),
            ..Default::default()
        };
        Self { root: json::Root { asset, ..Default::default() }, bin: Vec::new(), material: None }
    }

    /// Makes the bytes appended to the buffer since `offset` a buffer view (padded to 4 bytes) and an
    /// accessor over it, with `bounds` as its min and max.
    fn accessor(
        &mut self,
        offset: usize,
        count: usize,
        component: json::accessor::ComponentType,
        kind: json::accessor::Type,
        target: Option<json::buffer::Target>,
        bounds: Option<(json::Value, json::Value)>,
    ) -> json::Index<json::Accessor> {
        let length = self.bin.len() - offset;
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        let view = self.root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64::from(length),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            extensions: None,
            extras: Default::default(),
            name: None,
            target: target.map(Valid),
        });
        let (min, max) = bounds.unzip();
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(count),
            component_type: Valid(json::accessor::GenericComponentType(component)),
            extensions: None,
            extras: Default::default(),
            type_: Valid(kind),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    /// Appends VEC3 floats (vertex attributes when `target`, else animation data), with their bounds if
    /// asked.
    pub fn vec3s(&mut self, values: &[[f32; 3]], bounds: bool, target: bool) -> json::Index<json::Accessor> {
        let offset = self.bin.len();
        self.bin.reserve(values.len() * 12);
        for v in values.iter().flatten() {
            self.bin.extend_from_slice(&v.to_le_bytes());
        }
        let bounds = bounds.then(|| {
            let (lo, hi) = values.iter().fold(([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]), |(lo, hi), p| {
                (std::array::from_fn(|a| lo[a].min(p[a])), std::array::from_fn(|a| hi[a].max(p[a])))
            });
            (json::Value::from(lo.to_vec()), json::Value::from(hi.to_vec()))
        });
        let target = target.then_some(json::buffer::Target::ArrayBuffer);
        self.accessor(
            offset,
            values.len(),
            json::accessor::ComponentType::F32,
            json::accessor::Type::Vec3,
            target,
            bounds,
        )
    }

    /// Appends scalar floats (animation times: with their min and max, as glTF requires of sampler inputs).
    pub fn scalars(&mut self, values: &[f32]) -> json::Index<json::Accessor> {
        let offset = self.bin.len();
        for v in values {
            self.bin.extend_from_slice(&v.to_le_bytes());
        }
        let lo = values.iter().copied().fold(f32::INFINITY, f32::min);
        let hi = values.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        let bounds = Some((json::Value::from(vec![lo]), json::Value::from(vec![hi])));
        self.accessor(
            offset,
            values.len(),
            json::accessor::ComponentType::F32,
            json::accessor::Type::Scalar,
            None,
            bounds,
        )
    }

    /// Appends triangle indices, as u16 when every index fits below u16's maximum (which glTF reserves).
    fn indices(&mut self, indices: &[u32], vertex_count: usize) -> json::Index<json::Accessor> {
        let narrow = vertex_count < usize::from(u16::MAX);
        let offset = self.bin.len();
        self.bin.reserve(indices.len() * if narrow { 2 } else { 4 });
        for &i in indices {
            if narrow {
                self.bin.extend_from_slice(&(i as u16).to_le_bytes());
            } else {
                self.bin.extend_from_slice(&i.to_le_bytes());
            }
        }
        let component = if narrow { json::accessor::ComponentType::U16 } else { json::accessor::ComponentType::U32 };
        let (scalar, element) = (json::accessor::Type::Scalar, json::buffer::Target::ElementArrayBuffer);
        self.accessor(offset, indices.len(), component, scalar, Some(element), None)
    }

    /// The plain material of every mesh, added on first use.
    fn material(&mut self) -> json::Index<json::Material> {
        if let Some(material) = self.material {
            return material;
        }
        let material = self.root.push(json::Material {
            name: Some("voxel".into()),
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor([1.0; 4]),
                metallic_factor: json::material::StrengthFactor(0.0),
                roughness_factor: json::material::StrengthFactor(0.8),
                ..Default::default()
            },
            ..Default::default()
        });
        self.material = Some(material);
        material
    }

    /// Adds the mesh of `model`'s surface (greedy rectangles) named `name`, or nothing when it has no face;
    /// with what it holds (`bytes` 0).
    pub fn mesh(&mut self, model: &VoxelModel, name: &str) -> (Option<json::Index<json::Mesh>>, MeshStats) {
        let surface = surface(model);
        let vertices = SurfaceVertices::of(model, &surface);
        let mesh = (!surface.quads.is_empty()).then(|| {
            let attributes = BTreeMap::from([
                (Valid(json::mesh::Semantic::Positions), self.vec3s(&vertices.positions, true, true)),
                (Valid(json::mesh::Semantic::Normals), self.vec3s(&vertices.normals, false, true)),
                (Valid(json::mesh::Semantic::Colors(0)), self.vec3s(&vertices.colors, false, true)),
            ]);
            let indices = self.indices(&vertices.indices, vertices.positions.len());
            let material = self.material();
            self.root.push(json::Mesh {
                extensions: None,
                extras: Default::default(),
                name: Some(name.into()),
                primitives: vec![json::mesh::Primitive {
                    attributes,
                    extensions: None,
                    extras: Default::default(),
                    indices: Some(indices),
                    material: Some(material),
                    mode: Valid(json::mesh::Mode::Triangles),
                    targets: None,
                }],
                weights: None,
            })
        });
        let stats = MeshStats {
            faces: surface.faces,
            quads: surface.quads.len(),
            vertices: vertices.positions.len(),
            bytes: 0,
        };
        (mesh, stats)
    }

    /// The node that maps the normalized space of `spec`'s grid back to the original's world space ((world −
    /// centre) · scale is normalized), with `mesh` or `children`.
    pub fn placed_node(
        &mut self,
        spec: &GridSpec,
        name: &str,
        mesh: Option<json::Index<json::Mesh>>,
        children: Option<Vec<json::Index<json::Node>>>,
    ) -> json::Index<json::Node> {
        self.root.push(json::Node {
            name: Some(name.into()),
            mesh,
            children,
            translation: Some(spec.center),
            scale: Some([1.0 / spec.scale; 3]),
            ..Default::default()
        })
    }

    /// Declares the buffer (when anything was written to it) and the one scene of `node`.
    pub fn finish(mut self, node: json::Index<json::Node>) -> (json::Root, Vec<u8>) {
        if !self.bin.is_empty() {
            self.root.push(json::Buffer {
                byte_length: USize64::from(self.bin.len()),
                extensions: None,
                extras: Default::default(),
                name: None,
                uri: None,
            });
        }
        let scene =
            self.root.push(json::Scene { extensions: None, extras: Default::default(), name: None, nodes: vec![node] });
        self.root.scene = Some(scene);
        (self.root, self.bin)
    }
}

/// The glTF document of `model`'s surface.
fn document(model: &VoxelModel, options: &ExportOptions) -> Document {
    let mut b = Builder::new();
    let (mesh, stats) = b.mesh(model, &options.name);
    let node = b.placed_node(&model.spec, &options.name, mesh, None);
    let (root, bin) = b.finish(node);
    Document { root, bin, stats }
}

/// Encodes `model` as a binary glTF (.glb) in memory, with what it holds.
pub fn to_glb(model: &VoxelModel, options: &ExportOptions) -> Result<(Vec<u8>, MeshStats)> {
    let Document { root, bin, stats } = document(model, options);
    pack(&root, &bin, stats)
}

/// A document and its buffer packed as .glb bytes, with `stats.bytes` set.
fn pack(root: &json::Root, bin: &[u8], mut stats: MeshStats) -> Result<(Vec<u8>, MeshStats)> {
    let json = root.to_vec().map_err(crate::glb::encode_error)?;
    let bytes = crate::glb::pack(&json, bin)?;
    stats.bytes = bytes.len();
    Ok((bytes, stats))
}

/// Writes `model` as a binary glTF file.
pub fn write_glb(model: &VoxelModel, path: &Path, options: &ExportOptions) -> Result<MeshStats> {
    let Document { root, bin, stats } = document(model, options);
    write_glb_document(&root, &bin, stats, path)
}

/// Writes a document and its buffer as a .glb file; `bytes` in the result is the file's size.
pub(super) fn write_glb_document(root: &json::Root, bin: &[u8], stats: MeshStats, path: &Path) -> Result<MeshStats> {
    let (bytes, stats) = pack(root, bin, stats)?;
    std::fs::write(path, bytes).map_err(|e| VoxelError::Export { path: path.to_owned(), reason: e.to_string() })?;
    Ok(stats)
}

/// Writes `model` as a .gltf JSON file and, beside it, a .bin of the same stem that the JSON refers to.
/// `bytes` in the result counts both files.
pub fn write_gltf(model: &VoxelModel, path: &Path, options: &ExportOptions) -> Result<MeshStats> {
    let Document { root, bin, stats } = document(model, options);
    write_document(root, bin, stats, path)
}

/// Writes a document as a .gltf file and its buffer as a .bin beside it; `bytes` in the result counts both.
pub(super) fn write_document(
    mut root: json::Root,
    bin: Vec<u8>,
    mut stats: MeshStats,
    path: &Path,
) -> Result<MeshStats> {
    let bin_path = path.with_extension("bin");
    let export_error = |path: &Path, reason: String| VoxelError::Export { path: path.to_owned(), reason };
    if let Some(buffer) = root.buffers.first_mut() {
        let name = bin_path.file_name().ok_or_else(|| export_error(path, "not a file name".into()))?;
        buffer.uri = Some(uri_escape(&name.to_string_lossy()));
        std::fs::write(&bin_path, &bin).map_err(|e| export_error(&bin_path, e.to_string()))?;
    }
    let json = root.to_vec_pretty().map_err(|e| export_error(path, e.to_string()))?;
    std::fs::write(path, &json).map_err(|e| export_error(path, e.to_string()))?;
    stats.bytes = json.len() + bin.len();
    Ok(stats)
}

/// A file name as a relative URI reference: characters outside RFC 3986's unreserved set percent-encoded.
fn uri_escape(name: &str) -> String {
    name.bytes()
        .map(|b| match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'.' | b'_' | b'~' => char::from(b).to_string(),
            _ => format!("%{b:02X}"),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::mesh::tests::model_of;
    use crate::srgb::srgb_to_linear;

    /// The bottom layer of [`model_of`]`(k)`'s grid, 8k × 8k cells, in a checkerboard of two colours (nothing
    /// merges on its faces).
    fn checkerboard(k: u16) -> VoxelModel {
        let n = 8 * k;
        let cells =
            (0..n).flat_map(|x| (0..n).map(move |z| ([x, 0, z], if (x + z) % 2 == 0 { [255, 0, 0] } else { [0; 3] })));
        model_of(k, cells)
    }

    /// Reads a VEC3 float accessor back.
    fn read_vec3s(gltf: &gltf::Gltf, accessor: &gltf::Accessor<'_>) -> Vec<[f32; 3]> {
        let bin = gltf.blob.as_deref().unwrap();
        let view = accessor.view().unwrap();
        let bytes = &bin[view.offset()..view.offset() + view.length()];
        bytes
            .chunks_exact(12)
            .map(|c| std::array::from_fn(|k| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap())))
            .collect()
    }

    #[test]
    fn the_glb_passes_validation_with_exact_bounds_colors_and_the_inverse_normalization() {
        let m = model_of(1, [([0, 0, 0], [255, 128, 0]), ([3, 1, 2], [0, 0, 0]), ([1, 0, 0], [255, 128, 0])]);
        let (bytes, stats) = to_glb(&m, &ExportOptions { name: "thing".into() }).unwrap();
        assert_eq!(stats, MeshStats { faces: 16, quads: 12, vertices: 48, bytes: bytes.len() });
        let gltf = gltf::Gltf::from_slice(&bytes).expect("a valid glTF");
        let mesh = gltf.meshes().next().unwrap();
        assert_eq!(mesh.name(), Some("thing"));
        let prim = mesh.primitives().next().unwrap();
        let position = prim.get(&gltf::Semantic::Positions).unwrap();
        let positions = read_vec3s(&gltf, &position);
        assert_eq!(positions.len(), 48);
        let bound = |f: fn(f32, f32) -> f32| -> [f32; 3] {
            std::array::from_fn(|a| positions.iter().map(|p| p[a]).reduce(f).unwrap())
        };
        // Cells are 0.5 wide from the origin (-2, -1, -2): the model spans cells (0..4, 0..2, 0..3).
        assert_eq!(bound(f32::min), [-2.0, -1.0, -2.0]);
        assert_eq!(bound(f32::max), [0.0, 0.0, -0.5]);
        assert_eq!(position.min().unwrap(), serde_json::json!([-2.0, -1.0, -2.0]));
        assert_eq!(position.max().unwrap(), serde_json::json!([0.0, 0.0, -0.5]));
        let colors = read_vec3s(&gltf, &prim.get(&gltf::Semantic::Colors(0)).expect("COLOR_0"));
        let orange = [1.0, srgb_to_linear(128), 0.0];
        assert_eq!(colors.iter().filter(|&&c| c == orange).count(), 6 * 4, "two orange cells merge into 6 rectangles");
        assert_eq!(colors.iter().filter(|&&c| c == [0.0; 3]).count(), 6 * 4);
        let normals = read_vec3s(&gltf, &prim.get(&gltf::Semantic::Normals).unwrap());
        assert!(normals.iter().all(|n| n.iter().map(|c| c.abs()).sum::<f32>() == 1.0));
        let indices = prim.indices().unwrap();
        assert_eq!((indices.data_type(), indices.count()), (gltf::accessor::DataType::U16, 72));
        let pbr = prim.material().pbr_metallic_roughness();
        assert_eq!((pbr.base_color_factor(), pbr.metallic_factor(), pbr.roughness_factor()), ([1.0; 4], 0.0, 0.8));
        let node = gltf.default_scene().unwrap().nodes().next().unwrap();
        let (translation, _, scale) = node.transform().decomposed();
        assert_eq!((translation, scale), ([10.0, 0.0, -4.0], [0.5; 3]));
    }

    #[test]
    fn many_vertices_take_u32_indices_and_import_back_where_the_original_sat() {
        let m = checkerboard(17);
        let (bytes, stats) = to_glb(&m, &ExportOptions::default()).unwrap();
        // Top and bottom never merge; the sides of each row of 136 alternate colours too.
        assert_eq!(stats.quads, 2 * 136 * 136 + 4 * 136);
        let gltf = gltf::Gltf::from_slice(&bytes).unwrap();
        let prim = gltf.meshes().next().unwrap().primitives().next().unwrap();
        assert_eq!(prim.indices().unwrap().data_type(), gltf::accessor::DataType::U32);
        let soup = crate::import::load_slice(&bytes, None).unwrap();
        assert_eq!(soup.triangle_count(), 2 * stats.quads);
        // World = normalized / 2 + (10, 0, -4): the plate's 136 cells span ±34 normalized, ±17 in the world;
        // its layer is the grid's bottom, -17 to -16.5 normalized.
        let (lo, hi) = soup.bounds().unwrap();
        assert_eq!((lo, hi), ([10.0 - 17.0, -8.5, -4.0 - 17.0], [10.0 + 17.0, -8.25, -4.0 + 17.0]));
    }

    #[test]
    fn gltf_and_bin_files_hold_the_same_mesh_as_the_glb() {
        let m = checkerboard(1);
        let dir = std::env::temp_dir().join(format!("voxel-core-gltf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a plate.gltf");
        let stats = write_gltf(&m, &path, &ExportOptions::default()).unwrap();
        let bin = std::fs::metadata(dir.join("a plate.bin")).unwrap().len() as usize;
        let json = std::fs::read_to_string(&path).unwrap();
        assert!(json.contains("\"uri\": \"a%20plate.bin\""), "{json}");
        assert_eq!(stats.bytes, json.len() + bin);
        let from_files = crate::import::load_file(&path).unwrap();
        let from_glb = crate::import::load_slice(&to_glb(&m, &ExportOptions::default()).unwrap().0, None).unwrap();
        assert!(from_files.corners().eq(from_glb.corners()));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_empty_model_is_a_valid_file_with_no_mesh() {
        let (bytes, stats) = to_glb(&model_of(1, []), &ExportOptions::default()).unwrap();
        assert_eq!((stats.faces, stats.quads), (0, 0));
        let gltf = gltf::Gltf::from_slice(&bytes).unwrap();
        assert_eq!((gltf.meshes().count(), gltf.nodes().count(), gltf.buffers().count()), (0, 1, 0));
    }
}
