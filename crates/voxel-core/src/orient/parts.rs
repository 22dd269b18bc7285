//! The closed parts of a set of triangles (see the module docs of [`super`], Parts): sheets walked across
//! manifold edges and oriented consistently, the open ones dropped, the rest joined across the non-manifold
//! edges they do not balance alone, and each part's facing from its signed volume.

use glam::DVec3;

use super::edges::{Edges, NO_PARTNER, SAME_DIRECTION, ascends, has_area};
use super::weld;
use crate::grid::GridTriangles;

/// Marks a triangle that belongs to no closed part (of an open sheet, or with two corners at the same position).
pub(crate) const NO_PART: u32 = u32::MAX;

/// Union–find over sheets (the non-manifold edges join them into parts).
struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        Self { parent: (0..n as u32).collect() }
    }

    /// The root of `s` (halving the path: each node on it is pointed to its grandparent).
    fn find(&mut self, mut s: u32) -> u32 {
        while self.parent[s as usize] != s {
            let grandparent = self.parent[self.parent[s as usize] as usize];
            self.parent[s as usize] = grandparent;
            s = grandparent;
        }
        s
    }

    /// Puts `a` and `b` in one set (rooted at the lower root: the joins' order does not matter).
    fn join(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        self.parent[ra.max(rb) as usize] = ra.min(rb);
    }
}

/// The model's closed parts.
#[derive(Debug, PartialEq)]
pub(crate) struct Parts {
    /// The closed part of each triangle, or [`NO_PART`] (a triangle of an open sheet, or without area).
    pub of: Vec<u32>,
    /// Whether each triangle is reversed relative to its sheet's orientation (the one most of the sheet's
    /// triangles have in the file).
    pub reversed: Vec<bool>,
    /// Per closed part: whether it faces inwards (its signed volume, its sheets oriented, is negative).
    pub inward: Vec<bool>,
}

impl Parts {
    /// Finds the closed parts of `tris`, their corners welded by their exact grid-space positions.
    pub(crate) fn find(tris: &GridTriangles) -> Self {
        let welded = weld::weld_indexed(tris.vertices(), |&v| weld::grid_key(v), tris.corners());
        Self::of_welded(&welded.id, welded.first.len(), |t| tris.get(t))
    }

    /// The number of closed parts.
    pub(crate) fn count(&self) -> usize {
        self.inward.len()
    }

    /// Finds which way each closed part faces from the corners of its triangles (`corners` of triangle `t`,
    /// from any origin: a closed surface's signed volume does not depend on it).
    fn with_facing(mut self, corners: impl Fn(usize) -> [DVec3; 3]) -> Self {
        let mut volume = vec![0.0f64; self.count()];
        for (t, (&part, &reversed)) in self.of.iter().zip(&self.reversed).enumerate() {
            if part != NO_PART {
                let [a, b, c] = corners(t);
                let det = a.dot(b.cross(c));
                volume[part as usize] += if reversed { -det } else { det };
            }
        }
        self.inward = volume.iter().map(|&v| v < 0.0).collect();
        self
    }

    /// Finds the closed parts of triangles whose corners (three per triangle) are at the positions `id`
    /// (numbered below `positions`), and which way each faces from the corners' coordinates (`corners` of
    /// triangle `t`). The parts depend only on which corners share a position and on the triangle order: ties
    /// and non-manifold edges are decided in triangle and corner order.
    pub(crate) fn of_welded(id: &[u32], positions: usize, corners: impl Fn(usize) -> [DVec3; 3]) -> Self {
        let edges = Edges::of(id, positions);
        let mut sheets = Sheets::of(id, &edges.partner);
        for &c in &edges.border {
            let s = sheets.of[c as usize / 3] as usize;
            sheets.open[s] = true;
        }
        Self::close(id, sheets, &edges).with_facing(corners)
    }

    /// Drops the sheets that cannot be part of a closed surface, then joins the rest into parts across
    /// non-manifold edges.
    fn close(id: &[u32], sheets: Sheets, edges: &Edges) -> Self {
        let Sheets { of: sheet_of, reversed, mut open } = sheets;
        let sheet = |corner: u32| sheet_of[corner as usize / 3] as usize;
        // Each corner's step along its (non-manifold) edge, its sheet oriented: +1 ascending, −1 descending.
        let step = |c: u32| if ascends(id, c) ^ reversed[c as usize / 3] { 1 } else { -1 };
        // A non-manifold edge must be walked equally often both ways by the sheets kept; where it is not,
        // the sheets meeting there are dropped too (which may unbalance another edge: repeat).
        let mut changed = true;
        while changed {
            changed = false;
            for group in edges.non_manifold() {
                let balance: i32 = group.iter().filter(|&&c| !open[sheet(c)]).map(|&c| step(c)).sum();
                if balance != 0 {
                    for &c in group {
                        changed |= !open[sheet(c)];
                        open[sheet(c)] = true;
                    }
                }
            }
        }
        // Parts: the kept sheets, joined where they close each other — across a non-manifold edge that
        // they walk unequally often each way on their own (two boxes sharing an edge stay two parts).
        let mut union = UnionFind::new(open.len());
        let mut balance: Vec<(usize, i32)> = Vec::new();
        for group in edges.non_manifold() {
            balance.clear();
            for &c in group.iter().filter(|&&c| !open[sheet(c)]) {
                match balance.iter_mut().find(|(s, _)| *s == sheet(c)) {
                    Some((_, sum)) => *sum += step(c),
                    None => balance.push((sheet(c), step(c))),
                }
            }
            let mut unbalanced = balance.iter().filter(|b| b.1 != 0).map(|b| b.0 as u32);
            if let Some(first) = unbalanced.next() {
                for other in unbalanced {
                    union.join(first, other);
                }
            }
        }
        // Numbered in order of their first triangle: of their first sheet, which is their root.
        let mut part_of_sheet = vec![NO_PART; open.len()];
        let mut count = 0;
        for s in (0..open.len()).filter(|&s| !open[s]) {
            let root = union.find(s as u32) as usize;
            if root == s {
                part_of_sheet[s] = count;
                count += 1;
            } else {
                part_of_sheet[s] = part_of_sheet[root];
            }
        }
        let of = sheet_of.iter().map(|&s| if s == NO_PART { NO_PART } else { part_of_sheet[s as usize] }).collect();
        Self { of, reversed, inward: vec![false; count as usize] }
    }
}

/// Sheets: triangles connected through manifold edges, each oriented consistently where it can be.
struct Sheets {
    /// The sheet of each triangle ([`NO_PART`] for triangles without three distinct corners).
    of: Vec<u32>,
    /// Whether each triangle is reversed relative to its sheet's orientation.
    reversed: Vec<bool>,
    /// Per sheet: whether it is open (so far: whether it cannot be oriented).
    open: Vec<bool>,
}

impl Sheets {
    /// Walks the triangles (corners at positions `id`) across their manifold edges ([`Edges::partner`]), numbering
    /// the sheets in order of their first triangle, and orients each as most of its triangles are in the
    /// file (on a tie, as its first triangle is). Two triangles walking their shared edge the same way
    /// differ in orientation; a sheet where a cycle of them contradicts itself cannot be oriented (open).
    fn of(id: &[u32], partner: &[u32]) -> Self {
        let triangles = id.len() / 3;
        let mut seen = vec![UNSEEN; triangles];
        let mut walk = Walk { stack: vec![0; triangles], open: Vec::new(), against_most: Vec::new() };
        for first in 0..triangles {
            if seen[first] == UNSEEN && has_area(id, first) {
                walk.sheet(first as u32, &mut seen, partner);
            }
        }
        let Walk { open, against_most, .. } = walk;
        let of = seen.iter().map(|&v| ((v as i32) >> 1) as u32).collect();
        // Relative to the sheet's first triangle, then to the orientation most of the sheet has.
        let reversed = seen.iter().map(|&v| v != UNSEEN && ((v & 1 != 0) ^ against_most[(v >> 1) as usize])).collect();
        Self { of, reversed, open }
    }
}

/// Per triangle reached by the sheet walk: its sheet << 1 | whether it is reversed relative to the sheet's first
/// triangle. UNSEEN is even (not reversed) and gives NO_PART when shifted as an i32, as the sheet number does;
/// it is not a repeated byte, as `weld`'s empty slot mark.
const UNSEEN: u32 = u32::MAX - 1;

/// The sheet walk's state: its stack and what it found per sheet.
struct Walk {
    /// The triangles reached and not yet left: room for every triangle (each is pushed once).
    stack: Vec<u32>,
    /// Per sheet: whether a cycle contradicts itself.
    open: Vec<bool>,
    /// Per sheet: whether most of its triangles are reversed relative to its first one.
    against_most: Vec<bool>,
}

impl Walk {
    /// Walks a new sheet from its first triangle `first` across the manifold edges (`partner`), marking the
    /// triangles reached in `seen`.
    fn sheet(&mut self, first: u32, seen: &mut [u32], partner: &[u32]) {
        let s = self.open.len() as u32;
        let (mut size, mut against_first, mut contradiction) = (0usize, 0usize, false);
        seen[first as usize] = s << 1;
        self.stack[0] = first;
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let t = self.stack[top] as usize;
            size += 1;
            let here = seen[t];
            for &p in &partner[3 * t..3 * t + 3] {
                if p == NO_PARTNER {
                    continue;
                }
                let u = (p & !SAME_DIRECTION) as usize / 3;
                let there = here ^ u32::from(p & SAME_DIRECTION != 0);
                if seen[u] == UNSEEN {
                    seen[u] = there;
                    against_first += (there & 1) as usize;
                    self.stack[top] = u as u32;
                    top += 1;
                } else {
                    contradiction |= seen[u] != there;
                }
            }
        }
        self.open.push(contradiction);
        self.against_most.push(2 * against_first > size);
    }
}
