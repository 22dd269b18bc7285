//! Orientation for the winding fill: finds the model's closed parts, orients each consistently and gives
//! each triangle its [`Role`] in the column count of [`crate::fill`].
//!
//! # As in the file, when every column agrees
//!
//! First the triangles are taken facing as they do in the file. When in every column their steps add up
//! to zero and the winding number never drops below zero, these are the roles: no part can be inside out
//! there (its inside would wind −1) except as a cavity wall within other material, which is what it is
//! kept as anyway, a part with reversed triangles unbalances the columns through them, and an open sheet
//! is closed as far as any column can tell. That costs one pass over the crossings, and it is the case
//! for well-made models (every closed model of the corpus). Otherwise the parts are analysed:
//!
//! # Parts
//!
//! Corners are welded by their exact grid-space position (the positions the column test sees). A *sheet*
//! is a set of triangles connected through manifold edges (edges used by exactly two triangles); the walk
//! over those edges orients it consistently (each triangle keeps or reverses its corner order; the sheet
//! takes the orientation most of its triangles have in the file) unless a cycle contradicts itself. A
//! sheet is *open* when it cannot be oriented or has a border edge (used once); a non-manifold edge (used
//! three or more times) must be walked equally often in both directions by the sheets meeting there,
//! otherwise they are all open (repeated until every edge balances). The sheets left form closed surfaces;
//! a *closed part* is a set of them joined across the non-manifold edges they do not balance on their own.
//! So a sphere whose equator is shared with a cylinder's rim (a capsule built of overlapping parts) is one
//! closed part, two boxes sharing only an edge are two, and a box with a fin glued to one edge is a closed
//! box and an open fin.
//!
//! # Orientation of a closed part
//!
//! With its sheets oriented as above (so a few reversed triangles, or every other one, are corrected),
//! the part's signed volume tells whether it faces outwards (positive: it counts as it is) or inwards.
//! A part facing inwards is a *cavity* and keeps that orientation — its winding is −1 inside, so it
//! subtracts — only when no crossing of it with a grid column lies outside the material of the other
//! parts: the parts facing outwards, by the nonzero rule, plus the parity sheets, by parity (a crossing in
//! a column whose parity crossings do not pair up is outside only when it is outside the winding material
//! too). That is the inner wall of a hollow ball, even one whose outer wall has a hole. Otherwise — an
//! inside-out part on its own, or pushed half into another part — it is reversed as a whole and adds.
//! (A whole file turned inside out therefore fills as if it were not, except that a cavity wall in it,
//! now facing outwards, fills its cavity.)
//!
//! # Sheets that cannot be closed
//!
//! Open sheets (border edges: the fried egg's white, a model closed only through T-junctions), unbalanced
//! non-manifold ones and non-orientable ones count by parity (see the column count in
//! [`crate::fill`]), so a model made only of such parts fills exactly as whole-model parity did.

mod cache;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::DVec3;
use rayon::prelude::*;
use robust::{Coord, orient2d};

use crate::fill::{Columns, parity_counts};
use crate::geom::GridTriangle;

pub(crate) use cache::closed_parts;

/// How a triangle's column crossings count.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Role {
    /// A triangle of a closed part whose outward side faces down: a column crossing it upwards enters
    /// the part (winding +1).
    Enters,
    /// A triangle of a closed part whose outward side faces up: crossing it upwards leaves (winding −1).
    Leaves,
    /// A triangle of a part that cannot be oriented: counts by parity.
    Parity,
}

impl Role {
    /// The change of the winding number when a column crosses the triangle upwards (0 for parity).
    pub fn step(self) -> i32 {
        match self {
            Role::Enters => 1,
            Role::Leaves => -1,
            Role::Parity => 0,
        }
    }

    /// The role of the triangle with its corner order reversed.
    fn reversed(self) -> Self {
        match self {
            Role::Enters => Role::Leaves,
            Role::Leaves => Role::Enters,
            Role::Parity => Role::Parity,
        }
    }
}

/// Marks a triangle that belongs to no part (two corners at the same position: no surface).
const NO_PART: u32 = u32::MAX;

/// A corner's exact grid-space position as bits (−0 and +0 alike).
fn position_key(v: DVec3) -> [u64; 3] {
    [v.x, v.y, v.z].map(|c| (c + 0.0).to_bits())
}

/// A 64-bit mix (splitmix64's finalizer).
fn mix(mut x: u64) -> u64 {
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// A hash of a position.
fn position_hash(key: [u64; 3]) -> u64 {
    key.iter().fold(0x9e37_79b9_7f4a_7c15, |h, &w| mix(h ^ w))
}

/// Edge `corner % 3` of triangle `corner / 3` runs from its corner k to corner k + 1.
fn edge_ends(tris: &[GridTriangle], corner: u32) -> ([u64; 3], [u64; 3]) {
    let t = &tris[corner as usize / 3];
    let k = corner as usize % 3;
    (position_key(t[k]), position_key(t[(k + 1) % 3]))
}

/// The edge of `corner` without its direction (ends in ascending order), and whether the corner's
/// triangle walks it from the smaller end to the larger.
fn undirected(tris: &[GridTriangle], corner: u32) -> ([[u64; 3]; 2], bool) {
    let (a, b) = edge_ends(tris, corner);
    if a < b { ([a, b], true) } else { ([b, a], false) }
}

/// Union–find over triangles that also tracks, for each triangle, whether its corner order must be
/// reversed relative to its set's root for the set to be consistently oriented.
struct OrientingUnionFind {
    parent: Vec<u32>,
    /// Reversed relative to the parent.
    reversed: Vec<bool>,
    size: Vec<u32>,
    /// Per root: a cycle of constraints contradicted itself (the set cannot be oriented).
    contradiction: Vec<bool>,
}

impl OrientingUnionFind {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
            reversed: vec![false; n],
            size: vec![1; n],
            contradiction: vec![false; n],
        }
    }

    /// The root of `t` and whether `t` is reversed relative to it (halving the path: each node on it is
    /// pointed to its grandparent, in one pass).
    fn find(&mut self, t: u32) -> (u32, bool) {
        let (mut node, mut reversed) = (t, false);
        loop {
            let parent = self.parent[node as usize];
            if parent == node {
                return (node, reversed);
            }
            // A root is never reversed, so pointing a root's child at the root changes nothing.
            let grandparent = self.parent[parent as usize];
            self.reversed[node as usize] ^= self.reversed[parent as usize];
            self.parent[node as usize] = grandparent;
            reversed ^= self.reversed[node as usize];
            node = grandparent;
        }
    }

    /// Records that `a` and `b` share a manifold edge; `differ`: one of them must be reversed relative to
    /// the other (they walk the edge in the same direction).
    fn join(&mut self, a: u32, b: u32, differ: bool) {
        let (ra, pa) = self.find(a);
        let (rb, pb) = self.find(b);
        if ra == rb {
            self.contradiction[ra as usize] |= pa ^ pb != differ;
            return;
        }
        let (big, small) = if self.size[ra as usize] >= self.size[rb as usize] { (ra, rb) } else { (rb, ra) };
        self.parent[small as usize] = big;
        self.reversed[small as usize] = pa ^ pb ^ differ;
        self.size[big as usize] += self.size[small as usize];
        self.contradiction[big as usize] |= self.contradiction[small as usize];
    }
}

/// The model's closed parts.
#[derive(Debug, PartialEq)]
pub(crate) struct Parts {
    /// The closed part of each triangle, or [`NO_PART`] (a triangle of an open sheet, or without area).
    of: Vec<u32>,
    /// Whether each triangle is reversed relative to its sheet's orientation (the one most of the sheet's
    /// triangles have in the file).
    reversed: Vec<bool>,
    /// The number of closed parts.
    count: usize,
}

impl Parts {
    /// Finds the closed parts of `tris`.
    pub(crate) fn find(tris: &[GridTriangle]) -> Self {
        // Every edge of every triangle, keyed by a hash of its two ends (the sum of their hashes: the same
        // whichever way it is walked); the edges of triangles without three distinct corners get the key
        // `u64::MAX` and are left out below.
        let mut edges = vec![(0u64, 0u32); 3 * tris.len()];
        edges.par_chunks_mut(3).zip(tris.par_iter()).enumerate().for_each(|(t, (out, tri))| {
            let keys = tri.map(position_key);
            let hashes = keys.map(position_hash);
            let area = has_area(keys);
            for k in 0..3 {
                let hash = if area { mix(hashes[k].wrapping_add(hashes[(k + 1) % 3])) } else { u64::MAX };
                out[k] = (hash, (3 * t + k) as u32);
            }
        });
        // Only the hash orders: corners with equal hashes are grouped by position below whatever their order.
        let edges = grouped_by_hash(&edges);
        // A run of two corners with the same hash is all but always a manifold edge: note the partners
        // now and check them exactly below. Other runs are split into exact groups here (rare).
        let mut partner = vec![NO_PART; 3 * tris.len()];
        let mut union = OrientingUnionFind::new(tris.len());
        // Border and non-manifold edges, as groups of corners walking the same edge.
        let mut unpaired: Vec<Vec<u32>> = Vec::new();
        for run in edges.chunk_by(|a, b| a.0 == b.0) {
            let run_has_area = |&&(_, c): &&(u64, u32)| has_area(tris[c as usize / 3].map(position_key));
            if let [(hash, a), (_, b)] = *run
                && hash != u64::MAX
            {
                (partner[a as usize], partner[b as usize]) = (b, a);
                continue;
            }
            for group in same_edge_groups(tris, run.iter().filter(run_has_area).map(|e| e.1).collect()) {
                match group[..] {
                    [a, b] => join_across(tris, &mut union, a, b),
                    _ => unpaired.push(group),
                }
            }
        }
        // In triangle order: partners are usually near each other in memory, the hash order is random.
        for (a, &b) in partner.iter().enumerate() {
            let a = a as u32;
            if b == NO_PART || b < a {
                continue;
            }
            match same_edge(tris, a, b) {
                Some(same_direction) => union.join(a / 3, b / 3, same_direction),
                None => unpaired.extend([vec![a], vec![b]]),
            }
        }
        // In corner order, so that which sheets stay closed does not depend on the hash (nor on whether the
        // positions are the grid's or the soup's: see `cache`).
        unpaired.sort_unstable_by_key(|group| group[0]);
        let sheets = Sheets::of(tris, union);
        Self::close(tris, sheets, &unpaired)
    }

    /// Drops the sheets that cannot be part of a closed surface, then joins the rest into parts across
    /// non-manifold edges.
    fn close(tris: &[GridTriangle], sheets: Sheets, unpaired: &[Vec<u32>]) -> Self {
        let Sheets { of: sheet_of, reversed, mut open } = sheets;
        let sheet = |corner: u32| sheet_of[corner as usize / 3] as usize;
        for group in unpaired.iter().filter(|g| g.len() == 1) {
            open[sheet(group[0])] = true;
        }
        // A non-manifold edge must be walked equally often both ways by the sheets kept; where it is not,
        // the sheets meeting there are dropped too (which may unbalance another edge: repeat).
        let non_manifold: Vec<&Vec<u32>> = unpaired.iter().filter(|g| g.len() > 2).collect();
        let mut changed = true;
        while changed {
            changed = false;
            for group in &non_manifold {
                let balance: i32 = group
                    .iter()
                    .filter(|&&c| !open[sheet(c)])
                    .map(|&c| if undirected(tris, c).1 ^ reversed[c as usize / 3] { 1 } else { -1 })
                    .sum();
                if balance != 0 {
                    for &c in group.iter() {
                        changed |= !open[sheet(c)];
                        open[sheet(c)] = true;
                    }
                }
            }
        }
        // Parts: the kept sheets, joined where they close each other — across a non-manifold edge that
        // they walk unequally often each way on their own (two boxes sharing an edge stay two parts).
        let mut union = OrientingUnionFind::new(open.len());
        for group in &non_manifold {
            let mut balance: Vec<(usize, i32)> = Vec::new();
            for &c in group.iter().filter(|&&c| !open[sheet(c)]) {
                let step = if undirected(tris, c).1 ^ reversed[c as usize / 3] { 1 } else { -1 };
                match balance.iter_mut().find(|(s, _)| *s == sheet(c)) {
                    Some((_, sum)) => *sum += step,
                    None => balance.push((sheet(c), step)),
                }
            }
            let mut unbalanced = balance.iter().filter(|b| b.1 != 0).map(|b| b.0 as u32);
            if let Some(first) = unbalanced.next() {
                for other in unbalanced {
                    union.join(first, other, false);
                }
            }
        }
        let mut part_of_root = vec![NO_PART; open.len()];
        let mut parts = Self { of: vec![NO_PART; tris.len()], reversed, count: 0 };
        for (t, &s) in sheet_of.iter().enumerate() {
            let s = s as usize;
            if s == NO_PART as usize || open[s] {
                continue;
            }
            let root = union.find(s as u32).0 as usize;
            if part_of_root[root] == NO_PART {
                part_of_root[root] = parts.count as u32;
                parts.count += 1;
            }
            parts.of[t] = part_of_root[root];
        }
        parts
    }
}

/// `edges` with equal hashes (the first field) next to each other. The hashes are uniform, so a counting
/// sort by their top bits leaves buckets of one or two edges on average, and only a bucket of three or
/// more needs sorting to bring its equal hashes together: two passes over the edges instead of a
/// comparison sort.
fn grouped_by_hash(edges: &[(u64, u32)]) -> Vec<(u64, u32)> {
    let bits = edges.len().max(2).ilog2().min(24);
    let bucket = |hash: u64| (hash >> (64 - bits)) as usize;
    let mut start = vec![0u32; (1 << bits) + 1];
    for e in edges {
        start[bucket(e.0) + 1] += 1;
    }
    for b in 1..start.len() {
        start[b] += start[b - 1];
    }
    let mut next = start.clone();
    let mut sorted = vec![(0, 0); edges.len()];
    for &e in edges {
        let slot = &mut next[bucket(e.0)];
        sorted[*slot as usize] = e;
        *slot += 1;
    }
    for b in start.windows(2) {
        if b[1] - b[0] > 2 {
            sorted[b[0] as usize..b[1] as usize].sort_unstable_by_key(|e| e.0);
        }
    }
    sorted
}

/// Whether corners `a` and `b` walk the same edge (`Some`), and if so whether in the same direction. The
/// coordinates are finite, so comparing them is comparing their position keys.
fn same_edge(tris: &[GridTriangle], a: u32, b: u32) -> Option<bool> {
    let ends = |corner: u32| {
        let t = &tris[corner as usize / 3];
        let k = corner as usize % 3;
        (t[k], t[(k + 1) % 3])
    };
    let ((a0, a1), (b0, b1)) = (ends(a), ends(b));
    if a0 == b1 && a1 == b0 {
        Some(false)
    } else if a0 == b0 && a1 == b1 {
        Some(true)
    } else {
        None
    }
}

/// Joins the triangles of corners `a` and `b`, which walk the same manifold edge.
fn join_across(tris: &[GridTriangle], union: &mut OrientingUnionFind, a: u32, b: u32) {
    union.join(a / 3, b / 3, undirected(tris, a).1 == undirected(tris, b).1);
}

/// Whether a triangle's corners (as position keys) are three different points.
fn has_area(keys: [[u64; 3]; 3]) -> bool {
    keys[0] != keys[1] && keys[1] != keys[2] && keys[2] != keys[0]
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
    /// Numbers the sets of `union` in order of their first triangle and orients each as most of its
    /// triangles are in the file (on a tie, as its first triangle is: never as the union's root happens to
    /// be, which depends on the order of the joins).
    fn of(tris: &[GridTriangle], mut union: OrientingUnionFind) -> Self {
        let n = tris.len();
        let mut sheet_of_root = vec![NO_PART; n];
        let mut sheets = Self { of: vec![NO_PART; n], reversed: vec![false; n], open: Vec::new() };
        // Per sheet: triangles, how many are reversed relative to the root, and whether the first is.
        let mut size: Vec<usize> = Vec::new();
        let mut against_root: Vec<usize> = Vec::new();
        let mut first_against_root: Vec<bool> = Vec::new();
        for (t, tri) in tris.iter().enumerate() {
            if !has_area(tri.map(position_key)) {
                continue;
            }
            let (root, reversed) = union.find(t as u32);
            if sheet_of_root[root as usize] == NO_PART {
                sheet_of_root[root as usize] = sheets.open.len() as u32;
                sheets.open.push(union.contradiction[root as usize]);
                size.push(0);
                against_root.push(0);
                first_against_root.push(reversed);
            }
            let s = sheet_of_root[root as usize];
            sheets.of[t] = s;
            sheets.reversed[t] = reversed;
            size[s as usize] += 1;
            against_root[s as usize] += usize::from(reversed);
        }
        let flip: Vec<bool> = (0..size.len())
            .map(|s| 2 * against_root[s] > size[s] || (2 * against_root[s] == size[s] && first_against_root[s]))
            .collect();
        for t in 0..n {
            let s = sheets.of[t] as usize;
            if s != NO_PART as usize && flip[s] {
                sheets.reversed[t] = !sheets.reversed[t];
            }
        }
        sheets
    }
}

/// Splits corners whose edges have the same hash into groups walking the same edge (almost always one
/// group: a hash collision of different edges is all but impossible, but is handled exactly).
fn same_edge_groups(tris: &[GridTriangle], mut corners: Vec<u32>) -> Vec<Vec<u32>> {
    corners.sort_by_key(|&c| (undirected(tris, c).0, c));
    corners.chunk_by(|&a, &b| undirected(tris, a).0 == undirected(tris, b).0).map(<[u32]>::to_vec).collect()
}

/// The role of every triangle under the nonzero winding rule (see the module docs). `columns` are the
/// model's column crossings when the caller has them; otherwise `crossings` computes them. `closed_parts`
/// gives the closed parts of `tris` ([`Parts::find`], or [`closed_parts`] reusing a soup's), when the
/// triangles as in the file do not do.
pub(crate) fn winding_roles(
    tris: &[GridTriangle],
    columns: Option<&Columns>,
    crossings: impl FnOnce() -> Columns,
    closed_parts: impl FnOnce() -> Arc<Parts>,
) -> Vec<Role> {
    let computed;
    let columns = match columns {
        Some(c) => c,
        None => {
            computed = crossings();
            &computed
        }
    };
    let as_in_file: Vec<Role> = tris.par_iter().map(facing_role).collect();
    if consistent_as_in_file(columns, &as_in_file) {
        return as_in_file;
    }
    let parts = closed_parts();
    // Signed volume (×6) of each closed part with its sheets oriented as in the file.
    let mut volume = vec![0.0f64; parts.count];
    for (t, tri) in tris.iter().enumerate() {
        if parts.of[t] != NO_PART {
            let [a, b, c] = *tri;
            let det = a.dot(b.cross(c));
            volume[parts.of[t] as usize] += if parts.reversed[t] { -det } else { det };
        }
    }
    // Facing inwards in the file: a negative volume.
    let inward: Vec<bool> = volume.iter().map(|&v| v < 0.0).collect();
    let mut roles: Vec<Role> = as_in_file
        .into_par_iter()
        .enumerate()
        .map(|(t, role)| match (parts.of[t], parts.reversed[t]) {
            (NO_PART, _) => Role::Parity,
            (_, reversed) if reversed => role.reversed(),
            _ => role,
        })
        .collect();
    if !inward.contains(&true) {
        return roles;
    }
    let exposed = exposed_parts(columns, &roles, &parts.of, &inward);
    for (t, role) in roles.iter_mut().enumerate() {
        if parts.of[t] != NO_PART && exposed[parts.of[t] as usize] {
            *role = role.reversed();
        }
    }
    roles
}

/// The winding role of a triangle with its corner order as in the file.
fn facing_role(t: &GridTriangle) -> Role {
    let xy = |v: DVec3| Coord { x: v.x, y: v.y };
    let faces_up = orient2d(xy(t[0]), xy(t[1]), xy(t[2])) > 0.0;
    if faces_up { Role::Leaves } else { Role::Enters }
}

/// Whether the triangles as they face in the file already wind consistently as far as any column can
/// tell: in every column the steps add up to zero and the winding number never drops below zero.
fn consistent_as_in_file(columns: &Columns, roles: &[Role]) -> bool {
    (0..columns.len()).into_par_iter().all(|col| {
        let mut winding = 0i32;
        for c in columns.column(col) {
            winding += roles[c.triangle as usize].step();
            if winding < 0 {
                return false;
            }
        }
        winding == 0
    })
}

/// Which parts facing inwards (`inward`) have a column crossing outside the material of the other parts
/// (the winding of the parts not facing inwards plus the parity of the parity parts, counted from below;
/// in a column with an odd number of parity crossings only a crossing inside winding material counts,
/// the others are undecided).
fn exposed_parts(columns: &Columns, roles: &[Role], part_of: &[u32], inward: &[bool]) -> Vec<bool> {
    let exposed: Vec<AtomicBool> = inward.iter().map(|_| AtomicBool::new(false)).collect();
    (0..columns.len()).into_par_iter().for_each(|col| {
        let crossings = columns.column(col);
        let parity_counts = parity_counts(crossings, roles);
        let (mut winding, mut parity) = (0i32, 0i32);
        for c in crossings {
            let t = c.triangle as usize;
            let part = part_of[t] as usize;
            if part != NO_PART as usize && inward[part] {
                // Outside: no material here — and known to be none, which a column whose parity crossings
                // do not pair up (a hole in a parity part) cannot tell.
                if winding + parity == 0 && parity_counts {
                    exposed[part].store(true, Ordering::Relaxed);
                }
                continue;
            }
            match roles[t] {
                Role::Parity => parity ^= i32::from(parity_counts),
                role => winding += role.step(),
            }
        }
    });
    exposed.into_iter().map(AtomicBool::into_inner).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fill::crossings_by_rasterizing;
    use crate::grid::{GridSize, GridSpec};
    use crate::shapes::{IndexedMesh, cuboid};
    use crate::soup::TriangleSoup;

    fn grid_tris(mesh: &IndexedMesh) -> Vec<GridTriangle> {
        mesh.triangles.iter().map(|t| t.map(|i| DVec3::from(mesh.positions[i as usize].map(f64::from)))).collect()
    }

    /// The roles of `mesh`'s triangles, voxelized in a 4 × 4 × 4 grid around it.
    fn roles(mesh: &IndexedMesh) -> Vec<Role> {
        let soup = TriangleSoup::from_mesh(mesh, [1.0; 4]);
        let spec = GridSpec::fit(&soup, 9.0, GridSize::Resolution(4), 1.0, 1 << 20).unwrap();
        let tris = spec.grid_triangles(&soup);
        winding_roles(&tris, None, || crossings_by_rasterizing(&spec, &tris), || Arc::new(Parts::find(&tris)))
    }

    fn reversed(mut mesh: IndexedMesh, every: usize) -> IndexedMesh {
        for t in mesh.triangles.iter_mut().step_by(every) {
            t.swap(1, 2);
        }
        mesh
    }

    fn block() -> IndexedMesh {
        cuboid([0.25; 3], [3.75; 3])
    }

    #[test]
    fn grouping_by_hash_brings_equal_hashes_together() {
        // 3000 edges over 700 hashes, spread over the buckets and crowded into one (the top bits alike).
        let hashes = (0..3000u64).map(|i| match i % 7 {
            0 => u64::MAX - (i % 5),
            _ => mix(i % 700),
        });
        let edges: Vec<(u64, u32)> = hashes.zip(0..).collect();
        let grouped = grouped_by_hash(&edges);
        let mut seen = std::collections::HashSet::new();
        for run in grouped.chunk_by(|a, b| a.0 == b.0) {
            assert!(seen.insert(run[0].0), "hash {:x} in two runs", run[0].0);
        }
        let (mut a, mut b) = (edges.clone(), grouped);
        a.sort_unstable();
        b.sort_unstable();
        assert_eq!(a, b, "the same edges");
    }

    #[test]
    fn a_box_is_one_closed_part_and_its_bottom_enters() {
        let parts = Parts::find(&grid_tris(&block()));
        assert_eq!((parts.count, parts.of.iter().all(|&p| p == 0)), (1, true));
        // The bottom (normal −Z) enters, the top leaves; the sides are edge-on (the last four triangles are
        // the horizontal faces).
        let r = roles(&block());
        assert_eq!(r[8..], [Role::Enters, Role::Enters, Role::Leaves, Role::Leaves]);
    }

    #[test]
    fn reversed_triangles_and_inside_out_parts_are_corrected() {
        let good = roles(&block());
        for every in [1, 3, 4] {
            assert_eq!(roles(&reversed(block(), every))[8..], good[8..], "every {every}th triangle reversed");
        }
    }

    #[test]
    fn a_sheet_split_half_and_half_faces_as_its_first_triangle() {
        // Every other triangle reversed: six each way. The sheet takes the first triangle's facing (reversed
        // in the file), whatever the order of the joins; the part is then inside out, on its own, and flipped.
        let half = reversed(block(), 2);
        let parts = Parts::find(&grid_tris(&half));
        assert_eq!(parts.count, 1);
        assert_eq!(parts.reversed, (0..12).map(|t| t % 2 == 1).collect::<Vec<_>>());
        assert_eq!(roles(&half)[8..], roles(&block())[8..]);
    }

    #[test]
    fn a_cavity_facing_inwards_is_kept() {
        let mut hollow = block();
        let inner = reversed(cuboid([1.25; 3], [2.75; 3]), 1);
        hollow.positions.extend(&inner.positions);
        hollow.triangles.extend(inner.triangles.iter().map(|t| t.map(|i| i + 8)));
        let r = roles(&hollow);
        // The inner bottom leaves (the column leaves the solid into the cavity), the inner top enters.
        assert_eq!(r[20..], [Role::Leaves, Role::Leaves, Role::Enters, Role::Enters]);
        // Even when the outer box's winding has to be repaired.
        let mut mixed = hollow.clone();
        mixed.triangles[8].swap(1, 2);
        assert_eq!(roles(&mixed)[20..], r[20..]);
    }

    #[test]
    fn open_and_non_manifold_sheets_count_by_parity() {
        let mut open = block();
        open.triangles.pop();
        assert!(roles(&open).iter().all(|&r| r == Role::Parity));
        // Two boxes sharing one edge: two closed parts. A fin on a box's edge: the box stays closed.
        let mut two = cuboid([0.0; 3], [1.0; 3]);
        let other = cuboid([1.0; 3], [2.0; 3]);
        two.positions.extend(&other.positions);
        two.triangles.extend(other.triangles.iter().map(|t| t.map(|i| i + 8)));
        assert_eq!(Parts::find(&grid_tris(&two)).count, 2);
        let mut fin = cuboid([0.0; 3], [1.0; 3]);
        fin.positions.push([0.5, -0.5, 1.5]);
        fin.triangles.push([4, 5, 8]);
        let parts = Parts::find(&grid_tris(&fin));
        assert_eq!(parts.count, 1);
        assert_eq!(parts.of[..12], [0; 12]);
        assert_eq!(parts.of[12], NO_PART);
    }
}
