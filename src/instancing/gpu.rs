//! The voxels on the GPU: one storage buffer of [`GpuVoxel`]s (one per pool slot) drawn by a few chunk
//! entities that share one mesh of [`VOXELS_PER_CHUNK`] boxes and the voxel material. Bevy sees a few hundred
//! mesh entities at a million voxels, batched into one instanced draw per view (the main pass and the light's
//! shadow pass), instead of a mesh entity per voxel.
//!
//! The systems that move voxels write their looks into [`GpuVoxels`], the CPU mirror of the buffer, marking the
//! chunks they change; after `Update` those chunks become the frame's upload ranges, and extraction writes only
//! them with `RenderQueue::write_buffer`. The plugin owns the buffer: a `ShaderBuffer` asset created at its size
//! without data (so Bevy never uploads it whole), replaced by a bigger one when the pool outgrows it.

use bevy::camera::visibility::NoFrustumCulling;
use bevy::ecs::component::Mutable;
use bevy::mesh::MeshTag;
use bevy::prelude::*;
use bevy::render::render_asset::RenderAssets;
use bevy::render::renderer::RenderQueue;
use bevy::render::storage::{GpuShaderBuffer, ShaderBuffer};
use bevy::render::{Extract, ExtractSchedule, Render, RenderApp};
use bytemuck::{Pod, Zeroable};
use rayon::prelude::*;

use super::flight::{GpuClock, VoxelTweens};
use super::material::ChunkLayout;
use super::spring::GpuSprings;
use super::{VoxelAssets, VoxelCloud, VoxelMaterial, VoxelPool, mesh::chunk_mesh};
use crate::model::VoxelModelAsset;
use crate::schedule::InstancingSystems;
use crate::settings::VoxelSettings;

/// Voxels (boxes) in one chunk's mesh.
pub const VOXELS_PER_CHUNK: usize = 1024;

/// One voxel as the vertex shaders read it (32 bytes). Voxels only ever turn about y (the model's spin), so
/// the box's frame is its x axis in the xz plane (scale × (cos, −sin)), its height and its depth.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuVoxel {
    /// Centre (world space).
    pub translation: [f32; 3],
    /// sRGB RGBA8 (r | g << 8 | b << 16 | a << 24).
    pub color: u32,
    /// The box's x axis, x and z components (width × (cos, −sin) of its turn about y).
    pub x_axis: [f32; 2],
    /// Box height.
    pub scale_y: f32,
    /// Box depth.
    pub scale_z: f32,
}

impl GpuVoxel {
    /// The same voxel hidden (no size: it draws nothing), keeping its place and colour.
    pub fn hidden(&self) -> Self {
        Self { translation: self.translation, color: self.color, ..Self::default() }
    }

    /// Whether it draws anything.
    pub fn shows(&self) -> bool {
        self.scale_y != 0.0
    }

    /// Its centre.
    pub fn position(&self) -> Vec3 {
        Vec3::from(self.translation)
    }

    /// Its box size (width, height, depth; zero when hidden).
    pub fn scale(&self) -> Vec3 {
        Vec3::new(Vec2::from(self.x_axis).length(), self.scale_y, self.scale_z)
    }
}

/// What a storage buffer of the voxel material holds, one per pool slot.
pub trait Record: Pod + PartialEq + Default + Send + Sync {
    /// A number per record whose greatest in a chunk the chunk keeps (see [`Mirror::chunk_weight`]).
    fn weight(&self) -> f32;
    /// Points the material at `buffer` as this record's binding.
    fn bind(material: &mut VoxelMaterial, buffer: Handle<ShaderBuffer>);
}

impl Record for GpuVoxel {
    /// 1 when it shows: a chunk of weight 0 has nothing to draw.
    fn weight(&self) -> f32 {
        f32::from(u8::from(self.shows()))
    }

    fn bind(material: &mut VoxelMaterial, buffer: Handle<ShaderBuffer>) {
        material.extension.voxels = buffer;
    }
}

/// The CPU mirror of a storage buffer of records by pool slot (whole chunks), with the chunks changed since the
/// last gather; the plugin owns the GPU buffer.
#[derive(Debug, Default)]
pub struct Mirror<T> {
    /// The records by pool slot (as long as the buffer holds).
    pub items: Vec<T>,
    /// A flag per chunk: changed since the last gather.
    dirty: Vec<bool>,
    /// The greatest record weight per chunk, as of the last gather.
    weights: Vec<f32>,
    /// Ranges of records (start, end) the last gather found changed: this frame's uploads.
    ranges: Vec<(usize, usize)>,
    /// The GPU buffer (`None` until the pool has a voxel).
    pub buffer: Option<Handle<ShaderBuffer>>,
    /// Records the GPU buffer holds.
    buffer_len: usize,
    /// The buffer is new this frame: all of it is uploaded.
    pub whole: bool,
}

/// One chunk of a mirror handed to one task: its records, its changed flag and its weight.
pub struct Piece<'a, T> {
    /// The slot of its first record.
    pub start: usize,
    /// Its records.
    pub items: &'a mut [T],
    dirty: &'a mut bool,
    weight: &'a mut f32,
}

impl<T: Record> Piece<'_, T> {
    /// Sets record `i` of the piece, marking the chunk changed when it is (and raising its weight, as
    /// [`Mirror::set`]).
    #[inline]
    pub fn set(&mut self, i: usize, item: T) {
        if self.items[i] != item {
            self.items[i] = item;
            *self.dirty = true;
            *self.weight = self.weight.max(item.weight());
        }
    }
}

impl<T: Record> Mirror<T> {
    /// Ranges of records (start, end) to upload this frame (changed chunks, adjacent ones merged).
    pub fn dirty_ranges(&self) -> &[(usize, usize)] {
        &self.ranges
    }

    /// The greatest weight of chunk `c`'s records (0 for a chunk past the end).
    pub fn chunk_weight(&self, c: usize) -> f32 {
        self.weights.get(c).copied().unwrap_or(0.0)
    }

    /// Sets slot `slot` to `item`, marking its chunk changed when it is and raising its chunk's weight to the
    /// item's at once (the gather weighs it exactly); a slot past the buffer's end, which the pool's cap keeps from
    /// happening, is not drawn.
    pub fn set(&mut self, slot: usize, item: T) {
        let Some(old) = self.items.get_mut(slot) else { return };
        if *old != item {
            *old = item;
            let c = slot / VOXELS_PER_CHUNK;
            self.dirty[c] = true;
            self.weights[c] = self.weights[c].max(item.weight());
        }
    }

    /// The chunks as pieces, for tasks that write records in parallel (zip them with the pool's slots chunked by
    /// [`VOXELS_PER_CHUNK`]).
    pub fn pieces(&mut self) -> impl IndexedParallelIterator<Item = Piece<'_, T>> {
        let chunks = self.items.par_chunks_mut(VOXELS_PER_CHUNK);
        chunks
            .zip(self.dirty.par_iter_mut())
            .zip(self.weights.par_iter_mut())
            .enumerate()
            .map(|(c, ((items, dirty), weight))| Piece { start: c * VOXELS_PER_CHUNK, items, dirty, weight })
    }

    /// Turns the changed chunks into this frame's upload ranges and weighs them again.
    fn collect_changes(&mut self) {
        self.ranges.clear();
        for (c, dirty) in self.dirty.iter_mut().enumerate() {
            if !std::mem::take(dirty) {
                continue;
            }
            let (start, end) = (c * VOXELS_PER_CHUNK, (c + 1) * VOXELS_PER_CHUNK);
            self.weights[c] = self.items[start..end].iter().map(T::weight).fold(0.0, f32::max);
            match self.ranges.last_mut() {
                Some(last) if last.1 == start => last.1 = end,
                _ => self.ranges.push((start, end)),
            }
        }
    }

    /// Makes room for `slots` records: whole chunks and an eighth more (the buffer is replaced at the next gather;
    /// a pool grows seldom, to the largest model shown, so its buffers are not doubled: at a million voxels
    /// doubling would hold a million spare looks and tweens on both sides).
    pub fn reserve(&mut self, slots: usize) {
        if slots <= self.items.len() {
            return;
        }
        // One storage binding holds at most 128 MiB (the pool's cap keeps slots within it for every record).
        let most = (128 << 20) / size_of::<T>() / VOXELS_PER_CHUNK * VOXELS_PER_CHUNK;
        let needed = slots.div_ceil(VOXELS_PER_CHUNK).max(1);
        let chunks = needed + needed / 8;
        let len = (chunks * VOXELS_PER_CHUNK).min(most);
        self.items.resize(len, T::default());
        self.weights.resize(len / VOXELS_PER_CHUNK, 0.0);
        self.dirty.resize(len / VOXELS_PER_CHUNK, false);
    }

    /// Whether the GPU buffer is missing or smaller than the mirror.
    fn outgrown(&self) -> bool {
        self.buffer.is_none() || self.buffer_len < self.items.len()
    }
}

/// A resource holding a mirror (the looks, the flights).
pub trait Mirrored: Resource + Component<Mutability = Mutable> {
    /// Its records.
    type Item: Record;
    /// The mirror.
    fn mirror(&self) -> &Mirror<Self::Item>;
    /// The mirror, to change.
    fn mirror_mut(&mut self) -> &mut Mirror<Self::Item>;
}

/// The voxels' looks by pool slot: where each is drawn when it is not in flight.
#[derive(Resource, Debug, Default, Deref, DerefMut)]
pub struct GpuVoxels(pub Mirror<GpuVoxel>);

impl Mirrored for GpuVoxels {
    type Item = GpuVoxel;
    fn mirror(&self) -> &Mirror<GpuVoxel> {
        &self.0
    }
    fn mirror_mut(&mut self) -> &mut Mirror<GpuVoxel> {
        &mut self.0
    }
}

/// A chunk entity: it draws voxels `index × VOXELS_PER_CHUNK ..` (its `MeshTag` says which to the shader).
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
pub struct VoxelChunk(pub u32);

/// Collects this frame's changed chunks of a mirror: the upload ranges.
pub(super) fn gather<R: Mirrored>(mut mirrored: ResMut<R>) {
    mirrored.mirror_mut().collect_changes();
}

/// Replaces a mirror's GPU buffer when the pool outgrew it (the new one is uploaded whole).
fn fit_buffer<R: Mirrored>(
    mut mirrored: ResMut<R>,
    assets: Res<VoxelAssets>,
    mut buffers: ResMut<Assets<ShaderBuffer>>,
    mut materials: ResMut<Assets<VoxelMaterial>>,
) {
    let gpu = mirrored.mirror_mut();
    gpu.whole = false;
    if !gpu.items.is_empty() && gpu.outgrown() {
        let size = gpu.items.len() * size_of::<R::Item>();
        let buffer = buffers.add(ShaderBuffer::with_size(size, bevy::asset::RenderAssetUsages::RENDER_WORLD));
        if let Some(old) = gpu.buffer.replace(buffer.clone()) {
            buffers.remove(&old);
        }
        if let Some(mut material) = materials.get_mut(&assets.material) {
            R::Item::bind(&mut material, buffer);
        }
        gpu.buffer_len = gpu.items.len();
        gpu.whole = true;
    }
}

/// Voxels narrower than this many pixels on screen are drawn with the low detail shape.
pub const LOW_DETAIL_BELOW_PIXELS: f32 = 8.0;

/// Which shape the chunks draw: the style's detailed one, or the low detail one when voxels cover a few pixels.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Detail {
    /// The low detail shape.
    pub low: bool,
}

/// The `MeshTag` of chunk `index` (bit 31: it draws the low detail mesh).
pub fn chunk_tag(index: u32, low: bool) -> u32 {
    index | u32::from(low) << 31
}

/// The width in pixels of a box `size` wide at `distance` from a perspective camera with vertical field of view
/// `fov` (radians) over `height` pixels.
pub fn pixels_across(size: f32, distance: f32, fov: f32, height: f32) -> f32 {
    size * height / (2.0 * distance.max(1e-3) * (fov / 2.0).tan())
}

/// Chooses the detail from the width on screen of the model's voxels at the model's centre, seen by the first
/// active perspective camera (the lowest order).
fn choose_detail(
    pool: Res<VoxelPool>,
    models: Res<Assets<VoxelModelAsset>>,
    settings: Res<VoxelSettings>,
    cameras: Query<(&Camera, &GlobalTransform, &Projection)>,
    cloud: Query<&GlobalTransform, With<VoxelCloud>>,
    mut detail: ResMut<Detail>,
) {
    let camera = cameras.iter().filter(|(c, ..)| c.is_active).min_by_key(|(c, ..)| c.order);
    let Some((camera, at, Projection::Perspective(perspective))) = camera else { return };
    let Some(height) = camera.logical_viewport_size().map(|s| s.y) else { return };
    let model = pool.shown.and_then(|id| models.get(id));
    let cell = model.map_or(super::PLACEHOLDER_CELL, |m| m.spec.cell[0].min(m.spec.cell[2]));
    let centre = cloud.single().map_or(Vec3::ZERO, GlobalTransform::translation);
    let across = pixels_across(cell * settings.box_size, at.translation().distance(centre), perspective.fov, height);
    detail.set_if_neq(Detail { low: across < LOW_DETAIL_BELOW_PIXELS });
}

/// Whether chunk `c` has a voxel to draw: one that shows, or one in flight.
fn drawn(looks: &GpuVoxels, tweens: &VoxelTweens, clock: &GpuClock, c: usize) -> bool {
    looks.chunk_weight(c) > 0.0 || tweens.mirror().chunk_weight(c) > clock.time
}

/// Keeps one chunk entity per chunk of the pool, drawn while it has a voxel that shows, with the chosen detail.
fn fit_chunks(
    mut commands: Commands,
    gpu: Res<GpuVoxels>,
    tweens: Res<VoxelTweens>,
    clock: Res<GpuClock>,
    pool: Res<VoxelPool>,
    assets: Res<VoxelAssets>,
    detail: Res<Detail>,
    mut chunks: Query<(&VoxelChunk, &mut Visibility, &mut Mesh3d, &mut MeshTag)>,
    mut count: Local<usize>,
) {
    let mesh = if detail.low { &assets.low_chunk_mesh } else { &assets.chunk_mesh };
    let needed = pool.slots.len().div_ceil(VOXELS_PER_CHUNK);
    for c in *count..needed {
        commands.spawn((
            Name::new("voxel chunk"),
            VoxelChunk(c as u32),
            Mesh3d(mesh.clone()),
            MeshMaterial3d(assets.material.clone()),
            MeshTag(chunk_tag(c as u32, detail.low)),
            Transform::default(),
            // The boxes sit wherever their voxels are: the chunk mesh's own bounds say nothing about that.
            NoFrustumCulling,
            if drawn(&gpu, &tweens, &clock, c) { Visibility::Inherited } else { Visibility::Hidden },
        ));
    }
    *count = (*count).max(needed);
    for (chunk, mut visibility, mut chunk_mesh, mut tag) in &mut chunks {
        let shows = drawn(&gpu, &tweens, &clock, chunk.0 as usize);
        visibility.set_if_neq(if shows { Visibility::Inherited } else { Visibility::Hidden });
        if chunk_mesh.0 != *mesh {
            chunk_mesh.0 = mesh.clone();
            tag.0 = chunk_tag(chunk.0, detail.low);
        }
    }
}

/// Rebuilds the chunk meshes from the voxel shapes whenever a style changes them, and tells the material their
/// layout.
fn rebuild_chunk_meshes(
    mut events: MessageReader<AssetEvent<Mesh>>,
    assets: Res<VoxelAssets>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<VoxelMaterial>>,
) {
    let modified: Vec<AssetId<Mesh>> =
        events.read().filter_map(|e| if let AssetEvent::Modified { id } = e { Some(*id) } else { None }).collect();
    let pairs = [(&assets.mesh, &assets.chunk_mesh), (&assets.low_mesh, &assets.low_chunk_mesh)];
    let mut rebuilt = false;
    for (shape, chunk) in pairs {
        if let Some(voxel) = meshes.get(shape).filter(|_| modified.contains(&shape.id())) {
            let mesh = chunk_mesh(voxel);
            let _ = meshes.insert(chunk, mesh);
            rebuilt = true;
        }
    }
    let (Some(shape), Some(low)) = (meshes.get(&assets.mesh), meshes.get(&assets.low_mesh)) else { return };
    let layout = ChunkLayout::of(shape, low);
    if let Some(mut material) = materials.get_mut(&assets.material).filter(|m| rebuilt && m.extension.layout != layout)
    {
        material.extension.layout = layout;
    }
}

/// Render world: a whole buffer's contents waiting for its GPU buffer to exist.
#[derive(Resource)]
struct PendingUpload<R>(Option<(AssetId<ShaderBuffer>, Vec<u8>)>, std::marker::PhantomData<R>);

impl<R> Default for PendingUpload<R> {
    fn default() -> Self {
        Self(None, std::marker::PhantomData)
    }
}

/// Extraction: writes the chunks of a mirror that changed into its GPU buffer (all of it when the buffer is new).
fn upload<R: Mirrored>(
    mirrored: Extract<Res<R>>,
    buffers: Res<RenderAssets<GpuShaderBuffer>>,
    queue: Res<RenderQueue>,
    mut pending: ResMut<PendingUpload<R>>,
) {
    let gpu = mirrored.mirror();
    let Some(handle) = &gpu.buffer else { return };
    let target = buffers.get(handle.id()).filter(|_| !gpu.whole && pending.0.is_none());
    let Some(target) = target else {
        pending.0 = Some((handle.id(), bytemuck::cast_slice(&gpu.items).to_vec()));
        return;
    };
    for &(start, end) in gpu.dirty_ranges() {
        let end = end.min(gpu.items.len());
        let offset = (start * size_of::<R::Item>()) as u64;
        queue.write_buffer(&target.buffer, offset, bytemuck::cast_slice(&gpu.items[start..end]));
    }
}

/// Writes a new buffer's contents once Bevy has made it.
fn upload_pending<R: Mirrored>(
    buffers: Res<RenderAssets<GpuShaderBuffer>>,
    queue: Res<RenderQueue>,
    mut pending: ResMut<PendingUpload<R>>,
) {
    let Some((id, _)) = &pending.0 else { return };
    let Some(target) = buffers.get(*id) else { return };
    if let Some((_, bytes)) = pending.0.take() {
        queue.write_buffer(&target.buffer, 0, &bytes);
    }
}

/// Extraction: writes the frame's flight clock into its buffer.
fn upload_clock(
    clock: Extract<Res<GpuClock>>,
    assets: Extract<Res<VoxelAssets>>,
    buffers: Res<RenderAssets<GpuShaderBuffer>>,
    queue: Res<RenderQueue>,
) {
    if let Some(target) = buffers.get(assets.clock.id()) {
        queue.write_buffer(&target.buffer, 0, bytemuck::bytes_of(&**clock));
    }
}

/// Triangles the voxels submit to one pass a frame: every chunk drawn, whole (its boxes that hide included).
pub fn triangles_per_frame(world: &mut World) -> u64 {
    let assets = world.resource::<VoxelAssets>();
    let shape = if world.resource::<Detail>().low { assets.low_mesh.id() } else { assets.mesh.id() };
    let per_voxel = world.resource::<Assets<Mesh>>().get(shape).and_then(|m| m.indices()).map_or(0, |i| i.len() / 3);
    let mut chunks = world.query::<(&VoxelChunk, &Visibility)>();
    let drawn = chunks.iter(world).filter(|(_, v)| **v != Visibility::Hidden).count();
    (drawn * VOXELS_PER_CHUNK * per_voxel) as u64
}

/// The render side of the instancing plugin.
pub(super) fn plugin(app: &mut App) {
    app.init_resource::<Detail>();
    app.add_systems(
        PostUpdate,
        (
            rebuild_chunk_meshes.in_set(InstancingSystems::Meshes),
            (fit_buffer::<GpuVoxels>, fit_buffer::<VoxelTweens>, fit_buffer::<GpuSprings>)
                .in_set(InstancingSystems::Buffer),
            choose_detail.in_set(InstancingSystems::Detail),
            fit_chunks.in_set(InstancingSystems::Chunks),
        ),
    );
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else { return };
    render_app
        .init_resource::<PendingUpload<GpuVoxels>>()
        .init_resource::<PendingUpload<VoxelTweens>>()
        .init_resource::<PendingUpload<GpuSprings>>();
    render_app
        .add_systems(ExtractSchedule, (upload::<GpuVoxels>, upload::<VoxelTweens>, upload::<GpuSprings>, upload_clock));
    render_app.add_systems(
        Render,
        (upload_pending::<GpuVoxels>, upload_pending::<VoxelTweens>, upload_pending::<GpuSprings>)
            .in_set(InstancingSystems::Upload),
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::instancing::Turn;

    #[test]
    fn a_voxel_keeps_its_place_turn_size_and_colour_in_32_bytes() {
        assert_eq!(size_of::<GpuVoxel>(), 32);
        let turn = Turn::new(Quat::from_rotation_y(0.7));
        let v = turn.place(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.2, 0.24, 0.2), 0xff11_2233);
        assert_eq!(v.color, 0xff11_2233);
        assert!(v.position().distance(turn.rotation * Vec3::new(1.0, 2.0, 3.0)) < 1e-6);
        assert!(turn.unturn(v.position()).distance(Vec3::new(1.0, 2.0, 3.0)) < 1e-5);
        // The x axis is the width turned: (cos, −sin) × 0.2; the height and depth as given.
        assert!((v.x_axis[0] - 0.2 * 0.7f32.cos()).abs() < 1e-6 && (v.x_axis[1] + 0.2 * 0.7f32.sin()).abs() < 1e-6);
        assert!(v.scale().distance(Vec3::new(0.2, 0.24, 0.2)) < 1e-6);
        assert!(v.shows());
        let hidden = v.hidden();
        assert!(!hidden.shows() && hidden.x_axis == [0.0; 2] && hidden.scale_z == 0.0);
        assert_eq!((hidden.translation, hidden.color), (v.translation, v.color));
    }

    #[test]
    fn only_changed_chunks_are_uploaded_and_empty_chunks_are_not_drawn() {
        let mut gpu = GpuVoxels::default();
        gpu.reserve(3 * VOXELS_PER_CHUNK + 1);
        assert_eq!(gpu.items.len(), 4 * VOXELS_PER_CHUNK, "whole chunks");
        let mut big = GpuVoxels::default();
        big.reserve(800 * VOXELS_PER_CHUNK);
        assert_eq!(big.items.len(), 900 * VOXELS_PER_CHUNK, "and an eighth more");
        let shown = GpuVoxel { scale_y: 1.0, ..GpuVoxel::default() };
        gpu.set(5, shown);
        gpu.set(VOXELS_PER_CHUNK + 7, shown);
        // A task writing a piece marks its chunk too.
        gpu.pieces().filter(|p| p.start == 3 * VOXELS_PER_CHUNK).for_each(|mut p| p.set(0, shown));
        gpu.collect_changes();
        // Chunks 0 and 1 merge into one range; chunk 3 is another.
        assert_eq!(gpu.dirty_ranges(), &[(0, 2 * VOXELS_PER_CHUNK), (3 * VOXELS_PER_CHUNK, 4 * VOXELS_PER_CHUNK)]);
        let shows = |gpu: &GpuVoxels, c| gpu.chunk_weight(c) > 0.0;
        assert!(shows(&gpu, 0) && shows(&gpu, 1) && !shows(&gpu, 2) && shows(&gpu, 3));
        // The same value again changes nothing; hiding the last voxel of a chunk stops drawing it.
        gpu.set(5, shown);
        gpu.pieces().for_each(|mut p| p.set(0, p.items[0]));
        gpu.collect_changes();
        assert!(gpu.dirty_ranges().is_empty());
        gpu.set(VOXELS_PER_CHUNK + 7, GpuVoxel::default());
        gpu.collect_changes();
        assert_eq!(gpu.dirty_ranges(), &[(VOXELS_PER_CHUNK, 2 * VOXELS_PER_CHUNK)]);
        assert!(!shows(&gpu, 1));
        // A slot past the buffer is ignored.
        let len = gpu.items.len();
        gpu.set(len, shown);
    }

    #[test]
    fn the_detail_follows_the_size_on_screen() {
        // A 0.24 cell 17 units away under a 45° field of view over 720 pixels: about 12 pixels; 0.03: 1.5.
        let fov = std::f32::consts::FRAC_PI_4;
        assert!((pixels_across(0.24, 17.0, fov, 720.0) - 12.3).abs() < 0.1);
        assert!(pixels_across(0.03, 17.0, fov, 720.0) < LOW_DETAIL_BELOW_PIXELS);
        assert_eq!(chunk_tag(5, false), 5);
        assert_eq!(chunk_tag(5, true), 5 | 1 << 31);
    }
}
