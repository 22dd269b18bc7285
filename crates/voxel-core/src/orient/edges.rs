//! The edges of welded triangles: which corners walk the same edge.
//!
//! Corner `c` is the start of edge `c % 3` of triangle `c / 3`, which runs to the triangle's next corner.
//! The corners are bucketed by their edge's lower end (a counting pass, then one scatter into buckets sized
//! exactly: the position numbers are small integers; buckets with room for every corner at their position,
//! without the count, touched twice the memory, and a fresh process faulted in 800 more pages), and in each
//! bucket, a handful of corners, those with the same higher end walk the same edge.

use std::ops::Range;

/// The corner after `c` in its triangle.
fn next(c: u32) -> u32 {
    if c % 3 == 2 { c - 2 } else { c + 1 }
}

/// Whether triangle `t`'s corners are at three different positions (`id`: each corner's position).
pub(crate) fn has_area(id: &[u32], t: usize) -> bool {
    apart(id[3 * t], id[3 * t + 1], id[3 * t + 2])
}

/// Whether the positions `a`, `b` and `c` are three different ones.
fn apart(a: u32, b: u32, c: u32) -> bool {
    a != b && b != c && c != a
}

/// Calls `f` with every corner of the triangles with area (three per triangle, `id` their positions) and
/// the ends of the edge it walks.
fn for_each_edge(id: &[u32], mut f: impl FnMut(u32, u32, u32)) {
    for (t, corners) in id.chunks_exact(3).enumerate() {
        let [a, b, c] = [corners[0], corners[1], corners[2]];
        if apart(a, b, c) {
            let first = 3 * t as u32;
            f(first, a, b);
            f(first + 1, b, c);
            f(first + 2, c, a);
        }
    }
}

/// Whether corner `c` walks its edge from the lower position number to the higher.
pub(crate) fn ascends(id: &[u32], c: u32) -> bool {
    id[c as usize] < id[next(c) as usize]
}

/// The partner of a corner without one (alone on its edge, on a non-manifold edge, or in a triangle without
/// area); not a repeated byte, as `weld`'s empty slot mark.
pub(crate) const NO_PARTNER: u32 = u32::MAX >> 1;

/// Marks a partner that walks the shared edge in the same direction (the corner numbers are below 2³¹ − 1,
/// so never [`NO_PARTNER`]: three per triangle of a soup in memory).
pub(crate) const SAME_DIRECTION: u32 = 1 << 31;

/// Corner `c`'s bucket entry, `c` walking from position `a` to `b`: the edge's higher end in the high half,
/// then the corner, then whether it walks the edge from the higher end; so entries order by the higher end,
/// then by corner.
fn entry(c: u32, a: u32, b: u32) -> u64 {
    (u64::from(a.max(b)) << 32) | u64::from(c << 1) | u64::from(a > b)
}

/// The higher end of an entry's edge.
fn higher_end(entry: u64) -> u32 {
    (entry >> 32) as u32
}

/// The corner of an entry.
fn corner(entry: u64) -> u32 {
    entry as u32 >> 1
}

/// Bucket entries by an edge's lower end, each bucket sized exactly (a counting pass over the edges first).
struct Buckets {
    entries: Vec<u64>,
    /// Where each bucket starts in `entries`.
    start: Vec<u32>,
    /// Where each bucket's next entry goes.
    next: Vec<u32>,
}

impl Buckets {
    /// Empty buckets for the edges of the triangles (`id`: their corners' positions, numbered below `positions`).
    fn for_edges(id: &[u32], positions: usize) -> Self {
        let mut next = vec![0u32; positions];
        for_each_edge(id, |_, a, b| next[a.min(b) as usize] += 1);
        let mut total = 0;
        for n in &mut next {
            (*n, total) = (total, total + *n);
        }
        Self { entries: vec![0; total as usize], start: next.clone(), next }
    }

    /// Adds `entry` to bucket `p`.
    fn push(&mut self, p: u32, entry: u64) {
        let next = &mut self.next[p as usize];
        self.entries[*next as usize] = entry;
        *next += 1;
    }

    /// The entries of bucket `p`, in the order they were added.
    fn bucket(&mut self, p: usize) -> &mut [u64] {
        &mut self.entries[self.start[p] as usize..self.next[p] as usize]
    }
}

/// The edges of the triangles with area, by how many corners walk each.
pub(crate) struct Edges {
    /// Each corner's partner on a manifold edge (walked by exactly two corners), or'ed with
    /// [`SAME_DIRECTION`] when both walk it the same way; else [`NO_PARTNER`].
    pub partner: Vec<u32>,
    /// Corners alone on their edge (a border).
    pub border: Vec<u32>,
    /// The corners of the non-manifold edges (walked three or more times), ascending within an edge.
    corners: Vec<u32>,
    /// Each non-manifold edge's corners in `corners`, in order of their first corner.
    groups: Vec<Range<u32>>,
}

impl Edges {
    /// Groups the corners of the triangles (three per triangle, `id` their positions, numbered below
    /// `positions`) by the edge they walk, leaving out triangles without area.
    pub(crate) fn of(id: &[u32], positions: usize) -> Self {
        let mut bucketed = Buckets::for_edges(id, positions);
        for_each_edge(id, |c, a, b| bucketed.push(a.min(b), entry(c, a, b)));
        let mut found =
            Self { partner: vec![NO_PARTNER; id.len()], border: Vec::new(), corners: Vec::new(), groups: Vec::new() };
        for p in 0..positions {
            found.pair(bucketed.bucket(p));
        }
        let corners = &found.corners;
        found.groups.sort_unstable_by_key(|g| corners[g.start as usize]);
        found
    }

    /// Pairs the corners of one bucket (entries in corner order) that walk the same edge: an insertion sort
    /// (a bucket holds a handful of corners) makes each edge's corners a run, in corner order.
    fn pair(&mut self, bucket: &mut [u64]) {
        for i in 1..bucket.len() {
            let entry = bucket[i];
            let mut j = i;
            while j > 0 && bucket[j - 1] > entry {
                bucket[j] = bucket[j - 1];
                j -= 1;
            }
            bucket[j] = entry;
        }
        // Most edges are walked twice: those take the first branch, without looking for the run's end.
        let mut i = 0;
        while let Some(&first) = bucket.get(i) {
            let on_edge = |j: usize| bucket.get(j).is_some_and(|&e| higher_end(e) == higher_end(first));
            if !on_edge(i + 1) {
                self.border.push(corner(first));
                i += 1;
            } else if !on_edge(i + 2) {
                self.partners(first, bucket[i + 1]);
                i += 2;
            } else {
                let end = (i + 3..).find(|&j| !on_edge(j)).unwrap_or(bucket.len());
                self.non_manifold_edge(&bucket[i..end]);
                i = end;
            }
        }
    }

    /// Makes the corners of entries `a` and `b` partners on their edge.
    fn partners(&mut self, a: u64, b: u64) {
        // Both walk it from the same end: their last bits agree.
        let same = ((a ^ b ^ 1) as u32 & 1) * SAME_DIRECTION;
        self.partner[corner(a) as usize] = corner(b) | same;
        self.partner[corner(b) as usize] = corner(a) | same;
    }

    /// Records a non-manifold edge, walked by the corners of `edge` (its entries, in corner order).
    fn non_manifold_edge(&mut self, edge: &[u64]) {
        let from = self.corners.len() as u32;
        self.corners.extend(edge.iter().map(|&e| corner(e)));
        self.groups.push(from..self.corners.len() as u32);
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
        // Two triangles walking an edge the same way (one of them reversed).
        let same = Edges::of(&[0, 1, 2, 0, 1, 3], 4);
        assert_eq!(same.partner[..4], [3 | SAME_DIRECTION, NO_PARTNER, NO_PARTNER, SAME_DIRECTION]);
        assert_eq!(edges.partner.iter().filter(|&&p| p != NO_PARTNER).count(), 2);
        let mut border = edges.border.clone();
        border.sort_unstable();
        assert_eq!(border, [2, 4, 5, 7, 8, 10, 11]);
        assert!(ascends(&id, 0) && !ascends(&id, 3) && !has_area(&id, 4));
    }
}
