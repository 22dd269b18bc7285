//! Tiles screenshots side by side into one strip, each cropped to the middle of the stage (between the panel
//! and the preview tiles) and scaled down: `cargo run --example strip -- OUT.png FRAME.png…` (how
//! docs/anim-fox.png and docs/anim-morphcube.png were made from `--screenshot` frames).

use image::imageops::{FilterType, crop_imm, overlay, resize};
use image::{RgbImage, RgbaImage};

/// The middle of the stage in a 1280 × 720 window, where the model stands (x, y, width, height).
const STAGE: (u32, u32, u32, u32) = (420, 130, 480, 440);
/// Scale of each tile in the strip.
const SCALE: f32 = 0.6;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some((out, frames)) = args.split_first().filter(|(_, f)| !f.is_empty()) else {
        return Err("usage: strip OUT.png FRAME.png…".into());
    };
    let (x, y, w, h) = STAGE;
    let (tw, th) = ((w as f32 * SCALE) as u32, (h as f32 * SCALE) as u32);
    let mut strip = RgbaImage::new(tw * frames.len() as u32, th);
    for (i, path) in frames.iter().enumerate() {
        let frame = image::open(path).map_err(|e| format!("{path}: {e}"))?.to_rgba8();
        if frame.width() < x + w || frame.height() < y + h {
            return Err(format!("{path}: {}×{} is smaller than the stage crop", frame.width(), frame.height()).into());
        }
        let stage = crop_imm(&frame, x, y, w, h).to_image();
        overlay(&mut strip, &resize(&stage, tw, th, FilterType::Lanczos3), i64::from(tw * i as u32), 0);
    }
    let rgb: RgbImage = image::DynamicImage::ImageRgba8(strip).to_rgb8();
    rgb.save(out).map_err(|e| format!("{out}: {e}"))?;
    Ok(())
}
