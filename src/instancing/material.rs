//! The voxel material: `StandardMaterial` extended to read each voxel's colour from its `MeshTag`.

use bevy::pbr::{ExtendedMaterial, MaterialExtension};
use bevy::prelude::*;
use bevy::render::render_resource::AsBindGroup;
use bevy::shader::ShaderRef;

/// The one material every voxel shares (one batch).
pub type VoxelMaterial = ExtendedMaterial<StandardMaterial, VoxelExtension>;

/// The extension: no data of its own, only the fragment shader (the colour comes per instance from `MeshTag`).
#[derive(Asset, AsBindGroup, Reflect, Debug, Clone, Default)]
pub struct VoxelExtension {}

impl MaterialExtension for VoxelExtension {
    fn fragment_shader() -> ShaderRef {
        "shaders/voxel.wgsl".into()
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

/// The material: a soft plastic look.
pub fn voxel_material() -> VoxelMaterial {
    ExtendedMaterial {
        base: StandardMaterial { base_color: Color::WHITE, perceptual_roughness: 0.55, reflectance: 0.35, ..default() },
        extension: VoxelExtension {},
    }
}
