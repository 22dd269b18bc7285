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
use crate::radix;
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
/// materials skips its distances). A lone candidate is the nearest: only its closest point is found, not its
/// distance (one thread at R=128: the textured box's voxelization 115.5 → 104.0 M instructions, the milk truck's
/// 82.0 → 78.8 M, CesiumMan's 43.9 → 43.3 M).
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
    if rest.next().is_none() {
        return Some(Source::Nearest(first, closest_point_barycentric(p, &tris.get(first))));
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

/// What the colour walks read: the soup, its triangles on the grid and their shell.
#[derive(Clone, Copy)]
struct Surface<'a> {
    soup: &'a TriangleSoup,
    spec: &'a GridSpec,
    tris: &'a GridTriangles<'a>,
    shell: &'a Shell,
}

/// A visible cell that is a shell cell, queued for the colour pass's walk in the order of the triangles.
#[derive(Clone, Copy, Debug, Default)]
struct Queued {
    /// The first triangle of its shell row: the walk's order.
    first: u32,
    /// Its position among the visible cells.
    at: u32,
    /// Its row in the shell.
    row: u32,
}

/// From this many triangles on, and [`ORDERED_TRIANGLES_PER_CELL`] a visible cell, the colour pass walks the shell's
/// cells in the order of their first triangle ([`surface_colors`]): about 10 MB of vertices, colours and corners,
/// beyond the caches. (Below, the reorder's cost outweighed what it saved: fresh medians of 15 at R=128, the Fox
/// 2.0 → 2.8 ms, the milk truck 5.6 → 6.4.)
const ORDERED_TRIANGLES: usize = 1 << 18;

/// The fewest triangles a visible cell for [`ORDERED_TRIANGLES`]: the reorder costs a sort and a scattered write a
/// cell, and saves where each cell searches many triangles (the height field at R=256, 18 triangles a visible cell,
/// each cell boxing 29 candidates: −11 ms); where cells search few it costs more than it saves (fresh medians of 5:
/// spheres-1m at R=256, 0.25 triangles a cell, 652 → 876 ms; spheres-4m at R=128, 3.3 a cell, 629 → 700).
const ORDERED_TRIANGLES_PER_CELL: usize = 8;

/// The most bits of a queued cell's first triangle that order the walk: enough to walk a mesh's triangles in about
/// the order they are stored (2¹² groups: a few hundred triangles each at a million, a quarter of a row of a
/// 1000 × 1000 sheet), few enough for one counting pass.
const ORDER_BITS: u32 = 12;

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
    let mut colors = vec![NO_COLOR; visible.len()];
    let surface = Surface { soup, spec, tris, shell };
    let far = if tris.len() < ORDERED_TRIANGLES || tris.len() < visible.len() * ORDERED_TRIANGLES_PER_CELL {
        in_cell_order(surface, visible, &mut colors, progress)
    } else {
        in_triangle_order(surface, visible, &mut colors, progress)
    };
    if !far.is_empty() {
        let cells: Vec<u32> = far.iter().map(|&n| visible[n]).collect();
        for (n, nearest) in far.into_iter().zip(nearest_far(spec, tris, shell, &cells)) {
            colors[n] = nearest.map_or(NO_COLOR, |(t, w)| (sample(soup, t, w), soup.part_of(t)));
        }
    }
    colors
}

/// [`surface_colors`] in tasks of ascending visible cells, each walking its cells and the shell's side by side;
/// returns the positions of the cells without a source, ascending.
fn in_cell_order(surface: Surface, visible: &[u32], colors: &mut [([u8; 4], u32)], progress: &Progress) -> Vec<usize> {
    colors
        .par_chunks_mut(CELLS_PER_TASK)
        .zip(visible.par_chunks(CELLS_PER_TASK))
        .enumerate()
        .flat_map_iter(|(task, (out, chunk))| {
            let mut far = Vec::new();
            if progress.is_cancelled() {
                return far;
            }
            let (_, _, sources) = walk(surface, chunk, task * CELLS_PER_TASK, false);
            for (n, (color, slot)) in shaded(surface.soup, sources).zip(out).enumerate() {
                match color {
                    Some(color) => *slot = color,
                    None => far.push(task * CELLS_PER_TASK + n),
                }
            }
            far
        })
        .collect()
}

/// [`surface_colors`] with the shell's cells in the order of their first triangle rather than of the cells: the
/// searches then read the triangles' vertices and colours in about the order they are stored, where the cells'
/// order (x, then y, then z) crosses a mesh whose rows run along another axis row after row (the height field at
/// R=256, whose rows run along x: its equal work 117.5 → 103.5 ms, fresh medians of 11, about as fast as the same
/// sheet stored with its rows along z). Tasks of ascending cells queue each shell cell and find where any other
/// takes its colour; the queued cells are sorted by their first triangle (stably: a group's cells ascend), tasks of
/// them find theirs, and the colours go to their cells' positions. Returns the positions of the cells without a
/// source, ascending.
fn in_triangle_order(
    surface: Surface,
    visible: &[u32],
    colors: &mut [([u8; 4], u32)],
    progress: &Progress,
) -> Vec<usize> {
    let Surface { soup, spec, tris, shell } = surface;
    let (queued, others): (Vec<Vec<Queued>>, Vec<Vec<(usize, Option<([u8; 4], u32)>)>>) = visible
        .par_chunks(CELLS_PER_TASK)
        .enumerate()
        .map(|(task, chunk)| {
            if progress.is_cancelled() {
                return Default::default();
            }
            let (queued, at, sources) = walk(surface, chunk, task * CELLS_PER_TASK, true);
            (queued, at.into_iter().zip(shaded(soup, sources)).collect())
        })
        .unzip();
    let all = radix::bits_for(tris.len());
    let shift = all - all.min(ORDER_BITS);
    let queued = radix::sort_parts_by_key(queued, all - shift, |q| q.first >> shift);
    let mut walked = vec![NO_COLOR; queued.len()];
    walked.par_chunks_mut(CELLS_PER_TASK).zip(queued.par_chunks(CELLS_PER_TASK)).for_each(|(out, chunk)| {
        if progress.is_cancelled() {
            return;
        }
        let mut boxes = NO_BOXES;
        let mut coords = AscendingCoords::new(spec);
        let sources = chunk.iter().map(|q| {
            let cell = coords.of(visible[q.at as usize]);
            let candidates = shell.triangles_at(q.row as usize).map(|t| t as usize);
            color_source(soup, tris, centre(cell), candidates, &mut boxes)
        });
        for (slot, color) in out.iter_mut().zip(shaded(soup, sources.collect())) {
            *slot = color.unwrap_or(NO_COLOR); // (a shell row lists a triangle)
        }
    });
    for (q, color) in queued.iter().zip(walked) {
        colors[q.at as usize] = color;
    }
    let mut far = Vec::new();
    for (at, color) in others.into_iter().flatten() {
        match color {
            Some(color) => colors[at] = color,
            None => far.push(at),
        }
    }
    far
}

/// The colour and part from each of `sources` (`None` where a cell has no source): the texels first, in a loop of
/// their own, then the shading. (The texel reads of a large texture miss the caches: a few dozen instructions a
/// cell, the reads of many cells are under way at once, where behind each cell's search they took turns: the milk
/// truck's colours at R=128, 2,048² texels, 2.7 → 2.3 ms warm, 5.1 → 4.4 ms in a fresh process.)
fn shaded(soup: &TriangleSoup, sources: Vec<Option<Source>>) -> impl Iterator<Item = Option<([u8; 4], u32)>> + '_ {
    let texels: Vec<_> = sources
        .iter()
        .map(|source| match *source {
            Some(Source::Nearest(t, w)) => texel(soup, t, w),
            _ => None,
        })
        .collect();
    let mut last_flat = None;
    sources.into_iter().zip(texels).map(move |(source, texel)| {
        source.map(|source| match source {
            Source::Nearest(t, w) => (shade(soup, t, w, texel), soup.part_of(t)),
            // Neighbouring cells mostly share their flat colour: sampled once for a run of them.
            Source::Flat(t, flat) => match last_flat {
                Some((seen, color)) if seen == flat => color,
                _ => {
                    let color = (sample(soup, t, [1.0, 0.0, 0.0]), soup.part_of(t)); // any weights: its first corner
                    last_flat = Some((flat, color));
                    color
                }
            },
        })
    })
}

/// Walks the ascending visible `cells` (at positions `base..` of the visible cells) and the shell's cells side by
/// side, and finds where each cell takes its colour ([`color_source`]): among the shell triangles of the cell, else
/// of its face neighbours (`None` for a cell with neither). With `defer`, each shell cell is queued instead, and the
/// others' sources come with their positions; without, every cell's source comes in order.
fn walk(surface: Surface, cells: &[u32], base: usize, defer: bool) -> (Vec<Queued>, Vec<usize>, Vec<Option<Source>>) {
    let Surface { soup, spec, tris, shell } = surface;
    let mut coords = AscendingCoords::new(spec);
    let mut k = shell.cells.partition_point(|&c| c < cells[0]);
    // Where the last search for each face neighbour ended: the neighbours of ascending cells ascend, so each
    // search gallops a short way from there.
    let mut face_at = [k; 6];
    let (mut queued, mut positions, mut sources) = (Vec::new(), Vec::new(), Vec::new());
    if defer {
        queued.reserve(cells.len());
    } else {
        sources.reserve(cells.len());
    }
    let mut boxes = NO_BOXES;
    for (n, &i) in cells.iter().enumerate() {
        while shell.cells.get(k).is_some_and(|&c| c < i) {
            k += 1;
        }
        let at = base + n;
        let in_shell = shell.cells.get(k) == Some(&i);
        if in_shell && defer {
            let first = shell.triangles_at(k).next().unwrap_or(0); // (a shell row lists a triangle)
            queued.push(Queued { first, at: at as u32, row: k as u32 });
            continue;
        }
        let cell = coords.of(i);
        let p = centre(cell);
        if defer {
            positions.push(at);
        }
        sources.push(if in_shell {
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
    (queued, positions, sources)
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

    /// An open sheet of hills over 40 × 40 quads coloured by height, part 0 of the soup, its rows of triangles
    /// along x.
    fn hills() -> TriangleSoup {
        use crate::soup::{Material, Vertex};
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
        soup
    }

    #[test]
    fn far_cells_take_the_color_of_the_nearest_shell_cell() {
        use crate::{FillMode, GridSize, VoxelizeOptions};
        // Parity fills slabs whose sides lie far from the open sheet.
        let (soup, part) = (hills(), 0);
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
    fn the_walk_in_the_order_of_the_triangles_colours_every_cell_as_the_walk_in_the_order_of_the_cells() {
        use crate::shapes::cuboid;
        use crate::{FillMode, GridSize, VoxelizeOptions};
        // The hills, whose rows run along x where the cells ascend along z, and a plain box through them; parity
        // fills slabs whose sides lie far from the sheet (cells of no shell triangle).
        let mut soup = hills();
        soup.add_mesh(&cuboid([3.0, -0.5, 3.0], [6.0, 0.5, 5.0]), [0.9, 0.3, 0.2, 1.0], "box");
        let options = VoxelizeOptions { grid: GridSize::Resolution(48), fill: FillMode::Parity, ..Default::default() };
        let model = crate::voxelize(&soup, &options).unwrap();
        let spec = &model.spec;
        let visible: Vec<u32> = model
            .voxels()
            .filter(|v| v.visible)
            .map(|v| spec.index(u32::from(v.cell[0]), u32::from(v.cell[1]), u32::from(v.cell[2])) as u32)
            .collect();
        assert!(visible.is_sorted());
        let tris = spec.grid_triangles(&soup);
        let shell = crate::shell::shell(spec, &tris, &Progress::new());
        let in_shell = visible.iter().filter(|&&i| shell.cells.binary_search(&i).is_ok()).count();
        let mut by_cells = vec![NO_COLOR; visible.len()];
        let surface = Surface { soup: &soup, spec, tris: &tris, shell: &shell };
        let far = in_cell_order(surface, &visible, &mut by_cells, &Progress::new());
        let mut by_triangles = vec![NO_COLOR; visible.len()];
        assert_eq!(in_triangle_order(surface, &visible, &mut by_triangles, &Progress::new()), far);
        assert_eq!(by_triangles, by_cells);
        assert!(
            in_shell > 1000 && visible.len() > in_shell + far.len() + 100 && far.len() > 100,
            "{} visible cells: {in_shell} in the shell, {} far",
            visible.len(),
            far.len()
        );
        // Every cell but the far ones (coloured afterwards) has its colour; the box's cells take its one colour.
        let uncoloured: Vec<usize> = (0..visible.len()).filter(|&k| by_cells[k] == NO_COLOR).collect();
        assert_eq!(uncoloured, far);
        let boxed: Vec<_> = by_cells.iter().filter(|&&(_, p)| p == 1).collect();
        assert!(boxed.len() > 100 && boxed.iter().all(|&&(c, _)| c == boxed[0].0), "{} cells of the box", boxed.len());
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
        // Cells of one triangle take its closest point without its distance: the same texel.
        let lone = (0..colors.len()).filter(|&k| shell.triangles_at(k).count() == 1).count();
        assert!(lone > 500 && lone < colors.len() - 500, "{lone} cells of one triangle of {}", colors.len());
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
