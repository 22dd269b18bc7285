//! A tile for a file Bevy's glTF loader refuses but the core reads (bevy_gltf does not decode
//! EXT_texture_webp): the core's triangles as one flat-shaded mesh in their vertex colours times their
//! materials' base colours, without textures.

use bevy::asset::RenderAssetUsages;
use bevy::mesh::PrimitiveTopology;
use bevy::prelude::*;
use voxel_core::TriangleSoup;

/// The soup's triangles, flat-shaded, each corner in its linear vertex colour times its material's base colour.
pub(super) fn mesh(soup: &TriangleSoup) -> Mesh {
    let corners = soup.triangle_count() * 3;
    let (mut positions, mut colors) = (Vec::with_capacity(corners), Vec::with_capacity(corners));
    for t in 0..soup.triangle_count() {
        let base = soup.material_of(t).base_color;
        for corner in soup.triangle(t) {
            positions.push(corner.position);
            colors.push(std::array::from_fn::<f32, 4, _>(|k| corner.color[k] * base[k]));
        }
    }
    Mesh::new(PrimitiveTopology::TriangleList, RenderAssetUsages::default())
        .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions)
        .with_inserted_attribute(Mesh::ATTRIBUTE_COLOR, colors)
        .with_computed_flat_normals()
}

/// White (the vertex colours carry the colour), seen from both sides (models are not always closed).
pub(super) fn material() -> StandardMaterial {
    StandardMaterial { base_color: Color::WHITE, double_sided: true, cull_mode: None, ..default() }
}
