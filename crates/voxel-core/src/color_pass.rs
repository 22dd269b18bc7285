//! The colour pass: the colour and part of every visible cell, sampled at the closest point of the nearest
//! triangle, and the pastel remap of those colours.
//!
//! One parallel walk over the visible cells does everything for the cells near the surface (all but a few):
//! it steps along the shell's cells beside the visible ones (both ascending), takes the nearest of the
//! triangles the shell lists for the cell (or for its face neighbours), and samples the material there. The
//! cells far from every triangle are collected and take the colour of the nearest shell cell afterwards.

use glam::DVec3;
use rayon::prelude::*;

use crate::color::{flat_color, pastel, sample, shade, texel};
use crate::geom::{beyond, box_distance2, closest_point_barycentric, point_at};
use crate::grid::{AscendingCoords, GridSpec, GridTriangles};
use crate::progress::Progress;
use crate::shell::Shell;
use crate::shell::distance::nearest_shell_cells;
use crate::shell::octree::ShellOctree;
use crate::soup::TriangleSoup;

/// The steps to the six face neighbours.
const FACE_STEPS: [[i32; 3]; 6] = [[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1]];

/// Visible cells handed to one task of the colour pass.
const CELLS_PER_TASK: usize = 1024;

/// Far cells handed to one task of [`nearest_far`].
const FAR_PER_TASK: usize = 64;

/// Up to this many grid cells per far cell, [`nearest_far`] transforms the grid ([`nearest_shell_cells`]) rather
/// than walking the octree once a far cell. Measured on a 2-core VM (the height field at R=256 with `--fill
/// parity`: 3.7 M cells, 45,421 far cells a few dozen cells below the sheet): the transform 80–110 ms, about 25 ns
/// a cell; the walks 150–190 ms, about 3.5 µs each; even at about 140 cells per far cell.
const GRID_CELLS_PER_FAR_CELL: usize = 128;

/// The largest grid [`nearest_far`] transforms: 2²⁴ cells, 134 MB while it runs (a cube at R=256).
const TRANSFORM_CELLS: usize = 1 << 24;

/// The colour of a cell that no triangle can colour (every triangle has zero area), and its part.
const NO_COLOR: ([u8; 4], u32) = ([255; 4], 0);

/// Candidates whose boxes [`nearest_among`] measures before it measures any of them.
const BOXES_AT_ONCE: usize = 64;

/// Up to this many candidates, [`nearest_among`] measures each without its box: a box seldom spares a measurement
/// among so few (CesiumMan's cells of 2, 3 and 4 candidates at R=128 measured 1.9, 2.5 and 3.0 of them).
const MEASURED_WITHOUT_BOXES: usize = 4;

/// Room for the candidates' box distances of a round of [`nearest_among`], kept by its caller from cell to cell: an
/// array set up by each search wrote a kilobyte a cell (without, CesiumMan's and the Fox's whole voxelizations at
/// R=128 measured 3–4 % faster on one thread).
type Boxes = [(usize, f64); BOXES_AT_ONCE];

/// Fresh [`Boxes`].
const NO_BOXES: Boxes = [(0, 0.0); BOXES_AT_ONCE];

/// The nearest triangle to grid point `p` among `candidates` (ties: lower index), with the barycentric
/// weights of its closest point. Up to [`MEASURED_WITHOUT_BOXES`] candidates are each measured; more, best first,
/// up to [`BOXES_AT_ONCE`] at a time (their distances in `boxes`): their bounding boxes' distances first, then the
/// candidate of the nearest box is measured, then the others whose box is not [`beyond`] the nearest so far (a
/// cell crossed by many triangles much smaller than it measures a few).
fn nearest_among(
    tris: &GridTriangles,
    p: DVec3,
    candidates: impl Iterator<Item = usize>,
    boxes: &mut Boxes,
) -> Option<(usize, [f64; 3])> {
    let mut best = None;
    let mut candidates = candidates.peekable();
    while candidates.peek().is_some() {
        // The first few candidates are boxed only once there are more of them.
        let mut count = 0;
        for (slot, t) in boxes.iter_mut().zip(candidates.by_ref()) {
            let bound = if count < MEASURED_WITHOUT_BOXES { 0.0 } else { box_distance2(&tris.get(t), p) };
            *slot = (t, bound);
            count += 1;
        }
        let boxes = &mut boxes[..count];
        if count <= MEASURED_WITHOUT_BOXES {
            boxes.iter().for_each(|&(t, _)| measure(tris, p, t, &mut best));
            continue;
        }
        for slot in &mut boxes[..MEASURED_WITHOUT_BOXES] {
            slot.1 = box_distance2(&tris.get(slot.0), p);
        }
        let nearest_box = (0..count).min_by(|&a, &b| boxes[a].1.total_cmp(&boxes[b].1)).unwrap_or(0);
        let order = std::iter::once(nearest_box).chain((0..count).filter(|&k| k != nearest_box));
        for (t, bound) in order.map(|k| boxes[k]) {
            if !best.is_some_and(|(_, bd, _)| beyond(bound, bd)) {
                measure(tris, p, t, &mut best);
            }
        }
    }
    best.map(|(t, _, w)| (t, w))
}

/// Measures the distance from `p` to triangle `t` and keeps it in `best` (triangle, squared distance, weights)
/// if it is nearer, or as near with a lower index.
#[inline]
fn measure(tris: &GridTriangles, p: DVec3, t: usize, best: &mut Option<(usize, f64, [f64; 3])>) {
    let triangle = tris.get(t);
    let w = closest_point_barycentric(p, &triangle);
    let d = point_at(&triangle, w).distance_squared(p);
    if best.is_none_or(|(bt, bd, _)| d.total_cmp(&bd).then(t.cmp(&bt)).is_lt()) {
        *best = Some((t, d, w));
    }
}

/// Where a visible cell takes its colour from.
#[derive(Clone, Copy)]
enum Source {
    /// The nearest triangle and the barycentric weights of its closest point.
    Nearest(usize, [f64; 3]),
    /// Every candidate is flat with this part and colour ([`flat_color`]): any of them, here the first, samples
    /// alike, anywhere.
    Flat(usize, (u32, [f32; 4])),
}

/// Where grid point `p` takes its colour among `candidates` (none: `None`): the nearest ([`nearest_among`]), or,
/// when every candidate is flat with one colour and part, that colour (none is measured: a model of plain
/// materials skips its distances).
fn color_source(
    soup: &TriangleSoup,
    tris: &GridTriangles,
    p: DVec3,
    candidates: impl Iterator<Item = usize> + Clone,
    boxes: &mut Boxes,
) -> Option<Source> {
    let mut rest = candidates.clone();
    let first = rest.next()?;
    if let Some(flat) = flat_color(soup, first)
        && rest.clone().all(|t| flat_color(soup, t) == Some(flat))
    {
        return Some(Source::Flat(first, flat));
    }
    let (t, w) = nearest_among(tris, p, candidates, boxes)?;
    Some(Source::Nearest(t, w))
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
/// face lies). A cell farther from the surface (only where a fill leaves a side of solid open to the outside:
/// an open mesh's unmatched column) takes the colour of the nearest shell cell ([`ShellOctree`]; ties to the
/// lower index), as that cell is coloured at its own centre: the inside of a sliced model shows the surface
/// colour nearest to it, and a lookup costs a walk over cells near it, never over the triangles of a hill.
/// Once `progress` is cancelled the remaining tasks leave their cells uncoloured (the caller's next stage ends
/// the run).
pub(crate) fn surface_colors(
    soup: &TriangleSoup,
    spec: &GridSpec,
    tris: &GridTriangles,
    shell: &Shell,
    visible: &[u32],
    progress: &Progress,
) -> Vec<([u8; 4], u32)> {
    let color_at = |(t, w): (usize, [f64; 3])| (sample(soup, t, w), soup.part_of(t));
    let mut colors = vec![NO_COLOR; visible.len()];
    // Each task walks its visible cells and the shell's cells side by side to find where each takes its colour,
    // then reads their texels, then shades them, and returns the positions of the cells it could not colour.
    // The texel reads of a large texture miss the caches: in a loop of their own, a few dozen instructions a
    // cell, the reads of many cells are under way at once, where behind each cell's search they took turns
    // (the milk truck's colours at R=128, 2,048² texels: 2.7 → 2.3 ms warm, 5.1 → 4.4 ms in a fresh process).
    let far: Vec<usize> = colors
        .par_chunks_mut(CELLS_PER_TASK)
        .zip(visible.par_chunks(CELLS_PER_TASK))
        .enumerate()
        .flat_map_iter(|(task, (out, chunk))| {
            let mut far = Vec::new();
            if progress.is_cancelled() {
                return far;
            }
            let sources = sources(soup, spec, tris, shell, chunk);
            let texels: Vec<_> = sources
                .iter()
                .map(|source| match *source {
                    Some(Source::Nearest(t, w)) => texel(soup, t, w),
                    _ => None,
                })
                .collect();
            let mut last_flat = None;
            for (n, ((color, source), texel)) in out.iter_mut().zip(sources).zip(texels).enumerate() {
                *color = match source {
                    Some(Source::Nearest(t, w)) => (shade(soup, t, w, texel), soup.part_of(t)),
                    // Neighbouring cells mostly share their flat colour: sampled once for a run of them.
                    Some(Source::Flat(t, flat)) => match last_flat {
                        Some((seen, color)) if seen == flat => color,
                        _ => {
                            let color = color_at((t, [1.0, 0.0, 0.0])); // any weights: its first corner
                            last_flat = Some((flat, color));
                            color
                        }
                    },
                    None => {
                        far.push(task * CELLS_PER_TASK + n);
                        continue;
                    }
                };
            }
            far
        })
        .collect();
    if !far.is_empty() {
        let cells: Vec<u32> = far.iter().map(|&n| visible[n]).collect();
        for (n, nearest) in far.into_iter().zip(nearest_far(spec, tris, shell, &cells)) {
            colors[n] = nearest.map_or(NO_COLOR, color_at);
        }
    }
    colors
}

/// Where each of the ascending visible `cells` takes its colour ([`color_source`]): among the shell triangles of
/// the cell, else of its face neighbours; `None` for a cell with neither.
fn sources(
    soup: &TriangleSoup,
    spec: &GridSpec,
    tris: &GridTriangles,
    shell: &Shell,
    cells: &[u32],
) -> Vec<Option<Source>> {
    let mut coords = AscendingCoords::new(spec);
    let mut k = shell.cells.partition_point(|&c| c < cells[0]);
    // Where the last search for each face neighbour ended: the neighbours of ascending cells ascend, so each
    // search gallops a short way from there.
    let mut face_at = [k; 6];
    let mut sources = Vec::with_capacity(cells.len());
    let mut boxes = NO_BOXES;
    for &i in cells {
        while shell.cells.get(k).is_some_and(|&c| c < i) {
            k += 1;
        }
        let cell = coords.of(i);
        let p = centre(cell);
        sources.push(if shell.cells.get(k) == Some(&i) {
            color_source(soup, tris, p, shell.triangles_at(k).map(|t| t as usize), &mut boxes)
        } else {
            // The face neighbours' triangles, at most six lists.
            let (mut near, mut found) = ([0; 6], 0);
            for (step, at) in FACE_STEPS.into_iter().zip(&mut face_at) {
                let Some(neighbour) = spec.neighbour(cell, step) else { continue };
                match search_near(&shell.cells, *at, neighbour as u32) {
                    Ok(k) => {
                        (*at, near[found]) = (k, k);
                        found += 1;
                    }
                    Err(insert) => *at = insert,
                }
            }
            let candidates = near[..found].iter().flat_map(|&at| shell.triangles_at(at)).map(|t| t as usize);
            color_source(soup, tris, p, candidates, &mut boxes)
        });
    }
    sources
}

/// For each of `cells`, the nearest triangle at the centre of the nearest shell cell and the barycentric
/// weights of its closest point there (see [`surface_colors`]). The nearest shell cells come from a walk of the
/// shell's octree a cell, or, when there are many such cells for the grid's size ([`GRID_CELLS_PER_FAR_CELL`]) and
/// the grid is not too large for it ([`TRANSFORM_CELLS`]), from a distance transform of the grid: the same cells.
fn nearest_far(spec: &GridSpec, tris: &GridTriangles, shell: &Shell, cells: &[u32]) -> Vec<Option<(usize, [f64; 3])>> {
    let grid = spec.cell_count();
    let sources: Vec<Option<u32>> = if grid <= TRANSFORM_CELLS && grid <= cells.len() * GRID_CELLS_PER_FAR_CELL {
        nearest_shell_cells(spec, shell, cells)
    } else {
        let octree = ShellOctree::new(spec, shell);
        let octree = &octree;
        cells
            .par_chunks(FAR_PER_TASK)
            .flat_map_iter(|chunk| {
                // Each walk starts from the nearest shell cell of the cell before it: a far cell's neighbour's is
                // close to its own, and a close first guess prunes most of the walk.
                let mut guess = None;
                chunk.iter().map(move |&i| {
                    let source = octree.nearest(spec, spec.coords(i as usize), guess);
                    guess = source.or(guess);
                    source
                })
            })
            .collect()
    };
    sources
        .into_par_iter()
        .map_init(
            || NO_BOXES,
            |boxes, source| {
                let source = source?;
                let k = shell.cells.binary_search(&source).expect("the nearest shell cell is a shell cell");
                let p = centre(spec.coords(source as usize));
                nearest_among(tris, p, shell.triangles_at(k).map(|t| t as usize), boxes)
            },
        )
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
    fn far_cells_take_the_color_of_the_nearest_shell_cell() {
        use crate::soup::{Material, Vertex};
        use crate::{FillMode, GridSize, VoxelizeOptions};
        // An open sheet of hills coloured by height: parity fills slabs whose sides lie far from the sheet.
        let n = 40;
        let vertex = |i: u32, j: u32| {
            let (x, z) = (i as f32 / 4.0, j as f32 / 4.0);
            let y = 0.8 * (0.9 * x).sin() * (0.7 * z).cos() + 0.3 * (2.3 * x + 1.1 * z).sin();
            let t = (y + 1.1) / 2.2;
            Vertex { color: [0.1 + 0.8 * t, 0.4 + 0.4 * (1.0 - t), 0.9 - 0.7 * t, 1.0], ..Vertex::at([x, y, z]) }
        };
        let mut soup = TriangleSoup::default();
        let material = soup.add_material(Material::default());
        let part = soup.add_part(material, "hills");
        for (i, j) in (0..n).flat_map(|j| (0..n).map(move |i| (i, j))) {
            soup.push_triangle(part, [vertex(i, j), vertex(i, j + 1), vertex(i + 1, j)]);
            soup.push_triangle(part, [vertex(i + 1, j), vertex(i, j + 1), vertex(i + 1, j + 1)]);
        }
        let options = VoxelizeOptions { grid: GridSize::Resolution(48), fill: FillMode::Parity, ..Default::default() };
        let model = crate::voxelize(&soup, &options).unwrap();
        let spec = &model.spec;
        let tris = spec.grid_triangles(&soup);
        let shell = crate::shell::shell(spec, &tris, &crate::progress::Progress::new());
        let is_shell = |i: Option<usize>| i.is_some_and(|i| shell.cells.binary_search(&(i as u32)).is_ok());
        let distance2 = |a: [u32; 3], b: [u32; 3]| (0..3).map(|k| u64::from(a[k].abs_diff(b[k])).pow(2)).sum::<u64>();
        let mut far = 0;
        for v in model.voxels().filter(|v| v.visible) {
            let cell = v.cell.map(u32::from);
            let i = spec.index(cell[0], cell[1], cell[2]);
            if is_shell(Some(i)) || FACE_STEPS.iter().any(|&step| is_shell(spec.neighbour(cell, step))) {
                continue;
            }
            far += 1;
            let k = (0..shell.cells.len())
                .min_by_key(|&k| (distance2(cell, spec.coords(shell.cells[k] as usize)), shell.cells[k]))
                .unwrap();
            let p = centre(spec.coords(shell.cells[k] as usize));
            let (t, w) = nearest_among(&tris, p, shell.triangles_at(k).map(|t| t as usize), &mut { NO_BOXES }).unwrap();
            assert_eq!((v.color, v.part), (sample(&soup, t, w), part), "cell {cell:?}");
        }
        assert!(far > 100, "{far} far cells");
    }

    #[test]
    fn the_best_first_search_finds_the_nearest_triangle_of_a_whole_search() {
        let mut random = crate::lcg::Lcg::new(11);
        let mut next = |scale: f64| random.unit(scale);
        // Triangles much smaller than a cell crowding one cell, some large ones, and corners on a 1/4 lattice, so
        // that distances tie (none without area: the shell lists none).
        let mut triangles: Vec<[DVec3; 3]> = (0..700)
            .map(|k| {
                let size = if k % 10 == 0 { 3.0 } else { 0.2 };
                let (base, lattice) = (DVec3::new(next(2.0), next(2.0), next(2.0)), k % 3 == 0);
                std::array::from_fn(|_| {
                    let p = base + DVec3::new(next(size), next(size), next(size));
                    if lattice { (p * 4.0).round() / 4.0 } else { p }
                })
            })
            .collect();
        triangles.retain(|t| (t[1] - t[0]).cross(t[2] - t[0]).length_squared() > 0.0);
        assert!(triangles.len() > 500, "{}", triangles.len());
        let tris = GridTriangles::from_triangles(&triangles);
        for _ in 0..300 {
            let p = DVec3::new(next(2.0), next(2.0), next(2.0));
            let count = 1 + next(300.0) as usize;
            let candidates: Vec<usize> = (0..count).map(|_| next(triangles.len() as f64) as usize).collect();
            // Every candidate measured: the least distance, then the lower index.
            let whole = candidates
                .iter()
                .map(|&t| {
                    let w = closest_point_barycentric(p, &tris.get(t));
                    (point_at(&tris.get(t), w).distance_squared(p), t, w)
                })
                .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
                .map(|(_, t, w)| (t, w));
            assert_eq!(
                nearest_among(&tris, p, candidates.iter().copied(), &mut { NO_BOXES }),
                whole,
                "{count} candidates at {p}"
            );
        }
    }

    #[test]
    fn a_textured_cell_takes_the_texel_under_the_closest_point_of_the_nearest_triangle() {
        use crate::shapes::uv_sphere;
        use crate::soup::{Material, Texture, TextureBinding, Vertex, Wrap};
        use crate::{GridSize, VoxelizeOptions};
        use std::sync::Arc;
        // A sphere mapped by longitude and latitude onto 64 × 32 texels of distinct colours.
        let texels = (0..64 * 32).map(|k| [(k % 64 * 4) as u8, (k / 64 * 8) as u8, (k % 7 * 36) as u8, 255]).collect();
        let texture = Arc::new(Texture::new(64, 32, texels).unwrap());
        let mut soup = TriangleSoup::default();
        let material = soup.add_material(Material {
            base_color: [1.0; 4],
            texture: Some(TextureBinding { texture, wrap: [Wrap::Repeat, Wrap::ClampToEdge] }),
        });
        let part = soup.add_part(material, "globe");
        let sphere = uv_sphere(1.0, 32);
        let vertex = |i: u32| {
            let [x, y, z] = sphere.positions[i as usize];
            let uv = [z.atan2(x) / std::f32::consts::TAU + 0.5, y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI];
            Vertex { uv, ..Vertex::at([x, y, z]) }
        };
        for t in &sphere.triangles {
            soup.push_triangle(part, t.map(vertex));
        }
        let options = VoxelizeOptions { grid: GridSize::Resolution(40), ..Default::default() };
        let spec = GridSpec::fit(&soup, options.model_size, options.grid, 1.0, 1 << 26).unwrap();
        let tris = spec.grid_triangles(&soup);
        let shell = crate::shell::shell(&spec, &tris, &Progress::new());
        let colors = surface_colors(&soup, &spec, &tris, &shell, &shell.cells, &Progress::new());
        for (k, &(color, part)) in colors.iter().enumerate() {
            let p = centre(spec.coords(shell.cells[k] as usize));
            let (t, w) = nearest_among(&tris, p, shell.triangles_at(k).map(|t| t as usize), &mut { NO_BOXES }).unwrap();
            assert_eq!((color, part), (sample(&soup, t, w), 0), "cell {}", shell.cells[k]);
        }
        let distinct: std::collections::HashSet<_> = colors.iter().map(|&(color, _)| color).collect();
        assert!(colors.len() > 5000 && distinct.len() > 1000, "{} cells of {} colours", colors.len(), distinct.len());
    }

    #[test]
    fn a_cell_of_flat_triangles_takes_their_colour_as_the_nearest_would_give_it() {
        use crate::shapes::{torus, uv_sphere};
        use crate::{GridSize, VoxelizeOptions};
        // A plain sphere, a torus through it with a colour per vertex, and the sphere again in another plain part.
        let mut soup = TriangleSoup::default();
        soup.add_mesh(&uv_sphere(1.0, 24), [0.9, 0.3, 0.2, 1.0], "plain");
        let ring = soup.add_mesh(&torus(1.2, 0.3, 24), [1.0; 4], "ring");
        soup.add_mesh(&uv_sphere(1.0, 24).translated([0.1, 0.0, 0.0]), [0.2, 0.3, 0.9, 1.0], "other");
        let ring_vertices = soup.triangles().iter().zip(&soup.triangle_parts).filter(|(_, p)| **p == ring);
        let ring_vertices: Vec<u32> = ring_vertices.flat_map(|(t, _)| *t).collect();
        for (k, &v) in ring_vertices.iter().enumerate() {
            soup.colors_mut()[v as usize] = [(k % 7) as f32 / 7.0, 0.5, (k % 5) as f32 / 5.0, 1.0];
        }
        let options = VoxelizeOptions { grid: GridSize::Resolution(40), ..Default::default() };
        let spec = GridSpec::fit(&soup, options.model_size, options.grid, 1.0, 1 << 26).unwrap();
        let tris = spec.grid_triangles(&soup);
        let shell = crate::shell::shell(&spec, &tris, &Progress::new());
        let colors = surface_colors(&soup, &spec, &tris, &shell, &shell.cells, &Progress::new());
        let (mut flat, mut measured) = (0, 0);
        for (k, &(color, part)) in colors.iter().enumerate() {
            let own: Vec<u32> = shell.triangles_at(k).collect();
            let (t, w) = nearest_among(
                &tris,
                centre(spec.coords(shell.cells[k] as usize)),
                own.iter().map(|&t| t as usize),
                &mut { NO_BOXES },
            )
            .unwrap();
            assert_eq!((color, part), (sample(&soup, t, w), soup.triangle_parts[t]), "cell {}", shell.cells[k]);
            let first = flat_color(&soup, own[0] as usize);
            if first.is_some() && own.iter().all(|&t| flat_color(&soup, t as usize) == first) {
                flat += 1;
            } else {
                measured += 1;
            }
        }
        assert!(flat > 1000 && measured > 1000, "{flat} flat cells, {measured} measured");
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
