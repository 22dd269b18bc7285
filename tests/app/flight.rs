//! The GPU's flight curve and repel spring against the Rust ones: assets/shaders/voxel_flight.wgsl's `flown` and
//! `sprung` run in a compute pass on Mesa's lavapipe (software Vulkan) over thousands of tweens, springs, clocks
//! and looks, and every voxel they return is compared with `voxel_art::instancing::flown` (place, box, colour,
//! shown) and `GpuSpring::sprung` (place).

use bevy::math::Vec3;
use voxel_art::instancing::{GpuClock, GpuSpring, GpuVoxel, Spring, TweenShow, VoxelTween, flown};
use wgpu::util::DeviceExt;

/// Cases run.
const CASES: usize = 4096;

/// A compute entry point over the shader's own functions: out[i] = `call` of looks[i], records[i] (an array of
/// `record`) and clocks[i].
fn entry(record: &str, call: &str) -> String {
    format!(
        "
@group(0) @binding(0) var<storage, read> looks: array<Voxel>;
@group(0) @binding(1) var<storage, read> records: array<{record}>;
@group(0) @binding(2) var<storage, read> clocks: array<Clock>;
@group(0) @binding(3) var<storage, read_write> out: array<Voxel>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {{
    let i = id.x;
    if i < arrayLength(&out) {{
        out[i] = {call};
    }}
}}
"
    )
}

/// A software Vulkan device (lavapipe), if the machine has one; in CI its absence is a failure.
fn device() -> Option<(wgpu::Device, wgpu::Queue)> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::VULKAN,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    let adapter = bevy::tasks::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default())).ok();
    let Some(adapter) = adapter else {
        assert!(std::env::var_os("CI").is_none(), "no Vulkan adapter (mesa-vulkan-drivers: lavapipe) in CI");
        eprintln!("skipped: no Vulkan adapter");
        return None;
    };
    bevy::tasks::block_on(adapter.request_device(&wgpu::DeviceDescriptor::default())).ok()
}

/// A small generator for the cases (xorshift).
struct Draw(u64);

impl Draw {
    fn f32(&mut self, lo: f32, hi: f32) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        lo + (hi - lo) * (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }

    fn vec3(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.f32(lo, hi), self.f32(lo, hi), self.f32(lo, hi))
    }

    fn color(&mut self) -> u32 {
        (self.f32(0.0, 4_294_967_295.0)) as u32
    }
}

/// Tweens of every kind (before their delay, mid-flight, overshooting, landed), clocks at every angle and count,
/// and looks to fall back on.
fn cases() -> (Vec<GpuVoxel>, Vec<VoxelTween>, Vec<GpuClock>) {
    let mut draw = Draw(0x9e37_79b9_7f4a_7c15);
    let mut looks = Vec::new();
    let mut tweens = Vec::new();
    let mut clocks = Vec::new();
    for i in 0..CASES {
        let start = draw.f32(0.0, 100.0);
        let tween = VoxelTween {
            from: draw.vec3(-5.0, 5.0),
            to: draw.vec3(-5.0, 5.0),
            from_scale: draw.vec3(0.0, 0.3),
            to_scale: draw.vec3(0.01, 0.3),
            delay: draw.f32(0.0, 0.2),
            duration: draw.f32(0.0, 1.2),
            color_from: draw.color(),
            color_to: draw.color(),
            color_delay: draw.f32(0.0, 0.8),
            color_duration: draw.f32(0.0, 0.1),
            start,
            overshoot: if i % 3 == 0 { 0.0 } else { 3.0 },
            show: if i % 2 == 0 { TweenShow::Count as u32 } else { TweenShow::Always as u32 },
            ..Default::default()
        }
        .ending(draw.f32(0.0, 1.5));
        tweens.push(tween);
        let look = voxel_art::instancing::Turn::new(bevy::math::Quat::from_rotation_y(draw.f32(-3.0, 3.0))).place(
            draw.vec3(-5.0, 5.0),
            draw.vec3(0.01, 0.3),
            draw.color(),
        );
        looks.push(look);
        clocks.push(GpuClock::new(start + draw.f32(-0.1, 1.6), draw.f32(-7.0, 7.0), draw.f32(0.0, 8.0)));
    }
    (looks, tweens, clocks)
}

/// Runs the shader's functions through `entry` (see [`entry`]) over `looks`, `records` (a flight or a spring per
/// look) and `clocks` on `device`: a voxel per look.
fn run_on_gpu(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    entry: String,
    looks: &[GpuVoxel],
    records: &[u8],
    clocks: &[GpuClock],
) -> Vec<GpuVoxel> {
    let source = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/shaders/voxel_flight.wgsl"))
        .expect("the flight shader");
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("flight"),
        source: wgpu::ShaderSource::Wgsl((source + &entry).into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("flight"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let input = |bytes: &[u8]| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents: bytes,
            usage: wgpu::BufferUsages::STORAGE,
        })
    };
    let (looks_buffer, records_buffer, clocks_buffer) =
        (input(bytemuck::cast_slice(looks)), input(records), input(bytemuck::cast_slice(clocks)));
    let size = size_of_val(looks) as u64;
    let out = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let read = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let entries: Vec<wgpu::BindGroupEntry> = [&looks_buffer, &records_buffer, &clocks_buffer, &out]
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry { binding: i as u32, resource: b.as_entire_binding() })
        .collect();
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(looks.len().div_ceil(64) as u32, 1, 1);
    }
    encoder.copy_buffer_to_buffer(&out, 0, &read, 0, size);
    queue.submit([encoder.finish()]);
    read.slice(..).map_async(wgpu::MapMode::Read, |result| result.expect("the read-back buffer maps"));
    device.poll(wgpu::PollType::wait_indefinitely()).expect("the compute pass finishes");
    let mapped = read.slice(..).get_mapped_range();
    bytemuck::cast_slice(&mapped).to_vec()
}

#[test]
fn the_shaders_flight_is_the_rust_curve() {
    let Some((device, queue)) = device() else { return };
    let (looks, tweens, clocks) = cases();
    let gpu = run_on_gpu(
        &device,
        &queue,
        entry("Flight", "flown(looks[i], records[i], i % 8u, clocks[i])"),
        &looks,
        bytemuck::cast_slice(&tweens),
        &clocks,
    );
    let (mut flying, mut hidden) = (0, 0);
    for i in 0..CASES {
        let cpu = flown(&looks[i], &tweens[i], i % 8, &clocks[i]);
        let got = gpu[i];
        flying += usize::from(tweens[i].flies(clocks[i].time));
        hidden += usize::from(!cpu.shows());
        assert_eq!(got.shows(), cpu.shows(), "case {i}: shown");
        assert!(
            got.position().distance(cpu.position()) < 1e-3,
            "case {i}: at {} for {}",
            got.position(),
            cpu.position()
        );
        assert!(got.scale().distance(cpu.scale()) < 1e-4, "case {i}: box {} for {}", got.scale(), cpu.scale());
        let (a, b) = (got.color.to_le_bytes(), cpu.color.to_le_bytes());
        assert!(a.iter().zip(b).all(|(x, y)| x.abs_diff(y) <= 1), "case {i}: colour {a:?} for {b:?}");
    }
    // The cases cover flights and landed voxels, shown and hidden ones.
    assert!(flying > CASES / 4 && flying < CASES * 3 / 4, "{flying} of {CASES} in flight");
    assert!(hidden > CASES / 20, "{hidden} hidden");
}

#[test]
fn the_shaders_spring_is_the_rust_one() {
    let Some((device, queue)) = device() else { return };
    let (looks, _, _) = cases();
    let mut draw = Draw(0x2545_f491_4f6c_dd1d);
    let (mut springs, mut clocks) = (Vec::new(), Vec::new());
    for look in &looks {
        let since = draw.f32(0.0, 100.0);
        let pulled = draw.f32(0.0, 1.0) < 0.5;
        let spring = Spring { offset: draw.vec3(-1.0, 1.0), velocity: draw.vec3(-12.0, 12.0), since, pulled };
        springs.push(GpuSpring::from(spring));
        // A cursor ray through the voxel's home (unturned) or near it, or none; before the state, during the
        // return and long after it.
        let angle = (-look.x_axis[1]).atan2(look.x_axis[0]);
        let home = voxel_art::instancing::Turn::new(bevy::math::Quat::from_rotation_y(angle)).unturn(look.position());
        let ray = (draw.f32(0.0, 1.0) < 0.8).then(|| {
            let direction = bevy::math::Dir3::new(draw.vec3(-1.0, 1.0)).unwrap_or(bevy::math::Dir3::NEG_Z);
            bevy::math::Ray3d::new(home + draw.vec3(-1.0, 1.0) - *direction * 10.0, direction)
        });
        let clock = GpuClock::new(since + draw.f32(-0.1, 3.0), draw.f32(-7.0, 7.0), 0.0);
        clocks.push(clock.reaching(ray, draw.f32(0.2, 2.0), draw.f32(0.0, 1.0)));
    }
    let gpu = run_on_gpu(
        &device,
        &queue,
        entry("Spring", "sprung(looks[i], records[i], clocks[i])"),
        &looks,
        bytemuck::cast_slice(&springs),
        &clocks,
    );
    let mut moved = 0;
    for i in 0..CASES {
        let cpu = springs[i].sprung(&looks[i], &clocks[i]);
        let got = gpu[i];
        moved += usize::from(cpu.position().distance(looks[i].position()) > 1e-2);
        assert!(
            got.position().distance(cpu.position()) < 1e-4,
            "case {i}: at {} for {}",
            got.position(),
            cpu.position()
        );
        assert_eq!(
            (got.color, got.x_axis, got.scale_y, got.scale_z),
            (cpu.color, cpu.x_axis, cpu.scale_y, cpu.scale_z)
        );
    }
    // The cases cover springs pushed, returning and home.
    assert!(moved > CASES / 4 && moved < CASES * 3 / 4, "{moved} of {CASES} off their looks");
}
