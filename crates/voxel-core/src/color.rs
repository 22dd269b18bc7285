//! Colour: sampling a material at a point of a triangle (sRGB ↔ linear: [`crate::srgb`]), and the article's pastel
//! remap.

use crate::soup::TriangleSoup;
use crate::srgb::{linear_to_srgb, srgb_to_linear};

/// `x.round() as u8` for `x` in [0, 255] or NaN (half away from zero; NaN gives 0), without a libm call:
/// `x − ⌊x⌋` is exact for these values.
#[inline]
fn round_to_u8(x: f32) -> u8 {
    let whole = x as u8;
    whole + u8::from(x - f32::from(whole) >= 0.5)
}

/// The colour of triangle `t` at barycentric weights `w`: base colour factor × COLOR_0 × base-colour
/// texture, as sRGB RGBA8. COLOR_0 shared by the three corners is taken as it is, so an untextured triangle of
/// one colour has that colour wherever it is sampled ([`flat_color`]).
pub fn sample(soup: &TriangleSoup, t: usize, w: [f64; 3]) -> [u8; 4] {
    shade(soup, t, w, texel(soup, t, w))
}

/// The weights as [`sample`] interpolates with them, and the interpolation: each sum in the corners' order, as
/// `Iterator::sum` adds them (−0 + x = x, exactly).
fn lerp(w: [f64; 3]) -> impl Fn(f32, f32, f32) -> f32 {
    let [w0, w1, w2] = w.map(|w| w as f32);
    move |x, y, z| w0 * x + w1 * y + w2 * z
}

/// The base-colour texel of triangle `t` at barycentric weights `w` (`None` for a material without a texture):
/// the one memory read of [`sample`] that a large texture makes a cache miss, apart so that a caller can gather
/// many before it shades them.
pub fn texel(soup: &TriangleSoup, t: usize, w: [f64; 3]) -> Option<[u8; 4]> {
    let binding = soup.material_of(t).texture.as_ref()?;
    let lerp = lerp(w);
    // The corners' texture coordinates (not their positions).
    let [a, b, c] = soup.triangles()[t].map(|i| soup.uv(i as usize));
    let uv = [lerp(a[0], b[0], c[0]), lerp(a[1], b[1], c[1])];
    Some(binding.texture.sample_nearest(uv, binding.wrap))
}

/// [`sample`] with its [`texel`] read already.
pub fn shade(soup: &TriangleSoup, t: usize, w: [f64; 3], texel: Option<[u8; 4]>) -> [u8; 4] {
    let [a, b, c] = soup.triangle_colors(t);
    let material = soup.material_of(t);
    let lerp = lerp(w);
    let color = if a == b && b == c { a } else { std::array::from_fn(|ch| lerp(a[ch], b[ch], c[ch])) };
    let mut rgba = [0.0f32; 4];
    for (ch, out) in rgba.iter_mut().enumerate() {
        *out = material.base_color[ch] * color[ch];
    }
    if let Some(texel) = texel {
        for ch in 0..3 {
            rgba[ch] *= srgb_to_linear(texel[ch]);
        }
        rgba[3] *= f32::from(texel[3]) / 255.0;
    }
    [
        linear_to_srgb(rgba[0]),
        linear_to_srgb(rgba[1]),
        linear_to_srgb(rgba[2]),
        round_to_u8(rgba[3].clamp(0.0, 1.0) * 255.0),
    ]
}

/// The part and the linear COLOR_0 of triangle `t` when [`sample`] gives it one colour wherever it is
/// sampled: its material has no texture and its three corners share their COLOR_0. Two triangles with the
/// same flat colour sample alike (the part picks the material).
pub fn flat_color(soup: &TriangleSoup, t: usize) -> Option<(u32, [f32; 4])> {
    if soup.material_of(t).texture.is_some() {
        return None;
    }
    let [a, b, c] = soup.triangle_colors(t);
    (a == b && b == c).then_some((soup.part_of(t), a))
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
    fn rounding_without_libm_matches_round() {
        for i in 0..=255 * 64 {
            let x = i as f32 / 64.0;
            for x in [x, f32::from_bits(x.to_bits() + 1), f32::from_bits(x.to_bits().saturating_sub(1))] {
                if x <= 255.0 {
                    assert_eq!(round_to_u8(x), x.round() as u8, "{x}");
                }
            }
        }
        assert_eq!(round_to_u8(f32::NAN), 0);
        assert_eq!(round_to_u8(0.499_999_97), 0);
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
    fn a_sample_is_base_colour_times_corner_colours_times_the_texel_under_the_weighted_uv() {
        use crate::soup::{Material, Texture, TextureBinding, Vertex, Wrap};
        use std::sync::Arc;
        // 4 × 1 texels: red, green, blue, white at half alpha.
        let texels = vec![[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255], [255, 255, 255, 128]];
        let texture = Arc::new(Texture::new(4, 1, texels).unwrap());
        let mut soup = TriangleSoup::default();
        let plain = soup.add_material(Material { base_color: [0.5, 1.0, 1.0, 1.0], texture: None });
        let textured = soup.add_material(Material {
            base_color: [1.0, 1.0, 0.5, 1.0],
            texture: Some(TextureBinding { texture, wrap: [Wrap::ClampToEdge; 2] }),
        });
        let corner = |x: f32, u: f32| Vertex { position: [x, 0.0, x * x], uv: [u, 0.5], color: [1.0; 4] };
        let corners = [corner(0.0, 0.0), corner(1.0, 1.0), corner(2.0, 0.0)];
        for material in [plain, textured] {
            let part = soup.add_part(material, "part");
            soup.push_triangle(part, corners);
        }
        // Weights (1/8, 7/16, 7/16): u = 7/16 lands in the second texel; (0, 1, 0): u = 1 clamps to the last.
        let (w, corner_w) = ([0.125, 0.4375, 0.4375], [0.0, 1.0, 0.0]);
        assert_eq!(texel(&soup, 0, w), None);
        assert_eq!(sample(&soup, 0, w), [188, 255, 255, 255]);
        assert_eq!(texel(&soup, 1, w), Some([0, 255, 0, 255]));
        assert_eq!(sample(&soup, 1, w), [0, 255, 0, 255]);
        assert_eq!(texel(&soup, 1, corner_w), Some([255, 255, 255, 128]));
        assert_eq!(sample(&soup, 1, corner_w), [255, 255, 188, 128]);
        for t in 0..2 {
            assert_eq!(shade(&soup, t, w, texel(&soup, t, w)), sample(&soup, t, w));
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
