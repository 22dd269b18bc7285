//! A bounding volume hierarchy (obvhs BVH2) over grid-space triangles, for box and nearest-triangle queries.

use std::time::Duration;

use glam::{DVec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::{Boundable, BvhBuildParams};

use crate::geom::GridTriangle;

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
    pub fn build(tris: &[GridTriangle]) -> Self {
        let bounds: Vec<PaddedBounds> = tris.iter().map(padded).collect();
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

    /// The triangle nearest to `p` and its squared distance, where `distance2(t)` is the squared distance
    /// from `p` to triangle `t`; ties go to the lower index. Branch and bound, nearer child first: a node is
    /// skipped when its (padded, so never too far) box is farther than the best triangle so far, so a query
    /// visits the nodes near `p` rather than every triangle in a box around it.
    pub fn nearest(&self, p: DVec3, distance2: impl Fn(usize) -> f64) -> Option<(usize, f64)> {
        let nodes = &self.bvh.nodes;
        if self.bvh.primitive_indices.is_empty() || nodes.is_empty() {
            return None;
        }
        let box_distance2 = |node: u32| {
            let b = nodes[node as usize].aabb();
            let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
            (lo - p).max(p - hi).max(DVec3::ZERO).length_squared()
        };
        let mut best: Option<(usize, f64)> = None;
        let mut stack = vec![(0u32, box_distance2(0))];
        while let Some((index, d2)) = stack.pop() {
            if best.is_some_and(|(_, b)| d2 > b) {
                continue;
            }
            let node = &nodes[index as usize];
            if node.is_leaf() {
                for slot in node.first_index..node.first_index + node.prim_count {
                    let t = self.bvh.primitive_indices[slot as usize] as usize;
                    let d = distance2(t);
                    if best.is_none_or(|(bt, b)| d < b || (d == b && t < bt)) {
                        best = Some((t, d));
                    }
                }
                continue;
            }
            let children = [node.first_index, node.first_index + 1].map(|c| (c, box_distance2(c)));
            // The nearer child is pushed last, so it is searched first.
            let (near, far) =
                if children[0].1 <= children[1].1 { (children[0], children[1]) } else { (children[1], children[0]) };
            stack.push(far);
            stack.push(near);
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_matches_brute_force_with_ties_to_the_lower_index() {
        // A 9×9 field of small triangles in the plane z = 0, two copies of the middle one (indices 40, 81).
        let mut tris: Vec<GridTriangle> = (0..81)
            .map(|k| {
                let o = DVec3::new(f64::from(k % 9) * 3.0, f64::from(k / 9) * 3.0, 0.0);
                [o, o + DVec3::X, o + DVec3::Y]
            })
            .collect();
        tris.push(tris[40]);
        let bvh = TriangleBvh::build(&tris);
        let distance2 = |p: DVec3, t: usize| crate::geom::distance2(p, &tris[t]);
        for p in [DVec3::new(12.2, 12.2, 5.0), DVec3::new(-7.0, 30.0, 1.0), DVec3::new(25.5, 0.3, -2.0)] {
            let brute = (0..tris.len())
                .map(|t| (t, distance2(p, t)))
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
                .unwrap();
            assert_eq!(bvh.nearest(p, |t| distance2(p, t)), Some(brute), "{p}");
        }
        // Above the middle triangle: its copy (81) is as near, and the lower index wins.
        let above = DVec3::new(12.2, 12.2, 5.0);
        assert_eq!(bvh.nearest(above, |t| distance2(above, t)).map(|(t, _)| t), Some(40));
    }
}
