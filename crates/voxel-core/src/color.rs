//! Colour: sampling a material at a point of a triangle, sRGB ↔ linear, and the article's pastel remap.

use std::sync::LazyLock;

use crate::soup::TriangleSoup;

/// sRGB-encoded 8-bit component → linear.
pub fn srgb_to_linear(c: u8) -> f32 {
    static TABLE: LazyLock<[f32; 256]> = LazyLock::new(|| {
        std::array::from_fn(|c| {
            let c = c as f32 / 255.0;
            if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
        })
    });
    TABLE[usize::from(c)]
}

/// Linear component → sRGB-encoded 8-bit.
pub fn linear_to_srgb(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0).round() as u8
}

/// The colour of triangle `t` at barycentric weights `w`: base colour factor × COLOR_0 × base-colour
/// texture, as sRGB RGBA8.
pub fn sample(soup: &TriangleSoup, t: usize, w: [f64; 3]) -> [u8; 4] {
    let corners = soup.triangle(t);
    let material = soup.material_of(t);
    let lerp4 = |f: &dyn Fn(usize) -> [f32; 4]| -> [f32; 4] {
        std::array::from_fn(|c| (0..3).map(|k| w[k] as f32 * f(k)[c]).sum())
    };
    let vertex = lerp4(&|k| corners[k].color);
    let mut rgba: [f32; 4] = std::array::from_fn(|c| material.base_color[c] * vertex[c]);
    if let Some(binding) = &material.texture {
        let uv = [0, 1].map(|c| (0..3).map(|k| w[k] as f32 * corners[k].uv[c]).sum::<f32>());
        let texel = binding.texture.sample_nearest(uv, binding.wrap);
        for c in 0..3 {
            rgba[c] *= srgb_to_linear(texel[c]);
        }
        rgba[3] *= f32::from(texel[3]) / 255.0;
    }
    [
        linear_to_srgb(rgba[0]),
        linear_to_srgb(rgba[1]),
        linear_to_srgb(rgba[2]),
        (rgba[3].clamp(0.0, 1.0) * 255.0).round() as u8,
    ]
}

/// RGB (0..1) → HSL (each 0..1), as three.js `Color.getHSL`.
pub fn rgb_to_hsl(rgb: [f32; 3]) -> [f32; 3] {
    let [r, g, b] = rgb;
    let max = r.max(g).max(b);
    let min = r.min(g).min(b);
    let l = (max + min) / 2.0;
    if max == min {
        return [0.0, 0.0, l];
    }
    let d = max - min;
    let s = if l <= 0.5 { d / (max + min) } else { d / (2.0 - max - min) };
    let h = if max == r {
        (g - b) / d + if g < b { 6.0 } else { 0.0 }
    } else if max == g {
        (b - r) / d + 2.0
    } else {
        (r - g) / d + 4.0
    };
    [h / 6.0, s, l]
}

/// HSL (each 0..1) → RGB (0..1), as three.js `Color.setHSL`.
pub fn hsl_to_rgb(hsl: [f32; 3]) -> [f32; 3] {
    let [h, s, l] = hsl;
    let h = h.rem_euclid(1.0);
    let s = s.clamp(0.0, 1.0);
    let l = l.clamp(0.0, 1.0);
    if s == 0.0 {
        return [l; 3];
    }
    let p = if l <= 0.5 { l * (1.0 + s) } else { l + s - l * s };
    let q = 2.0 * l - p;
    let hue = |mut t: f32| {
        t = t.rem_euclid(1.0);
        if t < 1.0 / 6.0 {
            q + (p - q) * 6.0 * t
        } else if t < 0.5 {
            p
        } else if t < 2.0 / 3.0 {
            q + (p - q) * 6.0 * (2.0 / 3.0 - t)
        } else {
            q
        }
    };
    [hue(h + 1.0 / 3.0), hue(h), hue(h - 1.0 / 3.0)]
}

/// The article's pastel remap in HSL: saturation × 0.8, lightness × 0.8 + 0.2 (on the sRGB values).
pub fn pastel(rgba: [u8; 4]) -> [u8; 4] {
    let [h, s, l] = rgb_to_hsl([rgba[0], rgba[1], rgba[2]].map(|c| f32::from(c) / 255.0));
    let rgb = hsl_to_rgb([h, s * 0.8, l * 0.8 + 0.2]);
    let [r, g, b] = rgb.map(|c| (c * 255.0).round() as u8);
    [r, g, b, rgba[3]]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trips() {
        for c in [0u8, 1, 10, 100, 187, 255] {
            assert_eq!(linear_to_srgb(srgb_to_linear(c)), c);
        }
    }

    #[test]
    fn hsl_round_trips_and_matches_known_values() {
        let [h, s, l] = rgb_to_hsl([1.0, 0.0, 0.0]);
        assert_eq!((h, s, l), (0.0, 1.0, 0.5));
        for rgb in [[0.2, 0.4, 0.6], [0.9, 0.1, 0.5], [0.5, 0.5, 0.5]] {
            let back = hsl_to_rgb(rgb_to_hsl(rgb));
            for c in 0..3 {
                assert!((back[c] - rgb[c]).abs() < 1e-5, "{rgb:?} -> {back:?}");
            }
        }
    }

    #[test]
    fn pastel_lightens_and_desaturates() {
        // Pure red: s 1 → 0.8, l 0.5 → 0.6 ⇒ rgb (0.92, 0.28, 0.28).
        assert_eq!(pastel([255, 0, 0, 200]), [235, 71, 71, 200]);
        // Black becomes a light grey (l 0 → 0.2).
        assert_eq!(pastel([0, 0, 0, 255]), [51, 51, 51, 255]);
    }
}
