//! The GIF of a recording, written on its own thread while the app goes on: frames arrive numbered over a
//! channel (screenshots come back in any order) and are written in order. Each frame keeps only the pixels that
//! changed since the frame before, in the smallest rectangle holding them, the rest of the rectangle
//! transparent (the stage's backdrop and floor stay put while the voxels move, so most of a frame is
//! unchanged); those pixels get their own palette of at most 255 colours — exact when they have that few,
//! else NeuQuant's (`color_quant`, what the `gif` and `image` crates use) — and the 256th entry is the
//! transparent one. No dithering: it would change every pixel of every frame and defeat both the
//! transparency and LZW.

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender, channel};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use color_quant::NeuQuant;

/// How long the writer waits for a frame still missing once the recording has ended: a capture comes back two
/// or three app frames after it is taken, and a headless run on a busy CPU's software renderer takes seconds
/// a frame.
const MISSING_FRAME_TIMEOUT: Duration = Duration::from_secs(120);
/// The palette index of a pixel that keeps the previous frame's colour.
const TRANSPARENT: u8 = 255;
/// Pixels NeuQuant learns from at least (all of them when fewer): enough for a stable palette.
const NEUQUANT_SAMPLES: usize = 10_000;

/// One frame of a recording: its number (from 0), how long it shows and its pixels (RGBA, row by row).
pub struct GifFrame {
    /// The frame's place in the GIF.
    pub index: u32,
    /// How long it shows, in centiseconds.
    pub delay_cs: u16,
    /// width × height RGBA pixels.
    pub rgba: Vec<u8>,
}

/// What the writer is told.
enum Message {
    Frame(GifFrame),
    /// The recording has ended with this many frames.
    Finish(u32),
}

/// A GIF written: where, how many frames, its size and the encoder thread's work.
#[derive(Clone, Debug, PartialEq)]
pub struct GifSummary {
    /// The file.
    pub path: PathBuf,
    /// Frames in it.
    pub frames: u32,
    /// Its size in bytes.
    pub bytes: u64,
    /// Time the encoder thread spent quantizing and compressing frames, in seconds.
    pub encode_seconds: f32,
}

impl GifSummary {
    /// `path: N frames, X MB, encoded in Y s`.
    pub fn describe(&self) -> String {
        format!(
            "{}: {} frames, {:.2} MB, encoded in {:.2} s",
            self.path.display(),
            self.frames,
            self.bytes as f64 / 1e6,
            self.encode_seconds
        )
    }
}

/// The thread writing one GIF.
pub struct GifWriter {
    sender: Sender<Message>,
    thread: Option<JoinHandle<Result<GifSummary, String>>>,
}

impl GifWriter {
    /// Creates (truncates) the file now and starts the thread that writes `width` × `height` frames into it. The
    /// error names the file: `<file>: <reason>`.
    pub fn create(path: &Path, width: u16, height: u16) -> Result<Self, String> {
        let named = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
        let file = File::create(path).map_err(|e| named(&e))?;
        let (sender, receiver) = channel();
        let owned = path.to_owned();
        let thread = std::thread::Builder::new()
            .name("gif writer".into())
            .spawn(move || {
                write_gif(file, &owned, width, height, &receiver).map_err(|e| format!("{}: {e}", owned.display()))
            })
            .map_err(|e| named(&e))?;
        Ok(Self { sender, thread: Some(thread) })
    }

    /// A sender for frames, for the screenshot observers that deliver them.
    pub fn frames(&self) -> FrameSender {
        FrameSender(self.sender.clone())
    }

    /// The recording has ended with `frames` frames: the thread writes those still to come and closes the file.
    pub fn finish(&self, frames: u32) {
        // A send fails only when the thread has already stopped; `poll` then reports why.
        let _ = self.sender.send(Message::Finish(frames));
    }

    /// The outcome, once the thread has stopped.
    pub fn poll(&mut self) -> Option<Result<GifSummary, String>> {
        if !self.thread.as_ref()?.is_finished() {
            return None;
        }
        let thread = self.thread.take()?;
        Some(thread.join().unwrap_or_else(|_| Err("the GIF writer stopped unexpectedly".to_owned())))
    }
}

/// Hands frames to a [`GifWriter`].
#[derive(Clone)]
pub struct FrameSender(Sender<Message>);

impl FrameSender {
    /// Queues a frame (dropped when the writer has stopped: it reports why).
    pub fn send(&self, frame: GifFrame) {
        let _ = self.0.send(Message::Frame(frame));
    }
}

/// The writer thread: frames in order as they arrive, until the announced count is written.
fn write_gif(
    file: File,
    path: &Path,
    width: u16,
    height: u16,
    receiver: &Receiver<Message>,
) -> Result<GifSummary, String> {
    let gif_error = |e: gif::EncodingError| e.to_string();
    let mut encoder = gif::Encoder::new(BufWriter::new(file), width, height, &[]).map_err(gif_error)?;
    encoder.set_repeat(gif::Repeat::Infinite).map_err(gif_error)?;
    let mut pending = BTreeMap::new();
    let mut previous: Option<Vec<u8>> = None;
    let (mut written, mut expected) = (0u32, None);
    let mut busy = Duration::ZERO;
    while expected != Some(written) {
        let message = match expected {
            None => receiver.recv().map_err(|_| "the recording was abandoned".to_owned())?,
            Some(_) => receiver.recv_timeout(MISSING_FRAME_TIMEOUT).map_err(|e| match e {
                RecvTimeoutError::Timeout => format!("frame {written} was never captured"),
                RecvTimeoutError::Disconnected => "the recording was abandoned".to_owned(),
            })?,
        };
        match message {
            Message::Frame(frame) if frame.rgba.len() != usize::from(width) * usize::from(height) * 4 => {
                return Err(format!("frame {} was captured at another size", frame.index));
            }
            Message::Frame(frame) => {
                pending.insert(frame.index, frame);
            }
            Message::Finish(frames) => expected = Some(frames),
        }
        while let Some(frame) = pending.remove(&written) {
            let start = Instant::now();
            let encoded = changed_pixels(&frame.rgba, previous.as_deref(), width, height, frame.delay_cs);
            encoder.write_frame(&encoded).map_err(gif_error)?;
            busy += start.elapsed();
            previous = Some(frame.rgba);
            written += 1;
        }
    }
    let mut out = encoder.into_inner().map_err(gif_error)?;
    out.flush().map_err(|e| e.to_string())?;
    let bytes = out.get_ref().metadata().map_err(|e| e.to_string())?.len();
    Ok(GifSummary { path: path.to_owned(), frames: written, bytes, encode_seconds: busy.as_secs_f32() })
}

/// The GIF frame that turns `previous` (none for the first frame) into `rgba`: the rectangle of the pixels that
/// changed, those quantized and the others transparent. A frame without a change is one transparent pixel.
fn changed_pixels(rgba: &[u8], previous: Option<&[u8]>, width: u16, height: u16, delay: u16) -> gif::Frame<'static> {
    let w = usize::from(width);
    let changed = |i: usize| previous.is_none_or(|p| p[i * 4..i * 4 + 3] != rgba[i * 4..i * 4 + 3]);
    let (mut lo, mut hi) = ([usize::MAX; 2], [0usize; 2]);
    for i in (0..w * usize::from(height)).filter(|&i| changed(i)) {
        let (x, y) = (i % w, i / w);
        lo = [lo[0].min(x), lo[1].min(y)];
        hi = [hi[0].max(x), hi[1].max(y)];
    }
    let still = gif::Frame {
        delay,
        width: 1,
        height: 1,
        transparent: Some(0),
        palette: Some(vec![0; 3]),
        buffer: vec![0].into(),
        ..gif::Frame::default()
    };
    if lo[0] == usize::MAX {
        return still;
    }
    let rect: Vec<usize> = (lo[1]..=hi[1]).flat_map(|y| (lo[0]..=hi[0]).map(move |x| y * w + x)).collect();
    let rgb = |i: usize| [rgba[i * 4], rgba[i * 4 + 1], rgba[i * 4 + 2]];
    let colours: Vec<[u8; 3]> = rect.iter().filter(|&&i| changed(i)).map(|&i| rgb(i)).collect();
    let Palette { mut table, entries } = Palette::of(&colours);
    let buffer = rect.iter().map(|&i| if changed(i) { entries[&rgb(i)] } else { TRANSPARENT }).collect();
    table.resize(256 * 3, 0);
    gif::Frame {
        delay,
        // Keep: the next frame's transparent pixels show this one.
        dispose: gif::DisposalMethod::Keep,
        transparent: Some(TRANSPARENT),
        left: lo[0] as u16,
        top: lo[1] as u16,
        width: (hi[0] - lo[0] + 1) as u16,
        height: (hi[1] - lo[1] + 1) as u16,
        palette: Some(table),
        buffer,
        ..gif::Frame::default()
    }
}

/// A frame's colour table (at most 255 entries) and the entry of every colour of its changed pixels.
struct Palette {
    /// `[r, g, b, …]` in entry order.
    table: Vec<u8>,
    entries: HashMap<[u8; 3], u8>,
}

impl Palette {
    /// Every colour exactly when there are at most 255, else NeuQuant's 255 (each distinct colour looked up
    /// once: flat-shaded voxel faces repeat colours).
    fn of(colours: &[[u8; 3]]) -> Self {
        let mut entries: HashMap<[u8; 3], usize> = HashMap::new();
        for &c in colours {
            let next = entries.len();
            entries.entry(c).or_insert(next);
        }
        let limit = usize::from(TRANSPARENT);
        let table = if entries.len() <= limit {
            let mut table = vec![0; entries.len() * 3];
            for (c, &i) in &entries {
                table[i * 3..i * 3 + 3].copy_from_slice(c);
            }
            table
        } else {
            let rgba: Vec<u8> = colours.iter().flat_map(|c| [c[0], c[1], c[2], 255]).collect();
            let samplefac = (colours.len() / NEUQUANT_SAMPLES).clamp(1, 30) as i32;
            let quant = NeuQuant::new(samplefac, limit, &rgba);
            for (c, i) in &mut entries {
                *i = quant.index_of(&[c[0], c[1], c[2], 255]);
            }
            quant.color_map_rgb()
        };
        Self { table, entries: entries.into_iter().map(|(c, i)| (c, i as u8)).collect() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `w` × `h` frame: a vertical gradient with a red square of side 8 whose corner is at `square`.
    fn frame(w: usize, h: usize, square: [usize; 2]) -> Vec<u8> {
        let mut rgba = Vec::with_capacity(w * h * 4);
        for y in 0..h {
            for x in 0..w {
                let inside = (square[0]..square[0] + 8).contains(&x) && (square[1]..square[1] + 8).contains(&y);
                let p = if inside { [220, 40, 40, 255] } else { [250 - (y * 80 / h) as u8, 200, 220, 255] };
                rgba.extend_from_slice(&p);
            }
        }
        rgba
    }

    /// Decodes a GIF into its composed frames (RGBA) and their delays.
    fn decode(path: &Path) -> (u16, u16, Vec<(Vec<u8>, u16)>) {
        let mut options = gif::DecodeOptions::new();
        options.set_color_output(gif::ColorOutput::RGBA);
        let mut decoder = options.read_info(File::open(path).unwrap()).unwrap();
        let (w, h) = (decoder.width(), decoder.height());
        let mut canvas = vec![0u8; usize::from(w) * usize::from(h) * 4];
        let mut frames = Vec::new();
        while let Some(f) = decoder.read_next_frame().unwrap() {
            for y in 0..usize::from(f.height) {
                for x in 0..usize::from(f.width) {
                    let src = &f.buffer[(y * usize::from(f.width) + x) * 4..][..4];
                    if src[3] != 0 {
                        let at = ((y + usize::from(f.top)) * usize::from(w) + x + usize::from(f.left)) * 4;
                        canvas[at..at + 4].copy_from_slice(src);
                    }
                }
            }
            frames.push((canvas.clone(), f.delay));
        }
        (w, h, frames)
    }

    #[test]
    fn frames_sent_out_of_order_decode_back_in_order_with_their_delays_and_pixels() {
        let dir = std::env::temp_dir().join(format!("voxel-art-gif-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("square.gif");
        let (w, h) = (64, 40);
        let mut writer = GifWriter::create(&path, w as u16, h as u16).unwrap();
        let squares = [[4, 4], [12, 6], [12, 6], [30, 20]];
        let frames = writer.frames();
        for index in [2u32, 0, 3, 1] {
            let rgba = frame(w, h, squares[index as usize]);
            frames.send(GifFrame { index, delay_cs: [3, 3, 4, 3][index as usize], rgba });
        }
        writer.finish(4);
        let summary = loop {
            if let Some(result) = writer.poll() {
                break result.unwrap();
            }
            std::thread::sleep(Duration::from_millis(5));
        };
        assert_eq!((summary.frames, summary.bytes), (4, std::fs::metadata(&path).unwrap().len()));
        let (dw, dh, decoded) = decode(&path);
        assert_eq!((usize::from(dw), usize::from(dh), decoded.len()), (w, h, 4));
        assert_eq!(decoded.iter().map(|(_, d)| *d).collect::<Vec<_>>(), [3, 3, 4, 3]);
        for (k, (pixels, _)) in decoded.iter().enumerate() {
            // Fewer than 256 colours: every pixel exact, the square where it was drawn.
            assert_eq!(pixels, &frame(w, h, squares[k]), "frame {k}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn many_colours_are_quantized_close_and_a_still_frame_is_one_transparent_pixel() {
        let (w, h) = (48u16, 48u16);
        let rgba: Vec<u8> =
            (0..48 * 48).flat_map(|i: u32| [(i % 48 * 5) as u8, (i / 48 * 5) as u8, 128, 255]).collect();
        let first = changed_pixels(&rgba, None, w, h, 3);
        assert_eq!((first.width, first.height, first.transparent), (48, 48, Some(TRANSPARENT)));
        let table = first.palette.as_ref().unwrap();
        let errors: Vec<u32> = (0..48 * 48)
            .map(|i| {
                let at = usize::from(first.buffer[i]) * 3;
                (0..3).map(|c| i32::from(table[at + c]).abs_diff(i32::from(rgba[i * 4 + c]))).max().unwrap()
            })
            .collect();
        // 2,304 colours 5 apart in red and green share 255 entries: about one per 15 × 15 square of them.
        let worst = errors.iter().max().unwrap();
        let mean = errors.iter().sum::<u32>() as f32 / errors.len() as f32;
        assert!(*worst <= 40 && mean < 12.0, "worst channel error {worst}, mean {mean}");
        assert!(first.buffer.iter().all(|&i| i != TRANSPARENT), "the first frame has no transparent pixel");
        let still = changed_pixels(&rgba, Some(&rgba), w, h, 4);
        assert_eq!((still.width, still.height, still.transparent, still.delay), (1, 1, Some(0), 4));
    }

    #[test]
    fn a_file_that_cannot_be_created_is_named_in_the_error() {
        let missing = std::env::temp_dir().join("voxel-art-no-such-dir").join("sub").join("x.gif");
        let err = GifWriter::create(&missing, 8, 8).err().unwrap();
        assert!(err.starts_with(&format!("{}: ", missing.display())), "{err}");
    }
}
