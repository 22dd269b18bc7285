//! Renders the real app headless (Xvfb + Mesa's lavapipe Vulkan) and checks the screenshot's pixels.

use std::path::Path;
use std::process::Command;

use crate::common::scratch_dir;

fn hsl(rgb: [u8; 3]) -> [f32; 3] {
    voxel_core::color::rgb_to_hsl(rgb.map(|c| f32::from(c) / 255.0))
}

fn luminance(p: [u8; 3]) -> f32 {
    0.2126 * f32::from(p[0]) + 0.7152 * f32::from(p[1]) + 0.0722 * f32::from(p[2])
}

/// Mean colour of a 9×9 block around a logical point.
fn sample(img: &image::RgbaImage, at: [f32; 2]) -> [u8; 3] {
    let (cx, cy) = (at[0] as i64, at[1] as i64);
    let mut sum = [0u64; 3];
    let mut n = 0;
    for y in cy - 4..=cy + 4 {
        for x in cx - 4..=cx + 4 {
            if x >= 0 && y >= 0 && (x as u32) < img.width() && (y as u32) < img.height() {
                let p = img.get_pixel(x as u32, y as u32);
                for c in 0..3 {
                    sum[c] += u64::from(p[c]);
                }
                n += 1;
            }
        }
    }
    sum.map(|s| (s / n.max(1)) as u8)
}

/// Runs `voxel-art ARGS` under Xvfb with lavapipe; `None` when Xvfb is not installed (a failure under `CI=true`).
fn run_app(args: &[&std::ffi::OsStr]) -> Option<std::process::Output> {
    if Command::new("xvfb-run").arg("--help").output().is_err() {
        assert!(std::env::var("CI").as_deref() != Ok("true"), "xvfb-run is not installed (CI=true: it is required)");
        println!("skipped: xvfb-run is not installed (apt-get install xvfb xauth mesa-vulkan-drivers)");
        return None;
    }
    let runtime = scratch_dir("xdg");
    let output = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1280x720x24", env!("CARGO_BIN_EXE_voxel-art")])
        .args(args)
        .env("VK_ICD_FILENAMES", "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json")
        .env("WGPU_BACKEND", "vulkan")
        .env("XDG_RUNTIME_DIR", runtime)
        .output()
        .unwrap();
    Some(output)
}

/// Runs `voxel-art --screenshot OUT --frames N`.
fn screenshot(out: &Path, frames: u32) -> Option<std::process::Output> {
    run_app(&["--screenshot".as_ref(), out.as_os_str(), "--frames".as_ref(), frames.to_string().as_ref()])
}

/// Runs the app where it must fail: a non-zero status and `reason` in what it printed.
fn assert_run_fails(args: &[&std::ffi::OsStr], reason: &str) {
    let Some(run) = run_app(args) else { return };
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success(), "exit status {} for {args:?}", run.status);
    assert!(stderr.contains(reason), "no '{reason}' in:\n{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn a_screenshot_that_cannot_be_taken_or_written_exits_with_the_reason() {
    let dir = scratch_dir("screenshot-errors");
    let junk = dir.join("junk.glb");
    std::fs::write(&junk, b"not a model").unwrap();
    let out = dir.join("out.png");
    let only_junk = ["--no-shipped".as_ref(), junk.as_os_str(), "--screenshot".as_ref(), out.as_os_str()];
    assert_run_fails(&only_junk, "no model could be shown");
    let then = ["--screenshot".as_ref(), out.as_os_str(), "--then".as_ref(), "99".as_ref()];
    assert_run_fails(&then, "--then 99");
    let unwritable = dir.join("junk.glb").join("out.png");
    let args = ["--screenshot".as_ref(), unwritable.as_os_str(), "--frames".as_ref(), "1".as_ref()];
    assert_run_fails(&args, "cannot write");
    assert!(!out.exists());
}

#[test]
fn the_app_renders_pastel_voxels_on_a_lit_stage() {
    let dir = scratch_dir("render");
    let out = dir.join("stage.png");
    let Some(run) = screenshot(&out, 30) else { return };
    assert_lit_model(&run, &out, 2_000);
}

/// A fine grid (0.04: about 190 cells along the apple's diagonal, tens of thousands of voxels) drawn by the
/// instanced chunks, in the main pass and in the light's shadow map, at the low detail their size on screen asks for.
#[test]
fn a_fine_grid_renders_with_its_shadow() {
    let dir = scratch_dir("render-fine");
    let out = dir.join("fine.png");
    let args = [
        "--screenshot".as_ref(),
        out.as_os_str(),
        "--frames".as_ref(),
        "2".as_ref(),
        "--grid-size".as_ref(),
        "0.04".as_ref(),
    ];
    let Some(run) = run_app(&args) else { return };
    assert_lit_model(&run, &out, 10_000);
}

/// The screenshot `out` of a successful `run`: at least `model_pixels` pixels of the model's colour, the
/// background's gradient and the model's shadow on the floor.
fn assert_lit_model(run: &std::process::Output, out: &Path, model_pixels: usize) {
    assert!(run.status.success(), "app failed: {}\n{}", run.status, String::from_utf8_lossy(&run.stderr));
    let img = image::open(out).expect("screenshot written").to_rgba8();
    assert_eq!((img.width(), img.height()), (1280, 720));
    let probe_path = out.with_file_name(format!("{}.json", out.file_name().unwrap().to_string_lossy()));
    let probe: serde_json::Value = serde_json::from_slice(&std::fs::read(probe_path).unwrap()).unwrap();
    let point = |key: &str| -> [f32; 2] {
        let v = &probe[key];
        [v[0].as_f64().unwrap_or_else(|| panic!("{key} not on screen: {probe}")) as f32, v[1].as_f64().unwrap() as f32]
    };

    // The first model's voxel colour is on screen: many pixels share its hue, saturated.
    let model = probe["model_color"].as_array().expect("model colour");
    let model_rgb = [0, 1, 2].map(|i| model[i].as_u64().unwrap() as u8);
    let [h, s, _] = hsl(model_rgb);
    assert!(s > 0.2, "model colour {model_rgb:?} is too grey to recognise");
    let matching = img
        .pixels()
        .filter(|p| {
            let [ph, ps, pl] = hsl([p[0], p[1], p[2]]);
            let dh = (ph - h).abs().min(1.0 - (ph - h).abs());
            dh < 0.04 && ps > s * 0.5 && pl > 0.15 && pl < 0.95
        })
        .count();
    assert!(matching > model_pixels, "only {matching} pixels of the model's hue {h:.3}");

    // The background is a gradient: pinker at the top, more lilac lower down.
    let top = sample(&img, point("background_top"));
    let low = sample(&img, point("background_low"));
    let pink = |p: [u8; 3]| i32::from(p[0]) - i32::from(p[2]);
    assert!(pink(top) > pink(low) + 8, "no gradient: top {top:?}, low {low:?}");
    assert!(luminance(top) > 150.0 && luminance(low) > 150.0, "background too dark: {top:?} {low:?}");

    // The floor under the model (its shadow) is darker than the floor far from it.
    let shadow = sample(&img, point("shadow"));
    let far = sample(&img, point("floor_far"));
    assert!(luminance(shadow) + 20.0 < luminance(far), "no shadow: under {shadow:?}, far {far:?}");
}

/// A decoded GIF: its size and every frame as shown (each composed over the ones before) with its delay.
struct Gif {
    width: u32,
    height: u32,
    frames: Vec<(image::RgbaImage, u16)>,
}

fn decode_gif(path: &Path) -> Gif {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options.read_info(std::fs::File::open(path).expect("GIF written")).unwrap();
    let (width, height) = (u32::from(decoder.width()), u32::from(decoder.height()));
    let mut canvas = image::RgbaImage::new(width, height);
    let mut frames = Vec::new();
    while let Some(frame) = decoder.read_next_frame().unwrap() {
        let (w, left, top) = (u32::from(frame.width), u32::from(frame.left), u32::from(frame.top));
        for (i, p) in frame.buffer.chunks_exact(4).enumerate() {
            if p[3] != 0 {
                let (x, y) = (left + i as u32 % w, top + i as u32 / w);
                canvas.put_pixel(x, y, image::Rgba([p[0], p[1], p[2], 255]));
            }
        }
        frames.push((canvas.clone(), frame.delay));
    }
    Gif { width, height, frames }
}

/// Pixels of `img` whose hue is within 0.05 of `hue`, saturated and neither dark nor near white.
fn pixels_of_hue(img: &image::RgbaImage, hue: f32) -> usize {
    img.pixels()
        .filter(|p| {
            let [h, s, l] = hsl([p[0], p[1], p[2]]);
            let dh = (h - hue).abs().min(1.0 - (h - hue).abs());
            dh < 0.05 && s > 0.25 && l > 0.2 && l < 0.85
        })
        .count()
}

/// The record of a morph: the stage alone (the gradient backdrop edge to edge, no panel, no tiles), the apple's
/// red voxels in the first frame, the avocado's green ones at the end. At 192×108 the apple covers about 1,100
/// red pixels and the avocado about 600 green ones (the apple's leaf: about 150).
#[test]
fn the_app_records_a_morph_of_the_stage_as_a_gif() {
    let dir = scratch_dir("record");
    let out = dir.join("morph.gif");
    // The apple settles, then 0.6 s of the morph to the avocado are recorded.
    let args = ["--record", out.to_str().unwrap(), "--seconds", "0.6", "--record-size", "192x108", "--then", "1"];
    let Some(run) = run_app(&args.map(std::ffi::OsStr::new)) else { return };
    assert!(run.status.success(), "app failed: {}\n{}", run.status, String::from_utf8_lossy(&run.stderr));
    let gif = decode_gif(&out);
    assert_eq!((gif.width, gif.height, gif.frames.len()), (192, 108, 18));
    let delays: Vec<u16> = gif.frames.iter().map(|(_, d)| *d).collect();
    assert_eq!(&delays[..6], &[3, 3, 4, 3, 3, 4]);
    assert_eq!(delays.iter().map(|&d| u32::from(d)).sum::<u32>(), 60, "0.6 s of GIF");
    // The stage alone in every frame: the backdrop at the left and right edges, top to bottom (the panel and
    // the tiles would be dark or another colour there), pinker at the top than lower down.
    for (k, (frame, _)) in gif.frames.iter().enumerate() {
        for x in [4.0, 187.0] {
            let (top, low) = (sample(frame, [x, 4.0]), sample(frame, [x, 30.0]));
            let pink = |p: [u8; 3]| i32::from(p[0]) - i32::from(p[2]);
            assert!(pink(top) > pink(low) + 4, "frame {k}: no gradient at x = {x}: top {top:?}, low {low:?}");
            for y in [4.0, 30.0, 54.0, 78.0, 103.0] {
                let p = sample(frame, [x, y]);
                assert!(luminance(p) > 150.0, "frame {k}: not the backdrop at ({x}, {y}): {p:?}");
            }
        }
    }
    // The morph: the apple's red voxels at its start, the avocado's green ones at the end.
    let (first, last) = (&gif.frames[0].0, &gif.frames[17].0);
    let (red, green) = (0.0, 0.25);
    let [first_red, first_green] = [red, green].map(|hue| pixels_of_hue(first, hue));
    let [last_red, last_green] = [red, green].map(|hue| pixels_of_hue(last, hue));
    assert!(first_red > 500, "{first_red} red pixels at the start");
    assert!(last_green > 300, "{last_green} green pixels at the end");
    assert!(last_red * 4 < first_red, "the apple's red is not gone: {first_red} → {last_red}");
    assert!(first_green * 2 < last_green, "the avocado's green did not come: {first_green} → {last_green}");
}

#[test]
fn a_record_to_an_unwritable_path_exits_with_the_file_and_reason() {
    let dir = scratch_dir("record-errors");
    std::fs::write(dir.join("file"), b"not a folder").unwrap();
    let out = dir.join("file").join("out.gif");
    let args = ["--record".as_ref(), out.as_os_str(), "--seconds".as_ref(), "0.1".as_ref()];
    assert_run_fails(&args, &format!("error: {}: ", out.display()));
}
