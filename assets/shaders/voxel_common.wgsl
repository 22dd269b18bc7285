// The voxels of the instanced draw, shared by the main pass (voxel.wgsl) and the prepass (voxel_prepass.wgsl):
// a chunk entity draws a mesh of boxes; box k of chunk c is voxel c × voxels_per_chunk + k of the storage buffer
// (the chunk's index is its MeshTag, the box's is the vertex index over the vertices of one box). Bit 31 of the
// tag says the chunk draws the low detail mesh: three faces (+x, +y, +z, four vertices each), each turned to the
// side of the box that faces the viewer.
// A voxel in flight (a morph, a pop) is drawn from its flight at the frame's clock, one the cursor pushed from its
// look moved by its repel spring (voxel_flight.wgsl).
#import bevy_pbr::{mesh_bindings::mesh, mesh_functions, mesh_view_bindings::view, view_transformations::position_world_to_clip}
#import "shaders/voxel_flight.wgsl"::{Voxel, Flight, Clock, Spring, flown, sprung}

struct ChunkLayout {
    vertices_per_voxel: u32,
    low_vertices_per_voxel: u32,
    voxels_per_chunk: u32,
}

@group(#{MATERIAL_BIND_GROUP}) @binding(100) var<storage, read> voxels: array<Voxel>;
@group(#{MATERIAL_BIND_GROUP}) @binding(101) var<uniform> chunk_layout: ChunkLayout;
@group(#{MATERIAL_BIND_GROUP}) @binding(102) var<storage, read> flights: array<Flight>;
@group(#{MATERIAL_BIND_GROUP}) @binding(103) var<storage, read> clock: Clock;
@group(#{MATERIAL_BIND_GROUP}) @binding(104) var<storage, read> springs: array<Spring>;

// A vertex of a chunk's mesh: its voxel, and which face of the low detail box to turn over (0: none, 1..3: the
// x, y or z face).
struct BoxVertex {
    voxel: Voxel,
    flip: u32,
}

// (cos, −sin) of the voxel's turn about y.
fn turn_of(v: Voxel) -> vec2<f32> {
    let width = length(v.x_axis);
    return select(vec2(1.0, 0.0), v.x_axis / width, width > 0.0);
}

// The direction from the voxel towards the viewer, in the voxel's frame: towards the eye, or, in an
// orthographic view (a directional light's shadow map), the view's backward axis.
fn towards_viewer(v: Voxel) -> vec3<f32> {
    var d = view.world_position - v.translation;
    if view.clip_from_view[3].w == 1.0 {
        d = view.world_from_view[2].xyz;
    }
    let c = turn_of(v);
    return vec3(dot(d, vec3(c.x, 0.0, c.y)), d.y, dot(d, vec3(-c.y, 0.0, c.x)));
}

// The voxel whose box vertex `vertex_index` of instance `instance_index` belongs to.
fn box_vertex(instance_index: u32, vertex_index: u32) -> BoxVertex {
    let local = vertex_index - mesh[instance_index].first_vertex_index;
    let tag = mesh_functions::get_tag(instance_index);
    let low = (tag >> 31u) != 0u;
    let per_voxel = select(chunk_layout.vertices_per_voxel, chunk_layout.low_vertices_per_voxel, low);
    let slot = (tag & 0x7fffffffu) * chunk_layout.voxels_per_chunk + local / per_voxel;
    var voxel = voxels[slot];
    if slot < arrayLength(&springs) {
        voxel = sprung(voxel, springs[slot], clock);
    }
    if slot < arrayLength(&flights) {
        voxel = flown(voxel, flights[slot], slot, clock);
    }
    var flip = 0u;
    if low {
        let face = (local % per_voxel) / 4u;
        let toward = towards_viewer(voxel);
        if toward[face] < 0.0 {
            flip = face + 1u;
        }
    }
    return BoxVertex(voxel, flip);
}

// Turns a point (or normal) of a low detail face over to the opposite face: a half turn about the diagonal of
// the face's plane, so the face keeps its winding (front-facing from outside).
fn flipped(flip: u32, p: vec3<f32>) -> vec3<f32> {
    switch flip {
        case 1u: { return vec3(-p.x, p.z, p.y); }
        case 2u: { return vec3(p.z, -p.y, p.x); }
        case 3u: { return vec3(p.y, p.x, -p.z); }
        default: { return p; }
    }
}

// A point of the unit box (−0.5..0.5) in world space.
fn point_to_world(v: Voxel, p: vec3<f32>) -> vec3<f32> {
    let c = turn_of(v);
    let x = vec3(v.x_axis.x, 0.0, v.x_axis.y);
    let z = vec3(-c.y, 0.0, c.x) * v.scale_z;
    return v.translation + x * p.x + vec3(0.0, v.scale_y * p.y, 0.0) + z * p.z;
}

// A normal of the unit box in world space (the inverse transpose of turn × scale: turn × (n / scale)).
fn normal_to_world(v: Voxel, n: vec3<f32>) -> vec3<f32> {
    let c = turn_of(v);
    let m = n / max(vec3(length(v.x_axis), v.scale_y, v.scale_z), vec3(1e-8));
    return normalize(vec3(c.x * m.x - c.y * m.z, m.y, c.y * m.x + c.x * m.z));
}

// A vertex of a chunk's mesh placed at its voxel: the voxel and face flip, its world and clip positions.
struct PlacedVertex {
    voxel: Voxel,
    flip: u32,
    world_position: vec4<f32>,
    clip_position: vec4<f32>,
}

// Places the unit box point `position` of vertex `vertex_index` of instance `instance_index` at its voxel.
fn place(instance_index: u32, vertex_index: u32, position: vec3<f32>) -> PlacedVertex {
    let vertex = box_vertex(instance_index, vertex_index);
    let world = point_to_world(vertex.voxel, flipped(vertex.flip, position));
    return PlacedVertex(vertex.voxel, vertex.flip, vec4(world, 1.0), position_world_to_clip(world));
}

// A unit box normal of a placed vertex in world space.
fn placed_normal(placed: PlacedVertex, normal: vec3<f32>) -> vec3<f32> {
    return normal_to_world(placed.voxel, flipped(placed.flip, normal));
}
