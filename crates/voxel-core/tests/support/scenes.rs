//! Big scenes generated in code, written as .glb the way large exported models are laid out (included with
//! `#[path]` by the `big` bench and the tests): indexed `u32` primitives with float VEC4 `COLOR_0` and no
//! normals. Two kinds: many closed, overlapping vertex-coloured spheres (64 to a primitive), and one open
//! height field (a single sheet in one primitive). Deterministic: the same sizes give the same bytes.

#![allow(dead_code)] // each including target uses its own subset

use voxel_core::glb::{GlbBuilder, pack_document};

/// Spheres per primitive.
pub const SPHERES_PER_PRIMITIVE: usize = 64;
/// Meridians of a sphere.
const SEGMENTS: u32 = 32;
/// Latitude bands of a sphere: 2 · SEGMENTS · (BANDS − 1) = 1,024 triangles a sphere.
const BANDS: u32 = 17;
/// Triangles of one sphere.
pub const SPHERE_TRIANGLES: usize = (2 * SEGMENTS * (BANDS - 1)) as usize;

/// One indexed primitive: positions, linear RGBA colours and three `u32` indices a triangle.
#[derive(Clone, Debug, Default)]
pub struct Primitive {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Linear RGBA vertex colours (`COLOR_0`).
    pub colors: Vec<[f32; 4]>,
    /// Triangle corners, three a triangle.
    pub indices: Vec<u32>,
}

impl Primitive {
    /// The number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
}

/// A small deterministic generator (a 64-bit LCG; the top bits as a float in [0, 1)).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// `count` overlapping vertex-coloured spheres (1,024 triangles each), 64 to a primitive (the last may hold
/// fewer). The box they are scattered in grows with the count, so the overlap stays alike: about as much
/// sphere volume as box volume, each sphere pushed into several others.
pub fn spheres(count: usize) -> Vec<Primitive> {
    let mut rng = Lcg(0x5EED);
    let side = 16.0 * (count as f32 / 1024.0).cbrt();
    let mut primitives = Vec::new();
    for first in (0..count).step_by(SPHERES_PER_PRIMITIVE) {
        let mut prim = Primitive::default();
        for _ in first..(first + SPHERES_PER_PRIMITIVE).min(count) {
            let centre = [rng.next() * side, rng.next() * side, rng.next() * side];
            let radius = 0.6 + 1.2 * rng.next();
            let tint = [rng.next(), rng.next(), rng.next()];
            add_sphere(&mut prim, centre, radius, tint);
        }
        primitives.push(prim);
    }
    primitives
}

/// Appends a latitude–longitude sphere (outward facing, counter-clockwise seen from outside) whose colour
/// runs from `tint` at the bottom to white at the top.
fn add_sphere(prim: &mut Primitive, centre: [f32; 3], radius: f32, tint: [f32; 3]) {
    let base = prim.positions.len() as u32;
    let mut vertex = |y: f32, ring: f32, angle: f32| {
        let (s, c) = angle.sin_cos();
        prim.positions.push([centre[0] + radius * ring * c, centre[1] + radius * y, centre[2] + radius * ring * s]);
        let up = 0.5 * (y + 1.0);
        prim.colors.push([tint[0] + (1.0 - tint[0]) * up, tint[1] + (1.0 - tint[1]) * up, tint[2] * (1.0 - up), 1.0]);
    };
    vertex(-1.0, 0.0, 0.0); // south pole: base
    for band in 1..BANDS {
        let polar = std::f32::consts::PI * band as f32 / BANDS as f32;
        for seg in 0..SEGMENTS {
            vertex(-polar.cos(), polar.sin(), std::f32::consts::TAU * seg as f32 / SEGMENTS as f32);
        }
    }
    vertex(1.0, 0.0, 0.0); // north pole: base + 1 + SEGMENTS · (BANDS − 1)
    let ring = |band: u32, seg: u32| base + 1 + (band - 1) * SEGMENTS + seg % SEGMENTS;
    let north = base + 1 + SEGMENTS * (BANDS - 1);
    for seg in 0..SEGMENTS {
        prim.indices.extend([base, ring(1, seg), ring(1, seg + 1)]);
        prim.indices.extend([north, ring(BANDS - 1, seg + 1), ring(BANDS - 1, seg)]);
        for band in 1..BANDS - 1 {
            let (a, b, c, d) = (ring(band, seg), ring(band, seg + 1), ring(band + 1, seg), ring(band + 1, seg + 1));
            prim.indices.extend([a, c, b, b, c, d]);
        }
    }
}

/// An open height field over `n` × `n` quads (2n² triangles) in one primitive: a rolling sheet of hills, its
/// colour following the height.
pub fn height_field(n: u32) -> Primitive {
    let mut prim = Primitive::default();
    let step = 10.0 / n as f32;
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (i as f32 * step, j as f32 * step);
            let y = 0.8 * (0.9 * x).sin() * (0.7 * z).cos() + 0.3 * (2.3 * x + 1.1 * z).sin();
            let t = (y + 1.1) / 2.2;
            prim.positions.push([x, y, z]);
            prim.colors.push([0.1 + 0.8 * t, 0.4 + 0.4 * (1.0 - t), 0.9 - 0.7 * t, 1.0]);
        }
    }
    let at = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1));
            prim.indices.extend([a, c, b, b, c, d]);
        }
    }
    prim
}

/// Encodes `primitives` as one mesh of a one-node .glb: per primitive a POSITION (VEC3, with bounds), a
/// COLOR_0 (float VEC4) and a `u32` index accessor, each in its own buffer view, and one plain material.
pub fn to_glb(primitives: &[Primitive]) -> Vec<u8> {
    let mut glb = GlbBuilder::default();
    let mut json_primitives = Vec::new();
    for prim in primitives {
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for p in &prim.positions {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let count = prim.positions.len();
        let position = glb.accessor(
            &le_bytes(prim.positions.iter().flatten().map(|v| v.to_bits())),
            serde_json::json!({"componentType": 5126, "count": count, "type": "VEC3", "min": lo, "max": hi}),
        );
        let color = glb.accessor(
            &le_bytes(prim.colors.iter().flatten().map(|v| v.to_bits())),
            serde_json::json!({"componentType": 5126, "count": count, "type": "VEC4"}),
        );
        let index = glb.accessor(
            &le_bytes(prim.indices.iter().copied()),
            serde_json::json!({"componentType": 5125, "count": prim.indices.len(), "type": "SCALAR"}),
        );
        json_primitives.push(serde_json::json!({
            "attributes": {"POSITION": position, "COLOR_0": color},
            "indices": index,
            "material": 0,
        }));
    }
    let material = serde_json::json!([{"pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 0.8}}]);
    let (doc, bin) = glb.one_mesh("voxel-core generated scene", json_primitives, material);
    pack_document(&doc, &bin).expect("a .glb under 4 GiB")
}

/// Little-endian bytes of 32-bit words.
fn le_bytes(words: impl Iterator<Item = u32>) -> Vec<u8> {
    words.flat_map(u32::to_le_bytes).collect()
}

/// The held-out scenes of the `big` bench: 1M and 4M triangles of overlapping spheres, and a 2M-triangle
/// open height field.
pub fn big_scenes() -> impl Iterator<Item = (&'static str, fn() -> Vec<Primitive>)> {
    let spheres_1m: fn() -> Vec<Primitive> = || spheres(1024);
    let spheres_4m: fn() -> Vec<Primitive> = || spheres(4096);
    let field_2m: fn() -> Vec<Primitive> = || vec![height_field(1000)];
    [("spheres-1m.glb", spheres_1m), ("spheres-4m.glb", spheres_4m), ("heightfield-2m.glb", field_2m)].into_iter()
}
