//! Animated models: skins, morph targets and node channels posed at time t (hand-built files with poses
//! computed by hand, then the Khronos samples), and the fixed grid over a clip.

use std::f32::consts::FRAC_1_SQRT_2;

use serde_json::{Value, json};
use voxel_core::{
    AnimatedModel, TriangleSoup, Vertex, VoxelError, load_animated_file, load_animated_slice, load_slice, voxelize,
    voxelize_within,
};

#[cfg(feature = "cli")]
use voxel_core::cli::animation::{ClipRequest, voxelize_clip};
#[cfg(feature = "cli")]
use voxel_core::export::Format;
#[cfg(feature = "cli")]
use voxel_core::palette::ColorStage;

use crate::common::{at_resolution, glb, model};

/// Builds the binary chunk and the accessor list of a hand-made glTF.
#[derive(Default)]
struct Buffers {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Buffers {
    /// Adds an accessor of `kind` ("SCALAR", "VEC3", "MAT4"…) over little-endian `bytes` of `component`.
    fn add(&mut self, bytes: Vec<u8>, component: u32, kind: &str, count: usize) -> usize {
        let offset = self.bin.len();
        self.bin.extend_from_slice(&bytes);
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()}));
        self.accessors.push(
            json!({"bufferView": self.views.len() - 1, "componentType": component, "count": count, "type": kind}),
        );
        self.accessors.len() - 1
    }

    fn floats(&mut self, values: &[f32], kind: &str, width: usize) -> usize {
        self.add(values.iter().flat_map(|v| v.to_le_bytes()).collect(), 5126, kind, values.len() / width)
    }

    fn shorts(&mut self, values: &[u16], kind: &str, width: usize) -> usize {
        self.add(values.iter().flat_map(|v| v.to_le_bytes()).collect(), 5123, kind, values.len() / width)
    }

    /// A unit cube's positions and indices: (POSITION accessor, indices accessor, the positions).
    fn cube(&mut self) -> (usize, usize, Vec<[f32; 3]>) {
        let mesh = voxel_core::shapes::cuboid([0.0; 3], [1.0; 3]);
        let positions = self.floats(&mesh.positions.concat(), "VEC3", 3);
        self.accessors[positions]["min"] = json!([0.0, 0.0, 0.0]);
        self.accessors[positions]["max"] = json!([1.0, 1.0, 1.0]);
        let indices: Vec<u16> = mesh.triangles.iter().flatten().map(|&i| i as u16).collect();
        let indices = self.shorts(&indices, "SCALAR", 1);
        (positions, indices, mesh.positions.clone())
    }

    /// The .glb of `doc` with these buffers filled in.
    fn glb(self, mut doc: Value) -> Vec<u8> {
        doc["asset"] = json!({"version": "2.0"});
        doc["buffers"] = json!([{"byteLength": self.bin.len()}]);
        doc["bufferViews"] = json!(self.views);
        doc["accessors"] = json!(self.accessors);
        glb(&doc, &self.bin)
    }
}

/// The posed position of every corner, in soup order.
fn positions(soup: &TriangleSoup) -> Vec<[f32; 3]> {
    soup.corners().map(|v| v.position).collect()
}

fn pose(model: &mut AnimatedModel, clip: usize, t: f32) -> TriangleSoup {
    let mut soup = TriangleSoup::default();
    model.pose_into(clip, t, &mut soup).unwrap();
    soup
}

fn assert_close(a: [f32; 3], b: [f32; 3], what: &str) {
    assert!((0..3).all(|i| (a[i] - b[i]).abs() < 1e-4), "{what}: {a:?} != {b:?}");
}

/// A cube skinned to joint node 1 (rest at x = 2, bind pose there) and static joint node 2 at the origin;
/// the clip turns joint 1 from 0° to 90° about +Z over the first second and holds until t = 2. Corners with
/// z = 1 hang on both joints with weights 2 and 2 (not summing to 1), joint 1 through JOINTS_0/WEIGHTS_0 and
/// joint 2 through JOINTS_1/WEIGHTS_1; the others on `joint` alone. The skinned node is translated by 100
/// along x, which skinning must ignore.
fn skinned_cube(rotation_keys: &[f32], interpolation: &str, joint: u16) -> Vec<u8> {
    let mut b = Buffers::default();
    let (pos, idx, corners) = b.cube();
    let joints: Vec<u16> = corners.iter().flat_map(|p| [if p[2] > 0.5 { 0 } else { joint }, 0, 0, 0]).collect();
    let weights: Vec<f32> = corners.iter().flat_map(|p| [if p[2] > 0.5 { 2.0 } else { 1.0 }, 0.0, 0.0, 0.0]).collect();
    let second_joints: Vec<u16> = corners.iter().flat_map(|_| [1, 0, 0, 0]).collect();
    let second_weights: Vec<f32> =
        corners.iter().flat_map(|p| [if p[2] > 0.5 { 2.0 } else { 0.0 }, 0.0, 0.0, 0.0]).collect();
    let joints = b.shorts(&joints, "VEC4", 4);
    let weights = b.floats(&weights, "VEC4", 4);
    let second_joints = b.shorts(&second_joints, "VEC4", 4);
    let second_weights = b.floats(&second_weights, "VEC4", 4);
    let inverse_bind: Vec<f32> = [
        glam::Mat4::from_translation(glam::vec3(-2.0, 0.0, 0.0)).to_cols_array(),
        glam::Mat4::IDENTITY.to_cols_array(),
    ]
    .concat();
    let inverse_bind = b.floats(&inverse_bind, "MAT4", 16);
    let times = b.floats(&[0.0, 1.0, 2.0], "SCALAR", 1);
    let rotations = b.floats(rotation_keys, "VEC4", 4);
    b.glb(json!({
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"mesh": 0, "skin": 0, "translation": [100.0, 0.0, 0.0]},
            {"translation": [2.0, 0.0, 0.0]},
            {}
        ],
        "meshes": [{"primitives": [{"attributes": {
            "POSITION": pos, "JOINTS_0": joints, "WEIGHTS_0": weights, "JOINTS_1": second_joints, "WEIGHTS_1": second_weights
        }, "indices": idx}]}],
        "skins": [{"joints": [1, 2], "inverseBindMatrices": inverse_bind}],
        "animations": [{
            "name": "turn",
            "channels": [{"sampler": 0, "target": {"node": 1, "path": "rotation"}}],
            "samplers": [{"input": times, "output": rotations, "interpolation": interpolation}]
        }]
    }))
}

/// Identity, 90° about +Z, 90° about +Z (x, y, z, w).
const TURN_KEYS: [f32; 12] =
    [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, FRAC_1_SQRT_2, FRAC_1_SQRT_2, 0.0, 0.0, FRAC_1_SQRT_2, FRAC_1_SQRT_2];

#[test]
fn a_one_joint_skin_turned_90_degrees_moves_its_vertices_as_computed_by_hand() {
    let mut model = load_animated_slice(&skinned_cube(&TURN_KEYS, "LINEAR", 0), None).unwrap();
    assert_eq!(
        model.clips().iter().map(|c| (c.name.clone(), c.duration, c.channels)).collect::<Vec<_>>(),
        [("turn".to_owned(), 2.0, 1)]
    );
    let rest = model.rest_soup().clone();
    let posed = pose(&mut model, 0, 1.5);
    for (r, p) in positions(&rest).iter().zip(positions(&posed)) {
        // The static import places the cube with its node (x + 100); skinning ignores the node transform.
        let [x, y, z] = [r[0] - 100.0, r[1], r[2]];
        // Joint 1: T(2,0,0)·Rz(90°)·T(-2,0,0) maps (x, y, z) to (2 - y, x - 2, z).
        let turned = [2.0 - y, x - 2.0, z];
        let expected = if z > 0.5 { std::array::from_fn(|a| (turned[a] + [x, y, z][a]) / 2.0) } else { turned };
        assert_close(p, expected, "posed corner");
    }
    // At t = 0 the joint is at rest: the bind pose, without the node's translation.
    for (r, p) in positions(&rest).iter().zip(positions(&pose(&mut model, 0, 0.0))) {
        assert_close(p, [r[0] - 100.0, r[1], r[2]], "bind pose corner");
    }
    // Colours, parts and materials are the static import's.
    assert_eq!(posed.triangle_parts, rest.triangle_parts);
    assert_eq!(
        posed.corners().map(|v| v.color).collect::<Vec<_>>(),
        rest.corners().map(|v| v.color).collect::<Vec<_>>()
    );
}

#[test]
fn step_and_cubic_spline_rotations_sample_as_the_spec_says() {
    // STEP holds the previous key: at t = 0.9 still identity, at t = 1 the full turn.
    let mut step = load_animated_slice(&skinned_cube(&TURN_KEYS, "STEP", 0), None).unwrap();
    let rest = positions(&pose(&mut step, 0, 0.0));
    assert_eq!(positions(&pose(&mut step, 0, 0.9)), rest);
    let turned = positions(&pose(&mut step, 0, 1.0));
    assert_close(turned[0], [2.0 - rest[0][1], rest[0][0] - 2.0, rest[0][2]], "first corner at t = 1");
    // CUBICSPLINE with zero tangents: key values at the keys, and in between the Hermite blend
    // 3s² − 2s³ of the two quaternions, normalized: at s = 0.5 exactly half way, 45°.
    let zero = [0.0; 4];
    let keys: Vec<f32> = [
        zero,
        [0.0, 0.0, 0.0, 1.0],
        zero,
        zero,
        [0.0, 0.0, FRAC_1_SQRT_2, FRAC_1_SQRT_2],
        zero,
        zero,
        [0.0, 0.0, FRAC_1_SQRT_2, FRAC_1_SQRT_2],
        zero,
    ]
    .concat();
    let mut cubic = load_animated_slice(&skinned_cube(&keys, "CUBICSPLINE", 0), None).unwrap();
    let half = positions(&pose(&mut cubic, 0, 0.5));
    let (c, s) = (std::f32::consts::FRAC_PI_4.cos(), std::f32::consts::FRAC_PI_4.sin());
    let [x, y, z] = rest[0];
    let expected = [2.0 + (x - 2.0) * c - y * s, (x - 2.0) * s + y * c, z];
    let expected = if z > 0.5 { std::array::from_fn(|a| (expected[a] + rest[0][a]) / 2.0) } else { expected };
    assert_close(half[0], expected, "first corner at t = 0.5");
    assert_close(positions(&pose(&mut cubic, 0, 1.0))[0], turned[0], "cubic at the key");
}

#[test]
fn time_wraps_around_the_clip() {
    let mut model = load_animated_slice(&skinned_cube(&TURN_KEYS, "LINEAR", 0), None).unwrap();
    let at = positions(&pose(&mut model, 0, 0.25));
    assert_eq!(positions(&pose(&mut model, 0, 2.25)), at);
    assert_eq!(positions(&pose(&mut model, 0, -1.75)), at);
    assert_ne!(positions(&pose(&mut model, 0, 1.25)), at);
    let err = model.pose_into(0, f32::NAN, &mut TriangleSoup::default()).unwrap_err();
    assert!(err.to_string().contains("finite"), "{err}");
    let err = model.pose_into(1, 0.0, &mut TriangleSoup::default()).unwrap_err();
    assert!(err.to_string().contains("clip 1 does not exist"), "{err}");
}

#[test]
fn malformed_animation_data_is_an_error_and_the_static_import_still_works() {
    // Joint index 5 in a skin of two joints.
    let bytes = skinned_cube(&TURN_KEYS, "LINEAR", 5);
    let err = load_animated_slice(&bytes, None).unwrap_err();
    assert!(
        matches!(err, VoxelError::Invalid(_)) && err.to_string().contains("vertex joint 5 is out of range"),
        "{err}"
    );
    assert_eq!(load_slice(&bytes, None).unwrap().triangle_count(), 12);
    // Two keyframe times, three rotations.
    let err = load_animated_slice(&skinned_cube(&TURN_KEYS[..8], "LINEAR", 0), None).unwrap_err();
    assert!(err.to_string().contains("animation turn channel 0: 3 keyframes need 12 output values, found 8"), "{err}");
}

#[test]
fn a_primitive_that_uses_some_of_its_vertices_poses_just_those() {
    // The cube's vertices, but only its top face's two triangles (z = 1): four of the eight vertices used,
    // morphed +1 along x where x = 1 and moved by the node's translation.
    let mut b = Buffers::default();
    let (pos, _, corners) = b.cube();
    let top: Vec<u16> = (0..corners.len() as u16).filter(|&i| corners[usize::from(i)][2] == 1.0).collect();
    let top = b.shorts(&[top[0], top[1], top[3], top[0], top[3], top[2]], "SCALAR", 1);
    let deltas: Vec<f32> = corners.iter().flat_map(|p| [p[0], 0.0, 0.0]).collect();
    let deltas = b.floats(&deltas, "VEC3", 3);
    let times = b.floats(&[0.0, 2.0], "SCALAR", 1);
    let weights = b.floats(&[1.0, 1.0], "SCALAR", 1);
    let translations = b.floats(&[0.0, 0.0, 0.0, 4.0, 0.0, 0.0], "VEC3", 3);
    let bytes = b.glb(json!({
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}, "indices": top, "targets": [{"POSITION": deltas}]}], "weights": [0.0]}],
        "animations": [{"channels": [
            {"sampler": 0, "target": {"node": 0, "path": "weights"}},
            {"sampler": 1, "target": {"node": 0, "path": "translation"}}
        ], "samplers": [{"input": times, "output": weights}, {"input": times, "output": translations}]}]
    }));
    let mut model = load_animated_slice(&bytes, None).unwrap();
    let rest = model.rest_soup().clone();
    assert_eq!((rest.vertex_count(), rest.triangle_count()), (4, 2));
    assert!(rest.positions().iter().all(|p| p[2] == 1.0), "{:?}", rest.positions());
    let posed = pose(&mut model, 0, 1.0);
    for (r, p) in positions(&rest).iter().zip(positions(&posed)) {
        assert_close(p, [r[0] + r[0] + 2.0, r[1], r[2]], "posed corner");
    }
}

/// A cube on node 0 with one morph target (+1 along x for the corners at x = 1) and a translation, both
/// animated by clip 0: weights 0 → 1 (STEP at t = 1), translation (0,0,0) → (4,0,0) linear over 2 s.
pub(crate) fn morph_cube(scale_keys: Option<[f32; 9]>) -> Vec<u8> {
    let mut b = Buffers::default();
    let (pos, idx, corners) = b.cube();
    let deltas: Vec<f32> = corners.iter().flat_map(|p| [p[0], 0.0, 0.0]).collect();
    let deltas = b.floats(&deltas, "VEC3", 3);
    let times = b.floats(&[0.0, 1.0, 2.0], "SCALAR", 1);
    let weights = b.floats(&[0.0, 1.0, 1.0], "SCALAR", 1);
    let translations = b.floats(&[0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 4.0, 0.0, 0.0], "VEC3", 3);
    let mut channels = vec![
        json!({"sampler": 0, "target": {"node": 0, "path": "weights"}}),
        json!({"sampler": 1, "target": {"node": 0, "path": "translation"}}),
    ];
    let mut samplers = vec![
        json!({"input": times, "output": weights, "interpolation": "STEP"}),
        json!({"input": times, "output": translations}),
    ];
    if let Some(keys) = scale_keys {
        let scales = b.floats(&keys, "VEC3", 3);
        channels.push(json!({"sampler": 2, "target": {"node": 0, "path": "scale"}}));
        samplers.push(json!({"input": times, "output": scales}));
    }
    b.glb(json!({
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}, "indices": idx, "targets": [{"POSITION": deltas}]}], "weights": [0.0]}],
        "animations": [{"channels": channels, "samplers": samplers}]
    }))
}

#[test]
fn a_morph_weight_of_one_gives_the_targets_positions_and_a_translation_channel_moves_the_node() {
    let mut model = load_animated_slice(&morph_cube(None), None).unwrap();
    assert_eq!(model.clips()[0].name, "animation 0");
    let rest = positions(model.rest_soup());
    // t = 0.5: weight 0 (STEP), translation 1 along x.
    for (r, p) in rest.iter().zip(positions(&pose(&mut model, 0, 0.5))) {
        assert_close(p, [r[0] + 1.0, r[1], r[2]], "t = 0.5");
    }
    // t = 1.5: weight 1, the corners at x = 1 moved to x = 2 (the target), translation 3.
    for (r, p) in rest.iter().zip(positions(&pose(&mut model, 0, 1.5))) {
        assert_close(p, [r[0] * 2.0 + 3.0, r[1], r[2]], "t = 1.5");
    }
}

#[test]
fn the_grid_of_a_clip_keeps_its_size_and_place_while_the_model_grows() {
    // The cube also scales from 1 to 2 along every axis over the first second.
    let mut model =
        load_animated_slice(&morph_cube(Some([1.0, 1.0, 1.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0])), None).unwrap();
    let bounds = model.clip_bounds(0).unwrap();
    // Union of the poses: x from 0 to 4 + 2·2 (translation 4, width 2 scaled by 2), y and z 0..2.
    assert_close(bounds.0, [0.0, 0.0, 0.0], "bounds min");
    assert_close(bounds.1, [8.0, 2.0, 2.0], "bounds max");
    let options = at_resolution(24);
    let mut soup = TriangleSoup::default();
    let mut frames = Vec::new();
    for k in 0..8 {
        model.pose_into(0, k as f32 * 0.25, &mut soup).unwrap();
        frames.push((voxelize_within(&soup, &options, bounds).unwrap(), voxelize(&soup, &options).unwrap()));
    }
    let fixed = frames[0].0.spec;
    assert!(frames.iter().all(|(f, _)| f.spec == fixed), "the grid moved");
    // In the fixed grid the model grows 4× in volume (scale 1 → 2 on x, 1 → 2 on y and z and the morph
    // doubling x again is on from t = 1); a grid fitted per frame would rescale it and hide that.
    let first = frames[0].0.stats.voxels as f64;
    let last = frames[7].0.stats.voxels as f64;
    assert!((14.0..18.0).contains(&(last / first)), "{first} → {last}");
    let own = frames.iter().map(|(_, own)| own.spec.dims).collect::<std::collections::HashSet<_>>();
    assert!(own.len() > 1, "per-frame grids should differ: {own:?}");
}

#[test]
fn sampled_node_transforms_are_the_channels_values_and_the_rest_elsewhere() {
    let mut model = load_animated_slice(&skinned_cube(&TURN_KEYS, "LINEAR", 0), None).unwrap();
    assert_eq!(model.nodes().len(), 3);
    let locals = model.sample_nodes(0, 0.5).unwrap().to_vec();
    // Node 1 turns from identity to 90° about z over the first second: 45° half-way (slerp), at its rest place.
    let half = glam::Quat::from_rotation_z(std::f32::consts::FRAC_PI_4);
    assert!(locals[1].rotation.angle_between(half) < 1e-5, "{:?}", locals[1].rotation);
    assert_eq!(locals[1].translation, glam::vec3(2.0, 0.0, 0.0));
    // Nodes no channel moves keep their rest transform (the skinned node its translation by 100).
    assert_eq!(locals[0].translation, glam::vec3(100.0, 0.0, 0.0));
    assert_eq!((locals[2].rotation, locals[2].scale), (glam::Quat::IDENTITY, glam::Vec3::ONE));
    // Time wraps into the clip as posing does.
    let wrapped = model.sample_nodes(0, 2.5).unwrap()[1].rotation;
    assert!(wrapped.angle_between(half) < 1e-5);
    assert!(model.sample_nodes(1, 0.0).is_err() && model.sample_nodes(0, f32::NAN).is_err());
}

#[test]
fn a_model_without_animations_has_no_clips_and_cannot_be_posed() {
    let mut b = Buffers::default();
    let (pos, idx, _) = b.cube();
    let bytes = b.glb(json!({"scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}], "meshes": [{"primitives": [{"attributes": {"POSITION": pos}, "indices": idx}]}]}));
    let mut model = load_animated_slice(&bytes, None).unwrap();
    assert!(model.clips().is_empty());
    assert_eq!(
        model.rest_soup().corners().collect::<Vec<_>>(),
        load_slice(&bytes, None).unwrap().corners().collect::<Vec<_>>()
    );
    assert!(model.pose_into(0, 0.0, &mut TriangleSoup::default()).is_err());
    assert_eq!(
        model.into_rest_soup().corners().collect::<Vec<_>>(),
        load_slice(&bytes, None).unwrap().corners().collect::<Vec<_>>()
    );
}

/// Mean displacement between two poses of the corners whose bind position satisfies `select`.
fn mean_motion(bind: &TriangleSoup, a: &TriangleSoup, b: &TriangleSoup, select: impl Fn([f32; 3]) -> bool) -> f32 {
    let moved: Vec<f32> = (bind.corners().zip(a.corners()).zip(b.corners()))
        .filter(|((r, _), _)| select(r.position))
        .map(|((_, p), q)| (glam::Vec3::from(p.position) - glam::Vec3::from(q.position)).length())
        .collect();
    assert!(!moved.is_empty());
    moved.iter().sum::<f32>() / moved.len() as f32
}

/// The largest distance between the same corner in two poses.
fn max_motion(a: &TriangleSoup, b: &TriangleSoup) -> f32 {
    a.corners()
        .zip(b.corners())
        .map(|(p, q)| glam::Vec3::from(p.position).distance(q.position.into()))
        .fold(0.0, f32::max)
}

#[test]
fn the_fox_poses_away_from_its_bind_pose_and_moves_where_its_clips_move() {
    let Some(path) = model("khronos-fox.glb") else { return };
    let mut fox = load_animated_file(&path).unwrap();
    let clips: Vec<_> =
        fox.clips().iter().map(|c| (c.name.clone(), (c.duration * 1e4).round() / 1e4, c.channels)).collect();
    assert_eq!(clips, [("Survey".into(), 3.4167, 21), ("Walk".into(), 0.7083, 21), ("Run".into(), 1.1583, 21)]);
    let bind = fox.rest_soup().clone();
    // The fox is about 155 long (z), 79 high (y); its feet are at y < 10.
    for clip in 0..3 {
        let start = pose(&mut fox, clip, 0.0);
        assert!(max_motion(&bind, &start) > 10.0, "clip {clip} starts in the bind pose");
        let ([_, lo_y, _], [_, hi_y, _]) = start.bounds().unwrap();
        assert!(lo_y > -5.0 && (70.0..85.0).contains(&hi_y), "clip {clip}: height {lo_y}..{hi_y}");
    }
    let feet = |p: [f32; 3]| p[1] < 10.0;
    let back = |p: [f32; 3]| p[1] > 50.0;
    let ends = |p: [f32; 3]| p[2] < -60.0 || p[2] > 50.0;
    // Survey: the fox stands and looks round: head and tail swing, the feet stay planted.
    let (a, b) = (pose(&mut fox, 0, 0.0), pose(&mut fox, 0, 1.7));
    assert!(mean_motion(&bind, &a, &b, feet) < 0.1, "{}", mean_motion(&bind, &a, &b, feet));
    assert!(mean_motion(&bind, &a, &b, ends) > 5.0, "{}", mean_motion(&bind, &a, &b, ends));
    // Walk: the legs swing far more than the back moves.
    let (a, b) = (pose(&mut fox, 1, 0.0), pose(&mut fox, 1, 0.354));
    let (legs, body) = (mean_motion(&bind, &a, &b, feet), mean_motion(&bind, &a, &b, back));
    assert!(legs > 5.0 * body && legs > 15.0, "legs {legs}, back {body}");
}

#[test]
fn cesium_man_walks_with_sane_bounds_inside_the_clip_bounds() {
    let Some(path) = model("khronos-cesiumman.glb") else { return };
    let mut man = load_animated_file(&path).unwrap();
    assert_eq!(man.clips().iter().map(|c| (c.duration, c.channels)).collect::<Vec<_>>(), [(2.0, 57)]);
    let (bind_lo, bind_hi) = man.rest_soup().bounds().unwrap();
    let (lo, hi) = man.clip_bounds(0).unwrap();
    let bind = man.rest_soup().clone();
    for k in 0..8 {
        let posed = pose(&mut man, 0, k as f32 * 0.25);
        assert!(max_motion(&bind, &posed) > 0.2, "t = {}: still in the bind pose", k as f32 * 0.25);
        let (p_lo, p_hi) = posed.bounds().unwrap();
        // He keeps his height (1.5) while walking, and every pose lies in the clip's bounds.
        let height = (p_hi[1] - p_lo[1]) / (bind_hi[1] - bind_lo[1]);
        assert!((0.9..1.05).contains(&height), "t = {}: height ratio {height}", k as f32 * 0.25);
        assert!((0..3).all(|a| p_lo[a] >= lo[a] && p_hi[a] <= hi[a]), "{p_lo:?}..{p_hi:?} outside {lo:?}..{hi:?}");
    }
}

#[test]
fn the_morph_cubes_volume_follows_its_weights_in_a_fixed_grid() {
    let Some(path) = model("khronos-animatedmorphcube/AnimatedMorphCube.gltf") else { return };
    let mut cube = load_animated_file(&path).unwrap();
    let bounds = cube.clip_bounds(0).unwrap();
    let options = voxel_core::VoxelizeOptions::default();
    let rest = voxelize(cube.rest_soup(), &options).unwrap();
    let counts: Vec<usize> = [0.0, 1.05, 2.1]
        .iter()
        .map(|&t| voxelize_within(&pose(&mut cube, 0, t), &options, bounds).unwrap().stats.voxels)
        .collect();
    // At t = 0 both weights are 0: the rest cube. Then the "thin" target flattens it.
    assert_eq!(counts[0], rest.stats.voxels);
    assert!(counts[1] * 10 < counts[0] * 7 && counts[2] < counts[1], "{counts:?}");
}

#[test]
fn the_milk_trucks_wheels_turn_rigidly_and_its_body_stays() {
    let Some(path) = model("khronos-cesiummilktruck/CesiumMilkTruck.gltf") else { return };
    let mut truck = load_animated_file(&path).unwrap();
    let bind = truck.rest_soup().clone();
    let posed = pose(&mut truck, 0, 0.3125);
    let parts_named = |name: &str| -> Vec<u32> {
        bind.parts.iter().enumerate().filter(|(_, p)| p.name.starts_with(name)).map(|(i, _)| i as u32).collect()
    };
    let (bind_corners, posed_corners): (Vec<_>, Vec<_>) = (bind.corners().collect(), posed.corners().collect());
    let corners_of =
        |part: u32| -> Vec<usize> { (0..bind_corners.len()).filter(|&v| bind.triangle_parts[v / 3] == part).collect() };
    for part in parts_named("Cesium_Milk_Truck") {
        assert!(corners_of(part).iter().all(|&v| bind_corners[v].position == posed_corners[v].position));
    }
    let wheels = parts_named("Wheels");
    assert_eq!(wheels.len(), 2);
    for part in wheels {
        let corners = corners_of(part);
        let at = |soup: &[Vertex], v: usize| glam::Vec3::from(soup[v].position);
        let (bind, posed) = (&bind_corners[..], &posed_corners[..]);
        assert!(corners.iter().any(|&v| at(bind, v).distance(at(posed, v)) > 0.3), "wheel {part} did not turn");
        // Rigid: every corner keeps its distance to the part's first corner.
        let first = corners[0];
        for &v in &corners {
            let (before, after) = (at(bind, v).distance(at(bind, first)), at(posed, v).distance(at(posed, first)));
            assert!((before - after).abs() < 1e-4, "wheel {part} corner {v}: {before} → {after}");
        }
    }
}

/// Writes `bytes` to a fresh temporary folder as `name`; returns the folder.
#[cfg(feature = "cli")]
pub(crate) fn temp_model(name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("voxel-core-anim-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(name), bytes).unwrap();
    dir
}

/// The names of the files in `dir`, sorted.
#[cfg(feature = "cli")]
fn file_names(dir: &std::path::Path) -> Vec<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    names
}

#[cfg(feature = "cli")]
fn run(args: &[&std::ffi::OsStr]) -> i32 {
    voxel_core::cli::run(std::iter::once("voxel-art voxelize".into()).chain(args.iter().map(|a| a.to_os_string())))
}

#[cfg(feature = "cli")]
#[test]
fn the_cli_writes_one_vox_per_frame_of_a_clip() {
    let dir = temp_model("cube.glb", &morph_cube(None));
    let file = dir.join("cube.glb");
    let out = dir.join("frames");
    // 2 s at 4 frames per second: frames 0..8.
    let status = run(&[
        file.as_os_str(),
        "--animation".as_ref(),
        "0".as_ref(),
        "--fps".as_ref(),
        "4".as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(status, 0);
    let written = file_names(&out);
    assert_eq!(written, (0..8).map(|k| format!("cube-{k:04}.vox")).collect::<Vec<_>>());
    // The cube slides along x by 2 per second: frame 0 and frame 4 (t = 1) are different models.
    let first = dot_vox::load(out.join("cube-0000.vox").to_str().unwrap()).unwrap();
    let fifth = dot_vox::load(out.join("cube-0004.vox").to_str().unwrap()).unwrap();
    assert_eq!(first.models[0].size, fifth.models[0].size, "the grid changed");
    assert_ne!(first.models[0].voxels, fifth.models[0].voxels);
    // Listing works; unknown clips and unanimated models are errors.
    assert_eq!(run(&[file.as_os_str(), "--animation".as_ref(), "list".as_ref()]), 0);
    assert_eq!(run(&[file.as_os_str(), "--animation".as_ref(), "gallop".as_ref()]), 1);
    // --fps and --duration only go with --animation (a usage error).
    assert_eq!(run(&[file.as_os_str(), "--fps".as_ref(), "4".as_ref()]), 2);
    let still = temp_model(
        "still.glb",
        &voxel_core::glb::soup_to_glb(voxel_core::load_slice(&morph_cube(None), None).as_ref().unwrap()).unwrap(),
    );
    assert_eq!(run(&[still.join("still.glb").as_os_str(), "--animation".as_ref(), "list".as_ref()]), 1);
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&still).unwrap();
}

#[cfg(feature = "cli")]
#[test]
fn glb_frames_import_back_with_each_frames_cells() {
    let dir = temp_model("box.glb", &morph_cube(None));
    let file = dir.join("box.glb");
    let out = dir.join("frames");
    // The clip spans x = 0..6 (the unit cube slides 4 along x and doubles its width from t = 1): 24 cells of
    // 0.25 along it, so every face lies on a cell boundary.
    let options = voxel_core::VoxelizeOptions { grid: voxel_core::GridSize::Resolution(24), ..Default::default() };
    // 2 s at 4 frames per second: frames 0..8, moving 2 cells each.
    let colors = ColorStage::default();
    let request = ClipRequest {
        animation: "0",
        fps: 4.0,
        duration: None,
        out: Some(&out),
        format: Format::Glb,
        json: true,
        colors: &colors,
    };
    let lines = voxelize_clip(&file, &request, &options).unwrap();
    let written = file_names(&out);
    assert_eq!(written, (0..8).map(|k| format!("box-{k:04}.glb")).collect::<Vec<_>>());
    let (lo, hi) = load_animated_file(&file).unwrap().clip_bounds(0).unwrap();
    assert_eq!((lo, hi), ([0.0; 3], [6.0, 1.0, 1.0]));
    let cell = 0.25;
    let mut counts = Vec::new();
    for (k, line) in lines.iter().enumerate() {
        let frame: Value = serde_json::from_str(line).unwrap();
        let path = out.join(format!("box-{k:04}.glb"));
        assert_eq!(frame["gltf"], path.display().to_string());
        assert!(frame.get("vox").is_none(), "{frame}");
        assert_eq!(frame["mesh"]["bytes"], std::fs::metadata(&path).unwrap().len(), "frame {k}");
        assert_eq!(frame["mesh"]["quads"], 6, "frame {k}: a box of one colour is six rectangles");
        // Re-voxelized at the export's own cell size (its longest side in cells), the mesh is the frame's cells.
        let soup = voxel_core::load_file(&path).unwrap();
        assert_eq!(soup.triangle_count(), 12);
        let (a, b) = soup.bounds().unwrap();
        let sides: Vec<u32> = (0..3).map(|i| ((b[i] - a[i]) / cell).round() as u32).collect();
        let again = voxel_core::VoxelizeOptions {
            grid: voxel_core::GridSize::Resolution(*sides.iter().max().unwrap()),
            shell: voxel_core::ShellMode::None,
            ..Default::default()
        };
        let back = voxelize(&soup, &again).unwrap();
        assert_eq!(back.stats.voxels, sides.iter().product::<u32>() as usize, "frame {k}: {sides:?}");
        assert_eq!(frame["voxels"], back.stats.voxels, "frame {k}");
        counts.push(back.stats.voxels);
    }
    // 4 × 4 × 4 cells, then 8 × 4 × 4 from t = 1 (frame 4).
    assert_eq!(counts, [64, 64, 64, 64, 128, 128, 128, 128]);
    // From the command line: a .gltf and a .bin per frame, the frames of --duration.
    let gltf = dir.join("gltf");
    let args = ["-r", "24", "--animation", "0", "--fps", "4", "--format", "gltf", "--duration", "0.5", "--out"];
    let status = run(&[&[file.as_os_str()], &args.map(std::ffi::OsStr::new)[..], &[gltf.as_os_str()]].concat());
    assert_eq!(status, 0);
    let written = file_names(&gltf);
    assert_eq!(written, ["box-0000.bin", "box-0000.gltf", "box-0001.bin", "box-0001.gltf"]);
    let first = voxel_core::load_file(&gltf.join("box-0000.gltf")).unwrap();
    assert!(first.corners().eq(voxel_core::load_file(&out.join("box-0000.glb")).unwrap().corners()));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[cfg(feature = "cli")]
#[test]
fn the_cli_reports_every_frame_as_json_and_names_bad_requests() {
    let dir = temp_model("slide.glb", &morph_cube(None));
    let file = dir.join("slide.glb");
    let options = voxel_core::VoxelizeOptions::default();
    let request = ClipRequest {
        animation: "animation 0",
        fps: 2.0,
        duration: Some(3.0),
        out: None,
        format: Format::Vox,
        json: true,
        colors: &ColorStage::default(),
    };
    let lines = voxelize_clip(&file, &request, &options).unwrap();
    assert_eq!(lines.len(), 6);
    let frames: Vec<Value> = lines.iter().map(|l| serde_json::from_str(l).unwrap()).collect();
    for (k, f) in frames.iter().enumerate() {
        assert_eq!(f["file"], file.display().to_string());
        assert_eq!(f["clip"], "animation 0");
        assert_eq!(f["frame"], k);
        assert_eq!(f["time"], k as f64 * 0.5);
        assert_eq!(f["grid"], frames[0]["grid"]);
        assert!(f["voxels"].as_u64().unwrap() >= f["visible"].as_u64().unwrap() && f["visible"].as_u64().unwrap() > 0);
        assert!(f["voxelize_ms"].as_f64().unwrap() >= 0.0);
    }
    // t = 2.5 wraps to t = 0.5: the same cells.
    assert_eq!(frames[5]["voxels"], frames[1]["voxels"]);
    // The morph doubles the cube's width from t = 1: more voxels than at t = 0.5.
    assert!(frames[2]["voxels"].as_u64() > frames[1]["voxels"].as_u64());
    let list = voxelize_clip(&file, &ClipRequest { animation: "list", ..request }, &options).unwrap();
    let listed: Value = serde_json::from_str(&list[0]).unwrap();
    assert_eq!(
        (listed["clip"].as_str(), listed["duration"].as_f64(), listed["channels"].as_u64()),
        (Some("animation 0"), Some(2.0), Some(2))
    );
    let err = voxelize_clip(&file, &ClipRequest { animation: "7", ..request }, &options).unwrap_err();
    assert!(err.to_string().contains("no animation \"7\" (the model has 0: animation 0)"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_soup_beyond_the_given_bounds_is_clipped_at_the_grids_edge() {
    let soup = TriangleSoup::from_mesh(&voxel_core::shapes::cuboid([0.0; 3], [1.0; 3]), [1.0; 4]);
    // Bounds holding the cube's lower half along x: the grid covers it, the other half is cut off.
    let m = voxelize_within(&soup, &at_resolution(16), ([0.0; 3], [0.5, 1.0, 1.0])).unwrap();
    assert_eq!(m.stats.grid, [8, 16, 16]);
    assert_eq!(m.stats.voxels, 8 * 16 * 16);
}
