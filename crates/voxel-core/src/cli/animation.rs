//! `voxel-art voxelize FILE --animation <name|index|list> [--fps 12] [--duration S] [--out DIR [--format
//! vox|glb|gltf] | --out FILE.glb|FILE.gltf] [--json]`: voxelizes a clip frame by frame in one grid fitted to
//! all its poses (one file per frame in DIR, or one animated glTF that plays the frames), or lists the clips.

use std::path::Path;
use std::time::Instant;

use super::report::{Exported, stem, to_json};
use crate::anim::AnimatedModel;
use crate::error::{Result, VoxelError};
use crate::export::animated::AnimatedGltf;
use crate::export::{self, ExportOptions, Format, Written};
use crate::options::VoxelizeOptions;
use crate::palette::ColorStage;
use crate::soup::TriangleSoup;
use crate::voxelize::voxelize_within;

/// The most frames one command voxelizes (a guard against `--fps 1e9`).
pub const MAX_FRAMES: usize = 100_000;

/// What `--animation` and its companion flags ask for.
#[derive(Clone, Copy, Debug)]
pub struct ClipRequest<'a> {
    /// A clip name, a clip index, or `list`.
    pub animation: &'a str,
    /// Frames per second.
    pub fps: f32,
    /// Seconds to voxelize; one clip length when `None`.
    pub duration: Option<f32>,
    /// A folder for `<stem>-<frame>.<format>` files, or one animated `.glb` / `.gltf` file.
    pub out: Option<&'a Path>,
    /// The format of the frames' files.
    pub format: Format,
    /// One JSON object per line instead of readable lines.
    pub json: bool,
    /// The colour stage applied to every frame (with the first frame's chosen colours).
    pub colors: &'a ColorStage,
}

/// One frame's JSON line.
#[derive(serde::Serialize)]
struct FrameReport<'a> {
    file: &'a str,
    clip: &'a str,
    frame: usize,
    time: f32,
    grid: [u32; 3],
    voxels: usize,
    visible: usize,
    pose_ms: f64,
    voxelize_ms: f64,
    #[serde(flatten)]
    exported: Exported,
}

/// The JSON line of a clip written as one animated glTF, after its frames' lines.
#[derive(serde::Serialize)]
struct AnimationReport<'a> {
    file: &'a str,
    clip: &'a str,
    frames: usize,
    #[serde(flatten)]
    exported: Exported,
}

/// One clip's JSON line for `--animation list`.
#[derive(serde::Serialize)]
struct ClipReport<'a> {
    file: &'a str,
    index: usize,
    clip: &'a str,
    duration: f32,
    channels: usize,
}

/// Runs the request on `file` and returns the lines to print: one per clip for `list`, else one per frame.
pub fn voxelize_clip(file: &Path, request: &ClipRequest<'_>, options: &VoxelizeOptions) -> Result<Vec<String>> {
    let mut model = crate::import::load_animated_file(file)?;
    let name = file.display().to_string();
    if model.clips().is_empty() {
        return Err(VoxelError::Parameter("the model has no animations".into()));
    }
    if request.animation == "list" {
        return list_clips(&model, &name, request.json);
    }
    let clip = model.find_clip(request.animation).ok_or_else(|| {
        let names: Vec<String> = model.clips().iter().enumerate().map(|(i, c)| format!("{i}: {}", c.name)).collect();
        VoxelError::Parameter(format!("no animation {:?} (the model has {})", request.animation, names.join(", ")))
    })?;
    let info = model.clips()[clip].clone();
    let frames = frame_count(request.fps, request.duration.unwrap_or(info.duration))?;
    // An output path ending in .glb or .gltf is one animated file, anything else a folder of frames.
    let single = request.out.filter(|out| Format::of_path(out) != Format::Vox);
    let folder = request.out.filter(|_| single.is_none());
    if let Some(out) = folder {
        std::fs::create_dir_all(out).map_err(|e| VoxelError::Export { path: out.to_owned(), reason: e.to_string() })?;
    }
    let stem = stem(file);
    let mut animated = single.map(|_| AnimatedGltf::new(&ExportOptions { name: stem.clone() }));
    let bounds = model.clip_bounds(clip)?;
    let mut soup = TriangleSoup::default();
    let mut lines = Vec::with_capacity(frames);
    // The colours chosen for the first frame serve every frame.
    let mut frame_colors = request.colors.for_frames();
    for frame in 0..frames {
        let time = frame as f32 / request.fps;
        let t0 = Instant::now();
        model.pose_into(clip, time, &mut soup)?;
        let t1 = Instant::now();
        let mut voxels = voxelize_within(&soup, options, bounds)?;
        frame_colors.apply(&mut voxels)?;
        let voxelize_ms = t1.elapsed().as_secs_f64() * 1e3;
        let pose_ms = (t1 - t0).as_secs_f64() * 1e3;
        if let Some(animated) = &mut animated {
            animated.push_frame(&voxels, time)?;
        }
        let exported = match folder {
            Some(out) => {
                let path = out.join(format!("{stem}-{frame:04}.{}", request.format.extension()));
                let options = ExportOptions { name: format!("{stem}-{frame:04}") };
                Exported::new(&path, export::write(&voxels, &path, request.format, &options)?)
            }
            None => Exported::default(),
        };
        let s = voxels.stats;
        lines.push(if request.json {
            to_json(&FrameReport {
                file: &name,
                clip: &info.name,
                frame,
                time,
                grid: s.grid,
                voxels: s.voxels,
                visible: s.visible,
                pose_ms,
                voxelize_ms,
                exported,
            })?
        } else {
            format!(
                "{name} [{}] frame {frame} t={time:.3} s: {} voxels ({} visible); pose {pose_ms:.2} ms, voxelize {voxelize_ms:.1} ms{}",
                info.name,
                s.voxels,
                s.visible,
                exported.summary()
            )
        });
    }
    if let (Some(animated), Some(path)) = (animated, single) {
        let duration = frames as f32 / request.fps;
        let written = Written::Mesh(animated.write(path, Format::of_path(path), &info.name, duration)?);
        let exported = Exported::new(path, written);
        lines.push(if request.json {
            to_json(&AnimationReport { file: &name, clip: &info.name, frames, exported })?
        } else {
            format!("{name} [{}]: {frames} frames as one animation{}", info.name, exported.summary())
        });
    }
    Ok(lines)
}

/// The frames of `duration` seconds at `fps`: frame k at k / fps, the end excluded (it is the next loop's
/// start), at least one.
fn frame_count(fps: f32, duration: f32) -> Result<usize> {
    if !(fps.is_finite() && fps > 0.0) {
        return Err(VoxelError::Parameter(format!("--fps must be positive, got {fps}")));
    }
    if !(duration.is_finite() && duration >= 0.0) {
        return Err(VoxelError::Parameter(format!("--duration must be zero or more seconds, got {duration}")));
    }
    let frames = (f64::from(duration) * f64::from(fps) - 1e-6).ceil().max(1.0);
    if frames > MAX_FRAMES as f64 {
        return Err(VoxelError::Parameter(format!("{frames} frames is over the limit of {MAX_FRAMES}")));
    }
    Ok(frames as usize)
}

fn list_clips(model: &AnimatedModel, name: &str, json: bool) -> Result<Vec<String>> {
    model
        .clips()
        .iter()
        .enumerate()
        .map(|(index, c)| {
            if json {
                to_json(&ClipReport { file: name, index, clip: &c.name, duration: c.duration, channels: c.channels })
            } else {
                Ok(format!("{name}: clip {index} {:?}: {:.3} s, {} channels", c.name, c.duration, c.channels))
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_cover_the_duration_without_its_end() {
        assert_eq!(frame_count(12.0, 1.0).unwrap(), 12);
        assert_eq!(frame_count(12.0, 1.05).unwrap(), 13);
        assert_eq!(frame_count(30.0, 0.0).unwrap(), 1);
        assert!(frame_count(0.0, 1.0).unwrap_err().to_string().contains("--fps must be positive"));
        assert!(frame_count(12.0, -1.0).unwrap_err().to_string().contains("--duration"));
        assert!(frame_count(1e9, 1e9).unwrap_err().to_string().contains("over the limit"));
    }
}
