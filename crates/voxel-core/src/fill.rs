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
//! * the cell is inside when W + P ≠ 0.
//!
//! So closed parts fill by the nonzero rule (overlapping parts stay solid: W = 2), a cavity shell facing
//! inwards cancels its surroundings (W = 1 − 1 = 0, or P + W = 1 − 1 = 0 inside a parity solid), and
//! where only parity parts cross a column the rule is the article's parity. With every role `Parity`
//! (`FillMode::Parity`) it is exactly whole-model parity. The sums depend only on which crossings lie at
//! or below z_c, not on the order of crossings at equal depth, and the column test is exact, so the
//! winding steps add up to zero in every column (a closed part's always do; the file's facing is only used
//! as it is when they do): the count from below equals the count from above, which is what the reference
//! ([`reference_fill`]) uses.

use std::sync::OnceLock;

use rayon::prelude::*;

use crate::bvh::TriangleBvh;
use crate::columns::{Columns, Crossing, Role, crossings_by_bvh, crossings_by_rasterizing, parity_counts};
use crate::float;
use crate::geom::{covers_column, depth_at};
use crate::grid::{BitGrid, GridSpec, GridTriangles};
use crate::options::{FillMode, Method};
use crate::orient::{closed_parts, winding_roles};
use crate::progress::Progress;
use crate::soup::TriangleSoup;

/// Calls `emit` with the runs of cells of one column that are inside by the column count of the module
/// docs: cell k is inside when W + P ≠ 0 for the crossings at or below its centre k + 0.5.
fn column_runs(crossings: &[Crossing], roles: &[Role], nz: u32, mut emit: impl FnMut(std::ops::Range<u32>)) {
    let parity_counts = parity_counts(crossings, roles);
    let to_cell = |z: f64| float::ceil(z - 0.5).clamp(0.0, f64::from(nz)) as u32;
    let (mut winding, mut parity) = (0i32, 0i32);
    let mut entered: Option<f64> = None;
    for c in crossings {
        match roles[c.triangle as usize] {
            Role::Parity => parity ^= i32::from(parity_counts),
            role => winding += role.step(),
        }
        let inside = winding + parity != 0;
        match entered {
            None if inside => entered = Some(c.z),
            Some(z) if !inside => {
                let run = to_cell(z)..to_cell(c.z);
                if !run.is_empty() {
                    emit(run);
                }
                entered = None;
            }
            _ => {}
        }
    }
}

/// The solid from per-column crossings and the triangles' roles.
fn fill_columns(spec: &GridSpec, columns: &Columns, roles: &[Role]) -> BitGrid {
    let nz = spec.dims[2];
    let mut grid = BitGrid::new(spec.cell_count());
    for col in 0..columns.len() {
        let base = col * nz as usize;
        column_runs(columns.column(col), roles, nz, |run| {
            grid.set_range(base + run.start as usize..base + run.end as usize);
        });
    }
    grid
}

/// The solid by the column count, with the roles of `fill` (winding or parity) and the crossings of
/// `method`; `tris` are `soup`'s triangles on the grid `spec`. Once `progress` is cancelled it stops after the
/// crossings (cut short too) with an empty solid.
pub(crate) fn solid_fill(
    soup: &TriangleSoup,
    spec: &GridSpec,
    tris: &GridTriangles,
    fill: FillMode,
    method: Method,
    bvh: &OnceLock<TriangleBvh>,
    progress: &Progress,
) -> BitGrid {
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
            || closed_parts(soup, tris),
        ),
        _ => vec![Role::Parity; tris.len()],
    };
    match columns {
        Some(columns) => fill_columns(spec, &columns, &roles),
        None => reference_fill(spec, tris, &roles),
    }
}

/// The article's algorithm, kept small and obviously correct: for every cell centre, cast one +Z ray
/// against every triangle (brute force, no acceleration) and count the hits above the centre: the
/// winding number W as the sum of the hits' outward facings (+1 leaving upwards), P as the parity of the
/// parity hits; inside when W + P ≠ 0 (odd hits when every role is parity, the article's rule). It uses the
/// same robust column test as the fast paths.
fn reference_fill(spec: &GridSpec, tris: &GridTriangles, roles: &[Role]) -> BitGrid {
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
                    winding + parity != 0
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
        let roles: Vec<Role> = crossings.iter().map(|c| c.1).collect();
        let column: Vec<Crossing> =
            crossings.iter().enumerate().map(|(i, c)| Crossing { column: 0, triangle: i as u32, z: c.0 }).collect();
        let mut out = Vec::new();
        column_runs(&column, &roles, 10, |r| out.push(r));
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
}
