//! Preview viewports: each model's original glTF in a small viewport along the right edge, with its own
//! camera, render layer and soft coloured background, turning slowly; clicking one picks that model. An
//! animated model's tile plays its clip (`play`). A file too big for Bevy's glTF loader
//! ([`TILE_TRIANGLES`](crate::voxelize::TILE_TRIANGLES)) shows the surface of its voxels instead; a file Bevy's
//! glTF loader refuses but the core reads (WebP textures: bevy_gltf does not decode EXT_texture_webp) shows its
//! triangles untextured (`untextured`).

mod play;
mod untextured;

use bevy::app::{HierarchyPropagatePlugin, Propagate};
use bevy::camera::Viewport;
use bevy::camera::visibility::RenderLayers;
use bevy::color::Hsla;
use bevy::gltf::Gltf;
use bevy::prelude::*;
use bevy::window::PrimaryWindow;
use bevy::world_serialization::{WorldAsset, WorldAssetRoot};

use crate::input::PointerOverUi;
use crate::library::LibraryRequest;
use crate::model::{ModelLibrary, ModelStatus, VoxelModelAsset};

/// Previews get render layers 1..=MAX_PREVIEWS (layer 0 is the stage).
pub const MAX_PREVIEWS: usize = 24;
/// Largest preview tile edge, in logical pixels.
const TILE: f32 = 120.0;
/// Gap between tiles and from the window edge.
const MARGIN: f32 = 8.0;

/// A preview camera for library entry `.0`.
#[derive(Component, Debug)]
pub struct PreviewCamera(pub usize);

/// The turning root of a preview model.
#[derive(Component, Debug)]
pub struct PreviewModel(pub usize);

/// Tile rectangles (logical pixels, window space) for `n` previews in a window of `size`.
pub fn tile_rects(n: usize, size: Vec2) -> Vec<Rect> {
    if n == 0 {
        return Vec::new();
    }
    let edge = TILE.min((size.y - MARGIN) / n as f32 - MARGIN).max(24.0);
    (0..n)
        .map(|i| {
            let min = Vec2::new(size.x - MARGIN - edge, MARGIN + i as f32 * (edge + MARGIN));
            Rect::from_corners(min, min + Vec2::splat(edge))
        })
        .collect()
}

fn setup_light(mut commands: Commands) {
    let layers = RenderLayers::from_layers(&(1..=MAX_PREVIEWS).collect::<Vec<_>>());
    commands.spawn((
        Name::new("preview light"),
        DirectionalLight { illuminance: 9_000.0, shadow_maps_enabled: false, ..default() },
        Transform::from_xyz(2.0, 4.0, 5.0).looking_at(Vec3::ZERO, Vec3::Y),
        layers,
    ));
}

/// What a tile shows: the original glTF scene, a big file's voxel surface, or the core's triangles untextured.
enum TileContent {
    Scene(Handle<WorldAsset>),
    Surface(Handle<Mesh>),
    Untextured,
}

/// Spawns a camera and the original scene (a big file's voxel surface, or the core's triangles untextured when
/// Bevy could not load the file) for every loaded model that has none yet.
fn spawn_previews(
    mut commands: Commands,
    library: Res<ModelLibrary>,
    (gltfs, asset_server, models): (Res<Assets<Gltf>>, Res<AssetServer>, Res<Assets<VoxelModelAsset>>),
    (mut meshes, mut materials): (ResMut<Assets<Mesh>>, ResMut<Assets<StandardMaterial>>),
    cameras: Query<&PreviewCamera>,
) {
    let n = library.entries.len().min(MAX_PREVIEWS);
    for (i, entry) in library.entries.iter().enumerate().take(MAX_PREVIEWS) {
        if cameras.iter().any(|c| c.0 == i) || matches!(entry.status, ModelStatus::Loading | ModelStatus::Failed(_)) {
            continue;
        }
        let Some(soup) = entry.soup.as_ref() else { continue };
        let soup_bounds = || soup.bounds().unwrap_or(([-1.0; 3], [1.0; 3]));
        let (content, (lo, hi)) = match (&entry.tile_mesh, gltfs.get(&entry.gltf)) {
            (Some(mesh), _) => {
                // The surface is in the voxels' normalized space: fit their grid.
                let Some(model) = entry.latest(&models) else { continue };
                let spec = &model.spec;
                let hi = std::array::from_fn(|a| spec.origin[a] + spec.dims[a] as f32 * spec.cell[a]);
                (TileContent::Surface(mesh.clone()), (spec.origin, hi))
            }
            (None, Some(gltf)) => {
                let Some(scene) = gltf.default_scene.clone().or_else(|| gltf.scenes.first().cloned()) else { continue };
                (TileContent::Scene(scene), soup_bounds())
            }
            (None, None) if asset_server.load_state(&entry.gltf).is_failed() => {
                (TileContent::Untextured, soup_bounds())
            }
            (None, None) => continue,
        };
        let layer = RenderLayers::layer(i + 1);
        let hue = i as f32 / n.max(1) as f32 * 360.0;
        commands.spawn((
            Name::new(format!("preview camera {i}")),
            PreviewCamera(i),
            Camera3d::default(),
            Camera {
                order: 10 + i as isize,
                clear_color: ClearColorConfig::Custom(Color::from(Hsla::new(hue, 0.5, 0.7, 1.0))),
                ..default()
            },
            Transform::from_xyz(0.0, 0.9, 3.4).looking_at(Vec3::ZERO, Vec3::Y),
            layer.clone(),
        ));
        // Fit the model in a unit-ish sphere: scale its diagonal to 2.4 and centre it.
        let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
        let scale = 2.4 / (hi - lo).length().max(1e-6);
        let fit = Transform::from_scale(Vec3::splat(scale)).with_translation(-(lo + hi) / 2.0 * scale);
        let mut root = commands.spawn((
            Name::new(format!("preview {i}")),
            PreviewModel(i),
            Transform::default(),
            Visibility::default(),
            Propagate(layer),
        ));
        match content {
            TileContent::Scene(scene) => root.with_child((WorldAssetRoot(scene), fit)),
            TileContent::Surface(mesh) => {
                let material = materials.add(StandardMaterial { perceptual_roughness: 0.8, ..default() });
                root.with_child((Mesh3d(mesh), MeshMaterial3d(material), fit))
            }
            TileContent::Untextured => root.with_child((
                Mesh3d(meshes.add(untextured::mesh(soup))),
                MeshMaterial3d(materials.add(untextured::material())),
                fit,
            )),
        };
    }
}

/// Places the preview viewports along the right edge and turns the models.
fn layout_and_turn(
    window: Query<&Window, With<PrimaryWindow>>,
    library: Res<ModelLibrary>,
    time: Res<Time>,
    mut cameras: Query<(&PreviewCamera, &mut Camera)>,
    mut models: Query<(&PreviewModel, &mut Transform)>,
) {
    let Ok(window) = window.single() else { return };
    let rects = tile_rects(library.entries.len().min(MAX_PREVIEWS), window.size());
    let scale = window.scale_factor();
    for (preview, mut camera) in &mut cameras {
        let Some(rect) = rects.get(preview.0) else { continue };
        let position = (rect.min * scale).as_uvec2();
        let size = (rect.size() * scale).as_uvec2().max(UVec2::ONE);
        let fits = position.x + size.x <= window.physical_width() && position.y + size.y <= window.physical_height();
        camera.is_active = fits;
        if fits {
            camera.viewport = Some(Viewport { physical_position: position, physical_size: size, ..default() });
        }
    }
    for (preview, mut transform) in &mut models {
        let speed = if preview.0 == library.current { 1.2 } else { 0.5 };
        transform.rotate_y(speed * time.delta_secs());
    }
}

/// Hover marks the pointer as over the UI; a click on a tile picks its model.
fn pick(
    window: Query<&Window, With<PrimaryWindow>>,
    buttons: Res<ButtonInput<MouseButton>>,
    library: Res<ModelLibrary>,
    mut over: ResMut<PointerOverUi>,
    mut requests: MessageWriter<LibraryRequest>,
) {
    let Ok(window) = window.single() else { return };
    let rects = tile_rects(library.entries.len().min(MAX_PREVIEWS), window.size());
    let hit = window.cursor_position().and_then(|c| rects.iter().position(|r| r.contains(c)));
    over.preview = hit.is_some();
    if let (Some(i), true) = (hit, buttons.just_released(MouseButton::Left)) {
        requests.write(LibraryRequest::Select(i));
    }
}

pub(super) fn plugin(app: &mut App) {
    app.add_plugins(HierarchyPropagatePlugin::<RenderLayers>::new(PostUpdate));
    app.add_systems(Startup, setup_light);
    app.add_systems(Update, pick.in_set(crate::schedule::AppSystems::Pointer));
    app.add_systems(
        Update,
        (spawn_previews, layout_and_turn, play::systems()).chain().in_set(crate::schedule::AppSystems::Present),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_stack_down_the_right_edge_and_shrink_to_fit() {
        let rects = tile_rects(3, Vec2::new(1280.0, 720.0));
        assert_eq!(rects.len(), 3);
        assert!(rects.iter().all(|r| r.max.x <= 1280.0 - MARGIN + 0.01 && r.width() == TILE));
        assert!(rects[1].min.y > rects[0].max.y);
        let many = tile_rects(20, Vec2::new(1280.0, 720.0));
        assert!(many.last().unwrap().max.y <= 720.0);
    }
}
