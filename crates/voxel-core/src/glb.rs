//! Writes a [`TriangleSoup`] as a binary glTF (.glb): one mesh, one primitive and material per part,
//! flat normals, COLOR_0 where a part has vertex colours. Textures are not written. [`GlbBuilder`] lays out
//! the buffer, views and accessors of a one-mesh document (this writer's and the tests' scenes); [`pack`] is
//! the one place the core makes the .glb container (the export writes through it too).

use std::borrow::Cow;

use crate::error::{Result, VoxelError};
use crate::soup::TriangleSoup;

/// A glTF document being built over one binary buffer: every array added is a buffer view of its own with an
/// accessor on it. [`GlbBuilder::one_mesh`] makes it a scene of one node showing one mesh.
#[derive(Clone, Debug, Default)]
pub struct GlbBuilder {
    bin: Vec<u8>,
    views: Vec<serde_json::Value>,
    accessors: Vec<serde_json::Value>,
}

impl GlbBuilder {
    /// Appends `bytes` (padded to 4 bytes) as a buffer view and `accessor` on it (its `bufferView` is set
    /// here); returns the accessor's index.
    pub fn accessor(&mut self, bytes: &[u8], mut accessor: serde_json::Value) -> usize {
        self.views.push(serde_json::json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()}));
        self.bin.extend_from_slice(bytes);
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        accessor["bufferView"] = serde_json::json!(self.views.len() - 1);
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// The document of one node showing one mesh of `primitives` with `materials` (and the buffer, its views
    /// and the accessors), written by `generator`; and the buffer. Callers add what else they need (textures,
    /// animations, a buffer URI) before packing it with [`pack_document`] or writing it as .gltf.
    pub fn one_mesh(
        self,
        generator: &str,
        primitives: Vec<serde_json::Value>,
        materials: serde_json::Value,
    ) -> (serde_json::Value, Vec<u8>) {
        let doc = serde_json::json!({
            "asset": {"version": "2.0", "generator": generator},
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": primitives}],
            "materials": materials,
            "buffers": [{"byteLength": self.bin.len()}],
            "bufferViews": self.views,
            "accessors": self.accessors,
        });
        (doc, self.bin)
    }
}

/// Little-endian bytes of `f32`s.
fn f32_bytes(values: impl IntoIterator<Item = f32>) -> Vec<u8> {
    values.into_iter().flat_map(f32::to_le_bytes).collect()
}

/// Encodes `soup` as a .glb file.
pub fn soup_to_glb(soup: &TriangleSoup) -> Result<Vec<u8>> {
    let mut glb = GlbBuilder::default();
    let mut primitives = Vec::new();
    let add_accessor =
        |glb: &mut GlbBuilder, data: Vec<f32>, kind: &str, count: usize, bounds: Option<([f32; 3], [f32; 3])>| {
            let mut accessor = serde_json::json!({"componentType": 5126, "count": count, "type": kind});
            if let Some((lo, hi)) = bounds {
                accessor["min"] = serde_json::json!(lo);
                accessor["max"] = serde_json::json!(hi);
            }
            glb.accessor(&f32_bytes(data), accessor)
        };
    for (p, part) in soup.parts.iter().enumerate() {
        let tris: Vec<usize> = (0..soup.triangle_count()).filter(|&t| soup.triangle_parts[t] as usize == p).collect();
        if tris.is_empty() {
            continue;
        }
        let corners: Vec<_> = tris.iter().flat_map(|&t| soup.triangle(t)).collect();
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for v in &corners {
            for a in 0..3 {
                lo[a] = lo[a].min(v.position[a]);
                hi[a] = hi[a].max(v.position[a]);
            }
        }
        let positions = corners.iter().flat_map(|v| v.position).collect();
        let normals = tris
            .iter()
            .flat_map(|&t| {
                let c = soup.triangle(t);
                let e1 = glam::Vec3::from(c[1].position) - glam::Vec3::from(c[0].position);
                let e2 = glam::Vec3::from(c[2].position) - glam::Vec3::from(c[0].position);
                let n = e1.cross(e2).normalize_or(glam::Vec3::Y).to_array();
                [n, n, n].into_iter().flatten()
            })
            .collect();
        let mut attributes = serde_json::json!({
            "POSITION": add_accessor(&mut glb, positions, "VEC3", corners.len(), Some((lo, hi))),
            "NORMAL": add_accessor(&mut glb, normals, "VEC3", corners.len(), None),
        });
        if corners.iter().any(|v| v.color != [1.0; 4]) {
            let colors = corners.iter().flat_map(|v| v.color).collect();
            attributes["COLOR_0"] = serde_json::json!(add_accessor(&mut glb, colors, "VEC4", corners.len(), None));
        }
        primitives.push(serde_json::json!({"attributes": attributes, "material": part.material}));
    }
    let materials: Vec<_> = soup
        .materials
        .iter()
        .map(|m| serde_json::json!({"pbrMetallicRoughness": {"baseColorFactor": m.base_color, "metallicFactor": 0.0, "roughnessFactor": 0.8}}))
        .collect();
    let (doc, bin) = glb.one_mesh("voxel-core glb writer", primitives, serde_json::json!(materials));
    pack_document(&doc, &bin)
}

/// Packs a glTF document and its binary buffer into a .glb.
pub fn pack_document(doc: &serde_json::Value, bin: &[u8]) -> Result<Vec<u8>> {
    pack(&serde_json::to_vec(doc).map_err(encode_error)?, bin)
}

/// Packs glTF JSON and its binary buffer into the .glb container with the gltf crate's writer (the JSON
/// chunk padded with spaces, the BIN chunk, left out when empty, with zeros). A container over 4 GiB, which
/// the format's 32-bit lengths cannot describe, is an error.
pub fn pack(json: &[u8], bin: &[u8]) -> Result<Vec<u8>> {
    let chunk = |bytes: &[u8]| 8 + bytes.len().next_multiple_of(4);
    let length = 12 + chunk(json) + if bin.is_empty() { 0 } else { chunk(bin) };
    // The writer computes the header's length itself (and would truncate it to 32 bits): only checked here.
    let length = u32::try_from(length).map_err(|_| encode_error("over 4 GiB, the .glb limit"))?;
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header { magic: *b"glTF", version: 2, length },
        json: Cow::Borrowed(json),
        bin: (!bin.is_empty()).then_some(Cow::Borrowed(bin)),
    };
    glb.to_vec().map_err(encode_error)
}

/// The error of a glTF that cannot be encoded.
pub(crate) fn encode_error(reason: impl std::fmt::Display) -> VoxelError {
    VoxelError::Parameter(format!("cannot encode the glTF: {reason}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::{cuboid, uv_sphere};

    #[test]
    fn written_files_import_back_with_parts_materials_and_vertex_colors() {
        let mut soup = TriangleSoup::default();
        soup.add_mesh(&cuboid([0.0; 3], [1.0; 3]), [1.0, 0.0, 0.0, 1.0], "box");
        let sphere = soup.add_mesh(&uv_sphere(0.5, 6), [0.0, 1.0, 0.0, 1.0], "ball");
        let triangles = soup.triangles().to_vec();
        let in_sphere = (0..soup.triangle_count()).filter(|&t| soup.triangle_parts[t] == sphere).collect::<Vec<_>>();
        for t in in_sphere {
            for i in triangles[t] {
                soup.colors_mut()[i as usize] = [0.5, 0.5, 1.0, 1.0];
            }
        }
        let back = crate::import::load_slice(&soup_to_glb(&soup).unwrap(), None).unwrap();
        assert_eq!(back.triangle_count(), soup.triangle_count());
        assert_eq!(back.materials.len(), 2);
        assert_eq!(back.materials[0].base_color, [1.0, 0.0, 0.0, 1.0]);
        assert!(back.corners().eq(soup.corners()));
    }

    #[test]
    fn the_container_pads_both_chunks_and_leaves_out_an_empty_bin() {
        let json = br#"{"asset":{"version":"2.0"}}"#;
        let packed = pack(json, &[1, 2, 3]).unwrap();
        // Header, JSON chunk (27 bytes padded to 28), BIN chunk (3 padded to 4).
        assert_eq!(packed.len(), 12 + 8 + 28 + 8 + 4);
        assert_eq!(packed[8..12], (packed.len() as u32).to_le_bytes());
        let glb = gltf::binary::Glb::from_slice(&packed).unwrap();
        assert_eq!(*glb.json, [&json[..], b" "].concat());
        assert_eq!(glb.bin.as_deref(), Some(&[1, 2, 3, 0][..]));
        let without_bin = pack(b"{}", &[]).unwrap();
        assert_eq!(without_bin.len(), 12 + 8 + 4);
        assert!(gltf::binary::Glb::from_slice(&without_bin).unwrap().bin.is_none());
    }
}
