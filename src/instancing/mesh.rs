//! Voxel meshes: a rounded box like three.js `RoundedBoxGeometry` (size 1, corner radius, segments).

use bevy::asset::RenderAssetUsages;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::*;

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

#[cfg(test)]
mod tests {
    use super::*;
    use bevy::mesh::VertexAttributeValues;

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
    fn a_zero_radius_gives_a_plain_cube() {
        let p = positions(&rounded_box(0.0, 2));
        assert!(p.iter().all(|v| (v.abs().max_element() - 0.5).abs() < 1e-6));
    }
}
