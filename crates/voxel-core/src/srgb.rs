//! sRGB ↔ linear for 8-bit components: both directions by table, the tables written out here (their values are the
//! sRGB curve's, computed with `powf` and checked against it by the tests), so that the first colour a process
//! samples does not compute them (about 60 µs, on the critical path of a small model's voxelization).

/// `srgb_to_linear`'s values, as f32 bits: the curve `c / 12.92` up to 0.04045, else `((c + 0.055) / 1.055)^2.4`, of
/// `c` = k / 255, in f32.
const LINEAR_BITS: [u32; 256] = [
    0x00000000, 0x399f22b4, 0x3a1f22b4, 0x3a6eb40e, 0x3a9f22b4, 0x3ac6eb61, 0x3aeeb40e, 0x3b0b3e5d, 0x3b1f22b4,
    0x3b33070b, 0x3b46eb61, 0x3b5b518d, 0x3b70f18d, 0x3b83e1c6, 0x3b8fe616, 0x3b9c87fd, 0x3ba9c9b7, 0x3bb7ad6f,
    0x3bc63549, 0x3bd56361, 0x3be539c1, 0x3bf5ba70, 0x3c0373b5, 0x3c0c6152, 0x3c15a703, 0x3c1f45be, 0x3c293e6b,
    0x3c3391f7, 0x3c3e4149, 0x3c494d43, 0x3c54b6c7, 0x3c607eb1, 0x3c6ca5df, 0x3c792d22, 0x3c830aa8, 0x3c89af9f,
    0x3c9085db, 0x3c978dc5, 0x3c9ec7c2, 0x3ca63433, 0x3cadd37d, 0x3cb5a601, 0x3cbdac20, 0x3cc5e639, 0x3cce54ab,
    0x3cd6f7d5, 0x3cdfd010, 0x3ce8ddb9, 0x3cf2212c, 0x3cfb9ac1, 0x3d02a569, 0x3d0798dc, 0x3d0ca7e6, 0x3d11d2af,
    0x3d171963, 0x3d1c7c2e, 0x3d21fb3c, 0x3d2796b2, 0x3d2d4ebb, 0x3d332380, 0x3d39152b, 0x3d3f23e3, 0x3d454fd1,
    0x3d4b991c, 0x3d51ffef, 0x3d58846a, 0x3d5f26b7, 0x3d65e6fe, 0x3d6cc564, 0x3d73c20f, 0x3d7add29, 0x3d810b67,
    0x3d84b795, 0x3d887330, 0x3d8c3e4a, 0x3d9018f6, 0x3d940345, 0x3d97fd4a, 0x3d9c0716, 0x3da020bb, 0x3da44a4b,
    0x3da883d7, 0x3daccd70, 0x3db12728, 0x3db59112, 0x3dba0b3b, 0x3dbe95b5, 0x3dc33092, 0x3dc7dbe2, 0x3dcc97b6,
    0x3dd1641f, 0x3dd6412c, 0x3ddb2eef, 0x3de02d77, 0x3de53cd5, 0x3dea5d19, 0x3def8e52, 0x3df4d091, 0x3dfa23e8,
    0x3dff8861, 0x3e027f07, 0x3e054280, 0x3e080ea3, 0x3e0ae378, 0x3e0dc105, 0x3e10a754, 0x3e13966b, 0x3e168e52,
    0x3e198f10, 0x3e1c98ad, 0x3e1fab30, 0x3e22c6a3, 0x3e25eb09, 0x3e29186c, 0x3e2c4ed0, 0x3e2f8e41, 0x3e32d6c4,
    0x3e362861, 0x3e39831e, 0x3e3ce703, 0x3e405416, 0x3e43ca5f, 0x3e4749e4, 0x3e4ad2ae, 0x3e4e64c2, 0x3e520027,
    0x3e55a4e6, 0x3e595303, 0x3e5d0a8b, 0x3e60cb7c, 0x3e6495e0, 0x3e6869bf, 0x3e6c4720, 0x3e702e0c, 0x3e741e84,
    0x3e781890, 0x3e7c1c38, 0x3e8014c2, 0x3e82203c, 0x3e84308d, 0x3e8645ba, 0x3e885fc5, 0x3e8a7eb2, 0x3e8ca283,
    0x3e8ecb3d, 0x3e90f8e1, 0x3e932b74, 0x3e9562f8, 0x3e979f71, 0x3e99e0e2, 0x3e9c274e, 0x3e9e72b7, 0x3ea0c322,
    0x3ea31892, 0x3ea57308, 0x3ea7d289, 0x3eaa3718, 0x3eaca0b7, 0x3eaf0f69, 0x3eb18333, 0x3eb3fc18, 0x3eb67a18,
    0x3eb8fd37, 0x3ebb8579, 0x3ebe12e1, 0x3ec0a571, 0x3ec33d2d, 0x3ec5da17, 0x3ec87c33, 0x3ecb2383, 0x3ecdd00b,
    0x3ed081cd, 0x3ed338cc, 0x3ed5f50b, 0x3ed8b68d, 0x3edb7d54, 0x3ede4965, 0x3ee11ac1, 0x3ee3f16b, 0x3ee6cd67,
    0x3ee9aeb6, 0x3eec955d, 0x3eef815d, 0x3ef272ba, 0x3ef56976, 0x3ef86594, 0x3efb6717, 0x3efe6e02, 0x3f00bd2d,
    0x3f02460e, 0x3f03d1a7, 0x3f055ff9, 0x3f06f106, 0x3f0884cf, 0x3f0a1b56, 0x3f0bb49b, 0x3f0d50a0, 0x3f0eef67,
    0x3f1090f1, 0x3f12353e, 0x3f13dc51, 0x3f15862b, 0x3f1732cd, 0x3f18e239, 0x3f1a946f, 0x3f1c4971, 0x3f1e0141,
    0x3f1fbbdf, 0x3f21794e, 0x3f23398e, 0x3f24fca0, 0x3f26c286, 0x3f288b41, 0x3f2a56d3, 0x3f2c253d, 0x3f2df680,
    0x3f2fca9e, 0x3f31a197, 0x3f337b6c, 0x3f355820, 0x3f3737b3, 0x3f391a26, 0x3f3aff7c, 0x3f3ce7b5, 0x3f3ed2d2,
    0x3f40c0d4, 0x3f42b1be, 0x3f44a590, 0x3f469c4b, 0x3f4895f1, 0x3f4a9282, 0x3f4c9201, 0x3f4e946e, 0x3f5099cb,
    0x3f52a218, 0x3f54ad57, 0x3f56bb8a, 0x3f58ccb0, 0x3f5ae0cd, 0x3f5cf7e0, 0x3f5f11ec, 0x3f612eee, 0x3f634eef,
    0x3f6571e9, 0x3f6797e3, 0x3f69c0d6, 0x3f6beccd, 0x3f6e1bbf, 0x3f704db8, 0x3f7282af, 0x3f74baae, 0x3f76f5ae,
    0x3f7933b9, 0x3f7b74c6, 0x3f7db8e0, 0x3f800000,
];

/// [`Thresholds::thresholds`] as f32 bits: k from 0 to 256.
const THRESHOLD_BITS: [u32; 257] = [
    0x00000000, 0x391f22b4, 0x39eeb40e, 0x3a46eb61, 0x3a8b3e5d, 0x3ab3070b, 0x3adacfb7, 0x3b014c32, 0x3b153089,
    0x3b2914df, 0x3b3cf936, 0x3b50f2d1, 0x3b65fb9a, 0x3b7c3404, 0x3b89d060, 0x3b962333, 0x3ba314be, 0x3bb0a731,
    0x3bbedcb6, 0x3bcdb76c, 0x3bdd3966, 0x3bed64ae, 0x3bfe3b44, 0x3c07df90, 0x3c10f919, 0x3c1a6b32, 0x3c2436c7,
    0x3c2e5cc7, 0x3c38de19, 0x3c43bba3, 0x3c4ef646, 0x3c5a8ee2, 0x3c668654, 0x3c72dd73, 0x3c7f9512, 0x3c865703,
    0x3c8d1490, 0x3c940396, 0x3c9b247c, 0x3ca277a8, 0x3ca9fd79, 0x3cb1b654, 0x3cb9a299, 0x3cc1c2a9, 0x3cca16e3,
    0x3cd29fa4, 0x3cdb5d4d, 0x3ce45034, 0x3ced78b6, 0x3cf6d72f, 0x3d0035fc, 0x3d051bb6, 0x3d0a1cee, 0x3d0f39d1,
    0x3d14728a, 0x3d19c745, 0x3d1f382b, 0x3d24c56a, 0x3d2a6f24, 0x3d303586, 0x3d3618b9, 0x3d3c18e6, 0x3d423634,
    0x3d4870cb, 0x3d4ec8d3, 0x3d553e74, 0x3d5bd1d3, 0x3d628319, 0x3d69526a, 0x3d703fee, 0x3d774bce, 0x3d7e7627,
    0x3d82df92, 0x3d869374, 0x3d8a56cc, 0x3d8e29ad, 0x3d920c28, 0x3d95fe50, 0x3d9a0036, 0x3d9e11ec, 0x3da23384,
    0x3da66510, 0x3daaa6a0, 0x3daef847, 0x3db35a17, 0x3db7cc1d, 0x3dbc4e6c, 0x3dc0e116, 0x3dc5842a, 0x3dca37ba,
    0x3dcefbd7, 0x3dd3d090, 0x3dd8b5f6, 0x3dddac19, 0x3de2b30a, 0x3de7cad9, 0x3decf395, 0x3df22d4f, 0x3df7781a,
    0x3dfcd3fe, 0x3e012088, 0x3e03dfaf, 0x3e06a77c, 0x3e0977f7, 0x3e0c5127, 0x3e0f3314, 0x3e121dc6, 0x3e151144,
    0x3e180d95, 0x3e1b12c2, 0x3e1e20d1, 0x3e2137cb, 0x3e2457b7, 0x3e27809a, 0x3e2ab27c, 0x3e2ded67, 0x3e313160,
    0x3e347e6f, 0x3e37d49d, 0x3e3b33ed, 0x3e3e9c68, 0x3e420e14, 0x3e4588fa, 0x3e490d21, 0x3e4c9a8f, 0x3e50314b,
    0x3e53d15c, 0x3e577ac9, 0x3e5b2d99, 0x3e5ee9d2, 0x3e62af7c, 0x3e667e9d, 0x3e6a5740, 0x3e6e3963, 0x3e722512,
    0x3e761a53, 0x3e7a192d, 0x3e7e21a6, 0x3e8119e2, 0x3e8327c8, 0x3e853a87, 0x3e875222, 0x3e896e9e, 0x3e8b8ffc,
    0x3e8db641, 0x3e8fe170, 0x3e92118b, 0x3e944696, 0x3e968094, 0x3e98bf89, 0x3e9b0377, 0x3e9d4c61, 0x3e9f9a4b,
    0x3ea1ed38, 0x3ea4452a, 0x3ea6a225, 0x3ea9042d, 0x3eab6b43, 0x3eadd76b, 0x3eb048a9, 0x3eb2bf01, 0x3eb53a72,
    0x3eb7bb01, 0x3eba40b2, 0x3ebccb86, 0x3ebf5b82, 0x3ec1f0a7, 0x3ec48afa, 0x3ec72a7d, 0x3ec9cf32, 0x3ecc791e,
    0x3ecf2842, 0x3ed1dca2, 0x3ed49641, 0x3ed75521, 0x3eda1945, 0x3edce2b1, 0x3edfb167, 0x3ee2856a, 0x3ee55ebc,
    0x3ee83d62, 0x3eeb215c, 0x3eee0aaf, 0x3ef0f95d, 0x3ef3ed69, 0x3ef6e6d6, 0x3ef9e5a6, 0x3efce9e0, 0x3efff37f,
    0x3f018145, 0x3f030b82, 0x3f049878, 0x3f062827, 0x3f07ba92, 0x3f094fba, 0x3f0ae79f, 0x3f0c8244, 0x3f0e1faa,
    0x3f0fbfd2, 0x3f1162be, 0x3f13086e, 0x3f14b0e4, 0x3f165c22, 0x3f180a29, 0x3f19baf9, 0x3f1b6e95, 0x3f1d24fe,
    0x3f1ede35, 0x3f209a3b, 0x3f225912, 0x3f241abb, 0x3f25df37, 0x3f27a688, 0x3f2970ae, 0x3f2b3dac, 0x3f2d0d84,
    0x3f2ee033, 0x3f30b5be, 0x3f328e25, 0x3f346969, 0x3f36478c, 0x3f38288f, 0x3f3a0c73, 0x3f3bf33a, 0x3f3ddce5,
    0x3f3fc975, 0x3f41b8eb, 0x3f43ab48, 0x3f45a08f, 0x3f4798bf, 0x3f4993da, 0x3f4b91e2, 0x3f4d92d8, 0x3f4f96bd,
    0x3f519d91, 0x3f53a758, 0x3f55b410, 0x3f57c3bd, 0x3f59d65e, 0x3f5bebf6, 0x3f5e0485, 0x3f60200d, 0x3f623e91,
    0x3f64600b, 0x3f668486, 0x3f68abfa, 0x3f6ad671, 0x3f6d03e3, 0x3f6f345b, 0x3f7167d0, 0x3f739e4d, 0x3f75d7ca,
    0x3f781452, 0x3f7a53db, 0x3f7c9671, 0x3f7edc0e, 0x7f800000,
];

/// The linear value of each 8-bit sRGB component.
static LINEAR: [f32; 256] = from_bits(LINEAR_BITS);

/// sRGB-encoded 8-bit component → linear.
pub fn srgb_to_linear(c: u8) -> f32 {
    LINEAR[usize::from(c)]
}

/// The f32s of `bits`.
const fn from_bits<const N: usize>(bits: [u32; N]) -> [f32; N] {
    let mut values = [0.0; N];
    let mut k = 0;
    while k < N {
        values[k] = f32::from_bits(bits[k]);
        k += 1;
    }
    values
}

/// Linear component → sRGB-encoded 8-bit: exactly `linear_to_srgb_formula` (the sRGB curve in f32 with
/// `powf`, rounded), looked up instead of computed. The formula is non-decreasing in `c`, so its value is the
/// number of the 255 thresholds `t₁ ≤ … ≤ t₂₅₅` (tₖ: the smallest f32 it maps to k or more) that are ≤ `c`.
/// The f32s from 2⁻¹³ to 1 fall into 1,664 slices by the top 16 bits of their encoding (the exponent and 7
/// bits of the mantissa: each slice spans 1/128 of its start); a table gives the count at the start of `c`'s
/// slice, and the one threshold that may lie inside the slice (the curve rises by less than one step across a
/// slice: checked by the tests) is compared without a branch (one taken or not at random, where colours vary from
/// cell to cell, cost a misprediction a channel). Below 2⁻¹³ the formula gives 0.
pub fn linear_to_srgb(c: f32) -> u8 {
    let bits = c.to_bits();
    // From 1 up, negative values and NaN (sign bit set, or above +∞'s encoding): the formula's clamp and
    // saturating cast give 255 and 0.
    if bits >= 1f32.to_bits() {
        return if c >= 1.0 { 255 } else { 0 };
    }
    let Some(slice) = (bits >> SLICE_SHIFT).checked_sub(FIRST_SLICE) else {
        return 0; // below 2⁻¹³ (zero included), under the first threshold (checked by the tests)
    };
    let k = THRESHOLDS.at_slice[slice as usize];
    k + u8::from(c >= THRESHOLDS.thresholds[usize::from(k) + 1])
}

/// The low bits of an f32's encoding that a slice of [`linear_to_srgb`]'s table spans.
const SLICE_SHIFT: u32 = 16;

/// The first slice: the one starting at 2⁻¹³.
const FIRST_SLICE: u32 = (127 - 13) << (23 - SLICE_SHIFT);

/// Slices from 2⁻¹³ up to 1.
const SLICES: usize = (1f32.to_bits() >> SLICE_SHIFT) as usize - FIRST_SLICE as usize;

/// [`linear_to_srgb`]'s tables, built from the written-out thresholds when the crate is compiled.
static THRESHOLDS: Thresholds = Thresholds::new(from_bits(THRESHOLD_BITS));

/// The tables of [`linear_to_srgb`].
struct Thresholds {
    /// `thresholds[k]`, 1 ≤ k ≤ 255: the smallest f32 that the formula maps to k or more (`thresholds[0]` = 0,
    /// `thresholds[256]` = ∞: none is reached from 255).
    thresholds: [f32; 257],
    /// The number of thresholds at or below the start of each slice (the formula's value there).
    at_slice: [u8; SLICES],
}

impl Thresholds {
    /// The tables of `thresholds` (ascending).
    const fn new(thresholds: [f32; 257]) -> Self {
        let mut at_slice = [0; SLICES];
        let mut count = 0u8;
        let mut s = 0;
        while s < SLICES {
            let start = f32::from_bits((s as u32 + FIRST_SLICE) << SLICE_SHIFT);
            while count < 255 && thresholds[count as usize + 1] <= start {
                count += 1;
            }
            at_slice[s] = count;
            s += 1;
        }
        Self { thresholds, at_slice }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Linear component → sRGB-encoded 8-bit by the sRGB curve (`powf`): the definition [`linear_to_srgb`]
    /// tabulates.
    fn linear_to_srgb_formula(c: f32) -> u8 {
        let c = c.clamp(0.0, 1.0);
        let s = if c <= 0.003_130_8 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
        (s * 255.0).round() as u8
    }

    /// `thresholds[k]`: the smallest f32 that [`linear_to_srgb_formula`] maps to k or more.
    fn thresholds_of_the_formula() -> [f32; 257] {
        let mut thresholds = [0.0f32; 257];
        thresholds[256] = f32::INFINITY;
        for (k, threshold) in thresholds.iter_mut().enumerate().take(256).skip(1) {
            // Start at the curve's exact inverse at k − ½ and step one f32 at a time to the first value that
            // the formula maps to k or more (a few steps: the inverse is within rounding of it).
            let s = (k as f64 - 0.5) / 255.0;
            let guess = if s <= 0.04045 { s / 12.92 } else { ((s + 0.055) / 1.055).powf(2.4) };
            let mut t = guess as f32;
            while t > 0.0 && linear_to_srgb_formula(f32::from_bits(t.to_bits() - 1)) >= k as u8 {
                t = f32::from_bits(t.to_bits() - 1);
            }
            while linear_to_srgb_formula(t) < k as u8 {
                t = f32::from_bits(t.to_bits() + 1);
            }
            *threshold = t;
        }
        thresholds
    }

    #[test]
    fn the_written_tables_are_the_curves() {
        let linear: [f32; 256] = std::array::from_fn(|c| {
            let c = c as f32 / 255.0;
            if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
        });
        assert_eq!(LINEAR.map(f32::to_bits), linear.map(f32::to_bits));
        assert_eq!(THRESHOLDS.thresholds.map(f32::to_bits), thresholds_of_the_formula().map(f32::to_bits));
    }

    #[test]
    fn srgb_round_trips() {
        for c in [0u8, 1, 10, 100, 187, 255] {
            assert_eq!(linear_to_srgb(srgb_to_linear(c)), c);
        }
    }

    /// Whether the table gives the formula's value at `c`.
    fn table_matches(c: f32) -> bool {
        linear_to_srgb(c) == linear_to_srgb_formula(c)
    }

    #[test]
    fn the_srgb_table_is_the_formula_at_every_step_and_between() {
        let thresholds = THRESHOLDS.thresholds;
        for (k, &t) in thresholds.iter().enumerate().take(256).skip(1) {
            assert_eq!(usize::from(linear_to_srgb(t)), k, "at threshold {k}: {t}");
            let below = f32::from_bits(t.to_bits() - 1);
            assert_eq!(usize::from(linear_to_srgb_formula(below)), k - 1, "below threshold {k}");
            for c in [t, below, f32::from_bits(t.to_bits() + 1), f32::from_bits(t.to_bits() - 2)] {
                assert!(table_matches(c), "{c}");
            }
        }
        let specials = [f32::NAN, -f32::NAN, -1.0, -0.0, 0.0, 1e-45, 1.0, 1.5, f32::INFINITY, f32::NEG_INFINITY];
        assert!(specials.into_iter().all(table_matches));
        // Every slice's start and end, and a million evenly spaced values; below the first slice, 0.
        assert_eq!(f32::from_bits(FIRST_SLICE << SLICE_SHIFT), 2f32.powi(-13));
        assert!(thresholds[1] > 2f32.powi(-13), "{}", thresholds[1]);
        let start = |s: usize| f32::from_bits((s as u32 + FIRST_SLICE) << SLICE_SHIFT);
        assert_eq!(start(SLICES), 1.0);
        // At most one threshold inside a slice: the one comparison `linear_to_srgb` makes.
        let counts: Vec<u8> = (0..=SLICES).map(|s| linear_to_srgb_formula(start(s))).collect();
        assert!(counts.windows(2).all(|w| w[1] - w[0] <= 1), "{counts:?}");
        assert!((0..=SLICES).all(|s| table_matches(start(s)) && table_matches(f32::from_bits(start(s).to_bits() - 1))));
        assert!((0..=1_000_000).all(|i| table_matches(i as f32 / 1e6)));
    }

    /// Every f32, NaNs included (2³² values): `cargo test -p voxel-core --release -- --ignored`.
    #[test]
    #[ignore = "exhaustive, about a minute in release"]
    fn the_srgb_table_is_the_formula_for_every_f32() {
        let mismatch = (0..=u32::MAX).map(f32::from_bits).find(|&c| !table_matches(c));
        assert_eq!(mismatch.map(f32::to_bits), None);
    }
}
