//! Models the winding fill leaves empty, found before any crossing is counted: a terrain, a cloth, a sheet of
//! paper — one open surface that the lines along some axis cross at most once.
//!
//! # Why nothing is filled
//!
//! Say that every line along axis A through the cell centres crosses at most one triangle (the rasterizer's
//! exact test, [`crate::columns::Tally`]), and that every triangle within [`NEAR`] of a cell centre is crossed
//! by the line along A through that centre. The fill is declared empty only where the file's own facing does not
//! balance the +Z columns (some column's steps, added up in the same pass, do not come to zero; or the fill's own
//! check of the columns finds so: [`crate::orient::winding_roles`]; an open sheet that balances them counts as it
//! faces), so the roles come from the parts: closed, oriented surfaces count by winding, the rest by parity. A cell
//! is filled by the column count ([`crate::fill`]) in one of two ways, and neither can happen:
//!
//! * **Inside by parity alone** (W = 0, P = 1): the parity triangles must put it inside along X, Y and Z alike,
//!   and a line with an odd number of parity crossings, or with none, encloses nothing. Along A a line has at
//!   most one.
//! * **Inside by winding** (W ≠ 0): a line crosses a closed surface an even number of times (the signed crossings
//!   add up to zero), so one that crosses a single triangle does not cross a closed part: the triangles near a
//!   centre are not of one. W counts the closed parts' crossings below the cell centre p along its Z column, their
//!   depths rounded; as p is farther than [`NEAR`] from those triangles — a thousand times the rounding of a
//!   depth, even on a steep triangle, whose depth's error and distance along Z grow alike — W is exactly the
//!   closed parts' winding number around p, which is the same for every point near p: so also for the point that
//!   the rasterizer's tie-break puts on the line along A through p. On that line, the crossings on either side of
//!   the point add up (signed) to ± that winding number, so a non-zero one needs a crossing on each side: two.
//!
//! Both conditions are checked in one parallel pass over the triangles, which stops at the first line crossed
//! twice (a closed model's is found within the triangles of its first part) or the first triangle near a centre
//! whose line misses it. The axis is the one the triangles face most (a terrain's up axis: from a sample,
//! [`net_facing`]). Grids whose coordinates fall on a lattice do put centres on triangles: the height
//! field of `benches/big.rs` has one at R=256, on a triangle its up line crosses.

use glam::DVec3;
use rayon::prelude::*;

use crate::columns::{Tally, column_range, cycled, triangles_per_task};
use crate::geom::{GridTriangle, covers_column, triangle_normal};
use crate::grid::{GridSpec, GridTriangles};
use crate::progress::Progress;

/// The most triangles [`net_facing`] samples (about).
const FACING_SAMPLE: usize = 1 << 16;

/// The sum of the normals (twice the areas, signed by facing) of the triangles `keep` accepts, of all of them or,
/// in a big model, of an evenly spread sample of about [`FACING_SAMPLE`]: which way they face most (only an order
/// of work and whether the survey finds a height field depend on it, not the fill).
pub(super) fn net_facing(tris: &GridTriangles, keep: impl Fn(usize) -> bool) -> DVec3 {
    let every = tris.len().div_ceil(FACING_SAMPLE).max(1);
    (0..tris.len()).step_by(every).filter(|&t| keep(t)).map(|t| triangle_normal(&tris.get(t))).sum()
}

/// How near (in cells) a cell centre may come to a triangle for [`survey`] to decide: far above the
/// rounding of a crossing's depth (about 10⁻¹² of a cell on a grid of 2048).
const NEAR: f64 = 1e-9;

/// What one pass over the triangles tells the winding fill before it counts any crossing (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Survey {
    /// No line along the axis the triangles face most crosses two of them, and every triangle near a centre is
    /// crossed by that centre's line: the fill is empty where the file's facing does not balance the columns.
    pub lines_once: bool,
    /// With `lines_once`: the file's facing does not balance some +Z column (its steps do not add up to zero).
    pub unbalanced: bool,
}

impl Survey {
    /// Whether the winding fill is surely empty, before any crossing is counted.
    pub(crate) fn fills_nothing(self) -> bool {
        self.lines_once && self.unbalanced
    }
}

/// Surveys `tris` on `spec`'s grid (the module docs' test; `lines_once` false also once `progress` is cancelled):
/// one parallel pass that stops at the first line crossed twice or near miss, and adds up the file's steps in the
/// +Z columns as it goes.
pub(crate) fn survey(spec: &GridSpec, tris: &GridTriangles, progress: &Progress) -> Survey {
    let axis = net_facing(tris, |_| true).abs().max_position();
    let (lines, columns) = (Tally::new(spec, axis), Tally::new(spec, 2));
    let lines_once = (0..tris.len()).into_par_iter().with_min_len(triangles_per_task(tris.len())).all(|t| {
        let triangle = tris.get(t);
        // Most triangles of a big model lie between the lines (their box, widened by NEAR, holds no centre's
        // coordinate along one of the two axes across the lines): they cross none and come near no centre.
        let holds = |k: usize| {
            let [a, b, c] = triangle.map(|corner| corner[k]);
            holds_centre(a.min(b).min(c) - NEAR, a.max(b).max(c) + NEAR, spec.dims[k])
        };
        // The +Z columns lie across X and Y, the lines along the axis across the two others; one axis is in both
        // pairs, and where the box holds no centre's coordinate along it, the triangle crosses no line of either.
        let shared = usize::from(axis == 0);
        if !holds(shared) {
            return true;
        }
        let (column_other, line_other) = (1 - shared, 3 - axis - shared);
        let holds_column_other = holds(column_other);
        if holds_column_other {
            columns.step(&triangle);
        }
        let holds_line_other = if line_other == column_other { holds_column_other } else { holds(line_other) };
        !holds_line_other
            || !progress.is_cancelled() && lines.cross(&triangle) && !centre_near(spec.dims, &triangle, axis)
    });
    Survey { lines_once, unbalanced: lines_once && columns.any() }
}

/// Adding and then subtracting this rounds an `f64` of magnitude below 2⁵¹ to the nearest whole number.
const ROUNDING: f64 = 6_755_399_441_055_744.0;

/// Whether [lo, hi] holds a centre's coordinate k + 0.5 (0 ≤ k < `n`) along an axis: the test of
/// [`column_range`] in a few float operations (no rounding call, no cast: this runs for every triangle).
#[inline]
fn holds_centre(lo: f64, hi: f64, n: u32) -> bool {
    let (a, b) = (lo - 0.5, hi - 0.5);
    if !(a.abs() < ROUNDING / 8.0 && b.abs() < ROUNDING / 8.0) {
        return !column_range(lo, hi, n).is_empty(); // far out (or not a number)
    }
    let floor = |x: f64| {
        let nearest = (x + ROUNDING) - ROUNDING;
        if nearest > x { nearest - 1.0 } else { nearest }
    };
    let (first, last) = (-floor(-a), floor(b));
    first <= last && last >= 0.0 && first <= f64::from(n) - 1.0
}

/// Whether a cell centre of a grid of `dims` cells lies within [`NEAR`] of triangle `t` without the line along
/// `axis` through it crossing `t` ([`covers_column`]). Near: within `NEAR` of its bounding box and of its plane
/// (measured along the axis its normal is largest on, at every line of centres along it through the box); for a
/// triangle without a normal, any centre in its box.
fn centre_near(dims: [u32; 3], t: &GridTriangle, axis: usize) -> bool {
    let (lo, hi) = (t[0].min(t[1]).min(t[2]) - NEAR, t[0].max(t[1]).max(t[2]) + NEAR);
    if (0..3).any(|k| !holds_centre(lo[k], hi[k], dims[k])) {
        return false;
    }
    let centres = |k: usize| column_range(lo[k], hi[k], dims[k]);
    let normal = triangle_normal(t);
    let length = normal.length();
    if length == 0.0 {
        return true;
    }
    let w = normal.abs().max_position();
    let (u, v) = ((w + 1) % 3, (w + 2) % 3);
    let along = centres(w);
    let (first, last) = (f64::from(along.start) + 0.5, f64::from(along.end - 1) + 0.5);
    centres(u).any(|a| {
        centres(v).any(|b| {
            let mut p = DVec3::ZERO;
            (p[u], p[v]) = (f64::from(a) + 0.5, f64::from(b) + 0.5);
            // Where the plane meets the line through (a, b) along w, and the centre on it nearest to that.
            let at = t[0][w] - (normal[u] * (p[u] - t[0][u]) + normal[v] * (p[v] - t[0][v])) / normal[w];
            p[w] = ((at - 0.5).round() + 0.5).clamp(first, last);
            let line = cycled(p, axis);
            (at - p[w]).abs() * normal[w].abs() <= NEAR * length
                && !covers_column(&t.map(|c| cycled(c, axis)), [line.x, line.y])
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::GridSize;
    use crate::shapes::cuboid;
    use crate::soup::TriangleSoup;

    /// Cells per side of the test grid.
    const N: u32 = 8;

    /// A grid of N × N × N cells.
    fn grid() -> GridSpec {
        let soup = TriangleSoup::from_mesh(&cuboid([0.0; 3], [1.0; 3]), [1.0; 4]);
        let spec = GridSpec::fit(&soup, 9.0, GridSize::Resolution(N), 1.0, 1 << 20).unwrap();
        assert_eq!(spec.dims, [N; 3]);
        spec
    }

    /// A terrain over the whole grid facing up (+Y), 2 × 16 × 16 triangles; its height at (x, z) by `height`.
    fn terrain(height: impl Fn(f64, f64) -> f64) -> Vec<GridTriangle> {
        let at = |i: u32, k: u32| {
            let (x, z) = (f64::from(i) / 2.0, f64::from(k) / 2.0);
            DVec3::new(x, height(x, z), z)
        };
        (0..16)
            .flat_map(|i| (0..16).map(move |k| (i, k)))
            .flat_map(|(i, k)| [[at(i, k), at(i, k + 1), at(i + 1, k)], [at(i + 1, k), at(i, k + 1), at(i + 1, k + 1)]])
            .collect()
    }

    fn hills(x: f64, z: f64) -> f64 {
        4.0 + 1.7 * (0.9 * x).sin() * (0.7 * z).cos()
    }

    /// Whether the survey finds that no line crosses two of `tris` (and no near miss).
    fn lines_once(tris: &[GridTriangle]) -> bool {
        survey(&grid(), &GridTriangles::from_triangles(tris), &Progress::new()).lines_once
    }

    /// A closed prism along Y (from y = 1 to 7) over the triangle `section` of the XZ plane, facing out.
    fn prism(section: [[f64; 2]; 3]) -> Vec<GridTriangle> {
        let at = |k: usize, y: f64| DVec3::new(section[k][0], y, section[k][1]);
        let mut tris = vec![[at(0, 1.0), at(1, 1.0), at(2, 1.0)], [at(0, 7.0), at(2, 7.0), at(1, 7.0)]];
        for k in 0..3 {
            let next = (k + 1) % 3;
            tris.push([at(k, 1.0), at(k, 7.0), at(next, 1.0)]);
            tris.push([at(next, 1.0), at(k, 7.0), at(next, 7.0)]);
        }
        tris
    }

    #[test]
    fn a_terrain_fills_nothing_but_not_with_a_part_under_it() {
        let land = terrain(hills);
        assert!(land.iter().all(|t| triangle_normal(t).y > 0.0), "the terrain faces up");
        assert!(lines_once(&land));
        // A box under the hills: the lines along Y through it cross it twice.
        let block = cuboid([2.2, 0.2, 2.2], [5.8, 1.8, 5.8]);
        let mut with_box = land.clone();
        with_box
            .extend(block.triangles.iter().map(|t| t.map(|i| DVec3::from(block.positions[i as usize].map(f64::from)))));
        assert!(!lines_once(&with_box));
    }

    #[test]
    fn a_centre_on_a_triangle_counts_only_where_its_line_crosses_the_triangle() {
        // A floor through the centres at y = 3.5: the lines along Y cross it there.
        let floor = [DVec3::new(-1.0, 3.5, -1.0), DVec3::new(-1.0, 3.5, 20.0), DVec3::new(20.0, 3.5, -1.0)];
        assert!(lines_once(&[floor]));
        // Made of a lattice of half-cell triangles, its corners fall on centres, and there every triangle but one
        // meets the line beside it (the tie-break gives the centre to one): no decision, the parts decide.
        assert!(!lines_once(&terrain(|_, _| 3.5)));
        // A thin prism along Y beside the hills whose slanted face runs through the centres (4.5, y, 2.5): its lines
        // along Y are edge-on to that face and the prism holds no centre, so no line crosses it twice, but those
        // centres lie on a face their lines miss: no decision (where the tie-breaks of the +Z columns and of the
        // lines put such centres on different sides of the face, the columns fill them: see
        // `a_thin_part_whose_face_runs_through_centres…` in tests/voxelize/winding.rs).
        let on = prism([[4.0, 2.0], [5.0, 3.0], [4.9, 2.3]]);
        let mut land = terrain(hills);
        land.extend(&on);
        assert!(!lines_once(&land));
        // Moved a quarter of a cell along X, off every centre: nothing is filled, and the test says so.
        let off = prism([[4.25, 2.0], [5.25, 3.0], [5.15, 2.3]]);
        let mut land = terrain(hills);
        land.extend(&off);
        assert!(lines_once(&land));
    }

    #[test]
    fn a_tray_fills_nothing_but_a_tube_balanced_as_in_the_file_is_left_to_the_columns() {
        // A box without its top, facing out: every line along Z crosses its bottom once, and the file's facing
        // leaves those columns entering (+1) without leaving.
        let mut tray = cuboid([1.2, 1.2, 1.2], [6.8, 6.8, 6.8]);
        tray.triangles.truncate(10);
        let tris: Vec<GridTriangle> =
            tray.triangles.iter().map(|t| t.map(|i| DVec3::from(tray.positions[i as usize].map(f64::from)))).collect();
        let tray_survey = survey(&grid(), &GridTriangles::from_triangles(&tris), &Progress::new());
        assert_eq!(tray_survey, Survey { lines_once: true, unbalanced: true });
        assert!(tray_survey.fills_nothing());
        // A tube along X facing out, without caps: its lines along X cross nothing, but it crosses every +Z column
        // through it twice, entering and leaving: the file's facing balances them and fills its bore, which the
        // survey must not call empty.
        let ring = |k: u32, x: f64| {
            let a = std::f64::consts::TAU * f64::from(k % 16) / 16.0;
            DVec3::new(x, 4.0 + 2.1 * a.cos(), 4.0 + 2.1 * a.sin())
        };
        let tube: Vec<GridTriangle> = (0..16)
            .flat_map(|k| {
                [[ring(k, 1.3), ring(k + 1, 1.3), ring(k, 6.7)], [ring(k + 1, 1.3), ring(k + 1, 6.7), ring(k, 6.7)]]
            })
            .collect();
        assert!(tube.iter().all(|t| triangle_normal(t).dot(t[0] - DVec3::new(t[0].x, 4.0, 4.0)) > 0.0), "facing out");
        let tube_survey = survey(&grid(), &GridTriangles::from_triangles(&tube), &Progress::new());
        assert!(!tube_survey.unbalanced && !tube_survey.fills_nothing(), "{tube_survey:?}");
    }

    #[test]
    fn the_quick_filter_is_the_column_range_test() {
        let mut random = crate::lcg::Lcg::new(3);
        let (mut met, mut missed) = (0, 0);
        for _ in 0..200_000 {
            // Ends on a lattice of eighths, some nudged by a rounding, some beyond the grid.
            let mut end = |nudge: f64| (random.below(96) as f64 / 8.0 - 2.0) + nudge * (random.below(3) as f64 - 1.0);
            let (a, b) = (end(1e-15), end(1e-15));
            let (lo, hi) = (DVec3::new(a.min(b), 0.0, 0.0), DVec3::new(a.max(b), 0.0, 0.0));
            let exact = !column_range(lo.x, hi.x, N).is_empty();
            let quick = holds_centre(lo.x, hi.x, N);
            assert_eq!(quick, exact, "{lo} {hi}");
            met += usize::from(quick);
            missed += usize::from(!quick);
        }
        assert!(met > 100_000 && missed > 10_000, "{met} {missed}");
        for (lo, hi) in [(-1e9, 1e9), (1e9, 2e9), (-2e9, -1e9), (3.5, 3.5), (7.5, 40.0), (-40.0, 0.5), (-0.6, 0.4)] {
            assert_eq!(holds_centre(lo, hi, N), !column_range(lo, hi, N).is_empty(), "{lo} {hi}");
        }
    }
}
