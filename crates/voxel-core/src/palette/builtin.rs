//! The built-in palettes, by name (sRGB colours in the order their authors publish them).

/// PICO-8's 16 colours.
const PICO8: &str = "000000 1d2b53 7e2553 008751 ab5236 5f574f c2c3c7 fff1e8 ff004d ffa300 ffec27 00e436 29adff 83769c \
                     ff77a8 ffccaa";

/// The original Game Boy's four greens (Lospec "Nintendo Gameboy (BGB)").
const GAMEBOY: &str = "081820 346856 88c070 e0f8d0";

/// GrafxKid's Sweetie 16 (Lospec).
const SWEETIE16: &str = "1a1c2c 5d275d b13e53 ef7d57 ffcd75 a7f070 38b764 257179 29366f 3b5dc9 41a6f6 73eff7 f4f4f4 \
                         94b0c2 566c86 333c57";

/// ENDESGA 32 (Lospec).
const ENDESGA32: &str = "be4a2f d77643 ead4aa e4a672 b86f50 733e39 3e2731 a22633 e43b44 f77622 feae34 fee761 63c74d \
                         3e8948 265c42 193c3e 124e89 0099db 2ce8f5 ffffff c0cbdc 8b9bb4 5a6988 3a4466 262b44 181425 \
                         ff0044 68386c b55088 f6757a e8b796 c28569";

/// The names of the fixed built-in palettes (besides `original` and `pastel`), as `--palette` takes them.
pub const FIXED_NAMES: [&str; 5] = ["pico8", "gameboy", "magicavoxel", "endesga32", "sweetie16"];

/// The colours of the fixed built-in palette `name`, or `None` when there is none of that name.
pub fn colors(name: &str) -> Option<Vec<[u8; 3]>> {
    let hex = match name {
        "pico8" => PICO8,
        "gameboy" => GAMEBOY,
        "sweetie16" => SWEETIE16,
        "endesga32" => ENDESGA32,
        "magicavoxel" => return Some(magicavoxel()),
        _ => return None,
    };
    Some(hex.split_whitespace().map(|h| super::file::parse_hex_color(h).expect("a built-in colour")).collect())
}

/// MagicaVoxel's default palette: the 255 colours a .vox file without its own palette uses (`dot_vox` ships
/// them; its 256th entry is the unused index 0).
fn magicavoxel() -> Vec<[u8; 3]> {
    dot_vox::DEFAULT_PALETTE[..crate::vox::MAX_COLORS].iter().map(|c| [c.r, c.g, c.b]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_built_in_has_its_published_size_of_distinct_colors() {
        for (name, size) in [("pico8", 16), ("gameboy", 4), ("sweetie16", 16), ("endesga32", 32), ("magicavoxel", 255)]
        {
            let colors = colors(name).unwrap();
            let mut distinct = colors.clone();
            distinct.sort_unstable();
            distinct.dedup();
            assert_eq!((colors.len(), distinct.len()), (size, size), "{name}");
        }
        assert!(FIXED_NAMES.iter().all(|n| colors(n).is_some()));
        assert_eq!(colors("pico8").unwrap()[8], [0xff, 0x00, 0x4d]);
        // MagicaVoxel's default palette starts with white.
        assert_eq!(colors("magicavoxel").unwrap()[0], [255, 255, 255]);
        assert_eq!(colors("vga"), None);
    }
}
