//! Which cells a triangle overlaps ([`overlaps`]): a triangle in one cell, across one cell boundary or in one layer
//! of cells takes a short way; any other, the separating axis test a column of cells at a time ([`CellTester`]),
//! past the columns its projection's footprint test places outside it.

use glam::DVec3;

use super::cells::CellTester;
use crate::float;
use crate::geom::GridTriangle;
use crate::grid::{GridSpec, GridTriangles};

/// The axis along which the normal `n` is largest (the first of equals).
fn dominant_axis(n: DVec3) -> usize {
    let an = n.abs();
    if an.x >= an.y && an.x >= an.z {
        0
    } else if an.y >= an.z {
        1
    } else {
        2
    }
}

/// How much of the triangle–box test a candidate cell needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Test {
    /// No test: the cell's footprint lies outside the triangle's projection.
    Outside,
    /// The box axes and the plane: the cell's footprint lies inside the triangle's projection.
    Plane,
    /// The whole separating axis test.
    Full,
}

/// Where a unit square of the plane across a triangle's dominant axis lies against the triangle's projection
/// on that plane, by a margin far above rounding. Inside, no edge of the triangle passes over the square, and
/// a cell above it overlaps the triangle exactly when the triangle's plane crosses the cell; outside, no cell
/// above it overlaps the triangle.
struct FootprintTest {
    /// Per edge: its start (u, v), its direction (du, dv) times the projection's orientation, and the
    /// smallest value its edge function must exceed at a square's centre.
    edges: [([f64; 2], [f64; 2], f64); 3],
}

impl FootprintTest {
    /// Prepares triangle `t` projected on axes `u` and `v`; `orientation` is the sign of its projected area.
    fn new(t: &[[f64; 3]; 3], orientation: f64, u: usize, v: usize) -> Self {
        let edges = [0, 1, 2].map(|k| {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let dir = [(b[u] - a[u]) * orientation, (b[v] - a[v]) * orientation];
            // The edge function's drop from a square's centre to its worst corner, plus a margin.
            let reach = 0.5 * (dir[0].abs() + dir[1].abs());
            ([a[u], a[v]], dir, reach * (1.0 + 1e-9) + 1e-9)
        });
        Self { edges }
    }

    /// Where the square [iu, iu + 1] × [iv, iv + 1] lies: strictly inside, strictly outside one edge (then
    /// that edge's direction × the dominant axis separates the triangle from every cell above the square),
    /// or across an edge, each with the margin.
    fn place(&self, iu: u32, iv: u32) -> Test {
        let (cu, cv) = (f64::from(iu) + 0.5, f64::from(iv) + 0.5);
        let mut inside = true;
        for &(a, dir, reach) in &self.edges {
            let e = dir[0] * (cv - a[1]) - dir[1] * (cu - a[0]);
            if e < -reach {
                return Test::Outside;
            }
            inside &= e > reach;
        }
        if inside { Test::Plane } else { Test::Full }
    }
}

/// The cell holding coordinate `v` along an axis of `cells` cells (clamped to the grid).
#[inline]
fn cell_of(v: f64, cells: u32) -> u32 {
    // Clamped first, so truncation is the floor (and avoids a libm call).
    v.clamp(0.0, f64::from(cells) - 1.0) as u32
}

/// The last cell that the extent [`from`, `to`] along an axis of `cells` cells reaches with positive length:
/// the cell of `to`, or the one before when `to` is a whole number (a cell boundary) above `from` (clamped to
/// the grid). `to` is clamped to [0, `cells`] before its floor is taken, and only a `to` in that range can
/// equal its floor.
#[inline]
fn last_cell_of(from: f64, to: f64, cells: u32) -> u32 {
    let floor = float::min(float::max(to, 0.0), f64::from(cells)) as u32;
    let boundary = to > from && floor > 0 && f64::from(floor) == to;
    (floor - u32::from(boundary)).min(cells - 1)
}

/// Up to this many candidate columns, a triangle's footprints are not placed against its projection. (The FlightHelmet
/// at R=128, whose triangles mostly span 2–9 columns, builds its shell in 9.5–9.7 ms warm with a limit of 2, 4 or 6,
/// where a limit of 9 took 10.7; the corpus's other models and the big scenes measured the same either way.)
const FEW_COLUMNS: u32 = 4;

/// Hands each cell that triangle `tri` overlaps to `out`, with how many cells the triangle may overlap (cells
/// half-open along every axis, so a triangle on a cell boundary lands in one cell, not two; a triangle whose extent
/// along an axis ends exactly on a cell boundary does not reach the next cell, which it would only touch along an
/// edge or at a point, so a face lying on cell boundaries gets the same cells however its coordinates were rounded
/// before the grid snapped them).
pub(super) fn overlaps(spec: &GridSpec, tris: &GridTriangles, tri: usize, out: &mut impl FnMut(u32, Reach)) {
    let t = tris.get(tri);
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    if n.length_squared() <= 0.0 || n.is_nan() {
        return; // zero-area triangles add no surface
    }
    let (lo, hi) = float::bounds(t);
    let [nx, ny, nz] = spec.dims;
    // The cells of the triangle's extent.
    let first = [cell_of(lo.x, nx), cell_of(lo.y, ny), cell_of(lo.z, nz)];
    let last = [last_cell_of(lo.x, hi.x, nx), last_cell_of(lo.y, hi.y, ny), last_cell_of(lo.z, hi.z, nz)];
    let crossed = (last[0] - first[0]) + (last[1] - first[1]) + (last[2] - first[2]);
    let mut push = |c: [u32; 3], reach| out(spec.index(c[0], c[1], c[2]) as u32, reach);
    if crossed == 0 {
        // The whole triangle sits in one cell: it overlaps that cell and no other.
        push(first, Reach::Few);
        return;
    }
    let inside = lo.cmpge(DVec3::ZERO).all() && hi.cmple(DVec3::new(f64::from(nx), f64::from(ny), f64::from(nz))).all();
    if crossed == 1 && inside {
        // The triangle crosses one cell boundary, strictly (it has points on both sides of it), and lies in one
        // cell along the other axes (in the grid, not clamped onto its edge): it overlaps the cells on both sides.
        push(first, Reach::Few);
        push(last, Reach::Few);
        return;
    }
    let mut push = |index| out(index, Reach::Many);
    let d = dominant_axis(n);
    if inside && in_one_layer(first[d], last[d], hi[d], spec.dims[d]) {
        overlaps_in_layer(&t, d, [first, last], spec.strides(), &mut push);
        return;
    }
    overlaps_across(spec, &t, n, [lo.to_array(), hi.to_array()], [first, last], &mut push);
}

/// How many cells a triangle of [`overlaps`] may overlap.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Reach {
    /// One or two: the next triangle mostly overlaps them too.
    Few,
    /// More (the triangle takes the whole test).
    Many,
}

/// Whether a triangle inside the grid whose extent along its dominant axis ends at `hi` (in cells `first` to
/// `last` of `cells`) lies in one layer of cells for [`overlaps_in_layer`]: one cell along the axis, short of the
/// layer's upper face or in the grid's top layer. (A triangle whose extent ends on a lower layer's upper face,
/// touching it, takes the whole test: there the column test puts a column that meets the triangle only on that
/// face in the layer above; the top layer has none above it.)
fn in_one_layer(first: u32, last: u32, hi: f64, cells: u32) -> bool {
    first == last && (hi < f64::from(first + 1) || first + 1 == cells)
}

/// [`overlaps`] of a triangle `t` inside the grid that lies in one layer of cells across its dominant axis `d`
/// ([`in_one_layer`]; cells `first` to `last`): the cell above a square of the plane across `d` overlaps the
/// triangle exactly when the triangle's projection on that plane meets the square (closed sets; the layer holds
/// the triangle's whole extent along `d`). Every square of the extent meets the projection's bounding box, so the
/// test is the projection's three edge normals. Grid coordinates have few enough significant bits that these
/// products and sums are exact, as in the whole test. Each cell goes to `push` as its linear index, stepped by the
/// grid's `strides` ([`GridSpec::strides`]); a long row's cells form one run, whose ends are bisected ([`row_span`]).
fn overlaps_in_layer(
    t: &GridTriangle,
    d: usize,
    [first, last]: [[u32; 3]; 2],
    strides: [usize; 3],
    push: &mut impl FnMut(u32),
) {
    let (u, v) = ((d + 1) % 3, (d + 2) % 3);
    let p = [t[0], t[1], t[2]].map(|w| [w[u], w[v]]);
    let edges = [0, 1, 2].map(|k| EdgeBand::new(p[k], p[(k + 1) % 3], &p));
    let long = last[v] - first[v] >= SPAN_SEARCH_FROM;
    for iu in first[u]..=last[u] {
        let row = first[d] as usize * strides[d] + iu as usize * strides[u];
        let cu = f64::from(iu) + 0.5;
        if long {
            let Some(span) = row_span(first[v]..=last[v], &edges, cu) else { continue };
            for iv in span {
                push((row + iv as usize * strides[v]) as u32);
            }
            continue;
        }
        for iv in first[v]..=last[v] {
            if edges.iter().all(|e| e.meets(e.at(cu, iv))) {
                push((row + iv as usize * strides[v]) as u32);
            }
        }
    }
}

/// One edge of a triangle's projection on the plane across its dominant axis, for [`overlaps_in_layer`]: the edge's
/// normal in the plane, the range of the corners projected on it, and half the extent of a unit square's projection.
struct EdgeBand {
    normal: [f64; 2],
    lo: f64,
    hi: f64,
    reach: f64,
}

impl EdgeBand {
    /// The edge from `a` to `b` of the projected triangle `corners`.
    fn new(a: [f64; 2], b: [f64; 2], corners: &[[f64; 2]; 3]) -> Self {
        let normal = [a[1] - b[1], b[0] - a[0]];
        let [p0, p1, p2] = corners.map(|q| normal[0] * q[0] + normal[1] * q[1]);
        let (lo, hi) = (float::min(float::min(p0, p1), p2), float::max(float::max(p0, p1), p2));
        Self { normal, lo, hi, reach: 0.5 * (normal[0].abs() + normal[1].abs()) }
    }

    /// The projection on the normal of the centre (`cu`, `iv` + ½) of a square of the row at `cu`.
    #[inline]
    fn at(&self, cu: f64, iv: u32) -> f64 {
        self.normal[0] * cu + self.normal[1] * (f64::from(iv) + 0.5)
    }

    /// Whether the square whose centre projects to `at` reaches the corners' range from below.
    #[inline]
    fn above_lo(&self, at: f64) -> bool {
        self.lo <= at + self.reach
    }

    /// Whether the square whose centre projects to `at` reaches the corners' range from above.
    #[inline]
    fn below_hi(&self, at: f64) -> bool {
        self.hi >= at - self.reach
    }

    /// Whether the square whose centre projects to `at` meets the corners' range.
    #[inline]
    fn meets(&self, at: f64) -> bool {
        self.above_lo(at) && self.below_hi(at)
    }
}

/// In a row whose last cell lies this many cells or more past its first, [`overlaps_in_layer`] finds the ends of the
/// run of overlapped cells by bisection ([`row_span`]) rather than testing every cell (one thread, a voxelization at
/// R=128: the textured box 104.0 → 99.2 M instructions, the box of vertex colours 105.8 → 101.3 M, the milk truck
/// 78.8 → 77.8 M; with 4 or 16 rather than 8, each within 0.5 % of that).
const SPAN_SEARCH_FROM: u32 = 8;

/// The squares of a row (`row`: their positions along it, at least one; its centres at `cu` across it) that meet a
/// triangle's projection, given by its `edges`. Each edge's two tests are monotonic along the row: the projection of a
/// centre is a sum of a constant and a product by the square's coordinate, each rounded, and rounding keeps order, so
/// each test holds on a prefix or a suffix of the row (or all of it, or none), and all six on one run of squares,
/// whose ends bisection finds with the very tests a square at a time would make.
fn row_span(
    row: std::ops::RangeInclusive<u32>,
    edges: &[EdgeBand; 3],
    cu: f64,
) -> Option<std::ops::RangeInclusive<u32>> {
    let (mut start, mut end) = row.into_inner();
    for e in edges {
        let above_lo = |iv| e.above_lo(e.at(cu, iv));
        let below_hi = |iv| e.below_hi(e.at(cu, iv));
        // Where the projection grows along the row, the first test holds on a suffix and the second on a prefix;
        // where it shrinks, the other way round; across the row (a normal with no component along it) both are
        // constant.
        if e.normal[1] > 0.0 {
            start = first_holding(start, end, above_lo)?;
            end = last_holding(start, end, below_hi)?;
        } else {
            start = first_holding(start, end, below_hi)?;
            end = last_holding(start, end, above_lo)?;
        }
    }
    Some(start..=end)
}

/// The first of `from..=to` where `holds`, which holds on a suffix of it (`None`: nowhere).
fn first_holding(from: u32, to: u32, holds: impl Fn(u32) -> bool) -> Option<u32> {
    let (mut lo, mut hi) = (from, to + 1);
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if holds(mid) { hi = mid } else { lo = mid + 1 }
    }
    (lo <= to).then_some(lo)
}

/// The last of `from..=to` where `holds`, which holds on a prefix of it (`None`: nowhere).
fn last_holding(from: u32, to: u32, holds: impl Fn(u32) -> bool) -> Option<u32> {
    let (mut lo, mut hi) = (from, to + 1);
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if holds(mid) { lo = mid + 1 } else { hi = mid }
    }
    (lo > from).then(|| lo - 1)
}

/// [`overlaps`] of a triangle `t` with normal `n` whose extent `lo`, `hi` spans the cells `first` to `last`
/// (across more than one cell boundary, or clamped onto the grid's edge): each candidate cell is tested, a
/// column along the dominant axis at a time; each overlapped cell goes to `push` as its linear index, stepped from
/// the column's (where placing each cell's coordinates by axis and indexing them took 1–1.2 % of a small model's
/// voxelization: one thread, CesiumMan at R=128 45.37 → 44.86 M instructions, the milk truck 86.5 → 85.4 M).
#[inline(never)]
fn overlaps_across(
    spec: &GridSpec,
    t: &GridTriangle,
    n: DVec3,
    [lo, hi]: [[f64; 3]; 2],
    [first, last]: [[u32; 3]; 2],
    push: &mut impl FnMut(u32),
) {
    let corners = t.map(|w| w.to_array());
    let cell_of = |a: usize, v: f64| cell_of(v, spec.dims[a]);
    let last_cell_of = |a: usize, from: f64, to: f64| last_cell_of(from, to, spec.dims[a]);
    let d = dominant_axis(n);
    let (u, v) = ((d + 1) % 3, (d + 2) % 3);
    let n = n.to_array();
    // Placing the footprints pays for itself only where some lie well inside or outside the projection; a
    // triangle spanning a few columns gets the whole test everywhere (the same cells: the placement only
    // skips tests whose outcome it knows).
    let columns = (last[u] - first[u] + 1) * (last[v] - first[v] + 1);
    let inside = (columns > FEW_COLUMNS).then(|| FootprintTest::new(&corners, n[d].signum(), u, v));
    let tester = CellTester::new(t, d, lo, hi);
    let t0 = corners[0];
    let strides = spec.strides();
    for iu in first[u]..=last[u] {
        // The footprint's extent along u and v (clipped to the triangle's), and the plane's terms there.
        let us = [float::max(f64::from(iu), lo[u]), float::min(f64::from(iu + 1), hi[u])];
        let u_terms = us.map(|cu| n[u] * (cu - t0[u]));
        let Some(row) = tester.row(f64::from(iu) + 0.5) else { continue };
        for iv in first[v]..=last[v] {
            let test = inside.as_ref().map_or(Test::Full, |inside| inside.place(iu, iv));
            if test == Test::Outside {
                continue;
            }
            // Extent of the plane along the dominant axis over this cell's footprint.
            let vs = [float::max(f64::from(iv), lo[v]), float::min(f64::from(iv + 1), hi[v])];
            let mut dlo = f64::INFINITY;
            let mut dhi = f64::NEG_INFINITY;
            for u_term in u_terms {
                for cv in vs {
                    // n · (p − t0) = 0 solved for the dominant coordinate.
                    let pd = t0[d] - (u_term + n[v] * (cv - t0[v])) / n[d];
                    dlo = float::min(pd, dlo);
                    dhi = float::max(pd, dhi);
                }
            }
            let (dlo, dhi) = (float::max(dlo, lo[d]), float::min(dhi, hi[d]));
            let ids = cell_of(d, dlo)..=last_cell_of(d, dlo, dhi);
            if ids.is_empty() {
                continue;
            }
            let Some(column) = tester.column(&row, f64::from(iv) + 0.5, test == Test::Full) else { continue };
            let base = iu as usize * strides[u] + iv as usize * strides[v];
            for id in ids {
                if column.overlaps(f64::from(id) + 0.5) {
                    push((base + id as usize * strides[d]) as u32);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::BoxTester;

    #[test]
    fn squares_inside_the_projection_need_only_the_plane_test_and_squares_outside_none() {
        let mut random = crate::lcg::Lcg::new(7);
        let mut next = |scale: f64| random.unit(scale);
        let (mut inside_cells, mut outside_cells) = (0, 0);
        for _ in 0..200 {
            let t: GridTriangle = std::array::from_fn(|_| DVec3::new(next(12.0), next(12.0), next(12.0)));
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            let d = dominant_axis(n);
            let (u, v) = ((d + 1) % 3, (d + 2) % 3);
            let corners = t.map(|w| w.to_array());
            let (tester, inside) = (BoxTester::new(&t), FootprintTest::new(&corners, n[d].signum(), u, v));
            for (iu, iv, id) in (0..12).flat_map(|a| (0..12).flat_map(move |b| (0..12).map(move |c| (a, b, c)))) {
                let mut c = DVec3::ZERO;
                (c[u], c[v], c[d]) = (f64::from(iu) + 0.5, f64::from(iv) + 0.5, f64::from(id) + 0.5);
                let half = DVec3::splat(0.5);
                match inside.place(iu, iv) {
                    Test::Plane => {
                        inside_cells += 1;
                        assert_eq!(tester.overlaps(c, half), tester.overlaps_plane(c, half), "{t:?} at {c}");
                    }
                    Test::Outside => {
                        outside_cells += 1;
                        assert!(!tester.overlaps(c, half), "{t:?} at {c}");
                    }
                    _ => {}
                }
            }
        }
        assert!(inside_cells > 10_000 && outside_cells > 10_000, "{inside_cells} inside, {outside_cells} outside");
    }

    #[test]
    fn a_triangle_across_one_boundary_or_in_one_layer_gets_the_cells_the_whole_test_gives() {
        // Triangles of up to five cells at coordinates snapped to 1/8 of a cell (so that many corners and edges
        // lie on cell boundaries, the ties), in an 8³ grid.
        let spec = GridSpec::of_cells([8; 3]);
        let mut random = crate::lcg::Lcg::new(3);
        let mut next = |n: u64| random.below(n);
        let (mut across_one, mut in_layer, mut in_top_layer) = (0, 0, 0);
        for _ in 0..100_000 {
            let base = [0; 3].map(|_| next(7 * 8) as f64 / 8.0);
            let reach = [10, 10, 20, 40][next(4) as usize];
            let t: GridTriangle =
                std::array::from_fn(|_| DVec3::from(base.map(|b| b + next(reach) as f64 / 8.0)).min(DVec3::splat(8.0)));
            let tris = GridTriangles::from_triangles(&[t]);
            let mut fast = Vec::new();
            overlaps(&spec, &tris, 0, &mut |cell, _| fast.push(cell));
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            if n.length_squared() == 0.0 {
                assert!(fast.is_empty());
                continue;
            }
            let (lo, hi) = (t[0].min(t[1]).min(t[2]).to_array(), t[0].max(t[1]).max(t[2]).to_array());
            let first = [0, 1, 2].map(|a| cell_of(lo[a], 8));
            let last = [0, 1, 2].map(|a| last_cell_of(lo[a], hi[a], 8));
            let d = dominant_axis(n);
            match (0..3).map(|a| last[a] - first[a]).sum::<u32>() {
                0 => continue,
                1 => across_one += 1,
                _ if in_one_layer(first[d], last[d], hi[d], 8) => {
                    in_layer += 1;
                    in_top_layer += usize::from(hi[d] == 8.0);
                }
                _ => continue,
            }
            let mut whole = Vec::new();
            overlaps_across(&spec, &t, n, [lo, hi], [first, last], &mut |cell| whole.push(cell));
            whole.sort_unstable();
            fast.sort_unstable();
            assert_eq!(fast, whole, "{t:?}");
        }
        assert!(across_one > 5_000 && in_layer > 5_000, "{across_one} across one boundary, {in_layer} in a layer");
        assert!(in_top_layer > 500, "{in_top_layer} on the grid's upper face");
    }

    #[test]
    fn long_rows_of_a_triangle_in_one_layer_get_the_cells_the_whole_test_gives() {
        // Flat triangles across a 64³ grid, each in one layer along its dominant axis (corners on a 1/8 lattice,
        // so that edges pass through cell corners and along cell faces), their rows long enough to be bisected.
        let spec = GridSpec::of_cells([64; 3]);
        let mut random = crate::lcg::Lcg::new(17);
        let mut next = |n: u64| random.below(n);
        let (mut bisected, mut cells) = (0, 0);
        for _ in 0..3_000 {
            let d = next(3) as usize;
            let layer = next(64 * 8 - 8) as f64 / 8.0;
            let depth = [0.0, 0.125, 0.5][next(3) as usize];
            let t: GridTriangle = std::array::from_fn(|_| {
                let mut p = DVec3::ZERO;
                p[(d + 1) % 3] = next(64 * 8 + 1) as f64 / 8.0;
                p[(d + 2) % 3] = next(64 * 8 + 1) as f64 / 8.0;
                p[d] = (layer.floor() + (layer.fract() + depth * next(2) as f64).min(0.875)).min(64.0);
                p
            });
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            if n.length_squared() == 0.0 || dominant_axis(n) != d {
                continue;
            }
            let (lo, hi) = (t[0].min(t[1]).min(t[2]).to_array(), t[0].max(t[1]).max(t[2]).to_array());
            let first = [0, 1, 2].map(|a| cell_of(lo[a], 64));
            let last = [0, 1, 2].map(|a| last_cell_of(lo[a], hi[a], 64));
            if !in_one_layer(first[d], last[d], hi[d], 64) {
                continue;
            }
            let v = (d + 2) % 3;
            bisected += usize::from(last[v] - first[v] >= SPAN_SEARCH_FROM);
            let tris = GridTriangles::from_triangles(&[t]);
            let mut fast = Vec::new();
            overlaps(&spec, &tris, 0, &mut |cell, _| fast.push(cell));
            let mut whole = Vec::new();
            overlaps_across(&spec, &t, n, [lo, hi], [first, last], &mut |cell| whole.push(cell));
            fast.sort_unstable();
            whole.sort_unstable();
            assert_eq!(fast, whole, "{t:?}");
            cells += fast.len();
        }
        assert!(bisected > 1_000 && cells > 500_000, "{bisected} triangles of long rows, {cells} cells");
    }

    #[test]
    fn extents_ending_on_a_boundary_stop_before_it() {
        assert_eq!([cell_of(-2.0, 10), cell_of(3.7, 10), cell_of(10.0, 10), cell_of(f64::NAN, 10)], [0, 3, 9, 0]);
        let cases = [
            ((0.2, 3.0), 2),      // ends on the boundary of cell 3: does not reach it
            ((0.2, 3.5), 3),      // ends inside cell 3
            ((3.0, 3.0), 3),      // a point on the boundary: the cell above it
            ((-5.0, 0.0), 0),     // ends on the grid's lower face
            ((0.5, 10.0), 9),     // ends on the grid's upper face
            ((0.5, 12.0), 9),     // beyond the grid
            ((-9.0, -3.0), 0),    // wholly below it
            ((0.0, f64::NAN), 0), // no extent
            ((0.0, 1e300), 9),    // whole, far beyond the grid
            ((0.0, f64::INFINITY), 9),
        ];
        for ((from, to), last) in cases {
            assert_eq!(last_cell_of(from, to, 10), last, "[{from}, {to}]");
        }
    }
}
