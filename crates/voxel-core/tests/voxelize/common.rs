//! Shared helpers: model paths resolved at run time, hand-built GLB files.

use std::collections::HashSet;
use std::path::PathBuf;

#[path = "../support/models.rs"]
mod models;
pub use models::models_dir;

use voxel_core::shapes::IndexedMesh;

use voxel_core::{GridSize, VoxelModel, VoxelizeOptions};

/// A model of the corpus by relative path, or `None` when the corpus is absent.
pub fn model(relative: &str) -> Option<PathBuf> {
    models_dir().map(|d| d.join(relative))
}

/// Options at resolution `r`, defaults otherwise.
pub fn at_resolution(r: u32) -> VoxelizeOptions {
    VoxelizeOptions { grid: GridSize::Resolution(r), ..Default::default() }
}

/// The set of filled cells of a model.
pub fn cells(model: &VoxelModel) -> HashSet<[u16; 3]> {
    model.voxels().map(|v| v.cell).collect()
}

/// Volume of the model in cells of the fitted grid, relative to an analytic volume in world units.
pub fn relative_volume(model: &VoxelModel, world_volume: f64) -> f64 {
    let cell = f64::from(model.spec.cell[0]) * f64::from(model.spec.cell[1]) * f64::from(model.spec.cell[2]);
    let scale = f64::from(model.spec.scale);
    model.len() as f64 * cell / (world_volume * scale.powi(3))
}

/// Rotates a mesh about x by `angle` and then about z by 0.6·`angle`.
pub fn tilted(mut mesh: IndexedMesh, angle: f32) -> IndexedMesh {
    let (s, c) = angle.sin_cos();
    let (s2, c2) = (0.6 * angle).sin_cos();
    for p in &mut mesh.positions {
        let [x, y, z] = *p;
        let (y, z) = (c * y - s * z, s * y + c * z);
        *p = [c2 * x - s2 * y, s2 * x + c2 * y, z];
    }
    mesh
}

/// Packs a JSON document and a binary chunk into a .glb.
pub fn glb(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    voxel_core::glb::pack_document(json, bin).unwrap()
}

/// A unit cube (8 positions, 36 u16 indices) as little-endian bytes, positions first.
pub fn cube_buffer() -> (Vec<u8>, usize, usize) {
    cuboid_buffer([0.0; 3], [1.0; 3])
}

/// The box from `lo` to `hi` (8 positions, 36 u16 indices) as little-endian bytes, positions first, with the
/// byte length of the positions and the index count.
pub fn cuboid_buffer(lo: [f32; 3], hi: [f32; 3]) -> (Vec<u8>, usize, usize) {
    let mesh = voxel_core::shapes::cuboid(lo, hi);
    let mut bin = Vec::new();
    for p in &mesh.positions {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    let positions_len = bin.len();
    for t in &mesh.triangles {
        for &i in t {
            bin.extend_from_slice(&(i as u16).to_le_bytes());
        }
    }
    (bin, positions_len, mesh.triangles.len() * 3)
}

/// A glTF document of one cube mesh on one node; tests mutate it to make it hostile.
pub fn cube_document(bin_len: usize, positions_len: usize, index_count: usize) -> serde_json::Value {
    serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.2, 0.2, 1.0]}}],
        "buffers": [{"byteLength": bin_len}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": positions_len},
            {"buffer": 0, "byteOffset": positions_len, "byteLength": index_count * 2}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3", "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]},
            {"bufferView": 1, "componentType": 5123, "count": index_count, "type": "SCALAR"}
        ]
    })
}
