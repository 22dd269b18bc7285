//! A voxel model's surface as a Bevy mesh: the core's greedy rectangles with their colours, for the preview
//! tile of a file too big to show through Bevy's glTF loader (built on a worker, kept only in the render world).

use bevy::asset::RenderAssetUsages;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::*;
use voxel_core::VoxelModel;
use voxel_core::export::mesh::{SurfaceVertices, surface};

/// The surface of `model` in normalized model space, with linear vertex colours. Its data lives only in the
/// render world once uploaded: the main world never copies it.
pub fn surface_mesh(model: &VoxelModel) -> Mesh {
    let vertices = SurfaceVertices::of(model, &surface(model));
    let colors: Vec<[f32; 4]> = vertices.colors.iter().map(|&[r, g, b]| [r, g, b, 1.0]).collect();
    Mesh::new(PrimitiveTopology::TriangleList, RenderAssetUsages::RENDER_WORLD)
        .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, vertices.positions)
        .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, vertices.normals)
        .with_inserted_attribute(Mesh::ATTRIBUTE_COLOR, colors)
        .with_inserted_indices(Indices::U32(vertices.indices))
}

#[cfg(test)]
mod tests {
    use super::*;
    use voxel_core::{GridSize, TriangleSoup, VoxelizeOptions, shapes::cuboid, voxelize};

    #[test]
    fn a_cube_s_surface_is_six_rectangles_of_its_colour() {
        let cube = TriangleSoup::from_mesh(&cuboid([0.0; 3], [1.0; 3]), [1.0, 0.5, 0.2, 1.0]);
        let model = voxelize(&cube, &VoxelizeOptions { grid: GridSize::Resolution(8), ..default() }).unwrap();
        let mesh = surface_mesh(&model);
        assert_eq!(mesh.count_vertices(), 6 * 4);
        assert_eq!(mesh.indices().map(Indices::len), Some(6 * 6));
        let Some(bevy::mesh::VertexAttributeValues::Float32x4(colors)) = mesh.attribute(Mesh::ATTRIBUTE_COLOR) else {
            panic!("colours are RGBA floats")
        };
        // sRGB (255, 188, 124) back to linear.
        assert!(colors.iter().all(|c| (c[0] - 1.0).abs() < 1e-6 && (c[1] - 0.5).abs() < 3e-3 && c[3] == 1.0));
        assert_eq!(mesh.asset_usage, RenderAssetUsages::RENDER_WORLD);
    }
}
