//! The closed parts of a soup, found once and kept by the soup.
//!
//! The app voxelizes the same soup again at every grid size the user picks, and the part analysis (welding,
//! sheets, closed parts: see [`super`]) depends only on which corners share a position. So the soup keeps
//! the analysis of its own positions ([`SoupParts::kept_by`], in the soup's position cache: found when a winding
//! fill first needs it, dropped whenever its positions can change: a clone shares it, a new pose starts without
//! one), and
//! every grid on which no two of the soup's different positions land on the same grid point uses it (checked
//! at every grid: its snapping can weld two corners less than a snapping step apart, and then that grid's
//! own positions are analysed). The soup's positions are welded as the grid's are, so on such a grid the
//! parts are exactly the ones the grid's positions give.

use std::cell::Cell;
use std::sync::Arc;

use glam::DVec3;

use super::parts::Parts;
use super::weld::{all_different, grid_key, soup_key, weld, weld_indexed};
use crate::grid::GridTriangles;
use crate::soup::TriangleSoup;

/// The closed parts of a soup's own positions.
#[derive(Debug)]
pub(crate) struct SoupParts {
    /// The first corner at each of the soup's distinct positions.
    first: Vec<u32>,
    /// The parts its positions give.
    parts: Arc<Parts>,
}

impl SoupParts {
    /// The closed parts of `soup`'s positions, kept in its position cache: found on the first call.
    /// A voxelization may start the analysis on one thread while another waits for it here, so the analysis must
    /// not wait for the thread pool (it runs no rayon tasks): a thread blocked here then never holds work it needs.
    pub(crate) fn kept_by(soup: &TriangleSoup) -> &Self {
        thread_local!(static ANALYSING: Cell<bool> = const { Cell::new(false) });
        /// Clears the flag however the analysis ends (a panic included: the thread lives on in the pool).
        struct Analysing;
        impl Drop for Analysing {
            fn drop(&mut self) {
                ANALYSING.set(false);
            }
        }
        debug_assert!(!ANALYSING.get(), "the part analysis waited for the thread pool and ran into itself");
        soup.position_cache().get_or_init(|| {
            ANALYSING.set(true);
            let _analysing = Analysing;
            Self::of(soup)
        })
    }

    /// Whether `soup` keeps its closed parts (found, and its positions not changed since).
    pub(crate) fn kept(soup: &TriangleSoup) -> bool {
        soup.position_cache().get::<Self>().is_some()
    }

    /// Analyses `soup`'s positions.
    pub(crate) fn of(soup: &TriangleSoup) -> Self {
        let (positions, corners) = (soup.positions(), soup.triangles().as_flattened());
        // Vertices save work when corners share them (a soup of separate triangles has one a corner).
        let welded = if 2 * positions.len() <= corners.len() {
            weld_indexed(positions, |&p| soup_key(p), corners)
        } else {
            weld(corners, |&i| soup_key(positions[i as usize]))
        };
        // Seen from the first corner (exact differences in f64), so that a model far from the origin does not
        // lose its volume to rounding.
        let origin = corners.first().map_or(DVec3::ZERO, |&i| position(positions[i as usize]));
        let parts = Parts::of_welded(&welded.id, welded.first.len(), |t| {
            soup.triangle_positions(t).map(|p| position(p) - origin)
        });
        Self { parts: Arc::new(parts), first: welded.first }
    }

    /// Whether the soup's grid triangles `tris` keep its different positions apart.
    fn kept_apart_by(&self, tris: &GridTriangles) -> bool {
        let (vertices, corners) = (tris.vertices(), tris.corners());
        let on_grid = self.first.iter().map(|&c| grid_key(vertices[corners[c as usize] as usize]));
        all_different(self.first.len(), on_grid)
    }
}

/// A soup position in f64.
fn position(p: [f32; 3]) -> DVec3 {
    DVec3::from(p.map(f64::from))
}

/// The closed parts of `tris`, the triangles of `soup` on a grid: the soup's own when the grid keeps its
/// different positions apart, else found with the grid's positions.
pub(crate) fn closed_parts(soup: &TriangleSoup, tris: &GridTriangles) -> Arc<Parts> {
    let own = SoupParts::kept_by(soup);
    if own.kept_apart_by(tris) { Arc::clone(&own.parts) } else { Arc::new(Parts::find(tris)) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{GridSize, GridSpec};
    use crate::options::VoxelizeOptions;
    use crate::orient::weld::Welded;
    use crate::shapes::{IndexedMesh, cuboid};
    use crate::voxelize::voxelize;

    /// A box [0, 1]³ and a box from x = 1 + `gap` to 2, each without its face towards the other.
    fn boxes(gap: f32) -> TriangleSoup {
        let without_face = |lo: [f32; 3], hi: [f32; 3], x: f32| {
            let mut mesh = cuboid(lo, hi);
            let positions = mesh.positions.clone();
            mesh.triangles.retain(|t| !t.iter().all(|&i| positions[i as usize][0] == x));
            mesh
        };
        let mut mesh = without_face([0.0; 3], [1.0; 3], 1.0);
        append(&mut mesh, &without_face([1.0 + gap, 0.0, 0.0], [2.0, 1.0, 1.0], 1.0 + gap));
        TriangleSoup::from_mesh(&mesh, [1.0; 4])
    }

    fn append(mesh: &mut IndexedMesh, other: &IndexedMesh) {
        let offset = mesh.positions.len() as u32;
        mesh.positions.extend(&other.positions);
        mesh.triangles.extend(other.triangles.iter().map(|t| t.map(|i| i + offset)));
    }

    fn grid_tris(soup: &TriangleSoup, r: u32) -> GridTriangles<'_> {
        GridSpec::fit(soup, 9.0, GridSize::Resolution(r), 1.0, 1 << 24).unwrap().grid_triangles(soup)
    }

    fn cells(soup: &TriangleSoup, r: u32) -> Vec<[u16; 3]> {
        let options = VoxelizeOptions { grid: GridSize::Resolution(r), ..Default::default() };
        voxelize(soup, &options).unwrap().voxels().map(|v| v.cell).collect()
    }

    #[test]
    fn one_analysis_serves_every_grid_that_keeps_the_corners_apart() {
        // Touching: one closed box; a quarter apart: two open ones.
        for (gap, count) in [(0.0, 1), (0.25, 0)] {
            let soup = boxes(gap);
            let first = closed_parts(&soup, &grid_tris(&soup, 4));
            assert_eq!(first.count(), count);
            for r in [4, 16, 64] {
                let tris = grid_tris(&soup, r);
                let parts = closed_parts(&soup, &tris);
                assert!(Arc::ptr_eq(&parts, &first), "gap {gap}, R={r}: analysed again");
                assert_eq!(*parts, Parts::find(&tris), "gap {gap}, R={r}");
            }
        }
    }

    #[test]
    fn a_clone_shares_the_analysis_until_its_positions_change() {
        let soup = boxes(0.25);
        let tris = grid_tris(&soup, 16);
        let open = closed_parts(&soup, &tris);
        let mut moved = soup.clone();
        assert!(Arc::ptr_eq(&closed_parts(&moved, &tris), &open));
        // The right box moved against the left one: a closed box, in the clone only.
        for p in moved.positions_mut().iter_mut().filter(|p| p[0] == 1.25) {
            p[0] = 1.0;
        }
        let tris = grid_tris(&moved, 16);
        assert_eq!(closed_parts(&moved, &tris).count(), 1);
        assert_eq!(*closed_parts(&moved, &tris), Parts::find(&tris));
        assert!(Arc::ptr_eq(&closed_parts(&soup, &grid_tris(&soup, 16)), &open));
    }

    #[test]
    fn a_changed_soup_fills_as_a_fresh_one() {
        // A box with a bottom triangle reversed (so the parts are analysed) around a cavity facing inwards.
        let mut mesh = cuboid([0.0; 3], [3.0; 3]);
        mesh.triangles[8].swap(1, 2);
        let mut cavity = cuboid([1.0; 3], [2.0; 3]);
        cavity.triangles.iter_mut().for_each(|t| t.swap(1, 2));
        append(&mut mesh, &cavity);
        let mut soup = separate_corners(&TriangleSoup::from_mesh(&mesh, [1.0; 4]));
        let hollow = cells(&soup, 12);
        assert_eq!(hollow, cells(&soup, 12), "the analysis reused");
        // One corner of the cavity moved off its neighbours': the cavity's wall is cracked (open), so it
        // counts by parity and no longer subtracts.
        let corner = 3 * 12;
        soup.positions_mut()[corner][0] += 0.001;
        let filled = cells(&soup, 12);
        assert_eq!(filled, cells(&separate_corners(&soup), 12));
        assert_eq!((hollow.len() + 4 * 4 * 4, filled.len()), (12 * 12 * 12, 12 * 12 * 12));
    }

    #[test]
    fn corners_the_grid_welds_are_analysed_with_the_grids_positions() {
        // 2⁻²⁰ apart: two open boxes in the soup, one closed box on a coarse grid, whose snapping welds them.
        let soup = boxes(1.0 / (1 << 20) as f32);
        let tris = grid_tris(&soup, 4);
        let parts = closed_parts(&soup, &tris);
        assert_eq!(*parts, Parts::find(&tris));
        assert_eq!((parts.count(), SoupParts::kept_by(&soup).parts.count()), (1, 0));
    }

    fn welded_fields(w: Welded) -> (Vec<u32>, Vec<u32>) {
        (w.id, w.first)
    }

    #[test]
    fn the_imported_vertices_weld_as_the_corners_do() {
        let Some(dir) = crate::test_models::models_dir() else { return };
        let mut files = crate::files::expand_inputs(std::slice::from_ref(&dir));
        for sub in std::fs::read_dir(&dir).unwrap().flatten().filter(|e| e.path().is_dir()) {
            files.extend(crate::files::expand_inputs(&[sub.path()]));
        }
        assert!(files.len() >= 17, "{} corpus models", files.len());
        for file in &files {
            let soup = crate::import::load_file(file).unwrap();
            let (positions, corners) = (soup.positions(), soup.triangles().as_flattened());
            let by_corner = weld(corners, |&i| soup_key(positions[i as usize]));
            assert_eq!(
                welded_fields(weld_indexed(positions, |&p| soup_key(p), corners)),
                welded_fields(by_corner),
                "{}",
                file.display()
            );
        }
    }

    #[test]
    fn indexed_and_separate_corners_give_one_analysis_forgotten_when_positions_change() {
        let mesh = cuboid([0.0; 3], [1.0; 3]);
        let indexed = TriangleSoup::from_mesh(&mesh, [1.0; 4]);
        assert_eq!((indexed.vertex_count(), indexed.triangles().len()), (8, 12));
        let separate = separate_corners(&indexed);
        assert_eq!(separate.vertex_count(), 36);
        assert_eq!(*SoupParts::kept_by(&indexed).parts, *SoupParts::kept_by(&separate).parts);
        let mut moved = indexed.clone();
        moved.positions_mut()[0][0] = 0.5;
        let mut grown = indexed.clone();
        grown.push_triangle(0, [crate::soup::Vertex::at([0.0; 3]); 3]);
        assert!(SoupParts::kept(&indexed) && !SoupParts::kept(&moved) && !SoupParts::kept(&grown));
    }

    /// `soup`'s triangles in one part, each with three vertices of its own.
    fn separate_corners(soup: &TriangleSoup) -> TriangleSoup {
        let mut separate = TriangleSoup::default();
        let material = separate.add_material(Default::default());
        let part = separate.add_part(material, "separate");
        for t in 0..soup.triangle_count() {
            separate.push_triangle(part, soup.triangle(t));
        }
        separate
    }

    #[test]
    fn welding_the_sources_numbers_the_corners_as_welding_the_corners_does() {
        // Repeated sources (two at one position, one with a −0), an unused one, corners in a scattered order.
        let positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-0.0, 0.0, 0.0], [5.0, 5.0, 5.0]];
        let index = [2, 1, 3, 0, 2, 1, 1, 3, 2];
        let corners: Vec<[f32; 3]> = index.iter().map(|&i| positions[i as usize]).collect();
        let by_corner = weld(&corners, |&p| soup_key(p));
        assert_eq!(welded_fields(weld_indexed(&positions, |&p| soup_key(p), &index)), welded_fields(by_corner));
        assert_eq!(welded_fields(weld_indexed(&positions, |&p| soup_key(p), &index)).0, [0, 1, 2, 2, 0, 1, 1, 2, 0]);
    }
}
