//! The edges of welded triangles: which corners walk the same edge.
//!
//! Corner `c` is the start of edge `c % 3` of triangle `c / 3`, which runs to the triangle's next corner.
//! An edge is known by its two ends' position numbers; one pass through an open-addressing table numbers
//! the edges in order of their first corner and counts the corners walking each.

use super::NO_PART;

/// The corner after `c` in its triangle.
pub(crate) fn next(c: u32) -> u32 {
    if c % 3 == 2 { c - 2 } else { c + 1 }
}

/// Whether triangle `t`'s corners are at three different positions (`id`: each corner's position).
pub(crate) fn has_area(id: &[u32], t: usize) -> bool {
    let [a, b, c] = [id[3 * t], id[3 * t + 1], id[3 * t + 2]];
    a != b && b != c && c != a
}

/// Whether corner `c` walks its edge from the lower position number to the higher.
pub(crate) fn ascends(id: &[u32], c: u32) -> bool {
    id[c as usize] < id[next(c) as usize]
}

/// Marks a partner that walks the shared edge in the same direction (the corner numbers are below 2³¹:
/// three per triangle of a soup in memory).
pub(crate) const SAME_DIRECTION: u32 = 1 << 31;

/// The edges of the triangles with area, by how many corners walk each.
pub(crate) struct Edges {
    /// Each corner's partner on a manifold edge (walked by exactly two corners), or'ed with
    /// [`SAME_DIRECTION`] when both walk it the same way; else [`NO_PART`].
    pub partner: Vec<u32>,
    /// Corners alone on their edge (a border), ascending.
    pub border: Vec<u32>,
    /// The corners of the non-manifold edges (walked three or more times): ascending within an edge, the
    /// edges in order of their first corner.
    corners: Vec<u32>,
    /// Where each non-manifold edge's corners start in `corners` (and, last, their end).
    starts: Vec<u32>,
}

/// What is known of an edge while the corners are counted.
#[derive(Clone, Copy)]
struct Edge {
    /// Its ends' position numbers, lower first, as one key.
    ends: u64,
    /// The first two corners walking it.
    corners: [u32; 2],
    /// Whether its first corner walks it from the lower end.
    ascending: bool,
    /// How many corners walk it.
    count: u32,
}

/// The edges of triangles, numbered in order of their first corner: an open-addressing table of edge
/// numbers, at most half full.
struct EdgeTable {
    slots: Vec<u32>,
    bits: u32,
    edges: Vec<Edge>,
}

impl EdgeTable {
    fn new(corners: usize) -> Self {
        let bits = (2 * corners).next_power_of_two().max(2).ilog2();
        Self { slots: vec![u32::MAX; 1 << bits], bits, edges: Vec::with_capacity(corners / 2 + 1) }
    }

    /// The number of the edge with ends `ends`, added (walked by no corner yet) when new.
    fn number(&mut self, ends: u64) -> u32 {
        let mask = self.slots.len() - 1;
        let mut slot = (ends.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> (64 - self.bits)) as usize;
        loop {
            match self.slots[slot] {
                u32::MAX => {
                    let e = self.edges.len() as u32;
                    self.slots[slot] = e;
                    self.edges.push(Edge { ends, corners: [NO_PART; 2], ascending: false, count: 0 });
                    return e;
                }
                e if self.edges[e as usize].ends == ends => return e,
                _ => slot = (slot + 1) & mask,
            }
        }
    }
}

/// The edge that corner `k` of a triangle with corners at `corners` walks: its ends as one key, and
/// whether it walks it from the lower end.
fn walked(corners: &[u32], k: usize) -> (u64, bool) {
    let (a, b) = (corners[k], corners[(k + 1) % 3]);
    ((u64::from(a.min(b)) << 32) | u64::from(a.max(b)), a < b)
}

impl Edges {
    /// Groups the corners of the triangles (three per triangle, `id` their positions) by the edge they
    /// walk, leaving out triangles without area.
    pub(crate) fn of(id: &[u32]) -> Self {
        let mut table = EdgeTable::new(id.len());
        let mut found =
            Self { partner: vec![NO_PART; id.len()], border: Vec::new(), corners: Vec::new(), starts: Vec::new() };
        let with_area = id.chunks_exact(3).enumerate().filter(|&(t, _)| has_area(id, t));
        for (t, corners) in with_area.clone() {
            for k in 0..3 {
                let (ends, ascending) = walked(corners, k);
                let c = (3 * t + k) as u32;
                let e = table.number(ends) as usize;
                let edge = &mut table.edges[e];
                match edge.count {
                    0 => (edge.corners[0], edge.ascending) = (c, ascending),
                    1 => {
                        let same = if ascending == edge.ascending { SAME_DIRECTION } else { 0 };
                        let first = edge.corners[0];
                        edge.corners[1] = c;
                        (found.partner[first as usize], found.partner[c as usize]) = (c | same, first | same);
                    }
                    2 => edge.corners.iter().for_each(|&c| found.partner[c as usize] = NO_PART),
                    _ => {}
                }
                edge.count += 1;
            }
        }
        found.border = table.edges.iter().filter(|e| e.count == 1).map(|e| e.corners[0]).collect();
        if table.edges.iter().any(|e| e.count > 2) {
            // (edge, corner) on the non-manifold edges, in corner order; sorted by edge (numbered in order
            // of their first corner), the corners stay ascending.
            let mut non_manifold: Vec<(u32, u32)> = Vec::new();
            for (t, corners) in with_area {
                for k in 0..3 {
                    let e = table.number(walked(corners, k).0);
                    if table.edges[e as usize].count > 2 {
                        non_manifold.push((e, (3 * t + k) as u32));
                    }
                }
            }
            non_manifold.sort_by_key(|&(e, _)| e);
            for (k, &(e, c)) in non_manifold.iter().enumerate() {
                if k == 0 || non_manifold[k - 1].0 != e {
                    found.starts.push(k as u32);
                }
                found.corners.push(c);
            }
            found.starts.push(found.corners.len() as u32);
        }
        found
    }

    /// The non-manifold edges' corners, edge by edge in order of their first corner.
    pub(crate) fn non_manifold(&self) -> impl Iterator<Item = &[u32]> + Clone {
        self.starts.windows(2).map(|w| &self.corners[w[0] as usize..w[1] as usize])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corners_are_grouped_by_the_edge_they_walk() {
        // Three triangles on the edge 0–1 (one walking it the other way), a fourth sharing 1–2 with the first,
        // and a degenerate one (positions 3, 3, 4) left out.
        let id = [0, 1, 2, 1, 0, 3, 0, 1, 4, 2, 1, 5, 3, 3, 4];
        let edges = Edges::of(&id);
        assert_eq!(edges.non_manifold().collect::<Vec<_>>(), [&[0, 3, 6][..]]);
        assert_eq!((edges.partner[1], edges.partner[9]), (9, 1));
        // Two triangles walking an edge the same way (one of them reversed).
        let same = Edges::of(&[0, 1, 2, 0, 1, 3]);
        assert_eq!(same.partner[..4], [3 | SAME_DIRECTION, NO_PART, NO_PART, SAME_DIRECTION]);
        assert_eq!(edges.partner.iter().filter(|&&p| p != NO_PART).count(), 2);
        assert_eq!(edges.border, [2, 4, 5, 7, 8, 10, 11]);
        assert!(ascends(&id, 0) && !ascends(&id, 3) && !has_area(&id, 4));
    }
}
