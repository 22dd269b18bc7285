//! A bounding volume hierarchy (obvhs BVH2) over grid-space triangles, for box queries.

use std::time::Duration;

use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::{Boundable, BvhBuildParams};

use crate::geom::GridTriangle;
use crate::grid::GridTriangles;

/// A triangle's bounds, padded outwards so f64 → f32 rounding never shrinks them.
struct PaddedBounds(Aabb);

impl Boundable for PaddedBounds {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

fn padded(t: &GridTriangle) -> PaddedBounds {
    let lo = t[0].min(t[1]).min(t[2]);
    let hi = t[0].max(t[1]).max(t[2]);
    let pad = 1e-4 * (1.0 + hi.abs().max(lo.abs()).max_element());
    PaddedBounds(Aabb::new(Vec3A::from((lo - pad).as_vec3()), Vec3A::from((hi + pad).as_vec3())))
}

/// A BVH over the triangles of one model, built once.
pub struct TriangleBvh {
    bvh: Bvh2,
}

impl TriangleBvh {
    /// Builds the hierarchy (in parallel).
    pub fn build(tris: &GridTriangles) -> Self {
        let bounds: Vec<PaddedBounds> = tris.iter().map(|t| padded(&t)).collect();
        let bvh = build_bvh2(&bounds, BvhBuildParams::very_fast_build(), &mut Duration::default());
        Self { bvh }
    }

    /// Calls `visit` with the index of every triangle whose (padded) bounds meet `query`.
    pub fn for_each_in_box(&self, query: Aabb, mut visit: impl FnMut(usize)) {
        if self.bvh.primitive_indices.is_empty() {
            return;
        }
        self.bvh.aabb_traverse(query, |bvh, node_index| {
            let node = &bvh.nodes[node_index as usize];
            for slot in node.first_index..node.first_index + node.prim_count {
                visit(bvh.primitive_indices[slot as usize] as usize);
            }
            true
        });
    }
}
