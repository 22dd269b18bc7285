//! The voxel pool: a slot per voxel (its home cell, its repel spring, what moves it) and its look ([`GpuVoxel`]:
//! place, box, colour) in one array that is the GPU buffer's mirror. The transition and the styles write looks
//! in parallel, a chunk of slots to a task, marking the chunks they change; the render side ([`gpu`]) uploads
//! only those, and a few chunk entities draw the buffer (one instanced draw per view). No voxel is an entity:
//! a million of them cost Bevy nothing while they stand still. The pool grows to the largest model shown and
//! hides its spares. While no model is ready, random pastel boxes float in its place. The `transition` plugin
//! lays models out.

pub mod flight;
pub mod gpu;
pub mod material;
pub mod mesh;
pub mod spring;

use bevy::color::Hsla;
use bevy::math::{Mat3A, Vec3A};
use bevy::prelude::*;
use bevy::render::storage::ShaderBuffer;

pub use flight::{GpuClock, TweenShow, VoxelTween, VoxelTweens, back_out, flown, in_flight};
pub use gpu::{Detail, GpuVoxel, GpuVoxels, Mirror, Piece, VOXELS_PER_CHUNK, VoxelChunk, triangles_per_frame};
pub use material::{ChunkLayout, VoxelExtension, VoxelMaterial, pack_color, unpack_color, voxel_material};
pub use spring::{GpuSpring, GpuSprings, Spring};

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
    /// The flight clock's buffer.
    pub clock: Handle<ShaderBuffer>,
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
        // Placeholders until the pool has voxels (the render side replaces them at the pool's size), and the
        // clock, written every frame.
        let mut buffers = world.resource_mut::<Assets<ShaderBuffer>>();
        let mut buffer =
            |size| buffers.add(ShaderBuffer::with_size(size, bevy::asset::RenderAssetUsages::RENDER_WORLD));
        let voxels = buffer(VOXELS_PER_CHUNK * size_of::<GpuVoxel>());
        let flights = buffer(VOXELS_PER_CHUNK * size_of::<VoxelTween>());
        let springs = buffer(VOXELS_PER_CHUNK * size_of::<GpuSpring>());
        let clock = buffer(size_of::<GpuClock>());
        let mut material = voxel_material(voxels, flights, springs, clock.clone());
        material.extension.layout = layout;
        let material = world.resource_mut::<Assets<VoxelMaterial>>().add(material);
        Self { mesh, low_mesh, chunk_mesh, low_chunk_mesh, material, clock }
    }
}

/// The model's frame: its rotation is the model's spin. Voxels are not entities: they are slots of the
/// [`VoxelPool`], drawn from [`GpuVoxels`]; their looks are composed with the cloud's turn.
#[derive(Component, Debug, Default, Reflect)]
pub struct VoxelCloud;

/// A model's turn about y, ready to place voxels (its matrix computed once, not once per voxel).
#[derive(Clone, Copy, Debug)]
pub struct Turn {
    /// The rotation.
    pub rotation: Quat,
    matrix: Mat3A,
}

impl Turn {
    /// The turn by `rotation` (about y: voxels never tilt).
    pub fn new(rotation: Quat) -> Self {
        Self { rotation, matrix: Mat3A::from_quat(rotation) }
    }

    /// The look of a voxel at cloud-space `position` with box `scale` and colour `color`.
    #[inline]
    pub fn place(&self, position: Vec3, scale: Vec3, color: u32) -> GpuVoxel {
        let x = self.matrix.x_axis * scale.x;
        GpuVoxel {
            translation: (self.matrix * Vec3A::from(position)).into(),
            color,
            x_axis: [x.x, x.z],
            scale_y: scale.y,
            scale_z: scale.z,
        }
    }

    /// The cloud-space position of a world-space point.
    pub fn unturn(&self, world: Vec3) -> Vec3 {
        self.matrix.transpose() * world
    }
}

/// One slot of the pool: where its voxel belongs and what moves it now.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Slot {
    /// Its cell in the model shown.
    pub home: VoxelHome,
    /// Its repel spring (the GPU draws it: see [`spring`]).
    pub repel: Spring,
    /// Flying in a transition (or popping): the transition places it.
    pub flying: bool,
    /// Part of the falling pile: the pile places it.
    pub falling: bool,
    /// Holds no voxel now (a cell an animated model's pose emptied): hidden, left alone by the styles until a
    /// cell takes it again.
    pub vacant: bool,
}

impl Slot {
    /// At home, where the styles place it: not flying, not falling, not vacant.
    pub fn at_home(&self) -> bool {
        !self.flying && !self.falling && !self.vacant
    }
}

/// The voxel pool: a slot per voxel (what moves it), their looks in [`GpuVoxels`] (by slot). It grows to the
/// largest model shown; slots past the model's count are hidden.
#[derive(Resource, Debug, Default)]
pub struct VoxelPool {
    /// The slots.
    pub slots: Vec<Slot>,
    /// Slots in use (the rest are hidden).
    pub visible: usize,
    /// The model laid out now, if any (none: placeholder boxes).
    pub shown: Option<AssetId<VoxelModelAsset>>,
    /// The voxels are wanted elsewhere (the falling style drops them): an animated model's new poses wait.
    pub held: bool,
    /// Counts the times slots got new homes (whoever gives homes calls [`VoxelPool::rehome`]).
    pub homes: u64,
}

impl VoxelPool {
    /// Says that slots got new homes (what is kept about where homes lie is stale).
    pub fn rehome(&mut self) {
        self.homes += 1;
    }
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
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VoxelHome {
    /// Cell centre in the cloud's frame.
    pub position: Vec3,
    /// Box scale.
    pub scale: Vec3,
    /// Source part index.
    pub part: u32,
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

/// The most voxels the app draws: as many whole chunks as one storage binding (128 MiB) holds tweens for, about
/// 1.4M; a model with more shows its first this many (the panel says so).
pub const MAX_DRAWN: usize = (128 << 20) / size_of::<VoxelTween>() / VOXELS_PER_CHUNK * VOXELS_PER_CHUNK;

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

/// Makes sure the pool has at least `count` slots (new ones hidden), and the looks room for them.
pub fn grow_pool(pool: &mut VoxelPool, looks: &mut GpuVoxels, count: usize) {
    if pool.slots.len() < count {
        pool.slots.resize(count, Slot::default());
        looks.reserve(count);
        pool.rehome();
    }
}

fn setup(mut commands: Commands, mut pool: ResMut<VoxelPool>, mut looks: ResMut<GpuVoxels>) {
    commands.spawn((Name::new("voxel cloud"), VoxelCloud, Transform::default(), Visibility::Visible));
    grow_pool(&mut pool, &mut looks, PLACEHOLDER_COUNT);
}

/// Lays the voxels out for `targets` at once (in a cloud turned by `turn`): slot i takes target i, the rest are
/// hidden.
pub fn apply_targets(pool: &mut VoxelPool, looks: &mut GpuVoxels, targets: &[VoxelTarget], turn: Turn) {
    for slot in 0..pool.slots.len() {
        let look = match targets.get(slot) {
            Some(t) => turn.place(t.position, t.scale, pack_color(t.color)),
            None => looks.items[slot].hidden(),
        };
        looks.set(slot, look);
    }
    pool.visible = targets.len().min(pool.slots.len());
}

/// Grows the pool for the model to show, and its springs with it (so the cursor's first touch makes no buffer).
fn grow_for_current(
    mut pool: ResMut<VoxelPool>,
    mut looks: ResMut<GpuVoxels>,
    mut springs: ResMut<GpuSprings>,
    library: Res<ModelLibrary>,
    models: Res<Assets<VoxelModelAsset>>,
    settings: Res<VoxelSettings>,
) {
    let needed = library.current_ready(&models).map_or(0, |(_, m)| drawn_count(m, settings.hollow));
    grow_pool(&mut pool, &mut looks, needed);
    springs.reserve(pool.slots.len());
}

/// Logic: the pool and its layout (no GPU needed).
pub(super) fn plugin(app: &mut App) {
    app.init_resource::<VoxelPool>();
    app.init_resource::<GpuVoxels>();
    app.init_resource::<VoxelTweens>();
    app.init_resource::<GpuSprings>();
    app.init_resource::<GpuClock>();
    app.init_resource::<VoxelAssets>();
    app.register_type::<VoxelCloud>();
    app.add_systems(Startup, setup);
    app.add_systems(Update, grow_for_current.in_set(InstancingSystems::Grow));
    app.add_systems(
        PostUpdate,
        (gpu::gather::<GpuVoxels>, gpu::gather::<VoxelTweens>, gpu::gather::<GpuSprings>)
            .in_set(InstancingSystems::Gather),
    );
}

/// Rendering: the material's pipeline, the voxel buffer and the chunks that draw it.
pub fn render_plugin(app: &mut App) {
    app.add_plugins((MaterialPlugin::<VoxelMaterial>::default(), gpu::plugin));
}
