//! The closed parts of a soup, found once and reused at every grid.
//!
//! The app voxelizes the same soup again at every grid size the user picks, and the part analysis (welding,
//! sheets, closed parts: see [`super`]) is most of what the winding fill costs over parity on a model whose
//! columns do not balance as in the file. It depends only on which corners are at the same position, so the
//! parts of the soup's own positions serve every grid on which no two of the soup's different positions land
//! on the same grid point (checked at every grid; the grid's snapping can weld two corners less than a
//! snapping step apart, and then that grid's own positions are analysed). The analysis depends on the welding
//! only, not on the positions' hash order (ties and non-manifold edges are decided in triangle and corner
//! order), so the parts are the ones the grid's positions give.
//!
//! The last four soups are kept, each with a copy of its corner positions: a soup is recognised by comparing
//! them bit for bit, so a soup changed since (a new pose, an edited mesh) is analysed anew. A soup seen for
//! the first time is analysed on its grid; when it is voxelized again, its distinct positions are found, and
//! the parts of its first grid are the soup's when that grid kept them apart (else the soup's own positions
//! are analysed). So a soup voxelized once (the command line's files) costs only the copy of its positions
//! over the analysis of its grid.

use std::sync::{Arc, Mutex, OnceLock, PoisonError};

use glam::DVec3;

use super::{Parts, mix, position_key};
use crate::geom::GridTriangle;
use crate::grid::GridSpec;
use crate::soup::TriangleSoup;

/// How many soups are kept.
const KEPT: usize = 4;

/// The most recently used soups' parts, most recent first.
static RECENT: Mutex<Vec<Arc<SoupParts>>> = Mutex::new(Vec::new());

/// A soup seen, and its closed parts found with its own positions once it is seen again.
struct SoupParts {
    /// The soup's corner positions (as bits): what recognises it.
    corners: Vec<[u32; 3]>,
    /// The grid the soup was first voxelized on, and the parts found there.
    first: (GridSpec, Arc<Parts>),
    /// The analysis of its own positions.
    analysed: OnceLock<Analysis>,
}

/// The closed parts of a soup's own positions.
struct Analysis {
    /// Its distinct positions.
    distinct: Vec<[f32; 3]>,
    /// The parts its positions give.
    parts: Arc<Parts>,
}

impl SoupParts {
    /// Recognises `soup` from now on; `parts` were found on the grid `spec`.
    fn new(soup: &TriangleSoup, spec: GridSpec, parts: Arc<Parts>) -> Self {
        Self {
            corners: soup.vertices.iter().map(|v| v.position.map(f32::to_bits)).collect(),
            first: (spec, parts),
            analysed: OnceLock::new(),
        }
    }

    /// The analysis of `soup`'s own positions (found on the first call): the first grid's parts when that
    /// grid kept the soup's positions apart (the usual case), else those of the soup's positions.
    fn analysis(&self, soup: &TriangleSoup) -> &Analysis {
        self.analysed.get_or_init(|| {
            let positions: Vec<[f32; 3]> = soup.vertices.iter().map(|v| v.position).collect();
            let distinct = distinct(&positions);
            let parts = if keeps_apart(&self.first.0, &distinct) {
                Arc::clone(&self.first.1)
            } else {
                let tris: Vec<GridTriangle> =
                    positions.chunks_exact(3).map(|t| [0, 1, 2].map(|k| DVec3::from(t[k].map(f64::from)))).collect();
                Arc::new(Parts::find(&tris))
            };
            Analysis { distinct, parts }
        })
    }

    /// Whether this is `soup`'s analysis (the same corner positions, bit for bit).
    fn is_of(&self, soup: &TriangleSoup) -> bool {
        self.corners.len() == soup.vertices.len()
            && self.corners.iter().zip(&soup.vertices).all(|(c, v)| *c == v.position.map(f32::to_bits))
    }
}

/// The closed parts of `tris`, the triangles of `soup` on the grid `spec`: the soup's own, found once per
/// soup (from its second voxelization on), when the grid keeps its different positions apart; else found
/// with the grid's positions.
pub(crate) fn closed_parts(soup: &TriangleSoup, spec: &GridSpec, tris: &[GridTriangle]) -> Arc<Parts> {
    let found = {
        let mut recent = RECENT.lock().unwrap_or_else(PoisonError::into_inner);
        let at = recent.iter().position(|entry| entry.is_of(soup));
        at.map(|at| {
            let entry = recent.remove(at);
            recent.insert(0, Arc::clone(&entry));
            entry
        })
    };
    let Some(entry) = found else {
        let parts = Arc::new(Parts::find(tris));
        let mut recent = RECENT.lock().unwrap_or_else(PoisonError::into_inner);
        recent.insert(0, Arc::new(SoupParts::new(soup, *spec, Arc::clone(&parts))));
        recent.truncate(KEPT);
        return parts;
    };
    // Analysed outside the lock: another soup's voxelization need not wait for this one.
    let analysis = entry.analysis(soup);
    if keeps_apart(spec, &analysis.distinct) { Arc::clone(&analysis.parts) } else { Arc::new(Parts::find(tris)) }
}

/// The distinct values of `positions` (-0 and +0 alike), in order of first appearance.
fn distinct(positions: &[[f32; 3]]) -> Vec<[f32; 3]> {
    let keys: Vec<[u64; 3]> = positions.iter().map(|p| position_key(DVec3::from(p.map(f64::from)))).collect();
    firsts(&keys).into_iter().map(|i| positions[i as usize]).collect()
}

/// Whether the grid maps the different positions `distinct` to different grid points.
fn keeps_apart(spec: &GridSpec, distinct: &[[f32; 3]]) -> bool {
    let keys: Vec<[u64; 3]> = distinct.iter().map(|&p| position_key(spec.to_grid(p))).collect();
    firsts(&keys).len() == keys.len()
}

/// The index of the first of each distinct key, ascending (one pass through an open-addressing table twice
/// the keys' size).
fn firsts(keys: &[[u64; 3]]) -> Vec<u32> {
    let bits = (2 * keys.len()).next_power_of_two().max(2).ilog2();
    let mut slots = vec![u32::MAX; 1 << bits];
    let mask = slots.len() - 1;
    let mut firsts = Vec::new();
    for (i, key) in keys.iter().enumerate() {
        let mut slot = (mix(mix(key[0] ^ key[1].rotate_left(32)) ^ key[2]) >> (64 - bits)) as usize;
        loop {
            match slots[slot] {
                u32::MAX => {
                    slots[slot] = i as u32;
                    firsts.push(i as u32);
                    break;
                }
                j if keys[j as usize] == *key => break,
                _ => slot = (slot + 1) & mask,
            }
        }
    }
    firsts
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::GridSize;
    use crate::shapes::cuboid;

    /// A box [0, 1]³ and a box from x = 1 + `gap` to 2, each without its face towards the other.
    fn boxes(gap: f32) -> TriangleSoup {
        let without_face = |lo: [f32; 3], hi: [f32; 3], x: f32| {
            let mut mesh = cuboid(lo, hi);
            let positions = mesh.positions.clone();
            mesh.triangles.retain(|t| !t.iter().all(|&i| positions[i as usize][0] == x));
            mesh
        };
        let mut mesh = without_face([0.0; 3], [1.0; 3], 1.0);
        let other = without_face([1.0 + gap, 0.0, 0.0], [2.0, 1.0, 1.0], 1.0 + gap);
        let offset = mesh.positions.len() as u32;
        mesh.positions.extend(&other.positions);
        mesh.triangles.extend(other.triangles.iter().map(|t| t.map(|i| i + offset)));
        TriangleSoup::from_mesh(&mesh, [1.0; 4])
    }

    fn spec(soup: &TriangleSoup, r: u32) -> GridSpec {
        GridSpec::fit(soup, 9.0, GridSize::Resolution(r), 1.0, 1 << 24).unwrap()
    }

    fn positions(soup: &TriangleSoup) -> Vec<[f32; 3]> {
        soup.vertices.iter().map(|v| v.position).collect()
    }

    #[test]
    fn distinct_positions_weld_equal_corners_and_signed_zeros() {
        let found = distinct(&[[0.0, 1.0, 2.0], [-0.0, 1.0, 2.0], [0.0, 1.0, 2.5], [0.0, 1.0, 2.0]]);
        assert_eq!(found, [[0.0, 1.0, 2.0], [0.0, 1.0, 2.5]]);
        // Many keys, few distinct: the table's probing finds every repeat.
        let many: Vec<[f32; 3]> = (0..20_000).map(|i| [(i % 97) as f32, (i % 89) as f32 * 0.5, 1.0]).collect();
        assert_eq!(distinct(&many).len(), 97 * 89);
    }

    #[test]
    fn the_soups_parts_are_the_grids_at_every_grid_that_keeps_its_corners_apart() {
        // Two open boxes a quarter apart: no closed part.
        let soup = boxes(0.25);
        for r in [4, 16, 64] {
            let spec = spec(&soup, r);
            let tris = spec.grid_triangles(&soup);
            assert!(keeps_apart(&spec, &distinct(&positions(&soup))));
            let parts = closed_parts(&soup, &spec, &tris);
            assert_eq!(*parts, Parts::find(&tris), "R={r}");
            assert_eq!(parts.count, 0);
        }
        // Recognised by its positions only; the first grid's parts are the soup's.
        let spec = spec(&soup, 16);
        let parts = Arc::new(Parts::find(&spec.grid_triangles(&soup)));
        let analysed = SoupParts::new(&soup, spec, Arc::clone(&parts));
        assert!(Arc::ptr_eq(&analysed.analysis(&soup).parts, &parts));
        let mut moved = soup.clone();
        assert!(analysed.is_of(&moved));
        moved.vertices[0].position[2] = 0.5;
        assert!(!analysed.is_of(&moved));
    }

    #[test]
    fn corners_the_grid_welds_are_analysed_with_the_grids_positions() {
        // 2⁻²⁰ apart: two open boxes in the soup, one closed box on a coarse grid, whose snapping welds them.
        let soup = boxes(1.0 / (1 << 20) as f32);
        let spec = spec(&soup, 4);
        let tris = spec.grid_triangles(&soup);
        assert!(!keeps_apart(&spec, &distinct(&positions(&soup))));
        let parts = closed_parts(&soup, &spec, &tris);
        assert_eq!(*parts, Parts::find(&tris));
        // First seen on that grid, the soup is analysed with its own positions.
        let seen = SoupParts::new(&soup, spec, Arc::clone(&parts));
        assert_eq!((parts.count, seen.analysis(&soup).parts.count), (1, 0));
    }
}
