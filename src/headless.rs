//! The app without a window or GPU: `MinimalPlugins`, asset and glTF loading, the [`LogicPlugin`], and a
//! manual time step of one fixed step a frame. Logic tests and the frame benchmark build on it.

use bevy::image::{CompressedImageFormatSupport, CompressedImageFormats};
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;

use crate::LogicPlugin;
use crate::config::AppArgs;

/// A headless app with the logic plugins, configured by `args` as the app is; input resources are plain
/// (tests press keys by hand).
pub fn headless_app(args: &AppArgs) -> App {
    let mut app = App::new();
    let asset_plugin = crate::assets::asset_plugin(&mut app);
    app.add_plugins((
        MinimalPlugins.set(crate::threads::task_pools()),
        bevy::state::app::StatesPlugin,
        TransformPlugin,
        asset_plugin,
        bevy::mesh::MeshPlugin,
        bevy::image::ImagePlugin::default(),
        bevy::world_serialization::WorldSerializationPlugin,
        bevy::gltf::GltfPlugin::default(),
    ));
    // The asset types the renderer's plugins would register (the voxel material and its buffer included).
    app.init_asset::<StandardMaterial>();
    app.init_asset::<crate::instancing::VoxelMaterial>();
    app.init_asset::<bevy::render::storage::ShaderBuffer>();
    app.insert_resource(CompressedImageFormatSupport(CompressedImageFormats::NONE));
    app.init_resource::<ButtonInput<KeyCode>>();
    app.init_resource::<ButtonInput<MouseButton>>();
    app.insert_resource(TimeUpdateStrategy::ManualDuration(crate::schedule::FIXED_STEP));
    args.configure(&mut app);
    app.add_plugins(LogicPlugin);
    app.finish();
    app.cleanup();
    app
}
