// The voxels' prepass vertex shader (the light's shadow map, and any depth or normal prepass): each box of a
// chunk's mesh placed at its voxel (voxel_common.wgsl), as in the main pass.
#import bevy_pbr::prepass_io::VertexOutput
#import "shaders/voxel_common.wgsl"::{place, placed_normal}

struct VoxelVertex {
    @builtin(instance_index) instance_index: u32,
    @builtin(vertex_index) vertex_index: u32,
    @location(0) position: vec3<f32>,
#ifdef NORMAL_PREPASS_OR_DEFERRED_PREPASS
    @location(3) normal: vec3<f32>,
#endif
}

@vertex
fn vertex(in: VoxelVertex) -> VertexOutput {
    let placed = place(in.instance_index, in.vertex_index, in.position);
    var out: VertexOutput;
    out.world_position = placed.world_position;
    out.position = placed.clip_position;
#ifdef UNCLIPPED_DEPTH_ORTHO_EMULATION
    out.unclipped_depth = out.position.z;
    out.position.z = min(out.position.z, 1.0);
#endif
#ifdef NORMAL_PREPASS_OR_DEFERRED_PREPASS
    out.world_normal = placed_normal(placed, in.normal);
#endif
#ifdef MOTION_VECTOR_PREPASS
    out.previous_world_position = out.world_position;
#endif
#ifdef VERTEX_OUTPUT_INSTANCE_INDEX
    out.instance_index = in.instance_index;
#endif
    return out;
}
