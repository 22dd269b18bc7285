// A voxel, its flight and its repel spring, evaluated on the GPU as functions of the flight clock: the morph's
// per-voxel tween (back-out flight, colour switch, visible count, the model's spin) and the critically damped
// spring that brings a pushed voxel home. Plain WGSL with no bindings, imported by voxel_common.wgsl and, in the
// tests, run in a compute pass against the Rust twins (`instancing::flown`, `GpuSpring::sprung`).

// One voxel's look (32 bytes, `GpuVoxel` in src/instancing/gpu.rs). Voxels only turn about y: the box's x axis
// in the xz plane (width × (cos, −sin)), its height and its depth place it; a hidden voxel has no size.
struct Voxel {
    translation: vec3<f32>,
    color: u32,
    x_axis: vec2<f32>,
    scale_y: f32,
    scale_z: f32,
}

// One voxel's flight (96 bytes, `VoxelTween` in src/transition.rs): from and to in the model's frame, seconds
// after `start` on the flight clock.
struct Flight {
    from_position: vec3<f32>,
    delay: f32,
    to_position: vec3<f32>,
    duration: f32,
    from_scale: vec3<f32>,
    color_delay: f32,
    to_scale: vec3<f32>,
    color_duration: f32,
    color_from: u32,
    color_to: u32,
    start: f32,
    end: f32,
    overshoot: f32,
    show: u32,
    spare_a: u32,
    spare_b: u32,
}

// One voxel's repel spring (16 bytes, `GpuSpring` in src/instancing/spring.rs): offset and velocity in the
// model's frame as half floats, at clock time `since`, pulled from then on towards the cursor's push (the sign
// bit of `since` set) or home.
struct Spring {
    offset_xy: u32,
    offset_z_velocity_x: u32,
    velocity_yz: u32,
    since: f32,
}

// The spring's stiffness (1/s², `STIFFNESS`); the damping is critical.
const STIFFNESS: f32 = 140.0;

// The flight clock of the frame (`GpuClock` in src/instancing/flight.rs): seconds, the model's angle about y and
// the visible count; and the cursor in the model's frame (its reach around its ray, 0 without a cursor; its
// strength).
struct Clock {
    time: f32,
    angle: f32,
    shown: f32,
    radius: f32,
    ray_origin: vec3<f32>,
    strength: f32,
    ray_direction: vec3<f32>,
    pad: f32,
}

// `Flight::show`: the visible count decides, shown throughout, shown until the end.
const SHOW_COUNT: u32 = 0u;

// Back-out easing with overshoot `s`.
fn back_out(t: f32, s: f32) -> f32 {
    let u = clamp(t, 0.0, 1.0) - 1.0;
    return 1.0 + (s + 1.0) * u * u * u + s * u * u;
}

// Voxel `slot` as drawn at `clock`: its flight while it lasts, else its look.
fn flown(look: Voxel, f: Flight, slot: u32, clock: Clock) -> Voxel {
    let elapsed = clock.time - f.start;
    if !(elapsed < f.end) {
        return look;
    }
    let k = back_out((elapsed - f.delay) / max(f.duration, 1e-6), f.overshoot);
    let position = mix(f.from_position, f.to_position, vec3(k));
    let scale = mix(f.from_scale, f.to_scale, vec3(clamp(k, 0.0, 1.0)));
    let t = clamp((elapsed - f.color_delay) / max(f.color_duration, 1e-6), 0.0, 1.0);
    let rgba = round(mix(unpack4x8unorm(f.color_from), unpack4x8unorm(f.color_to), vec4(t)) * 255.0) / 255.0;
    let shows = f.show != SHOW_COUNT || f32(slot) < clock.shown;
    let c = cos(clock.angle);
    let s = sin(clock.angle);
    var v: Voxel;
    v.translation = vec3(c * position.x + s * position.z, position.y, c * position.z - s * position.x);
    v.color = pack4x8unorm(rgba);
    if shows {
        v.x_axis = vec2(c, -s) * scale.x;
        v.scale_y = scale.y;
        v.scale_z = scale.z;
    }
    return v;
}

// A unit vector perpendicular to the unit vector `d` (glam's `any_orthonormal_vector`).
fn any_orthonormal(d: vec3<f32>) -> vec3<f32> {
    let sign = select(-1.0, 1.0, d.z >= 0.0);
    let a = -1.0 / (sign + d.z);
    let b = d.x * d.y * a;
    return vec3(b, sign + d.y * d.y * a, -d.y);
}

// The cursor's push at `p` (the model's frame): away from its ray, falling off linearly to nothing at its radius.
fn push(p: vec3<f32>, clock: Clock) -> vec3<f32> {
    let along = max(dot(p - clock.ray_origin, clock.ray_direction), 0.0);
    let away = p - (clock.ray_origin + clock.ray_direction * along);
    let d2 = dot(away, away);
    if !(d2 < clock.radius * clock.radius) {
        return vec3(0.0);
    }
    let d = sqrt(d2);
    let n = select(any_orthonormal(clock.ray_direction), away / d, d > 1e-5);
    return n * (clock.radius - d) * clock.strength;
}

// `look` moved by its spring at `clock`: with y the offset from the target (the cursor's push at the voxel while
// it is pulled, else home), y(τ) = (y₀ + (v₀ + ω y₀) τ) e^(−ω τ), τ seconds since the state; turned with the
// voxel.
fn sprung(look: Voxel, spring: Spring, clock: Clock) -> Voxel {
    let xy = unpack2x16float(spring.offset_xy);
    let zx = unpack2x16float(spring.offset_z_velocity_x);
    let yz = unpack2x16float(spring.velocity_yz);
    let offset = vec3(xy, zx.x);
    let velocity = vec3(zx.y, yz);
    let width = length(look.x_axis);
    let c = select(vec2(1.0, 0.0), look.x_axis / width, width > 0.0);
    let home = vec3(c.x * look.translation.x + c.y * look.translation.z, look.translation.y,
        c.x * look.translation.z - c.y * look.translation.x);
    let pulled = (bitcast<u32>(spring.since) >> 31u) != 0u;
    let goal = select(vec3(0.0), push(home, clock), pulled);
    let w = sqrt(STIFFNESS);
    let tau = max(clock.time - abs(spring.since), 0.0);
    let y = offset - goal;
    let moved = goal + (y + (velocity + y * w) * tau) * exp(-w * tau);
    var v = look;
    v.translation = look.translation + vec3(c.x * moved.x - c.y * moved.z, moved.y, c.x * moved.z + c.y * moved.x);
    return v;
}
