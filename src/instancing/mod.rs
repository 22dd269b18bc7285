//! The voxel pool: one entity per voxel (its transform, its colour packed in its `MeshTag`, its visibility),
//! which the transition and the styles move; none of them is a mesh entity. The render side ([`gpu`]) copies
//! what changed into one storage buffer drawn by a few chunk entities (one instanced draw per view). The pool
//! grows to the largest model shown and hides its spares. While no model is ready, random pastel boxes float in
//! its place. The `transition` plugin lays models out.

pub mod gpu;
pub mod material;
pub mod mesh;

use bevy::color::Hsla;
use bevy::math::{Affine3A, Mat3A};
use bevy::mesh::MeshTag;
use bevy::prelude::*;
use bevy::render::storage::ShaderBuffer;

pub use gpu::{Detail, GpuVoxel, GpuVoxels, VOXELS_PER_CHUNK, VoxelChunk, triangles_per_frame};
pub use material::{ChunkLayout, VoxelExtension, VoxelMaterial, pack_color, unpack_color, voxel_material};

use voxel_core::Voxel;

use crate::model::{ModelLibrary, VoxelModelAsset};
use crate::rng::Rng;
use crate::schedule::InstancingSystems;
use crate::settings::VoxelSettings;

/// The voxels' shape (detailed and low detail), the chunk meshes repeating them and the material (made when
/// the plugin is built, so styles can dress them from the first state transition on).
#[derive(Resource, Debug, Clone)]
pub struct VoxelAssets {
    /// The voxel shape (the style's: a rounded box to start with).
    pub mesh: Handle<Mesh>,
    /// The shape drawn when a voxel covers a few pixels (the box's three faces towards the viewer).
    pub low_mesh: Handle<Mesh>,
    /// [`VOXELS_PER_CHUNK`] copies of the shape, the mesh chunk entities draw …
    pub chunk_mesh: Handle<Mesh>,
    /// … and of the low detail shape.
    pub low_chunk_mesh: Handle<Mesh>,
    /// The one material.
    pub material: Handle<VoxelMaterial>,
}

impl FromWorld for VoxelAssets {
    fn from_world(world: &mut World) -> Self {
        let roundness =
            world.get_resource::<VoxelSettings>().map_or(VoxelSettings::default().roundness, |s| s.roundness);
        let (shape, low) = (mesh::rounded_box(roundness, 2), mesh::facing_box(false));
        let layout = ChunkLayout::of(&shape, &low);
        let (chunk, low_chunk) = (mesh::chunk_mesh(&shape), mesh::chunk_mesh(&low));
        let mut meshes = world.resource_mut::<Assets<Mesh>>();
        let (mesh, low_mesh) = (meshes.add(shape), meshes.add(low));
        let (chunk_mesh, low_chunk_mesh) = (meshes.add(chunk), meshes.add(low_chunk));
        // A placeholder until the pool has voxels (the render side replaces it at the pool's size).
        let size = VOXELS_PER_CHUNK * size_of::<GpuVoxel>();
        let voxels = world
            .resource_mut::<Assets<ShaderBuffer>>()
            .add(ShaderBuffer::with_size(size, bevy::asset::RenderAssetUsages::RENDER_WORLD));
        let mut material = voxel_material(voxels);
        material.extension.layout = layout;
        let material = world.resource_mut::<Assets<VoxelMaterial>>().add(material);
        Self { mesh, low_mesh, chunk_mesh, low_chunk_mesh, material }
    }
}

/// The model's frame: its rotation is the model's spin. Voxels are not its children (a hierarchy of 100k
/// children costs milliseconds of transform propagation a frame); their transforms are composed with it.
#[derive(Component, Debug, Default, Reflect)]
pub struct VoxelCloud;

/// A voxel's world transform for cloud-space `position` and `scale` in a cloud turned by `rotation`.
pub fn voxel_transform(rotation: Quat, position: Vec3, scale: Vec3) -> Transform {
    Transform { translation: rotation * position, rotation, scale }
}

/// The global transform of a voxel at world `translation` with box `scale`, in a cloud turned by `turn` (the
/// same affine as `GlobalTransform::from(voxel_transform(..))`, with the cloud's rotation matrix computed once
/// per frame by the caller). Voxels have no parent, so the systems that move them write this directly.
#[inline]
pub fn voxel_global(turn: Mat3A, scale: Vec3, translation: Vec3) -> GlobalTransform {
    GlobalTransform::from(Affine3A {
        matrix3: Mat3A::from_cols(turn.x_axis * scale.x, turn.y_axis * scale.y, turn.z_axis * scale.z),
        translation: translation.into(),
    })
}

/// A voxel entity and its index in the pool.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq, Reflect)]
pub struct VoxelSlot(pub u32);

/// The pool's bookkeeping.
#[derive(Resource, Debug, Default)]
pub struct VoxelPool {
    /// Voxel entities, by slot.
    pub slots: Vec<Entity>,
    /// Slots in use (the rest are hidden).
    pub visible: usize,
    /// The model laid out now, if any (none: placeholder boxes).
    pub shown: Option<AssetId<VoxelModelAsset>>,
    /// The voxels are wanted elsewhere (the falling style drops them): an animated model's new poses wait.
    pub held: bool,
}

/// Where one voxel of a model goes: centre in cloud space, scale and colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelTarget {
    /// Cell centre.
    pub position: Vec3,
    /// Box scale (cell size × box size).
    pub scale: Vec3,
    /// sRGB RGBA8.
    pub color: [u8; 4],
    /// Source part of the model (styles may animate parts differently).
    pub part: u32,
}

/// Where a voxel belongs in the model shown: its cell centre (cloud space), box scale and source part. The
/// transition sets it; styles animate around it.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq, Reflect)]
pub struct VoxelHome {
    /// Cell centre in the cloud's frame.
    pub position: Vec3,
    /// Box scale.
    pub scale: Vec3,
    /// Source part index.
    pub part: u32,
}

/// A slot inside the model's range that holds no voxel now (a cell an animated model's pose emptied): hidden,
/// and left alone by the styles until a cell takes it again.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq, Eq, Reflect)]
pub struct Vacant;

/// Mouse-repel displacement of a voxel (in the cloud's frame, like its home) and its spring velocity.
#[derive(Component, Clone, Copy, Debug, Default, PartialEq, Reflect)]
pub struct RepelOffset {
    /// Current displacement.
    pub offset: Vec3,
    /// Current velocity of the displacement.
    pub velocity: Vec3,
}

/// The floor height under a model (a little below its lowest cell).
pub fn floor_height(model: &voxel_core::VoxelModel) -> f32 {
    model.spec.origin[1] - 1.0
}

/// Where voxel `v` of `model` goes, with boxes `box_size` of a cell.
pub fn voxel_target(model: &voxel_core::VoxelModel, v: &Voxel, box_size: f32) -> VoxelTarget {
    let scale = Vec3::from(model.spec.cell) * box_size;
    VoxelTarget { position: Vec3::from(model.center(v)), scale, color: v.color, part: v.part }
}

/// The most voxels the app draws: a model with more shows its first this many (the panel says so).
pub const MAX_DRAWN: usize = 2_000_000;

/// How many voxels of `model` are drawn (only its visible ones when `hollow`; at most [`MAX_DRAWN`]).
pub fn drawn_count(model: &VoxelModelAsset, hollow: bool) -> usize {
    model.shown_count(hollow).min(MAX_DRAWN)
}

/// The voxel layout of `model` (only its visible voxels when `hollow`, at most [`MAX_DRAWN`]) with boxes
/// `box_size` of a cell.
pub fn targets_for(model: &VoxelModelAsset, box_size: f32, hollow: bool) -> Vec<VoxelTarget> {
    model.shown(hollow).take(MAX_DRAWN).map(|v| voxel_target(model, &v, box_size)).collect()
}

/// Number of placeholder boxes shown before any model is ready.
pub const PLACEHOLDER_COUNT: usize = 240;

/// The cell of the placeholder boxes.
pub const PLACEHOLDER_CELL: f32 = 0.24;

/// Random pastel boxes around the origin (the article's start-up state).
pub fn placeholder_targets(count: usize, seed: u64) -> Vec<VoxelTarget> {
    let mut rng = Rng::new(seed);
    let cell = PLACEHOLDER_CELL;
    (0..count)
        .map(|_| {
            let mut coord = || ((rng.f32() - 0.5) * 6.0 / cell).round() * cell;
            let position = Vec3::new(coord(), coord(), coord());
            let color = Color::from(Hsla::new(rng.f32() * 360.0, 0.8, 0.8, 1.0)).to_srgba().to_u8_array();
            VoxelTarget { position, scale: Vec3::splat(cell), color, part: 0 }
        })
        .collect()
}

fn voxel_bundle(slot: u32) -> impl Bundle {
    (
        Name::new("voxel"),
        VoxelSlot(slot),
        MeshTag(0),
        VoxelHome::default(),
        RepelOffset::default(),
        Transform::default(),
        Visibility::Hidden,
    )
}

/// Makes sure the pool has at least `count` slots.
pub fn grow_pool(commands: &mut Commands, pool: &mut VoxelPool, count: usize) {
    while pool.slots.len() < count {
        let slot = pool.slots.len() as u32;
        pool.slots.push(commands.spawn(voxel_bundle(slot)).id());
    }
}

fn setup(mut commands: Commands, mut pool: ResMut<VoxelPool>) {
    commands.spawn((Name::new("voxel cloud"), VoxelCloud, Transform::default(), Visibility::Visible));
    grow_pool(&mut commands, &mut pool, PLACEHOLDER_COUNT);
}

/// The voxels' query: slot, transform, colour, visibility (the cloud excluded).
pub type VoxelQuery<'w, 's> = Query<
    'w,
    's,
    (&'static VoxelSlot, &'static mut Transform, &'static mut MeshTag, &'static mut Visibility),
    Without<VoxelCloud>,
>;

/// Lays the voxels out for `targets` at once (in a cloud turned by `rotation`): slot i takes target i, the
/// rest are hidden.
pub fn apply_targets(pool: &mut VoxelPool, targets: &[VoxelTarget], rotation: Quat, voxels: &mut VoxelQuery) {
    for (slot, mut transform, mut tag, mut visibility) in voxels.iter_mut() {
        match targets.get(slot.0 as usize) {
            Some(t) => {
                *transform = voxel_transform(rotation, t.position, t.scale);
                tag.0 = pack_color(t.color);
                visibility.set_if_neq(Visibility::Inherited);
            }
            None => {
                visibility.set_if_neq(Visibility::Hidden);
            }
        }
    }
    pool.visible = targets.len().min(pool.slots.len());
}

/// Grows the pool for the model to show.
fn grow_for_current(
    mut commands: Commands,
    mut pool: ResMut<VoxelPool>,
    library: Res<ModelLibrary>,
    models: Res<Assets<VoxelModelAsset>>,
    settings: Res<VoxelSettings>,
) {
    let needed = library.current_ready(&models).map_or(0, |(_, m)| drawn_count(m, settings.hollow));
    if needed > pool.slots.len() {
        grow_pool(&mut commands, &mut pool, needed);
    }
}

/// Logic: the pool and its layout (no GPU needed).
pub(super) fn plugin(app: &mut App) {
    app.init_resource::<VoxelPool>();
    app.init_resource::<VoxelAssets>();
    app.register_type::<VoxelSlot>()
        .register_type::<VoxelCloud>()
        .register_type::<VoxelHome>()
        .register_type::<Vacant>()
        .register_type::<RepelOffset>();
    app.add_systems(Startup, setup);
    app.add_systems(Update, grow_for_current.in_set(InstancingSystems::Grow));
}

/// Rendering: the material's pipeline, the voxel buffer and the chunks that draw it.
pub fn render_plugin(app: &mut App) {
    app.add_plugins((MaterialPlugin::<VoxelMaterial>::default(), gpu::plugin));
}
