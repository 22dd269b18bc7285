//! `--screenshot out.png --frames N [--then M]`: once the first model has settled, run N more frames (with
//! `--then`, switch to model M first: a frame of the morph), save the window to a PNG and exit (status 0). It
//! exits with status 1, saying why, when the [`Cue`] fails (no model can be shown, `--then` names no model of
//! the list) and when the PNG cannot be written. With
//! several `--anim-time`s, each capture is followed by a jump of the animation to the next time and N more
//! frames, and the PNGs are numbered (`out-0.png`, …). Next to
//! the PNG, `out.png.json`
//! names where the camera projects the points a test checks: the floor under the model (in its shadow), the
//! floor far from it, the background, and the model's most common voxel colour.

use std::path::{Path, PathBuf};

use bevy::prelude::*;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured};

use crate::animation::AnimationRequest;
use crate::camera::MainCamera;
use crate::cue::{Cue, CueParams, CueState};
use crate::instancing::VoxelPool;
use crate::model::VoxelModelAsset;
use crate::schedule::ScreenshotSystems;
use crate::settings::VoxelSettings;
use crate::stage::{Floor, KeyLight};

/// `--screenshot`: what to capture and when.
#[derive(Resource, Clone, Debug)]
pub struct ScreenshotPlugin {
    /// The PNG to write (the probe goes next to it, `.json` appended).
    pub path: PathBuf,
    /// Frames to run once the first model has settled (or, with `then`, from the switch).
    pub frames: u32,
    /// Switch to this model once the first has settled, and capture a frame of the morph.
    pub then: Option<usize>,
    /// Animation times to jump to after the first capture, one capture each (`--anim-time` beyond the first).
    pub seeks: Vec<f32>,
}

impl ScreenshotPlugin {
    /// Where capture `shot` goes: the path itself when there is one capture, else `stem-<shot>.<ext>`.
    fn shot_path(&self, shot: usize) -> PathBuf {
        if self.seeks.is_empty() {
            return self.path.clone();
        }
        let stem = self.path.file_stem().unwrap_or_default().to_string_lossy();
        let ext = self.path.extension().map_or(String::new(), |e| format!(".{}", e.to_string_lossy()));
        self.path.with_file_name(format!("{stem}-{shot}{ext}"))
    }
}

/// How far the capture has got.
#[derive(Default)]
struct Progress {
    cue: Cue,
    frames: u32,
    requested: bool,
    shot: usize,
}

/// Screen points (logical pixels) a screenshot test checks.
#[derive(serde::Serialize, Debug, Default)]
pub struct ScreenshotProbe {
    /// The floor where the model's shadow falls.
    pub shadow: Option<[f32; 2]>,
    /// The floor far from the model.
    pub floor_far: Option<[f32; 2]>,
    /// Background near the top of the window.
    pub background_top: [f32; 2],
    /// Background lower down.
    pub background_low: [f32; 2],
    /// The most common voxel colour of the shown model (sRGB).
    pub model_color: Option<[u8; 3]>,
}

/// Whether the segment from `from` to `to` passes within `radius` of any of `centers`.
fn blocked(from: Vec3, to: Vec3, centers: &[Vec3], radius: f32) -> bool {
    let d = to - from;
    let len2 = d.length_squared().max(1e-12);
    centers.iter().any(|c| {
        let t = ((*c - from).dot(d) / len2).clamp(0.0, 1.0);
        (from + d * t).distance_squared(*c) < radius * radius
    })
}

fn probe(
    camera: &Camera,
    camera_transform: &GlobalTransform,
    light: &GlobalTransform,
    floor_y: f32,
    model: Option<&VoxelModelAsset>,
    hollow: bool,
    window: Vec2,
) -> ScreenshotProbe {
    let on_screen = |p: Vec3| {
        camera
            .world_to_viewport(camera_transform, p)
            .ok()
            .filter(|s| s.x > 300.0 && s.x < window.x - 160.0 && s.y > 10.0 && s.y < window.y - 10.0)
    };
    let eye = camera_transform.translation();
    let (centers, radius) = model.map_or((Vec::new(), 0.0), |m| {
        let cell = Vec3::from(m.spec.cell);
        (m.shown(hollow).map(|v| Vec3::from(m.center(&v))).collect::<Vec<_>>(), cell.max_element() * 0.87)
    });
    // Every voxel centre's shadow on the floor, along the light's direction.
    let dir = light.forward().as_vec3();
    let shadows: Vec<Vec3> =
        if dir.y < -1e-3 { centers.iter().map(|c| *c + dir * ((floor_y - c.y) / dir.y)).collect() } else { Vec::new() };
    let lit_visible = |p: Vec3| !blocked(p + Vec3::Y * 0.01, eye, &centers, radius);
    // The floor point deepest in the shadow (most voxel shadows around it) that the camera sees.
    let shadow = shadows
        .iter()
        .step_by((shadows.len() / 400).max(1))
        .filter(|p| lit_visible(**p))
        .filter_map(|p| on_screen(*p).map(|s| (shadows.iter().filter(|q| q.distance(*p) < 0.5).count(), s)))
        .max_by_key(|(n, _)| *n)
        .map(|(_, s)| s);
    let floor_far = (0..48).map(|k| k as f32 / 48.0 * std::f32::consts::TAU).find_map(|a| {
        let p = Vec3::new(6.5 * a.cos(), floor_y, 6.5 * a.sin());
        let clear = shadows.iter().all(|q| q.distance(p) > 2.0) && lit_visible(p);
        clear.then(|| on_screen(p)).flatten()
    });
    let model_color = model.and_then(|m| {
        let mut counts = std::collections::HashMap::new();
        for v in m.shown(hollow) {
            *counts.entry([v.color[0], v.color[1], v.color[2]]).or_insert(0usize) += 1;
        }
        counts.into_iter().max_by_key(|&(c, n)| (n, c)).map(|(c, _)| c)
    });
    ScreenshotProbe {
        shadow: shadow.map(|s| s.to_array()),
        floor_far: floor_far.map(|s| s.to_array()),
        background_top: [window.x - 200.0, 6.0],
        background_low: [window.x - 200.0, window.y * 0.3],
        model_color,
    }
}

fn sidecar_path(png: &Path) -> PathBuf {
    let mut name = png.as_os_str().to_owned();
    name.push(".json");
    PathBuf::from(name)
}

/// Waits for the cue (the first model settled, or with `then` the morph begun), counts the frames, then writes
/// the probe and captures the window.
fn drive(
    mut commands: Commands,
    request: Res<ScreenshotPlugin>,
    pool: Res<VoxelPool>,
    models: Res<Assets<VoxelModelAsset>>,
    settings: Res<VoxelSettings>,
    camera: Query<(&Camera, &GlobalTransform), With<MainCamera>>,
    light: Query<&GlobalTransform, With<KeyLight>>,
    floor: Query<&GlobalTransform, With<Floor>>,
    window: Query<&Window>,
    mut cue: CueParams,
    mut seek: MessageWriter<AnimationRequest>,
    mut progress: Local<Progress>,
    mut exit: MessageWriter<AppExit>,
) {
    if progress.requested {
        return;
    }
    match progress.cue.poll(&mut cue, request.then) {
        CueState::Waiting => return,
        CueState::Ready => {}
        CueState::Failed(reason) => {
            error!("no screenshot: {reason}");
            exit.write(AppExit::error());
            progress.requested = true;
            return;
        }
    }
    progress.frames += 1;
    if progress.frames < request.frames {
        return;
    }
    let shot = progress.shot;
    let last = shot == request.seeks.len();
    if last {
        progress.requested = true;
    } else {
        // This capture, then the next time and --frames more.
        seek.write(AnimationRequest::Seek(request.seeks[shot]));
        progress.shot += 1;
        progress.frames = 0;
    }
    let png = request.shot_path(shot);
    if let (Ok((camera, camera_transform)), Ok(light), Ok(floor), Ok(window)) =
        (camera.single(), light.single(), floor.single(), window.single())
    {
        let model = pool.shown.and_then(|id| models.get(id));
        let probe =
            probe(camera, camera_transform, light, floor.translation().y, model, settings.hollow, window.size());
        let json = serde_json::to_string_pretty(&probe).unwrap_or_default();
        let sidecar = sidecar_path(&png);
        if let Err(e) = std::fs::write(&sidecar, json) {
            error!("cannot write {}: {e}", sidecar.display());
            exit.write(AppExit::error());
            return;
        }
    }
    info!("saving screenshot to {}", png.display());
    let path = png;
    commands.spawn(Screenshot::primary_window()).observe(
        move |captured: On<ScreenshotCaptured>, mut exit: MessageWriter<AppExit>| {
            let saved = captured
                .image
                .clone()
                .try_into_dynamic()
                .map_err(|e| e.to_string())
                .and_then(|image| image.to_rgb8().save(&path).map_err(|e| e.to_string()));
            match saved {
                Ok(()) => {
                    info!("screenshot saved to {}", path.display());
                    if last {
                        exit.write(AppExit::Success);
                    }
                }
                Err(e) => {
                    error!("cannot write the screenshot {}: {e}", path.display());
                    exit.write(AppExit::error());
                }
            }
        },
    );
}

impl Plugin for ScreenshotPlugin {
    fn build(&self, app: &mut App) {
        // Time steps exactly one fixed step (1/60 s) a frame, so frame N is the same moment of an animation however
        // slowly a software renderer draws.
        app.insert_resource(bevy::time::TimeUpdateStrategy::ManualDuration(crate::schedule::FIXED_STEP));
        app.insert_resource(self.clone());
        app.add_systems(Update, drive.in_set(ScreenshotSystems));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn several_animation_times_number_their_pngs() {
        let one = ScreenshotPlugin { path: "shots/fox.png".into(), frames: 20, then: None, seeks: Vec::new() };
        assert_eq!(one.shot_path(0), PathBuf::from("shots/fox.png"));
        let three = ScreenshotPlugin { seeks: vec![0.3, 0.6], ..one };
        let paths: Vec<PathBuf> = (0..3).map(|i| three.shot_path(i)).collect();
        assert_eq!(paths, ["shots/fox-0.png", "shots/fox-1.png", "shots/fox-2.png"].map(PathBuf::from));
        assert_eq!(sidecar_path(&paths[1]), PathBuf::from("shots/fox-1.png.json"));
    }
}
