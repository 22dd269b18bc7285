// Voxel fragment shader: StandardMaterial lighting with the base colour taken from the instance's MeshTag
// (sRGB RGBA8 packed as r | g << 8 | b << 16 | a << 24).
#import bevy_pbr::{
    pbr_fragment::pbr_input_from_standard_material,
    pbr_functions::{alpha_discard, apply_pbr_lighting, main_pass_post_lighting_processing},
    forward_io::{VertexOutput, FragmentOutput},
    mesh_functions,
}
#import bevy_render::color_operations::srgb_to_linear

@fragment
fn fragment(in: VertexOutput, @builtin(front_facing) is_front: bool) -> FragmentOutput {
    var pbr_input = pbr_input_from_standard_material(in, is_front);
    let c = unpack4x8unorm(mesh_functions::get_tag(in.instance_index));
    pbr_input.material.base_color = pbr_input.material.base_color * vec4(srgb_to_linear(c.rgb), 1.0);
    pbr_input.material.base_color = alpha_discard(pbr_input.material, pbr_input.material.base_color);
    var out: FragmentOutput;
    out.color = apply_pbr_lighting(pbr_input);
    out.color = main_pass_post_lighting_processing(pbr_input, out.color);
    return out;
}
