//! Bevy's renderer on wgpu's no-op backend: every CPU cost of a frame (extraction, batching, uploads) and no
//! GPU, no window. The frame benchmark measures with it and the app-wide ambiguity test builds the whole app
//! on it.

use std::sync::Arc;

use bevy::app::PluginGroupBuilder;
use bevy::prelude::*;
use bevy::render::RenderPlugin;
use bevy::render::renderer::{RenderAdapter, RenderAdapterInfo, RenderInstance, RenderQueue, WgpuWrapper};
use bevy::render::settings::RenderCreation;
use bevy::window::ExitCondition;
use bevy::winit::WinitPlugin;

/// Bevy's default plugins as the app sets them (task pools, assets) but without winit or a window, the renderer
/// on the no-op backend.
pub fn default_plugins(app: &mut App) -> PluginGroupBuilder {
    let asset_plugin = crate::assets::asset_plugin(app);
    DefaultPlugins
        .set(crate::threads::task_pools())
        .set(WindowPlugin {
            primary_window: None,
            exit_condition: ExitCondition::DontExit,
            close_when_requested: false,
            ..default()
        })
        .set(RenderPlugin { render_creation: renderer(), ..default() })
        .set(asset_plugin)
        .disable::<WinitPlugin>()
}

/// A renderer on wgpu's no-op backend: the adapter's features (minus the experimental ones and the
/// adapter-specific texture format features the no-op adapter claims but Bevy would then query), default limits.
pub fn renderer() -> RenderCreation {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::NOOP,
        backend_options: wgpu::BackendOptions { noop: wgpu::NoopBackendOptions { enable: true }, ..default() },
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    let adapter = bevy::tasks::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))
        .expect("wgpu's no-op backend always has an adapter");
    let mut features = adapter.features();
    features.remove(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES);
    features.remove(wgpu::Features::all_experimental_mask());
    let (device, queue) = bevy::tasks::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_features: features,
        required_limits: wgpu::Limits::default(),
        ..default()
    }))
    .expect("wgpu's no-op adapter gives a device with its own features");
    let info = adapter.get_info();
    RenderCreation::manual(
        device.into(),
        RenderQueue(Arc::new(WgpuWrapper::new(queue))),
        RenderAdapterInfo(WgpuWrapper::new(info)),
        RenderAdapter(Arc::new(WgpuWrapper::new(adapter))),
        RenderInstance(Arc::new(WgpuWrapper::new(instance))),
    )
}
