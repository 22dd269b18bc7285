//! The edges of welded triangles: which corners walk the same edge.
//!
//! Corner `c` is the start of edge `c % 3` of triangle `c / 3`, which runs to the triangle's next corner.
//! The corners are bucketed by their edge's lower position number (one counting pass and one scatter: the
//! positions are small integers), and each bucket, a handful of corners, is sorted by the edge's other end.

use std::ops::Range;

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

/// The edges of the triangles with area, by how many corners walk each.
pub(crate) struct Edges {
    /// Each corner's partner on a manifold edge (walked by exactly two corners), else [`NO_PART`].
    pub partner: Vec<u32>,
    /// Corners alone on their edge (a border).
    pub border: Vec<u32>,
    /// The corners of the non-manifold edges (walked three or more times), ascending within an edge.
    corners: Vec<u32>,
    /// Each non-manifold edge's corners in `corners`, in order of their first corner.
    groups: Vec<Range<u32>>,
}

impl Edges {
    /// Groups the corners of the triangles (three per triangle, `id` their positions, `positions` how many
    /// there are) by the edge they walk, leaving out triangles without area.
    pub(crate) fn of(id: &[u32], positions: usize) -> Self {
        let corners = (0..id.len() as u32).filter(|&c| has_area(id, c as usize / 3));
        let ends = |c: u32| {
            let (a, b) = (id[c as usize], id[next(c) as usize]);
            if a < b { (a, b) } else { (b, a) }
        };
        let mut start = vec![0u32; positions + 1];
        for c in corners.clone() {
            start[ends(c).0 as usize + 1] += 1;
        }
        for p in 1..start.len() {
            start[p] += start[p - 1];
        }
        let mut at = start.clone();
        // Per bucket: (the edge's higher end, corner), in corner order.
        let mut bucketed = vec![(0u32, 0u32); start[positions] as usize];
        for c in corners {
            let (lo, hi) = ends(c);
            bucketed[at[lo as usize] as usize] = (hi, c);
            at[lo as usize] += 1;
        }
        let mut edges =
            Self { partner: vec![NO_PART; id.len()], border: Vec::new(), corners: Vec::new(), groups: Vec::new() };
        for bucket in start.windows(2) {
            let bucket = &mut bucketed[bucket[0] as usize..bucket[1] as usize];
            bucket.sort_unstable();
            for edge in bucket.chunk_by(|a, b| a.0 == b.0) {
                match *edge {
                    [(_, a)] => edges.border.push(a),
                    [(_, a), (_, b)] => (edges.partner[a as usize], edges.partner[b as usize]) = (b, a),
                    _ => {
                        let from = edges.corners.len() as u32;
                        edges.corners.extend(edge.iter().map(|e| e.1));
                        edges.groups.push(from..edges.corners.len() as u32);
                    }
                }
            }
        }
        edges.groups.sort_unstable_by_key(|g| edges.corners[g.start as usize]);
        edges
    }

    /// The non-manifold edges' corners, edge by edge in order of their first corner.
    pub(crate) fn non_manifold(&self) -> impl Iterator<Item = &[u32]> + Clone {
        self.groups.iter().map(|g| &self.corners[g.start as usize..g.end as usize])
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
        let edges = Edges::of(&id, 6);
        assert_eq!(edges.non_manifold().collect::<Vec<_>>(), [&[0, 3, 6][..]]);
        assert_eq!((edges.partner[1], edges.partner[9]), (9, 1));
        assert_eq!(edges.partner.iter().filter(|&&p| p != NO_PART).count(), 2);
        let mut border = edges.border.clone();
        border.sort_unstable();
        assert_eq!(border, [2, 4, 5, 7, 8, 10, 11]);
        assert!(ascends(&id, 0) && !ascends(&id, 3) && !has_area(&id, 4));
    }
}
