// The voxels' main pass: each box of a chunk's mesh placed at its voxel (voxel_common.wgsl), StandardMaterial
// lighting with the voxel's colour (sRGB RGBA8) as base colour.
#import bevy_pbr::{
    pbr_fragment::pbr_input_from_standard_material,
    pbr_functions::{alpha_discard, apply_pbr_lighting, main_pass_post_lighting_processing},
    forward_io::{VertexOutput, FragmentOutput},
}
#import bevy_render::color_operations::srgb_to_linear
#import "shaders/voxel_common.wgsl"::{place, placed_normal}

struct VoxelVertex {
    @builtin(instance_index) instance_index: u32,
    @builtin(vertex_index) vertex_index: u32,
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
}

struct VoxelVertexOutput {
    @builtin(position) position: vec4<f32>,
    @location(0) world_position: vec4<f32>,
    @location(1) world_normal: vec3<f32>,
    @location(2) @interpolate(flat) color: u32,
    @location(3) @interpolate(flat) instance_index: u32,
}

@vertex
fn vertex(in: VoxelVertex) -> VoxelVertexOutput {
    let placed = place(in.instance_index, in.vertex_index, in.position);
    var out: VoxelVertexOutput;
    out.world_position = placed.world_position;
    out.position = placed.clip_position;
    out.world_normal = placed_normal(placed, in.normal);
    out.color = placed.voxel.color;
    out.instance_index = in.instance_index;
    return out;
}

@fragment
fn fragment(voxel: VoxelVertexOutput, @builtin(front_facing) is_front: bool) -> FragmentOutput {
    var in: VertexOutput;
    in.position = voxel.position;
    in.world_position = voxel.world_position;
    in.world_normal = voxel.world_normal;
#ifdef VERTEX_OUTPUT_INSTANCE_INDEX
    in.instance_index = voxel.instance_index;
#endif
    var pbr_input = pbr_input_from_standard_material(in, is_front);
    let c = unpack4x8unorm(voxel.color);
    pbr_input.material.base_color = pbr_input.material.base_color * vec4(srgb_to_linear(c.rgb), 1.0);
    pbr_input.material.base_color = alpha_discard(pbr_input.material, pbr_input.material.base_color);
    var out: FragmentOutput;
    out.color = apply_pbr_lighting(pbr_input);
    out.color = main_pass_post_lighting_processing(pbr_input, out.color);
    return out;
}
