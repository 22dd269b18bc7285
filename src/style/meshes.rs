//! Style meshes, all fitting the unit cell (−0.5..0.5) so one voxel scale serves every style.

use bevy::prelude::*;

use crate::instancing::mesh::rounded_box;

/// A Lego brick: a slightly bevelled body and a stud on top, the stud's top at the cell's top.
pub fn brick() -> Mesh {
    let body_top = 0.32;
    let body = rounded_box(0.04, 1).scaled_by(Vec3::new(1.0, body_top + 0.5, 1.0)).translated_by(Vec3::new(
        0.0,
        (body_top - 0.5) / 2.0,
        0.0,
    ));
    let stud_height = 0.5 - body_top;
    let stud = Cylinder::new(0.3, stud_height).mesh().resolution(20).build().translated_by(Vec3::new(
        0.0,
        body_top + stud_height / 2.0,
        0.0,
    ));
    let mut mesh = body;
    // Both meshes carry positions, normals and UVs, so they merge.
    let _ = mesh.merge(&stud);
    mesh
}

/// A bubble: a smooth sphere filling the cell.
pub fn bubble() -> Mesh {
    Sphere::new(0.5).mesh().ico(3).unwrap_or_else(|_| Sphere::new(0.5).mesh().uv(24, 16))
}

#[cfg(test)]
mod tests {
    use super::*;
    use bevy::mesh::VertexAttributeValues;

    fn bounds(mesh: &Mesh) -> (Vec3, Vec3) {
        let Some(VertexAttributeValues::Float32x3(p)) = mesh.attribute(Mesh::ATTRIBUTE_POSITION) else { panic!() };
        p.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), v| (lo.min(Vec3::from(*v)), hi.max(Vec3::from(*v))))
    }

    #[test]
    fn style_meshes_fill_the_unit_cell() {
        for mesh in [brick(), bubble()] {
            let (lo, hi) = bounds(&mesh);
            assert!((lo - Vec3::splat(-0.5)).abs().max_element() < 1e-3, "{lo}");
            assert!((hi - Vec3::splat(0.5)).abs().max_element() < 1e-3, "{hi}");
        }
        // The brick has a stud: vertices above the body inside the stud's radius only.
        let Some(VertexAttributeValues::Float32x3(p)) = brick().attribute(Mesh::ATTRIBUTE_POSITION).cloned() else {
            panic!()
        };
        assert!(p.iter().filter(|v| v[1] > 0.33).all(|v| (v[0] * v[0] + v[2] * v[2]).sqrt() <= 0.3 + 1e-4));
    }
}
