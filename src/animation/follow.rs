//! The voxels follow the pose: each pool slot of an animated model shows one cell, so a cell that stays filled
//! keeps its voxel (slot) and only takes the new pose's colour, a cell that empties pops out (a short scale
//! tween to nothing, then its slot is vacant) and a cell that fills pops in on a free slot. A morph lays the
//! model out anew (the transition's slot order), and the map is rebuilt from that layout; poses placed while a
//! morph runs or while the pool is held (the falling style) are applied once it is over.

use std::collections::HashMap;

use bevy::prelude::*;

use crate::instancing::{
    GpuClock, GpuSprings, GpuVoxel, GpuVoxels, Slot, Turn, TweenShow, VoxelHome, VoxelPool, VoxelTarget, VoxelTween,
    VoxelTweens, grow_pool, pack_color, targets_for,
};
use crate::model::{ModelLibrary, VoxelModelAsset};
use crate::settings::VoxelSettings;
use crate::transition::{ActiveTransition, Layouts, TransitionSettings, TransitionStarted};

use super::PosePlaced;

/// Seconds a voxel takes to pop in or out.
pub const POP_SECONDS: f32 = 0.15;

/// The size a voxel pops in from, as a fraction of its box.
const POP_SPECK: f32 = 1e-3;

/// A cell, by its centre's bits (centres of one grid are computed alike, so equal cells have equal bits).
type CellKey = [u32; 3];

fn key(position: Vec3) -> CellKey {
    position.to_array().map(f32::to_bits)
}

/// Which pool slot shows which cell of the animated model on screen.
#[derive(Resource, Debug, Default)]
pub struct CellSlots {
    /// The pose the slots show (an animated model's), if any.
    model: Option<AssetId<VoxelModelAsset>>,
    /// Cell → slot.
    cells: HashMap<CellKey, u32>,
    /// Slots popping out, with the cell they leave.
    leaving: HashMap<u32, CellKey>,
    /// A pose was placed that the slots do not show yet.
    stale: bool,
}

impl CellSlots {
    /// The pose the slots show, if it is an animated model's.
    pub fn model(&self) -> Option<AssetId<VoxelModelAsset>> {
        self.model
    }

    /// Each cell shown (its centre, in the cloud's frame) and its slot.
    pub fn cells(&self) -> impl Iterator<Item = (Vec3, u32)> + '_ {
        self.cells.iter().map(|(cell, slot)| (Vec3::from_array(cell.map(f32::from_bits)), *slot))
    }

    /// Whether a placed pose waits to be shown.
    pub fn is_stale(&self) -> bool {
        self.stale
    }
}

/// A pop starting at clock time `start`: the voxel stays on its cell and scales from `from` to `to`, shown
/// throughout (its look says whether it shows once landed: not after popping out).
fn pop(position: Vec3, from: Vec3, to: Vec3, color: u32, start: f32) -> VoxelTween {
    VoxelTween {
        from: position,
        to: position,
        from_scale: from,
        to_scale: to,
        duration: POP_SECONDS,
        color_from: color,
        color_to: color,
        color_duration: POP_SECONDS,
        start,
        show: TweenShow::Always as u32,
        ..Default::default()
    }
    .ending(0.0)
}

/// Whether `model` is the pose of an animated model of the library.
fn is_pose(library: &ModelLibrary, model: AssetId<VoxelModelAsset>) -> bool {
    library.entries.iter().filter_map(|e| e.animation.as_ref()?.pose.as_ref()).any(|pose| pose.id() == model)
}

/// Rebuilds the map when a morph starts, then moves the voxels to each new pose once nothing else moves them.
pub(super) fn follow(
    mut slots: ResMut<CellSlots>,
    mut started: MessageReader<TransitionStarted>,
    mut placed: MessageReader<PosePlaced>,
    library: Res<ModelLibrary>,
    models: Res<Assets<VoxelModelAsset>>,
    settings: Res<VoxelSettings>,
    transition: Res<TransitionSettings>,
    active: Res<ActiveTransition>,
    mut pool: ResMut<VoxelPool>,
    mut looks: ResMut<GpuVoxels>,
    mut tweens: ResMut<VoxelTweens>,
    mut springs: ResMut<GpuSprings>,
    clock: Res<GpuClock>,
    mut layouts: ResMut<Layouts>,
) {
    if let Some(morph) = started.read().last() {
        // The morph gives every slot up to the new count a cell (slot i: cell i of the layout).
        pool.slots.iter_mut().for_each(|s| s.vacant = false);
        *slots = CellSlots::default();
        if let Some(model) = models.get(morph.model).filter(|_| is_pose(&library, morph.model)) {
            let laid_out = layouts.of(morph.model, model, &settings, &transition);
            slots.cells = laid_out.iter().enumerate().map(|(i, t)| (key(t.position), i as u32)).collect();
            slots.model = Some(morph.model);
        }
    }
    let model_id = slots.model;
    slots.stale |= placed.read().any(|p| Some(p.model) == model_id);
    let Some(model) = model_id
        .filter(|id| slots.stale && active.running.is_none() && !pool.held && pool.shown == Some(*id))
        .and_then(|id| models.get(id))
    else {
        return;
    };
    let targets = targets_for(model, settings.box_size, settings.hollow);
    let turn = Turn::new(active.turn());
    let CellSlots { cells, leaving, stale, .. } = &mut *slots;
    *stale = false;
    // A slot whose pop-out is over is free again.
    leaving.retain(|slot, _| pool.slots[*slot as usize].flying);
    // Cells that stay keep their voxel and take the new colour; the others pop out.
    let mut wanted: HashMap<CellKey, &VoxelTarget> = targets.iter().map(|t| (key(t.position), t)).collect();
    cells.retain(|cell, slot| {
        let i = *slot as usize;
        let look = looks.items[i];
        if let Some(target) = wanted.remove(cell) {
            looks.set(i, GpuVoxel { color: pack_color(target.color), ..look });
            return true;
        }
        let position = pool.slots[i].home.position;
        springs.clear(i, &mut pool.slots[i]);
        tweens.fly(&mut pool, i, pop(position, look.scale(), Vec3::ZERO, look.color, clock.time));
        looks.set(i, look.hidden());
        pool.slots[i].vacant = true;
        leaving.insert(*slot, *cell);
        false
    });
    // Cells that fill pop in: on the slot still leaving them, else on the lowest free slot (the pool grows).
    let mut returning: HashMap<CellKey, u32> = leaving.iter().map(|(slot, cell)| (*cell, *slot)).collect();
    let mut used = vec![false; pool.slots.len()];
    cells.values().chain(leaving.keys()).for_each(|s| used[*s as usize] = true);
    let mut next_free = 0;
    for target in targets.iter().filter(|t| wanted.contains_key(&key(t.position))) {
        let cell = key(target.position);
        let (slot, from) = match returning.remove(&cell) {
            Some(slot) => {
                leaving.remove(&slot);
                (slot, looks.items[slot as usize].scale().max(target.scale * POP_SPECK))
            }
            None => {
                while next_free < used.len() && used[next_free] {
                    next_free += 1;
                }
                if next_free == used.len() {
                    grow_pool(&mut pool, &mut looks, used.len() + 1);
                    used.push(false);
                }
                // A voxel of no size is a hidden one: a pop-in starts at a speck of its size, shown.
                (next_free as u32, target.scale * POP_SPECK)
            }
        };
        used[slot as usize] = true;
        cells.insert(cell, slot);
        let VoxelTarget { position, scale, color, part } = *target;
        let i = slot as usize;
        pool.slots[i] = Slot { home: VoxelHome { position, scale, part }, ..Slot::default() };
        pool.rehome();
        let color = pack_color(color);
        looks.set(i, turn.place(position, scale, color));
        tweens.fly(&mut pool, i, pop(position, from, scale, color, clock.time));
    }
    pool.visible = used.iter().rposition(|u| *u).map_or(0, |last| last + 1);
}
