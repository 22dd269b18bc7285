//! Ordered 3-D dithering: a cell whose colour lies between two palette colours takes the farther one when
//! its threshold, from a 4×4×4 Bayer-like pattern, lies below how far along the way it is; over a patch of
//! cells the two mix in the colour's proportions, with no error carried from cell to cell (so a cell's
//! colour depends on its own sample and place only, whatever the order or thread count).

use super::oklab::{Lab, distance2};

/// The 2×2×2 pattern the 4×4×4 one is built from: each threshold in turn as far as possible from those
/// before it (0 and 1 at opposite corners, and so on).
const BASE: [[[u8; 2]; 2]; 2] = [[[0, 7], [5, 2]], [[3, 4], [6, 1]]];

/// The threshold of `cell` in (0, 1): the 4×4×4 pattern repeated over the grid (the coarse 2×2×2 step
/// decides the low bits, as Bayer matrices are built).
pub(super) fn threshold(cell: [u16; 3]) -> f32 {
    let at = |shift: u16| {
        let [x, y, z] = cell.map(|c| usize::from((c >> shift) & 1));
        u16::from(BASE[x][y][z])
    };
    (f32::from(at(0) * 8 + at(1)) + 0.5) / 64.0
}

/// The index of the palette colour `c` takes at a cell of threshold `t`: of the two nearest colours, the
/// second when `t` is below how far `c`'s projection lies along the way from the first to it.
pub(super) fn pick(palette: &[Lab], c: &Lab, t: f32) -> usize {
    let (mut first, mut second) = ((f32::INFINITY, 0), (f32::INFINITY, 0));
    for (i, p) in palette.iter().enumerate() {
        let d = distance2(p, c);
        if d < first.0 {
            second = first;
            first = (d, i);
        } else if d < second.0 {
            second = (d, i);
        }
    }
    if second.0.is_infinite() {
        return first.1;
    }
    let (a, b) = (&palette[first.1], &palette[second.1]);
    let ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let along = ((c[0] - a[0]) * ab[0] + (c[1] - a[1]) * ab[1] + (c[2] - a[2]) * ab[2]) / distance2(a, b);
    if t < along.clamp(0.0, 1.0) { second.1 } else { first.1 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pattern_holds_each_of_64_thresholds_once_per_4x4x4_block() {
        let mut seen = [false; 64];
        for x in 0..4 {
            for y in 0..4 {
                for z in 0..4 {
                    let t = threshold([x, y, z]);
                    seen[(t * 64.0) as usize] = true;
                    assert_eq!(t, threshold([x + 4, y + 8, z + 12]), "repeats every 4 cells");
                }
            }
        }
        assert!(seen.iter().all(|&s| s));
    }

    #[test]
    fn a_color_a_quarter_of_the_way_takes_the_far_color_in_a_quarter_of_the_cells() {
        let palette = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let c = [0.25, 0.0, 0.0];
        let cells = (0..4).flat_map(|x| (0..4).flat_map(move |y| (0..4).map(move |z| [x, y, z])));
        let far = cells.filter(|&cell| pick(&palette, &c, threshold(cell)) == 1).count();
        assert_eq!(far, 16);
        // On a palette colour, always that colour.
        assert!((0..64).all(|t| pick(&palette, &[1.0, 0.0, 0.0], (t as f32 + 0.5) / 64.0) == 1));
    }
}
