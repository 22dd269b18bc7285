//! Oklab (Björn Ottosson's perceptual colour space): distances there follow how different colours look, so
//! palette matching and colour reduction work in it.

use crate::srgb::srgb_to_linear;

/// An Oklab colour: lightness L and the two opponent axes a, b.
pub(super) type Lab = [f32; 3];

/// sRGB → Oklab.
pub(super) fn from_srgb(c: [u8; 3]) -> Lab {
    let [r, g, b] = c.map(srgb_to_linear);
    let l = (0.412_221_46 * r + 0.536_332_55 * g + 0.051_445_995 * b).cbrt();
    let m = (0.211_903_5 * r + 0.680_699_5 * g + 0.107_396_96 * b).cbrt();
    let s = (0.088_302_46 * r + 0.281_718_85 * g + 0.629_978_7 * b).cbrt();
    [
        0.210_454_26 * l + 0.793_617_8 * m - 0.004_072_047 * s,
        1.977_998_5 * l - 2.428_592_2 * m + 0.450_593_7 * s,
        0.025_904_037 * l + 0.782_771_77 * m - 0.808_675_77 * s,
    ]
}

/// The squared distance between two Oklab colours.
pub(super) fn distance2(a: &Lab, b: &Lab) -> f32 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)
}

/// The index of the colour of `palette` nearest to `c` (the first of equals).
pub(super) fn nearest(palette: &[Lab], c: &Lab) -> usize {
    let mut best = (f32::INFINITY, 0);
    for (i, p) in palette.iter().enumerate() {
        let d = distance2(p, c);
        if d < best.0 {
            best = (d, i);
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_black_and_red_have_their_published_coordinates() {
        let close = |a: Lab, b: Lab| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-3);
        assert!(close(from_srgb([255, 255, 255]), [1.0, 0.0, 0.0]), "{:?}", from_srgb([255; 3]));
        assert!(close(from_srgb([0, 0, 0]), [0.0, 0.0, 0.0]));
        assert!(close(from_srgb([255, 0, 0]), [0.627_955, 0.224_863, 0.125_846]), "{:?}", from_srgb([255, 0, 0]));
    }
}
