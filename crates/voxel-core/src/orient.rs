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
//! Corners are welded by their exact position (the soup's own, once per soup: see `soup_parts`; a grid's
//! where its snapping welds two of the soup's positions), numbering the positions. A *sheet* is a set of
//! triangles connected through manifold edges (edges used by exactly two triangles, found by bucketing the
//! corners by their edge's ends: see `edges`); a walk over those edges orients it consistently (each
//! triangle keeps or reverses its corner order; the sheet takes the orientation most of its triangles have
//! in the file) unless a cycle contradicts itself. A
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
//! [`crate::fill`]: where they alone fill a cell, they must enclose it along every axis).

mod edges;
mod parts;
mod soup_parts;
mod weld;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::DVec3;
use rayon::prelude::*;

use crate::columns::{Columns, Role, parity_counts};
use crate::soup::TriangleSoup;
use parts::{NO_PART, Parts};
use soup_parts::SoupParts;

pub(crate) use soup_parts::closed_parts;

/// The role of every triangle under the nonzero winding rule (see the module docs). `columns` are the
/// model's column crossings when the caller has them; otherwise `crossings` computes them. `closed_parts`
/// gives the closed parts of the triangles ([`Parts::find`], or [`closed_parts`] reusing a soup's), when the
/// triangles as in the file do not do; unless `fills_nothing` finds first that with roles from the parts,
/// whatever they are, the fill is empty: then `None`.
pub(crate) fn winding_roles(
    columns: Option<&Columns>,
    crossings: impl FnOnce() -> Columns,
    fills_nothing: impl FnOnce() -> bool,
    closed_parts: impl FnOnce() -> Arc<Parts>,
) -> Option<Vec<Role>> {
    let computed;
    let columns = match columns {
        Some(c) => c,
        None => {
            computed = crossings();
            &computed
        }
    };
    let as_in_file: Vec<Role> = columns.faces_up.iter().map(|&up| Role::facing(up)).collect();
    if consistent_as_in_file(columns, &as_in_file) {
        return Some(as_in_file);
    }
    if fills_nothing() {
        return None;
    }
    let parts = closed_parts();
    let inward = &parts.inward;
    let mut roles = as_in_file;
    for ((role, &part), &reversed) in roles.iter_mut().zip(&parts.of).zip(&parts.reversed) {
        *role = match part {
            NO_PART => Role::Parity,
            _ if reversed => role.reversed(),
            _ => *role,
        };
    }
    if !inward.contains(&true) {
        return Some(roles);
    }
    let exposed = exposed_parts(columns, &roles, &parts.of, inward);
    for (t, role) in roles.iter_mut().enumerate() {
        if parts.of[t] != NO_PART && exposed[parts.of[t] as usize] {
            *role = role.reversed();
        }
    }
    Some(roles)
}

/// Analyses `soup`'s closed parts now (the analysis it keeps, [`SoupParts::kept_by`]) when it has none
/// yet and its facing hints that a winding fill will need them ([`parts_likely_needed`]): then the caller can run
/// this beside work that does not (the grid's set-up), unless that work is already over (`settled`: then the
/// fill has run the analysis itself if it needed it). A soup that the hint misses is analysed when its columns
/// show the need, as before.
pub(crate) fn analyse_parts_ahead(soup: &TriangleSoup, settled: &AtomicBool) {
    // `settled` is asked again after the hint's pass over the triangles.
    let over = || settled.load(Ordering::Relaxed);
    if !over() && !SoupParts::kept(soup) && parts_likely_needed(soup) && !over() {
        SoupParts::kept_by(soup);
    }
}

/// Whether `soup`'s triangles, facing as in the file, fail to cancel out on the XY plane, yet do not all face
/// one way along an axis. Their areas projected along the columns, signed by facing, do not add up to zero
/// (beyond rounding and quantization: more than 10⁻⁵ of their sum unsigned; the Draco milk truck leaves
/// 1.7·10⁻⁶, the FlightHelmet's open sheets 7·10⁻⁴). A closed surface's do, whichever way it faces; an open
/// sheet's, or a closed part's with some horizontal triangles reversed, usually do not, and then the columns of a
/// fine grid cannot all balance as in the file, so the winding fill will need the soup's part analysis — unless
/// it finds first that it fills nothing (a terrain, a cloth: see `fill::height_field`), which a sheet whose
/// projected areas along some axis all face one way (to within 10⁻³ of their sum unsigned) most likely is. Only
/// a hint for starting that analysis before the grid exists: the fill itself decides by its columns
/// ([`winding_roles`]).
fn parts_likely_needed(soup: &TriangleSoup) -> bool {
    // Differences of nearby f32 coordinates are exact; their products are exact in f64.
    let sides = |t: usize| {
        let [a, b, c] = soup.triangle_positions(t);
        let d = |p: [f32; 3]| DVec3::from(std::array::from_fn::<f64, 3, _>(|k| f64::from(p[k] - a[k])));
        (d(b), d(c))
    };
    // Facing one way: from a sample of about 2¹⁶, evenly spread (a sheet facing one way does so in any sample; a
    // closed surface does not), first, as it settles a terrain at once.
    let every = soup.triangle_count().div_ceil(1 << 16).max(1);
    let (mut net, mut total) = (DVec3::ZERO, DVec3::ZERO);
    for t in (0..soup.triangle_count()).step_by(every) {
        let (b, c) = sides(t);
        let twice = b.cross(c);
        net += twice;
        total += twice.abs();
    }
    if (0..3).any(|k| total[k] > 0.0 && net[k].abs() >= (1.0 - 1e-3) * total[k]) {
        return false;
    }
    // Along Z from every triangle: a closed surface's cancel only in the sum of all.
    let (mut net_z, mut total_z) = (0.0f64, 0.0f64);
    for t in 0..soup.triangle_count() {
        let (b, c) = sides(t);
        let twice_area = b.x * c.y - b.y * c.x;
        net_z += twice_area;
        total_z += twice_area.abs();
    }
    net_z.abs() > 1e-5 * total_z
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
    use glam::DVec3;

    use super::*;
    use crate::columns::crossings_by_rasterizing;
    use crate::grid::{GridSize, GridSpec, GridTriangles};
    use crate::progress::Progress;
    use crate::shapes::{IndexedMesh, cuboid};
    use crate::soup::TriangleSoup;

    fn grid_tris(mesh: &IndexedMesh) -> GridTriangles<'_> {
        GridTriangles::indexed(mesh.positions.iter().map(|p| DVec3::from(p.map(f64::from))).collect(), &mesh.triangles)
    }

    /// The roles of `mesh`'s triangles, voxelized in a 4 × 4 × 4 grid around it.
    fn roles(mesh: &IndexedMesh) -> Vec<Role> {
        let soup = TriangleSoup::from_mesh(mesh, [1.0; 4]);
        let spec = GridSpec::fit(&soup, 9.0, GridSize::Resolution(4), 1.0, 1 << 20).unwrap();
        let tris = spec.grid_triangles(&soup);
        winding_roles(
            None,
            || crossings_by_rasterizing(&spec, &tris, &Progress::new()),
            || false,
            || Arc::new(Parts::find(&tris)),
        )
        .expect("the roles")
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
    fn a_box_is_one_closed_part_and_its_bottom_enters() {
        let parts = Parts::find(&grid_tris(&block()));
        assert_eq!((parts.count(), parts.of.iter().all(|&p| p == 0)), (1, true));
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
        assert_eq!(parts.count(), 1);
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
    fn the_hint_sees_open_sheets_and_reversed_horizontal_triangles_but_not_closed_surfaces_nor_height_fields() {
        let hint = |mesh: &IndexedMesh| parts_likely_needed(&TriangleSoup::from_mesh(mesh, [1.0; 4]));
        // Closed, facing out or in: the projections cancel.
        assert!(!hint(&block()) && !hint(&reversed(block(), 1)));
        // A reversed bottom triangle (the last four are the horizontal faces: bottom, then top), or half the top
        // missing.
        let mut bottom = block();
        bottom.triangles[8].swap(1, 2);
        let mut open = block();
        open.triangles.truncate(11);
        assert!(hint(&bottom) && hint(&open));
        // Without its top the box is a tray: every triangle that projects on the XY plane faces down, as a
        // terrain's face up: the fill will find it empty without the parts.
        let mut tray = block();
        tray.triangles.truncate(10);
        assert!(!hint(&tray));
        // A reversed side triangle projects to a line: nothing to see, the columns decide.
        let mut side = block();
        side.triangles[0].swap(1, 2);
        assert!(!hint(&side));
    }

    #[test]
    fn a_soup_is_analysed_ahead_only_when_its_facing_does_not_cancel_and_the_passes_are_not_over() {
        use crate::options::{FillMode, VoxelizeOptions};
        use crate::voxelize::voxelize;
        let analysed_ahead = |mesh: &IndexedMesh| {
            let soup = TriangleSoup::from_mesh(mesh, [1.0; 4]);
            analyse_parts_ahead(&soup, &AtomicBool::new(false));
            SoupParts::kept(&soup)
        };
        // A closed box: nothing to analyse ahead.
        assert!(!analysed_ahead(&block()));
        // With a speck of a horizontal triangle beside it, which no column crosses: the columns still balance,
        // but the projections do not cancel, so the hint starts the analysis.
        let mut speck = block();
        speck.positions.extend([[3.9, 1.3, 1.7], [4.0, 1.3, 1.7], [3.9, 1.4, 1.7]]);
        speck.triangles.push([8, 9, 10]);
        let soup = TriangleSoup::from_mesh(&speck, [1.0; 4]);
        let spec = GridSpec::fit(&soup, 9.0, GridSize::Resolution(8), 1.0, 1 << 20).unwrap();
        let columns = crossings_by_rasterizing(&spec, &spec.grid_triangles(&soup), &Progress::new());
        let as_in_file: Vec<Role> = columns.faces_up.iter().map(|&up| Role::facing(up)).collect();
        assert!(consistent_as_in_file(&columns, &as_in_file), "the speck must cross no column");
        assert!(analysed_ahead(&speck));
        // With one thread the passes are over before the analysis could start, and they did not need it.
        let options = VoxelizeOptions { grid: GridSize::Resolution(8), fill: FillMode::Winding, ..Default::default() };
        let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        one_thread.install(|| voxelize(&soup, &options)).unwrap();
        assert!(!SoupParts::kept(&soup));
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
        assert_eq!(Parts::find(&grid_tris(&two)).count(), 2);
        let mut fin = cuboid([0.0; 3], [1.0; 3]);
        fin.positions.push([0.5, -0.5, 1.5]);
        fin.triangles.push([4, 5, 8]);
        let parts = Parts::find(&grid_tris(&fin));
        assert_eq!(parts.count(), 1);
        assert_eq!(parts.of[..12], [0; 12]);
        assert_eq!(parts.of[12], NO_PART);
    }
}
