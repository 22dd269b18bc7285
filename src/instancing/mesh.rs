//! Voxel meshes: a rounded box like three.js `RoundedBoxGeometry` (size 1, corner radius, segments), and the
//! chunk mesh that repeats a voxel's shape for the instanced draw.

use bevy::asset::RenderAssetUsages;
use bevy::mesh::{Indices, PrimitiveTopology, VertexAttributeValues};
use bevy::prelude::*;

use super::VOXELS_PER_CHUNK;

/// A unit box (edge 1, centred) whose edges and corners are rounded with `radius` (0..=0.5), each rounding
/// made of `segments` steps. Every face is a grid whose outer rows bend onto the rounding; positions are
/// the inner box clamped point pushed out by `radius` along the offset, as RoundedBoxGeometry does.
pub fn rounded_box(radius: f32, segments: u32) -> Mesh {
    let radius = radius.clamp(0.0, 0.5);
    let segments = segments.max(1);
    let half = 0.5f32;
    let inner = half - radius;
    // Coordinates along one face axis: the rounding zone, the flat middle, the rounding zone.
    let mut ticks: Vec<f32> = (0..=segments).map(|i| -half + radius * i as f32 / segments as f32).collect();
    ticks.extend((0..=segments).map(|i| inner + radius * i as f32 / segments as f32));
    ticks.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
    let n = ticks.len();
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    let mut indices = Vec::new();
    let faces = [
        (Vec3::X, Vec3::NEG_Z, Vec3::Y),
        (Vec3::NEG_X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::X, Vec3::NEG_Z),
        (Vec3::NEG_Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::NEG_X, Vec3::Y),
    ];
    for (normal, u_axis, v_axis) in faces {
        let base = positions.len() as u32;
        for (j, &v) in ticks.iter().enumerate() {
            for (i, &u) in ticks.iter().enumerate() {
                let flat = normal * half + u_axis * u + v_axis * v;
                let core = flat.clamp(Vec3::splat(-inner), Vec3::splat(inner));
                let offset = flat - core;
                let dir = if offset.length_squared() > 1e-12 { offset.normalize() } else { normal };
                positions.push((core + dir * radius).to_array());
                normals.push(dir.to_array());
                uvs.push([i as f32 / (n - 1) as f32, j as f32 / (n - 1) as f32]);
            }
        }
        for j in 0..n as u32 - 1 {
            for i in 0..n as u32 - 1 {
                let a = base + j * n as u32 + i;
                let (b, c, d) = (a + 1, a + n as u32 + 1, a + n as u32);
                indices.extend_from_slice(&[a, b, c, a, c, d]);
            }
        }
    }
    Mesh::new(PrimitiveTopology::TriangleList, RenderAssetUsages::default())
        .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions)
        .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, normals)
        .with_inserted_attribute(Mesh::ATTRIBUTE_UV_0, uvs)
        .with_inserted_indices(Indices::U32(indices))
}

/// The low detail voxel: the +x, +y and +z faces of the unit box (4 vertices each, in that order: 6 triangles).
/// The vertex shader turns each face to the side of the box that faces the viewer, so three faces draw the box
/// as the viewer (the camera, or the light for its shadow map) sees it. Normals are the faces' own, or with
/// `radial` point out from the centre (shaded like a sphere, for bubbles).
pub fn facing_box(radial: bool) -> Mesh {
    let faces = [
        [[0.5, -0.5, -0.5], [0.5, 0.5, -0.5], [0.5, 0.5, 0.5], [0.5, -0.5, 0.5]],
        [[-0.5, 0.5, -0.5], [-0.5, 0.5, 0.5], [0.5, 0.5, 0.5], [0.5, 0.5, -0.5]],
        [[-0.5, -0.5, 0.5], [0.5, -0.5, 0.5], [0.5, 0.5, 0.5], [-0.5, 0.5, 0.5]],
    ];
    let positions: Vec<[f32; 3]> = faces.iter().flatten().copied().collect();
    let normals: Vec<[f32; 3]> = positions
        .iter()
        .enumerate()
        .map(|(i, p)| if radial { Vec3::from(*p).normalize().to_array() } else { Vec3::AXES[i / 4].to_array() })
        .collect();
    let indices = (0..3u32).flat_map(|f| [0, 1, 2, 0, 2, 3].map(|i| 4 * f + i)).collect();
    Mesh::new(PrimitiveTopology::TriangleList, RenderAssetUsages::default())
        .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions)
        .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, normals)
        .with_inserted_indices(Indices::U32(indices))
}

/// The mesh of a chunk: [`VOXELS_PER_CHUNK`] copies of `voxel`.
pub fn chunk_mesh(voxel: &Mesh) -> Mesh {
    copies_of(voxel, VOXELS_PER_CHUNK as u32)
}

/// `copies` copies of `voxel`'s positions and normals, one after another (copy k's vertices are
/// `k × vertices .. (k + 1) × vertices`: the vertex shader finds its voxel from the vertex index), all at the
/// origin: the vertex shader places each at its voxel.
pub fn copies_of(voxel: &Mesh, copies: u32) -> Mesh {
    let attribute = |id| match voxel.attribute(id) {
        Some(VertexAttributeValues::Float32x3(values)) => values.clone(),
        _ => Vec::new(),
    };
    let (positions, normals) = (attribute(Mesh::ATTRIBUTE_POSITION), attribute(Mesh::ATTRIBUTE_NORMAL));
    let indices: Vec<u32> =
        voxel.indices().map_or_else(|| (0..positions.len() as u32).collect(), |i| i.iter().map(|i| i as u32).collect());
    let vertices = positions.len() as u32;
    let copies_of = |values: &[[f32; 3]]| values.repeat(copies as usize);
    let all_indices = (0..copies).flat_map(|k| indices.iter().map(move |i| i + k * vertices)).collect();
    Mesh::new(PrimitiveTopology::TriangleList, RenderAssetUsages::default())
        .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, copies_of(&positions))
        .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, copies_of(&normals))
        .with_inserted_indices(Indices::U32(all_indices))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn positions(mesh: &Mesh) -> Vec<Vec3> {
        match mesh.attribute(Mesh::ATTRIBUTE_POSITION) {
            Some(VertexAttributeValues::Float32x3(p)) => p.iter().map(|p| Vec3::from(*p)).collect(),
            _ => panic!("no positions"),
        }
    }

    #[test]
    fn the_box_fits_the_unit_cube_and_corners_are_rounded() {
        let mesh = rounded_box(0.15, 3);
        let p = positions(&mesh);
        assert!(p.iter().all(|v| v.abs().max_element() <= 0.5 + 1e-5));
        // The flat part of each face reaches the cube (its corners sit at ±(0.5 − radius)); only there.
        let flat: Vec<_> = p.iter().filter(|v| (v.x - 0.5).abs() < 1e-5).collect();
        assert!(flat.iter().any(|v| (v.y - 0.35).abs() < 1e-5 && (v.z - 0.35).abs() < 1e-5));
        assert!(flat.iter().all(|v| v.y.abs() <= 0.35 + 1e-5 && v.z.abs() <= 0.35 + 1e-5));
        let corner = p.iter().map(|v| v.length()).fold(0.0f32, f32::max);
        let expected = (Vec3::splat(0.35).length()) + 0.15;
        assert!((corner - expected).abs() < 1e-4, "{corner} vs {expected}");
    }

    #[test]
    fn a_chunk_repeats_the_voxel_one_copy_after_another() {
        let voxel = rounded_box(0.15, 2);
        let chunk = copies_of(&voxel, 3);
        let n = voxel.count_vertices();
        assert_eq!(chunk.count_vertices(), 3 * n);
        assert_eq!(positions(&chunk)[2 * n + 5], positions(&voxel)[5]);
        let (one, all) = (voxel.indices().unwrap().len(), chunk.indices().unwrap());
        assert_eq!(all.len(), 3 * one);
        // Copy k's triangles use copy k's vertices only.
        let third: Vec<usize> = all.iter().skip(2 * one).collect();
        assert!(third.iter().all(|i| (2 * n..3 * n).contains(i)));
        assert!(chunk.attribute(Mesh::ATTRIBUTE_UV_0).is_none(), "the chunk carries only what the shaders read");
    }

    #[test]
    fn the_facing_box_has_three_outward_faces() {
        let mesh = facing_box(false);
        let p = positions(&mesh);
        let Some(VertexAttributeValues::Float32x3(n)) = mesh.attribute(Mesh::ATTRIBUTE_NORMAL) else { panic!() };
        let indices: Vec<usize> = mesh.indices().unwrap().iter().collect();
        assert_eq!((p.len(), indices.len()), (12, 18));
        for t in indices.chunks(3) {
            let (a, b, c) = (p[t[0]], p[t[1]], p[t[2]]);
            // Counter-clockwise seen from outside: the winding's normal is the face's, on the face's side.
            let face = (b - a).cross(c - a).normalize();
            assert_eq!(face, Vec3::from(n[t[0]]), "{t:?}");
            assert!((a.dot(face) - 0.5).abs() < 1e-6);
        }
        // Face k is the vertices 4k..4k + 4 (the shader finds a vertex's face that way).
        assert!((0..12).all(|i| Vec3::from(n[i]) == Vec3::AXES[i / 4]));
    }

    #[test]
    fn a_zero_radius_gives_a_plain_cube() {
        let p = positions(&rounded_box(0.0, 2));
        assert!(p.iter().all(|v| (v.abs().max_element() - 0.5).abs() < 1e-6));
    }
}
