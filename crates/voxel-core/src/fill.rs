//! Solid fill: the column crossings ([`crate::columns`]) counted by the nonzero winding rule or by parity, the
//! article's per-point reference, and flood fill from outside.
//!
//! # The column count
//!
//! Every triangle has a [`Role`] (see [`crate::columns`]; [`crate::orient`] orients the model's closed parts): a
//! winding triangle (of a closed, oriented part — or any triangle, when the file's own facing already
//! balances every column) *enters* (+1) or *leaves* (−1) when a +Z column crosses it, by whether its
//! outward side faces down or up; a triangle of a sheet that cannot be closed (open, non-manifold) counts
//! by *parity*. For a cell centre at height z_c, with the crossings at or below z_c:
//!
//! * W = the sum of the steps of the winding crossings (the winding number of the closed parts);
//! * P = the number of parity crossings, modulo 2 — or 0 in a column with an odd number of parity
//!   crossings (only open meshes give those; such a column is not filled by them, instead of being filled
//!   down to the grid's floor);
//! * the cell is inside when W + P ≠ 0 — except that a cell inside by parity alone (W = 0, P = 1) under the
//!   winding rule stays inside only where the parity triangles enclose it along X and along Y as well (the same
//!   rule in the columns of those axes, through the parity triangles alone). An open sheet thus fills only what
//!   it encloses seen along every axis, whichever way the model lies in the grid: a box closed only through a
//!   T-junction fills, but a terrain's hills and valleys, or the bore of an open pipe, which columns across them
//!   cross an even number of times, stay empty (the columns along the terrain's up axis, or the pipe's, cross
//!   it once or not at all).
//!
//! So closed parts fill by the nonzero rule (overlapping parts stay solid: W = 2), a cavity shell facing
//! inwards cancels its surroundings (W = 1 − 1 = 0, or P + W = 1 − 1 = 0 inside a parity solid), and
//! where only parity parts cross a column the rule is the article's parity. With every role `Parity`
//! (`FillMode::Parity`) it is exactly whole-model parity, along Z alone. The sums depend only on which
//! crossings lie at or below z_c, not on the order of crossings at equal depth, and the column test is exact, so the
//! winding steps add up to zero in every column (a closed part's always do; the file's facing is only used
//! as it is when they do): the count from below equals the count from above, which is what the reference
//! ([`reference_fill`]) uses.

mod height_field;

use std::sync::OnceLock;

use glam::DVec3;
use rayon::prelude::*;

use crate::bvh::TriangleBvh;
use crate::columns::{
    Columns, Crossing, Role, crossings_along, crossings_by_bvh, crossings_by_rasterizing, cycled, parity_counts,
};
use crate::float;
use crate::geom::{covers_column, depth_at};
use crate::grid::{BitGrid, GridSpec, GridTriangles};
use crate::options::{FillMode, Method};
use crate::orient::{closed_parts, winding_roles};
use crate::progress::Progress;
use crate::soup::TriangleSoup;
use height_field::{net_facing, survey};

/// Calls `emit` with the runs of cells of one column that are inside by the column count of the module
/// docs: cell k is inside when W + P ≠ 0 for the crossings at or below its centre k + 0.5. Each run comes with
/// whether its cells are inside by parity alone (W = 0, P = 1); a run is split where that changes.
fn column_runs(crossings: &[Crossing], roles: &[Role], nz: u32, mut emit: impl FnMut(std::ops::Range<u32>, bool)) {
    let parity_counts = parity_counts(crossings, roles);
    let to_cell = |z: f64| float::ceil(z - 0.5).clamp(0.0, f64::from(nz)) as u32;
    let (mut winding, mut parity) = (0i32, 0i32);
    // Where the current run started, and whether it is inside by parity alone.
    let mut entered: Option<(f64, bool)> = None;
    for c in crossings {
        match roles[c.triangle as usize] {
            Role::Parity => parity ^= i32::from(parity_counts),
            role => winding += role.step(),
        }
        let now = (winding + parity != 0).then_some(winding == 0);
        if now == entered.map(|(_, parity_only)| parity_only) {
            continue;
        }
        if let Some((z, parity_only)) = entered {
            let run = to_cell(z)..to_cell(c.z);
            if !run.is_empty() {
                emit(run, parity_only);
            }
        }
        entered = now.map(|parity_only| (c.z, parity_only));
    }
}

/// Keeps of `cells` (inside by parity alone along Z) those that the triangles whose role is [`Role::Parity`]
/// enclose along X and along Y too ([`enclosed_along`]): an open sheet fills only what it encloses seen along
/// every axis. An axis at a time until none is left, first the one the sheets face most ([`facing_most`]): the
/// one whose columns most likely cross them an odd number of times (a terrain's up axis).
fn keep_enclosed(spec: &GridSpec, tris: &GridTriangles, roles: &[Role], cells: &mut BitGrid, progress: &Progress) {
    let keep = |t: usize| roles[t] == Role::Parity;
    let first = facing_most(tris, roles);
    for axis in [first, 1 - first] {
        if cells.count() == 0 {
            return;
        }
        let columns = match axis {
            0 => crossings_along::<0>(spec, tris, keep, progress),
            _ => crossings_along::<1>(spec, tris, keep, progress),
        };
        cells.intersect(&enclosed_along(spec, &columns, axis, roles));
    }
}

/// Of X (0) and Y (1), the axis along which the parity triangles face most ([`net_facing`]).
fn facing_most(tris: &GridTriangles, roles: &[Role]) -> usize {
    let net = net_facing(tris, |t| roles[t] == Role::Parity);
    usize::from(net.y.abs() > net.x.abs())
}

/// The cells inside by parity in `columns`, the columns along `axis` of the parity triangles (see
/// [`crate::columns::crossings_along`] for their numbering).
fn enclosed_along(spec: &GridSpec, columns: &Columns, axis: usize, roles: &[Role]) -> BitGrid {
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut grid = BitGrid::new(spec.cell_count());
    for col in 0..columns.len() {
        let mut cell = [0u32; 3];
        (cell[u], cell[v]) = (col as u32 / spec.dims[v], col as u32 % spec.dims[v]);
        column_runs(columns.column(col), roles, spec.dims[axis], |run, _| {
            for k in run {
                cell[axis] = k;
                grid.set(spec.index(cell[0], cell[1], cell[2]));
            }
        });
    }
    grid
}

/// The solid from per-column crossings and the triangles' roles; with `apart`, the cells inside by parity alone
/// (W = 0, P = 1) apart from it.
fn fill_columns(spec: &GridSpec, columns: &Columns, roles: &[Role], apart: bool) -> (BitGrid, Option<BitGrid>) {
    let nz = spec.dims[2];
    let mut grid = BitGrid::new(spec.cell_count());
    let mut parity_only = apart.then(|| BitGrid::new(spec.cell_count()));
    for col in 0..columns.len() {
        let base = col * nz as usize;
        column_runs(columns.column(col), roles, nz, |run, alone| {
            let cells = base + run.start as usize..base + run.end as usize;
            match &mut parity_only {
                Some(apart) if alone => apart.set_range(cells),
                _ => grid.set_range(cells),
            }
        });
    }
    (grid, parity_only)
}

/// The solid by the column count, with the roles of `fill` (winding or parity) and the crossings of
/// `method`; `tris` are `soup`'s triangles on the grid `spec`. Under the winding rule, cells inside by parity
/// alone (the sheets that cannot be closed) stay inside only where the parity triangles enclose them along X
/// and Y too ([`keep_enclosed`]). The winding rule's fast methods first survey the triangles
/// ([`height_field::survey`]): a model that no line along some axis crosses twice fills nothing, found without
/// the crossings or the part analysis. Once `progress` is cancelled it stops after the crossings (cut short too)
/// with an empty solid.
pub(crate) fn solid_fill(
    soup: &TriangleSoup,
    spec: &GridSpec,
    tris: &GridTriangles,
    fill: FillMode,
    method: Method,
    bvh: &OnceLock<TriangleBvh>,
    progress: &Progress,
) -> BitGrid {
    // The reference decides every cell by itself.
    let surveyed = (fill == FillMode::Winding && method != Method::Reference).then(|| survey(spec, tris, progress));
    if surveyed.is_some_and(|s| s.fills_nothing()) {
        return BitGrid::new(spec.cell_count());
    }
    let columns = match method {
        Method::Fast => Some(crossings_by_rasterizing(spec, tris, progress)),
        Method::Bvh => Some(crossings_by_bvh(spec, tris, bvh.get_or_init(|| TriangleBvh::build(tris)))),
        Method::Reference => None,
    };
    if progress.is_cancelled() {
        return BitGrid::new(spec.cell_count()); // the caller's next stage ends the run
    }
    let roles = match fill {
        FillMode::Winding => winding_roles(
            columns.as_ref(),
            || crossings_by_rasterizing(spec, tris, progress),
            || surveyed.is_some_and(|s| s.lines_once),
            || closed_parts(soup, tris),
        ),
        _ => Some(vec![Role::Parity; tris.len()]),
    };
    let Some(roles) = roles else {
        return BitGrid::new(spec.cell_count());
    };
    // Under the winding rule the cells inside by parity alone (the sheets that cannot be closed) must be enclosed
    // along X and Y too.
    let agree = fill == FillMode::Winding && roles.contains(&Role::Parity);
    match columns {
        Some(columns) => {
            let (mut solid, parity_only) = fill_columns(spec, &columns, &roles, agree);
            if let Some(mut cells) = parity_only {
                keep_enclosed(spec, tris, &roles, &mut cells, progress);
                solid.unite(&cells);
            }
            solid
        }
        None => reference_fill(spec, tris, &roles, agree),
    }
}

/// The article's algorithm, kept small and obviously correct: for every cell centre, cast one +Z ray
/// against every triangle (brute force, no acceleration) and count the hits above the centre: the
/// winding number W as the sum of the hits' outward facings (+1 leaving upwards), P as the parity of the
/// parity hits; inside when W + P ≠ 0 (odd hits when every role is parity, the article's rule). With `agree`, a
/// centre inside by parity alone (W = 0, P = 1) must be enclosed by the parity triangles along X and Y too
/// ([`enclosed_by_parity`]). It uses the same robust column test as the fast paths.
fn reference_fill(spec: &GridSpec, tris: &GridTriangles, roles: &[Role], agree: bool) -> BitGrid {
    let [nx, ny, nz] = spec.dims;
    let inside: Vec<Vec<u32>> = (0..nx * ny)
        .into_par_iter()
        .map(|col| {
            let p = [f64::from(col / ny) + 0.5, f64::from(col % ny) + 0.5];
            (0..nz)
                .filter(|&k| {
                    let zc = f64::from(k) + 0.5;
                    let (mut winding, mut parity) = (0i32, 0i32);
                    for (t, role) in tris.iter().zip(roles) {
                        if covers_column(&t, p) && depth_at(&t, p) > zc {
                            match role {
                                Role::Parity => parity ^= 1,
                                role => winding -= role.step(),
                            }
                        }
                    }
                    let centre = DVec3::new(p[0], p[1], zc);
                    match (winding, parity) {
                        (0, 1) if agree => (0..2).all(|axis| enclosed_by_parity(tris, roles, axis, centre)),
                        _ => winding + parity != 0,
                    }
                })
                .collect()
        })
        .collect();
    let mut grid = BitGrid::new(spec.cell_count());
    for (col, ks) in inside.iter().enumerate() {
        for &k in ks {
            grid.set(col * nz as usize + k as usize);
        }
    }
    grid
}

/// Whether the parity triangles enclose `centre` along `axis`, brute force: the line along `axis` through it
/// crosses them an even number of times, an odd number of them beyond it.
fn enclosed_by_parity(tris: &GridTriangles, roles: &[Role], axis: usize, centre: DVec3) -> bool {
    let c = cycled(centre, axis);
    let (mut all, mut beyond) = (0, 0);
    for (t, _) in tris.iter().zip(roles).filter(|(_, role)| **role == Role::Parity) {
        let t = t.map(|corner| cycled(corner, axis));
        if covers_column(&t, [c.x, c.y]) {
            all += 1;
            beyond += usize::from(depth_at(&t, [c.x, c.y]) > c.z);
        }
    }
    all % 2 == 0 && beyond % 2 == 1
}

/// Cells reachable from outside the grid through cells not in `walls` (6-connected).
pub(crate) fn reachable_from_outside(spec: &GridSpec, walls: &BitGrid) -> BitGrid {
    let [nx, ny, nz] = spec.dims;
    let mut reached = BitGrid::new(spec.cell_count());
    let mut queue: Vec<usize> = Vec::new();
    let mut seed = |i: usize, reached: &mut BitGrid| {
        if !walls.get(i) && !reached.get(i) {
            reached.set(i);
            queue.push(i);
        }
    };
    for x in 0..nx {
        for y in 0..ny {
            for z in 0..nz {
                let border = x == 0 || y == 0 || z == 0 || x == nx - 1 || y == ny - 1 || z == nz - 1;
                if border {
                    seed(spec.index(x, y, z), &mut reached);
                }
            }
        }
    }
    let strides = [ny as usize * nz as usize, nz as usize, 1];
    while let Some(i) = queue.pop() {
        let c = spec.coords(i);
        for a in 0..3 {
            if c[a] > 0 {
                let j = i - strides[a];
                if !walls.get(j) && !reached.get(j) {
                    reached.set(j);
                    queue.push(j);
                }
            }
            if c[a] + 1 < spec.dims[a] {
                let j = i + strides[a];
                if !walls.get(j) && !reached.get(j) {
                    reached.set(j);
                    queue.push(j);
                }
            }
        }
    }
    reached
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The runs of a column whose crossings are (z, role), triangle i having the i-th role.
    fn runs(crossings: &[(f64, Role)]) -> Vec<std::ops::Range<u32>> {
        flagged(crossings).into_iter().map(|(r, _)| r).fold(Vec::new(), |mut out, r| {
            // Runs split where the parity-only flag changes are joined again.
            match out.last_mut() {
                Some(last) if last.end == r.start => last.end = r.end,
                _ => out.push(r),
            }
            out
        })
    }

    /// The runs of [`runs`] as `column_runs` emits them, with the flag of cells inside by parity alone.
    fn flagged(crossings: &[(f64, Role)]) -> Vec<(std::ops::Range<u32>, bool)> {
        let roles: Vec<Role> = crossings.iter().map(|c| c.1).collect();
        let column: Vec<Crossing> =
            crossings.iter().enumerate().map(|(i, c)| Crossing { column: 0, triangle: i as u32, z: c.0 }).collect();
        let mut out = Vec::new();
        column_runs(&column, &roles, 10, |r, parity_only| out.push((r, parity_only)));
        out
    }

    #[test]
    fn runs_follow_parity_and_drop_odd_columns() {
        use Role::Parity as P;
        assert_eq!(runs(&[(1.2, P), (3.7, P), (5.0, P), (6.0, P)]), vec![1..4, 5..6]);
        assert!(runs(&[(1.2, P), (3.7, P), (5.0, P)]).is_empty());
        // A crossing exactly at a centre: the centre counts as at-or-above, as in the reference (z > zc).
        assert_eq!(runs(&[(1.5, P), (3.5, P)]), vec![1..3]);
    }

    #[test]
    fn runs_follow_the_winding_number() {
        use Role::{Enters as E, Leaves as L, Parity as P};
        // Two overlapping parts: the overlap (W = 2) stays inside, where parity would empty it.
        assert_eq!(runs(&[(1.2, E), (3.2, E), (5.2, L), (7.2, L)]), vec![1..7]);
        // A cavity facing inwards inside a part: W = 1 − 1 = 0 in it.
        assert_eq!(runs(&[(1.2, E), (3.2, L), (5.2, E), (7.2, L)]), vec![1..3, 5..7]);
        // The same cavity inside a parity solid: P + W = 1 − 1 = 0.
        assert_eq!(runs(&[(1.2, P), (3.2, L), (5.2, E), (7.2, P)]), vec![1..3, 5..7]);
        // An odd parity column ignores its parity crossings but keeps the winding part.
        assert_eq!(runs(&[(0.2, P), (1.2, E), (3.2, L)]), vec![1..3]);
    }

    #[test]
    fn runs_say_which_cells_are_inside_by_parity_alone() {
        use Role::{Enters as E, Leaves as L, Parity as P};
        // A part inside a parity solid: parity alone around it, winding (W = 1, P = 1) within it.
        assert_eq!(flagged(&[(1.2, P), (3.2, E), (5.2, L), (7.2, P)]), vec![(1..3, true), (3..5, false), (5..7, true)]);
        // A cavity in a parity solid: parity alone on both sides, nothing within.
        assert_eq!(flagged(&[(1.2, P), (3.2, L), (5.2, E), (7.2, P)]), vec![(1..3, true), (5..7, true)]);
        // Winding alone.
        assert_eq!(flagged(&[(1.2, E), (3.2, L)]), vec![(1..3, false)]);
    }
}
