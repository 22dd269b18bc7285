//! The voxel material: `StandardMaterial` extended with the voxels' storage buffers (looks, flights, springs, clock). Its vertex shaders (the main
//! pass and the prepass, which draws the light's shadow map) place each box of a chunk's mesh at its voxel:
//! voxel = chunk (`MeshTag`) × boxes per chunk + vertex index / vertices per box.

use bevy::pbr::{ExtendedMaterial, MaterialExtension};
use bevy::prelude::*;
use bevy::render::render_resource::AsBindGroup;
use bevy::render::storage::ShaderBuffer;
use bevy::shader::ShaderRef;

/// The one material every chunk of voxels shares (one batch).
pub type VoxelMaterial = ExtendedMaterial<StandardMaterial, VoxelExtension>;

/// How the chunk meshes are laid out: their boxes and the vertices of each, in the detailed mesh and in the low
/// detail one (a chunk's `MeshTag` has bit 31 set when it draws the low detail mesh).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Reflect, bevy::render::render_resource::ShaderType)]
pub struct ChunkLayout {
    /// Vertices of one voxel in the detailed chunk mesh.
    pub vertices_per_voxel: u32,
    /// Vertices of one voxel in the low detail chunk mesh.
    pub low_vertices_per_voxel: u32,
    /// Voxels per chunk.
    pub voxels_per_chunk: u32,
}

impl ChunkLayout {
    /// The layout of chunk meshes made of `shape` and `low` (the detailed and the low detail voxel).
    pub fn of(shape: &Mesh, low: &Mesh) -> Self {
        Self {
            vertices_per_voxel: shape.count_vertices() as u32,
            low_vertices_per_voxel: low.count_vertices() as u32,
            voxels_per_chunk: crate::instancing::VOXELS_PER_CHUNK as u32,
        }
    }
}

/// The extension: the voxels (a [`crate::instancing::gpu::GpuVoxel`] each, by pool slot) and the chunk layout.
#[derive(Asset, AsBindGroup, Reflect, Debug, Clone, Default)]
pub struct VoxelExtension {
    /// The voxels, written range by range by the instancing plugin.
    #[storage(100, read_only)]
    pub voxels: Handle<ShaderBuffer>,
    /// The chunk mesh's layout.
    #[uniform(101)]
    pub layout: ChunkLayout,
    /// The voxels' flights ([`crate::instancing::VoxelTween`]s by pool slot), written when they start.
    #[storage(102, read_only)]
    pub flights: Handle<ShaderBuffer>,
    /// The frame's flight clock ([`crate::instancing::GpuClock`]), written every frame.
    #[storage(103, read_only)]
    pub clock: Handle<ShaderBuffer>,
    /// The voxels' repel springs ([`crate::instancing::GpuSpring`]s by pool slot), written while the cursor
    /// pushes them.
    #[storage(104, read_only)]
    pub springs: Handle<ShaderBuffer>,
}

/// The voxel shader (vertex, prepass vertex and fragment entry points).
const SHADER: &str = "shaders/voxel.wgsl";

impl MaterialExtension for VoxelExtension {
    fn vertex_shader() -> ShaderRef {
        SHADER.into()
    }

    fn fragment_shader() -> ShaderRef {
        SHADER.into()
    }

    // Only a material with its own prepass vertex shader is bound in the shadow pass (`PREPASS_READS_MATERIAL`):
    // without it the light would see the chunk's mesh of boxes piled up at the origin.
    fn prepass_vertex_shader() -> ShaderRef {
        "shaders/voxel_prepass.wgsl".into()
    }
}

/// Packs an sRGB colour into a `MeshTag` value (r | g << 8 | b << 16 | a << 24).
pub fn pack_color(rgba: [u8; 4]) -> u32 {
    u32::from_le_bytes(rgba)
}

/// Unpacks a `MeshTag` value into sRGB RGBA8.
pub fn unpack_color(tag: u32) -> [u8; 4] {
    tag.to_le_bytes()
}

/// The material reading `voxels`, `flights`, `springs` and `clock`: a soft plastic look.
pub fn voxel_material(
    voxels: Handle<ShaderBuffer>,
    flights: Handle<ShaderBuffer>,
    springs: Handle<ShaderBuffer>,
    clock: Handle<ShaderBuffer>,
) -> VoxelMaterial {
    ExtendedMaterial {
        base: StandardMaterial { base_color: Color::WHITE, perceptual_roughness: 0.55, reflectance: 0.35, ..default() },
        extension: VoxelExtension { voxels, layout: ChunkLayout::default(), flights, clock, springs },
    }
}
