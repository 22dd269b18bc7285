//! The shell's triangle–cell overlap test, one column of unit cells along the triangle's dominant axis at a
//! time: [`BoxTester`](crate::geom::BoxTester)'s separating axis test for boxes of half size ½, with
//! everything that depends only on the triangle computed once and everything that depends only on the
//! column once per column. A cell then costs its extent along the column, the plane and the edge directions
//! that are not perpendicular to the column, a multiply-add each.
//!
//! The answers are exactly `BoxTester`'s: every comparison is made between the same floating-point values,
//! computed by the same operations in the same order (a product that does not depend on the cell is merely
//! computed before the loop over the column; a product with a zero component is an exact zero in either).

use glam::DVec3;

use crate::geom::{GridTriangle, for_each_edge_axis, triangle_normal};

/// Half the side of a cell.
const HALF: f64 = 0.5;

/// An edge × box-axis direction of the separating axis test, with its components across and along the column
/// (`across[k]` along axis `(d + 1 + k) % 3`).
#[derive(Clone, Copy, Debug, Default)]
struct EdgeAxis {
    across: [f64; 2],
    along: f64,
    /// The range of the triangle's corners projected on the direction.
    lo: f64,
    hi: f64,
    /// Half the extent of a cell's projection on the direction.
    reach: f64,
}

impl EdgeAxis {
    /// Whether the triangle's projection meets the projection of the cell whose centre projects to `c`.
    #[inline]
    fn meets(&self, c: f64) -> bool {
        self.lo - c <= self.reach && self.hi - c >= -self.reach
    }
}

/// A triangle prepared for the overlap tests of the unit cells of columns along axis `d`.
pub(super) struct CellTester {
    d: usize,
    /// The triangle's extent along `d`, and across it (axes `(d + 1) % 3` and `(d + 2) % 3`).
    lo_along: f64,
    hi_along: f64,
    lo_across: [f64; 2],
    hi_across: [f64; 2],
    /// The plane: the normal across and along `d`, the offset n · t0, and half the extent of a cell's projection
    /// on n.
    normal_across: [f64; 2],
    normal_along: f64,
    plane: f64,
    plane_reach: f64,
    /// The edge directions perpendicular to `d` (the same for every cell of a column): the first
    /// `column_axis_count`.
    column_axes: [EdgeAxis; 3],
    column_axis_count: usize,
    /// The other edge directions: the first `cell_axis_count`.
    cell_axes: [EdgeAxis; 6],
    cell_axis_count: usize,
}

impl CellTester {
    /// Prepares triangle `t`, which spans `lo` to `hi`, for columns along axis `d`. (Inlined: built in its caller's
    /// frame rather than copied there.)
    #[inline]
    pub fn new(t: &GridTriangle, d: usize, lo: [f64; 3], hi: [f64; 3]) -> Self {
        let (u, v) = ((d + 1) % 3, (d + 2) % 3);
        let normal = triangle_normal(t);
        let n = normal.to_array();
        let mut tester = Self {
            d,
            lo_along: lo[d],
            hi_along: hi[d],
            lo_across: [lo[u], lo[v]],
            hi_across: [hi[u], hi[v]],
            normal_across: [n[u], n[v]],
            normal_along: n[d],
            plane: normal.dot(t[0]),
            plane_reach: DVec3::splat(HALF).dot(normal.abs()),
            column_axes: [EdgeAxis::default(); 3],
            column_axis_count: 0,
            cell_axes: [EdgeAxis::default(); 6],
            cell_axis_count: 0,
        };
        for_each_edge_axis(t, |k, dir, lo, hi| {
            // The sum of two halves, as `DVec3::dot` computes it with the zero component's exact zero.
            let reach = HALF * dir[(k + 1) % 3].abs() + HALF * dir[(k + 2) % 3].abs();
            let axis = EdgeAxis { across: [dir[u], dir[v]], along: dir[d], lo, hi, reach };
            if k == d {
                tester.column_axes[tester.column_axis_count] = axis;
                tester.column_axis_count += 1;
            } else {
                tester.cell_axes[tester.cell_axis_count] = axis;
                tester.cell_axis_count += 1;
            }
        });
        tester
    }

    /// The row of columns whose cell centres lie at `cu` along axis `(d + 1) % 3`, or `None` when no cell of
    /// it overlaps the triangle.
    #[inline]
    pub fn row(&self, cu: f64) -> Option<Row> {
        if self.lo_across[0] - cu > HALF || self.hi_across[0] - cu < -HALF {
            return None;
        }
        Some(Row {
            column_terms: std::array::from_fn(|k| self.column_axes[k].across[0] * cu),
            cell_terms: std::array::from_fn(|k| self.cell_axes[k].across[0] * cu),
            plane_term: self.normal_across[0] * cu,
        })
    }

    /// The column of `row` whose cell centres lie at `cv` along axis `(d + 2) % 3`, or `None` when no cell of
    /// it overlaps the triangle. With `edges` false only the box axes and the plane are tested (as
    /// [`BoxTester::overlaps_plane`](crate::geom::BoxTester::overlaps_plane)).
    #[inline]
    pub fn column(&self, row: &Row, cv: f64, edges: bool) -> Option<Column<'_>> {
        if self.lo_across[1] - cv > HALF || self.hi_across[1] - cv < -HALF {
            return None;
        }
        // A direction · a cell centre without its component along d (the product of the zero component is an
        // exact zero): the row's product plus this column's, in that order.
        let mut columns = self.column_axes[..self.column_axis_count].iter().zip(row.column_terms);
        if edges && !columns.all(|(a, term)| a.meets(term + a.across[1] * cv)) {
            return None;
        }
        let mut bases = [0.0; 6];
        if edges {
            let cells = self.cell_axes[..self.cell_axis_count].iter().zip(row.cell_terms);
            for (base, (axis, term)) in bases.iter_mut().zip(cells) {
                *base = term + axis.across[1] * cv;
            }
        }
        // n · c summed in the order x, y, z, as `DVec3::dot` does, with the product along `d` added per cell:
        // (along + first) + second.
        let (pu, pv) = (row.plane_term, self.normal_across[1] * cv);
        let plane_terms = match self.d {
            0 => [pu, pv],       // x = d, y = u, z = v
            1 => [pv, pu],       // x = v, y = d, z = u (x + y = y + x exactly)
            _ => [pu + pv, 0.0], // x = u, y = v, z = d
        };
        Some(Column { tester: self, plane_terms, bases, edges })
    }
}

/// The products of a row of columns that do not depend on the column: each edge direction's and the
/// normal's component along `(d + 1) % 3` times the row's centre coordinate.
pub(super) struct Row {
    column_terms: [f64; 3],
    cell_terms: [f64; 6],
    plane_term: f64,
}

/// One column of cells along a [`CellTester`]'s axis.
pub(super) struct Column<'a> {
    tester: &'a CellTester,
    /// The plane's dot product is (normal along · centre along + `plane_terms[0]`) + `plane_terms[1]`.
    plane_terms: [f64; 2],
    /// Per cell axis, its direction · the centre without its component along the column.
    bases: [f64; 6],
    edges: bool,
}

impl Column<'_> {
    /// Whether the triangle overlaps the cell of the column centred at `cd` along the axis (touching counts).
    #[inline]
    pub fn overlaps(&self, cd: f64) -> bool {
        let t = self.tester;
        if t.lo_along - cd > HALF || t.hi_along - cd < -HALF {
            return false;
        }
        let dot = (t.normal_along * cd + self.plane_terms[0]) + self.plane_terms[1];
        if (t.plane - dot).abs() > t.plane_reach {
            return false;
        }
        // A cell axis has a zero component across the column: its dot product is base + along · cd exactly.
        !self.edges
            || t.cell_axes[..t.cell_axis_count].iter().zip(&self.bases).all(|(a, &base)| a.meets(base + a.along * cd))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::BoxTester;

    /// Random triangles on a coarse lattice (so that corners, edges and planes often pass exactly through
    /// cell corners, edges and faces: the ties of the test), and finer ones.
    fn triangles(count: usize) -> Vec<GridTriangle> {
        let mut random = crate::lcg::Lcg::new(99);
        let mut next = |steps: u64| random.below(steps);
        (0..count)
            .map(|k| {
                let step = [0.5, 0.25, 1.0 / 1024.0][k % 3];
                std::array::from_fn(|_| {
                    DVec3::from_array(std::array::from_fn(|_| next((8.0 / step) as u64) as f64 * step))
                })
            })
            .collect()
    }

    #[test]
    fn columns_give_the_box_testers_answers_cell_for_cell() {
        let half = DVec3::splat(0.5);
        let (mut hits, mut misses) = (0, 0);
        for t in triangles(600) {
            let plain = BoxTester::new(&t);
            for d in 0..3 {
                let tester = CellTester::new(&t, d, t[0].min(t[1]).min(t[2]).into(), t[0].max(t[1]).max(t[2]).into());
                let (u, v) = ((d + 1) % 3, (d + 2) % 3);
                for (iu, iv) in (0..9).flat_map(|a| (0..9).map(move |b| (a, b))) {
                    for edges in [false, true] {
                        let mut center = DVec3::ZERO;
                        (center[u], center[v]) = (f64::from(iu) + 0.5, f64::from(iv) + 0.5);
                        let row = tester.row(center[u]);
                        let column = row.and_then(|row| tester.column(&row, center[v], edges));
                        for id in 0..9 {
                            center[d] = f64::from(id) + 0.5;
                            let expected =
                                if edges { plain.overlaps(center, half) } else { plain.overlaps_plane(center, half) };
                            let got = column.as_ref().is_some_and(|c| c.overlaps(center[d]));
                            assert_eq!(got, expected, "{t:?}, axis {d}, cell {center}, edge tests {edges}");
                            (hits, misses) = if got { (hits + 1, misses) } else { (hits, misses + 1) };
                        }
                    }
                }
            }
        }
        assert!(hits > 50_000 && misses > 50_000, "{hits} overlaps, {misses} misses");
    }
}
