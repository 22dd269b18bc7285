//! Palette files: a Lospec-style `.hex` list (one `rrggbb` a line, `;` comments), a `.png` strip (its distinct
//! pixels, in reading order) or a MagicaVoxel `.vox` (its 255 colours).

use std::path::Path;

use crate::error::{Result, VoxelError};

/// The most colours a palette file may hold.
pub const MAX_FILE_COLORS: usize = 4096;

/// `rrggbb` (a leading `#` allowed) as sRGB.
pub(super) fn parse_hex_color(text: &str) -> Option<[u8; 3]> {
    let hex = text.strip_prefix('#').unwrap_or(text);
    if hex.len() != 6 || !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
        return None;
    }
    let channel = |k: usize| u8::from_str_radix(&hex[2 * k..2 * k + 2], 16).ok();
    Some([channel(0)?, channel(1)?, channel(2)?])
}

/// Why a palette file was refused (the caller names the file).
fn invalid(reason: impl Into<String>) -> VoxelError {
    VoxelError::Palette(reason.into())
}

/// The colours of the palette file at `path`, by its extension: `.hex`, `.png` or `.vox`. Repeated colours
/// are kept once, at their first place.
pub fn read(path: &Path) -> Result<Vec<[u8; 3]>> {
    let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let bytes = std::fs::read(path).map_err(|source| VoxelError::Io { path: path.to_owned(), source })?;
    let colors = match extension.as_deref() {
        Some("hex") => from_hex(&bytes)?,
        Some("png") => from_png(&bytes)?,
        Some("vox") => from_vox(&bytes)?,
        _ => return Err(invalid("a palette file is .hex, .png or .vox")),
    };
    let colors = first_of_each(colors);
    match colors.len() {
        0 => Err(invalid("the palette has no colours")),
        n if n > MAX_FILE_COLORS => {
            Err(invalid(format!("the palette has {n} colours, over the limit of {MAX_FILE_COLORS}")))
        }
        _ => Ok(colors),
    }
}

/// The colours in their order, each kept at its first place only.
fn first_of_each(colors: Vec<[u8; 3]>) -> Vec<[u8; 3]> {
    let mut seen = rustc_hash::FxHashSet::default();
    colors.into_iter().filter(|c| seen.insert(*c)).collect()
}

/// A `.hex` list: one `rrggbb` a line; blank lines and `;` comments ignored.
fn from_hex(bytes: &[u8]) -> Result<Vec<[u8; 3]>> {
    let text = std::str::from_utf8(bytes).map_err(|_| invalid("a .hex palette is text, and this is not UTF-8"))?;
    let mut colors = Vec::new();
    for (number, line) in text.lines().enumerate() {
        let line = line.split(';').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let color = parse_hex_color(line)
            .ok_or_else(|| invalid(format!("line {}: {line:?} is not a colour rrggbb", number + 1)))?;
        colors.push(color);
        if colors.len() > MAX_FILE_COLORS {
            break;
        }
    }
    Ok(colors)
}

/// A `.png` strip: its opaque pixels' colours in reading order (fully transparent pixels skipped).
fn from_png(bytes: &[u8]) -> Result<Vec<[u8; 3]>> {
    let image = image::load_from_memory_with_format(bytes, image::ImageFormat::Png)
        .map_err(|e| invalid(format!("not a readable PNG ({e})")))?;
    let rgba = image.to_rgba8();
    Ok(rgba.pixels().filter(|p| p[3] > 0).map(|p| [p[0], p[1], p[2]]).collect())
}

/// A `.vox`: its palette's 255 colours (MagicaVoxel's default when it has none).
fn from_vox(bytes: &[u8]) -> Result<Vec<[u8; 3]>> {
    let data = dot_vox::load_bytes(bytes).map_err(|e| invalid(format!("not a readable .vox file ({e})")))?;
    Ok(data.palette.iter().take(crate::vox::MAX_COLORS).map(|c| [c.r, c.g, c.b]).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str, bytes: &[u8]) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("voxel-core-palette-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        path
    }

    #[test]
    fn a_hex_list_skips_comments_blank_lines_and_repeats() {
        let path = temp("a.hex", b"; a palette\nff0000\n\n#00FF00 ; green\r\nff0000\n0000ff\n");
        assert_eq!(read(&path).unwrap(), [[255, 0, 0], [0, 255, 0], [0, 0, 255]]);
    }

    #[test]
    fn bad_files_are_refused_with_the_reason() {
        let reason = |name: &str, bytes: &[u8]| read(&temp(name, bytes)).unwrap_err().to_string();
        assert_eq!(
            reason("b.hex", b"ff0000\nbanana\n"),
            "not a usable palette: line 2: \"banana\" is not a colour rrggbb"
        );
        assert_eq!(reason("c.hex", b"; nothing\n"), "not a usable palette: the palette has no colours");
        assert!(reason("d.png", b"not a png").starts_with("not a usable palette: not a readable PNG"));
        assert!(reason("e.vox", b"VOX nonsense").starts_with("not a usable palette: not a readable .vox file"));
        assert_eq!(reason("f.txt", b"ff0000"), "not a usable palette: a palette file is .hex, .png or .vox");
        let missing = read(Path::new("/nonexistent/palette.hex")).unwrap_err().to_string();
        assert!(missing.starts_with("cannot read /nonexistent/palette.hex: "), "{missing}");
    }
}
