//! One animated glTF of a clip's voxel frames (`--animation CLIP --out FILE.glb`): re-imported and posed at
//! each frame's time, it shows that frame's cells.
#![cfg(feature = "cli")]

use std::path::Path;

use serde_json::Value;
use voxel_core::cli::animation::{ClipRequest, voxelize_clip};
use voxel_core::export::Format;
use voxel_core::palette::ColorStage;
use voxel_core::{GridSize, ShellMode, TriangleSoup, VoxelizeOptions, load_animated_file, voxelize_within};

use crate::animation::{morph_cube, temp_model};
use crate::common::{cells, model};

/// Writes `clip` of `file` (at `fps`, `duration` seconds) as the animated file `out`; returns the JSON lines.
fn write_animated(file: &Path, out: &Path, clip: &str, fps: f32, duration: Option<f32>, r: u32) -> Vec<Value> {
    let options = VoxelizeOptions { grid: GridSize::Resolution(r), ..Default::default() };
    let colors = ColorStage::default();
    let request = ClipRequest {
        animation: clip,
        fps,
        duration,
        out: Some(out),
        format: Format::Vox,
        json: true,
        colors: &colors,
    };
    let lines = voxelize_clip(file, &request, &options).unwrap();
    lines.iter().map(|l| serde_json::from_str(l).unwrap()).collect()
}

/// Checks that the animated export `out` of `clip` of `file`, posed at each frame's time, holds the cells of
/// that frame of the source (both voxelized in the grid of the source clip's bounds).
fn assert_frames_round_trip(file: &Path, out: &Path, clip: usize, times: &[f32], r: u32) {
    let options = VoxelizeOptions { grid: GridSize::Resolution(r), ..Default::default() };
    let mut source = load_animated_file(file).unwrap();
    let bounds = source.clip_bounds(clip).unwrap();
    let mut exported = load_animated_file(out).unwrap();
    assert_eq!(exported.clips().len(), 1);
    // The export's faces lie on cell boundaries: its fill alone gives the cells.
    let again = VoxelizeOptions { shell: ShellMode::None, ..options };
    let (mut posed, mut played) = (TriangleSoup::default(), TriangleSoup::default());
    for (k, &t) in times.iter().enumerate() {
        source.pose_into(clip, t, &mut posed).unwrap();
        let want = voxelize_within(&posed, &options, bounds).unwrap();
        exported.pose_into(0, t, &mut played).unwrap();
        let got = voxelize_within(&played, &again, bounds).unwrap();
        assert!(!want.is_empty());
        assert_eq!(cells(&got), cells(&want), "frame {k} at {t} s");
    }
}

#[test]
fn a_clip_as_one_glb_plays_each_frames_cells() {
    let dir = temp_model("slide.glb", &morph_cube(None));
    let file = dir.join("slide.glb");
    let out = dir.join("slide-voxels.glb");
    // 2 s at 4 frames per second: 8 frames, the cube sliding and then doubling its width.
    let lines = write_animated(&file, &out, "0", 4.0, None, 24);
    assert_eq!(lines.len(), 9, "a line per frame, then the file's");
    assert!(lines[..8].iter().all(|l| l.get("gltf").is_none()));
    let summary = &lines[8];
    assert_eq!(summary["gltf"], out.display().to_string());
    assert_eq!((summary["frames"].as_u64(), summary["clip"].as_str()), (Some(8), Some("animation 0")));
    assert_eq!(summary["mesh"]["bytes"], std::fs::metadata(&out).unwrap().len());
    assert_eq!(summary["mesh"]["quads"], 8 * 6, "a box of one colour is six rectangles a frame");
    let gltf = gltf::Gltf::open(&out).unwrap();
    assert_eq!((gltf.nodes().count(), gltf.meshes().count(), gltf.materials().count()), (9, 8, 1));
    let animation = gltf.animations().next().unwrap();
    assert_eq!(animation.channels().count(), 8);
    assert!(animation.samplers().all(|s| s.interpolation() == gltf::animation::Interpolation::Step));
    let times: Vec<f32> = (0..8).map(|k| k as f32 / 4.0).collect();
    assert_frames_round_trip(&file, &out, 0, &times, 24);
    // The clip loops after its 2 s: the last key repeats the first frame.
    let exported = load_animated_file(&out).unwrap();
    assert_eq!(exported.clips()[0].duration, 2.0);
    // A .gltf path writes the same animation as JSON beside a .bin.
    let json = dir.join("slide-voxels.gltf");
    let lines = write_animated(&file, &json, "0", 4.0, Some(1.0), 24);
    assert_eq!(lines.len(), 5);
    assert!(dir.join("slide-voxels.bin").is_file());
    assert_frames_round_trip(&file, &json, 0, &[0.0, 0.25, 0.5, 0.75], 24);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_fox_running_as_one_glb_plays_each_frames_cells() {
    let Some(fox) = model("khronos-fox.glb") else { return };
    let dir = temp_model("fox.glb", &std::fs::read(&fox).unwrap());
    let out = dir.join("fox-run.glb");
    let lines = write_animated(&dir.join("fox.glb"), &out, "Run", 8.0, Some(0.5), 32);
    assert_eq!(lines.len(), 5);
    let clip = load_animated_file(&fox).unwrap().find_clip("Run").unwrap();
    assert_frames_round_trip(&fox, &out, clip, &[0.0, 0.125, 0.25, 0.375], 32);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn several_models_cannot_share_one_animated_file() {
    let dir = temp_model("a.glb", &morph_cube(None));
    std::fs::write(dir.join("b.glb"), morph_cube(None)).unwrap();
    let out = dir.join("both.glb");
    let args = ["voxel-art voxelize", "a.glb", "b.glb", "--animation", "0", "--out", "both.glb"];
    let args = args.map(|a| if a.ends_with(".glb") { dir.join(a).into_os_string() } else { a.into() });
    assert_eq!(voxel_core::cli::run(args), 1);
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
