//! The colour pass: the colour and part of every visible cell, sampled at the closest point of the nearest
//! triangle, and the pastel remap of those colours.
//!
//! One parallel walk over the visible cells does everything for the cells near the surface (all but a few):
//! it steps along the shell's cells beside the visible ones (both ascending), takes the nearest of the
//! triangles the shell lists for the cell (or for its face neighbours), and samples the material there. The
//! cells far from every triangle are collected and coloured afterwards through one spatial index.

use std::sync::OnceLock;

use glam::DVec3;
use rayon::prelude::*;

use crate::bvh::TriangleBvh;
use crate::color::{pastel, sample};
use crate::geom::{GridTriangle, closest_point_barycentric, distance2, farther_than, point_at};
use crate::grid::{AscendingCoords, GridSpec};
use crate::shell::Shell;
use crate::shell::octree::ShellOctree;
use crate::soup::TriangleSoup;

/// The steps to the six face neighbours.
const FACE_STEPS: [[i32; 3]; 6] = [[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1]];

/// Visible cells handed to one task of the colour pass.
const CELLS_PER_TASK: usize = 1024;

/// Far cells handed to one task of [`nearest_far`].
const FAR_PER_TASK: usize = 64;

/// The colour of a cell that no triangle can colour (every triangle has zero area), and its part.
const NO_COLOR: ([u8; 4], u32) = ([255; 4], 0);

/// The nearest triangle to grid point `p` among `candidates` (ties: lower index), with the barycentric
/// weights of its closest point. A candidate that [`farther_than`] the nearest so far is not measured (cells
/// crossed by many triangles much smaller than a cell skip most of theirs).
fn nearest_among(
    tris: &[GridTriangle],
    p: DVec3,
    candidates: impl Iterator<Item = usize>,
) -> Option<(usize, [f64; 3])> {
    let mut best: Option<(usize, f64, [f64; 3])> = None;
    for t in candidates {
        if best.is_some_and(|(_, bd, _)| farther_than(&tris[t], p, bd)) {
            continue;
        }
        let w = closest_point_barycentric(p, &tris[t]);
        let d = point_at(&tris[t], w).distance_squared(p);
        if best.is_none_or(|(bt, bd, _)| d.total_cmp(&bd).then(t.cmp(&bt)).is_lt()) {
            best = Some((t, d, w));
        }
    }
    best.map(|(t, _, w)| (t, w))
}

/// The position of `target` in the ascending `cells` (`Ok`), or where it would be inserted (`Err`), searched
/// outwards from position `k` (a galloping search: the cost grows with the log of the distance).
fn search_near(cells: &[u32], k: usize, target: u32) -> Result<usize, usize> {
    let (mut lo, mut hi) = (k.min(cells.len()), k.min(cells.len()));
    let mut step = 1;
    if cells.get(k).is_some_and(|&c| c < target) {
        while hi < cells.len() && cells[hi] < target {
            (lo, hi) = (hi, (hi + step).min(cells.len()));
            step *= 2;
        }
    } else {
        while lo > 0 && cells[lo - 1] >= target {
            (hi, lo) = (lo, lo.saturating_sub(step));
            step *= 2;
        }
    }
    // Now cells[..lo] < target and cells[hi..] >= target or hi is the end.
    let at = lo + cells[lo..hi].partition_point(|&c| c < target);
    if cells.get(at) == Some(&target) { Ok(at) } else { Err(at) }
}

/// The centre of a cell in grid coordinates.
fn centre(c: [u32; 3]) -> DVec3 {
    DVec3::new(f64::from(c[0]) + 0.5, f64::from(c[1]) + 0.5, f64::from(c[2]) + 0.5)
}

/// The colour and part of every visible cell: the material colour at the closest point of the nearest
/// triangle among the shell triangles of the cell, else of its face neighbours (where the surface crossing a
/// face lies), else of the whole model. Cells that far from the surface only occur where an open mesh leaves
/// a column unmatched; for them one index is built, outside the parallel loop, and each lookup walks the
/// part of it near its cell: a BVH over the triangles when they are fewer than the shell cells (a big
/// triangle spans many cells, whose boxes bound it loosely), else an octree over the shell cells (built in
/// time linear in the shell, where a BVH over many small triangles would cost more to build than the shell).
/// Both give the nearest triangle of nonzero area, ties to the lower index.
pub(crate) fn surface_colors(
    soup: &TriangleSoup,
    spec: &GridSpec,
    tris: &[GridTriangle],
    shell: &Shell,
    visible: &[u32],
    bvh: &OnceLock<TriangleBvh>,
) -> Vec<([u8; 4], u32)> {
    let color_at = |(t, w): (usize, [f64; 3])| (sample(soup, t, w), soup.triangle_parts[t]);
    let mut colors = vec![NO_COLOR; visible.len()];
    // Each task walks its visible cells and the shell's cells side by side, colours each cell at once, and
    // returns the positions of the cells it could not colour.
    let far: Vec<usize> = colors
        .par_chunks_mut(CELLS_PER_TASK)
        .zip(visible.par_chunks(CELLS_PER_TASK))
        .enumerate()
        .flat_map_iter(|(task, (out, chunk))| {
            let mut far = Vec::new();
            let mut coords = AscendingCoords::new(spec);
            let mut k = shell.cells.partition_point(|&c| c < chunk[0]);
            // Where the last search for each face neighbour ended: the neighbours of ascending cells ascend,
            // so each search gallops a short way from there.
            let mut face_at = [k; 6];
            for (n, (color, &i)) in out.iter_mut().zip(chunk).enumerate() {
                while shell.cells.get(k).is_some_and(|&c| c < i) {
                    k += 1;
                }
                let own: &[u32] = if shell.cells.get(k) == Some(&i) { shell.triangles_at(k) } else { &[] };
                let cell = coords.of(i);
                let p = centre(cell);
                let nearest = match *own {
                    // One candidate is the nearest: no distance to compare.
                    [t] => Some((t as usize, closest_point_barycentric(p, &tris[t as usize]))),
                    _ => nearest_among(tris, p, own.iter().map(|&t| t as usize)).or_else(|| {
                        let faces = FACE_STEPS.into_iter().zip(&mut face_at);
                        let near = faces.filter_map(|(step, at)| {
                            let found = search_near(&shell.cells, *at, spec.neighbour(cell, step)? as u32);
                            *at = found.unwrap_or_else(|insert| insert);
                            found.ok()
                        });
                        let candidates = near.flat_map(|at| shell.triangles_at(at).iter().map(|&t| t as usize));
                        nearest_among(tris, p, candidates)
                    }),
                };
                match nearest {
                    Some(nearest) => *color = color_at(nearest),
                    None => far.push(task * CELLS_PER_TASK + n),
                }
            }
            far
        })
        .collect();
    if !far.is_empty() {
        let cells: Vec<u32> = far.iter().map(|&n| visible[n]).collect();
        for (n, nearest) in far.into_iter().zip(nearest_far(spec, tris, shell, bvh, &cells)) {
            colors[n] = nearest.map_or(NO_COLOR, color_at);
        }
    }
    colors
}

/// The nearest triangle of nonzero area to each of `cells` and the barycentric weights of its closest point,
/// through a BVH or a shell octree (see [`surface_colors`]).
fn nearest_far(
    spec: &GridSpec,
    tris: &[GridTriangle],
    shell: &Shell,
    bvh: &OnceLock<TriangleBvh>,
    cells: &[u32],
) -> Vec<Option<(usize, [f64; 3])>> {
    // Each lookup gets the nearest triangle of the cell before it (in the same task): a far cell's neighbour's
    // nearest triangle is close to its own, and a close first guess prunes most of the walk.
    let far: Box<dyn Fn(DVec3, Option<usize>) -> Option<usize> + Sync> = if tris.len() < shell.cells.len() {
        let bvh = bvh.get_or_init(|| TriangleBvh::build(tris));
        let has_area = |t: &GridTriangle| (t[1] - t[0]).cross(t[2] - t[0]).length_squared() > 0.0;
        Box::new(move |p, _| {
            let d2 = |t: usize| if has_area(&tris[t]) { distance2(p, &tris[t]) } else { f64::INFINITY };
            bvh.nearest(p, d2).filter(|n| n.1.is_finite()).map(|n| n.0)
        })
    } else {
        let octree = ShellOctree::new(spec, shell, tris);
        Box::new(move |p, guess| octree.nearest(tris, p, guess))
    };
    let far = &far;
    cells
        .par_chunks(FAR_PER_TASK)
        .flat_map_iter(|chunk| {
            let mut guess = None;
            chunk.iter().map(move |&i| {
                let p = centre(spec.coords(i as usize));
                let nearest = far(p, guess);
                guess = nearest.or(guess);
                nearest.map(|t| (t, closest_point_barycentric(p, &tris[t])))
            })
        })
        .collect()
}

/// Applies the pastel remap to every colour. Neighbouring cells often share a colour, so each task keeps
/// the remaps it has computed in a small cache keyed by the colour.
pub(crate) fn pastel_all(colors: &mut [([u8; 4], u32)]) {
    /// Cache slots per task (a power of two).
    const SLOTS: usize = 64;
    colors.par_chunks_mut(CELLS_PER_TASK).for_each(|chunk| {
        let mut cache: [Option<([u8; 4], [u8; 4])>; SLOTS] = [None; SLOTS];
        for (color, _) in chunk {
            let key = u32::from_le_bytes(*color);
            // The slot: the colour's bits mixed by a multiplicative hash, top bits.
            let slot = (key.wrapping_mul(0x9E37_79B9) >> (32 - SLOTS.trailing_zeros())) as usize;
            *color = match cache[slot] {
                Some((from, to)) if from == *color => to,
                _ => {
                    let to = pastel(*color);
                    cache[slot] = Some((*color, to));
                    to
                }
            };
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn galloping_finds_the_cells_present_and_the_insertion_points_from_any_start() {
        let cells: Vec<u32> = (0..300).map(|k| k * 8 + k % 7).collect();
        for k in 0..=cells.len() {
            for target in 0..cells[cells.len() - 1] + 5 {
                assert_eq!(search_near(&cells, k, target), cells.binary_search(&target), "from {k} for {target}");
            }
        }
        assert_eq!(search_near(&[], 0, 4), Err(0));
    }

    #[test]
    fn the_cached_pastel_remap_is_the_remap() {
        // Runs of a colour, colours that share a cache slot, and a colour coming back after others.
        let mut colors: Vec<([u8; 4], u32)> = (0..5000u32)
            .map(|i| {
                let v = (i / 7).wrapping_mul(2_654_435_761).to_le_bytes();
                ([v[0], v[1], v[2], v[3]], i)
            })
            .collect();
        colors.extend((0..300).map(|i| ([10, 20, 30, (i % 3) as u8], i)));
        let expected: Vec<([u8; 4], u32)> = colors.iter().map(|&(c, part)| (pastel(c), part)).collect();
        pastel_all(&mut colors);
        assert_eq!(colors, expected);
    }
}
