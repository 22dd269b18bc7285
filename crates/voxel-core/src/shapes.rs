//! Closed indexed meshes of simple solids (analytic volumes known): used by tests, benchmarks and the
//! generator of the app's shipped models.

use std::f32::consts::{PI, TAU};

/// An indexed triangle mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IndexedMesh {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Triangles as vertex indices, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
}

impl IndexedMesh {
    /// Moves every vertex by `offset`.
    pub fn translated(mut self, offset: [f32; 3]) -> Self {
        for p in &mut self.positions {
            for a in 0..3 {
                p[a] += offset[a];
            }
        }
        self
    }

    /// Rotates every vertex about `axis` (through the origin) by `angle` radians.
    pub fn rotated(mut self, axis: [f32; 3], angle: f32) -> Self {
        let q = glam::Quat::from_axis_angle(glam::Vec3::from(axis).normalize(), angle);
        for p in &mut self.positions {
            *p = (q * glam::Vec3::from(*p)).to_array();
        }
        self
    }

    /// Scales every vertex by `factor` per axis.
    pub fn scaled(mut self, factor: [f32; 3]) -> Self {
        for p in &mut self.positions {
            for a in 0..3 {
                p[a] *= factor[a];
            }
        }
        self
    }
}

/// An axis-aligned box from `min` to `max` (12 triangles).
pub fn cuboid(min: [f32; 3], max: [f32; 3]) -> IndexedMesh {
    let c = |i: u32| {
        [
            if i & 1 == 0 { min[0] } else { max[0] },
            if i & 2 == 0 { min[1] } else { max[1] },
            if i & 4 == 0 { min[2] } else { max[2] },
        ]
    };
    let positions = (0..8).map(c).collect();
    let quads = [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]];
    let triangles = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
    IndexedMesh { positions, triangles }
}

/// A latitude–longitude sphere of `radius` around the origin with `rings` rings and 2·`rings` sectors.
pub fn uv_sphere(radius: f32, rings: u32) -> IndexedMesh {
    let rings = rings.max(2);
    let sectors = 2 * rings;
    let mut positions = vec![[0.0, radius, 0.0]];
    for i in 1..rings {
        let theta = PI * i as f32 / rings as f32;
        for j in 0..sectors {
            let phi = TAU * j as f32 / sectors as f32;
            positions.push([radius * theta.sin() * phi.cos(), radius * theta.cos(), radius * theta.sin() * phi.sin()]);
        }
    }
    positions.push([0.0, -radius, 0.0]);
    let bottom = positions.len() as u32 - 1;
    let at = |i: u32, j: u32| 1 + (i - 1) * sectors + j % sectors;
    let mut triangles = Vec::new();
    for j in 0..sectors {
        triangles.push([0, at(1, j + 1), at(1, j)]);
        triangles.push([bottom, at(rings - 1, j), at(rings - 1, j + 1)]);
    }
    for i in 1..rings - 1 {
        for j in 0..sectors {
            triangles.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            triangles.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    IndexedMesh { positions, triangles }
}

/// The upper half of a sphere of `radius` (dome over the xz plane). With `closed`, a flat disc closes its
/// base; without, it is an open shell.
pub fn dome(radius: f32, rings: u32, closed: bool) -> IndexedMesh {
    let rings = rings.max(2);
    let sectors = 4 * rings;
    let mut positions = vec![[0.0, radius, 0.0]];
    for i in 1..=rings {
        let theta = PI / 2.0 * i as f32 / rings as f32;
        for j in 0..sectors {
            let phi = TAU * j as f32 / sectors as f32;
            positions.push([radius * theta.sin() * phi.cos(), radius * theta.cos(), radius * theta.sin() * phi.sin()]);
        }
    }
    let at = |i: u32, j: u32| 1 + (i - 1) * sectors + j % sectors;
    let mut triangles = Vec::new();
    for j in 0..sectors {
        triangles.push([0, at(1, j + 1), at(1, j)]);
    }
    for i in 1..rings {
        for j in 0..sectors {
            triangles.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            triangles.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    if closed {
        positions.push([0.0; 3]);
        let centre = positions.len() as u32 - 1;
        for j in 0..sectors {
            triangles.push([centre, at(rings, j), at(rings, j + 1)]);
        }
    }
    IndexedMesh { positions, triangles }
}

/// A torus around the y axis: ring radius `major`, tube radius `minor`, `segments` × `segments`/2 quads.
pub fn torus(major: f32, minor: f32, segments: u32) -> IndexedMesh {
    let (n, m) = (segments.max(3), (segments / 2).max(3));
    let mut positions = Vec::new();
    for i in 0..n {
        let u = TAU * i as f32 / n as f32;
        for j in 0..m {
            let v = TAU * j as f32 / m as f32;
            let r = major + minor * v.cos();
            positions.push([r * u.cos(), minor * v.sin(), r * u.sin()]);
        }
    }
    let at = |i: u32, j: u32| (i % n) * m + j % m;
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..m {
            triangles.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            triangles.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    IndexedMesh { positions, triangles }
}

/// A closed cylinder along y from `y0` to `y1` (caps as fans around centre vertices).
pub fn cylinder(radius: f32, y0: f32, y1: f32, segments: u32) -> IndexedMesh {
    let n = segments.max(3);
    let mut positions = vec![[0.0, y0, 0.0], [0.0, y1, 0.0]];
    for y in [y0, y1] {
        for i in 0..n {
            let a = TAU * i as f32 / n as f32;
            positions.push([radius * a.cos(), y, radius * a.sin()]);
        }
    }
    let bottom = |i: u32| 2 + i % n;
    let top = |i: u32| 2 + n + i % n;
    let mut triangles = Vec::new();
    for i in 0..n {
        triangles.push([0, bottom(i), bottom(i + 1)]);
        triangles.push([1, top(i + 1), top(i)]);
        triangles.push([bottom(i), top(i), top(i + 1)]);
        triangles.push([bottom(i), top(i + 1), bottom(i + 1)]);
    }
    IndexedMesh { positions, triangles }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// Every edge of a closed mesh is used exactly twice, once in each direction.
    fn assert_closed(mesh: &IndexedMesh) {
        let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
        for t in &mesh.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_default() += if a < b { 1 } else { -1 };
            }
        }
        assert!(edges.values().all(|&v| v == 0), "open or inconsistently wound mesh");
    }

    #[test]
    fn solids_are_closed_and_consistently_wound() {
        assert_closed(&cuboid([0.0; 3], [1.0; 3]));
        assert_closed(&uv_sphere(1.0, 8));
        assert_closed(&torus(2.0, 0.5, 16));
        assert_closed(&cylinder(1.0, 0.0, 2.0, 12));
        assert_closed(&dome(1.0, 6, true));
    }
}
