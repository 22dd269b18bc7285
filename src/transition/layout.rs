//! Layouts: a model's voxels in the order the morph hands them to slots (slot i of the old layout flies to rank
//! i of the new one), and the few kept for reuse. A big layout is made off the frame, in a task.

use std::sync::Arc;

use bevy::prelude::*;
use bevy::tasks::Task;
use bevy::tasks::futures::check_ready;
use rayon::prelude::*;

use super::{Assignment, TransitionSettings};
use crate::instancing::{VoxelTarget, targets_for};
use crate::model::VoxelModelAsset;
use crate::settings::VoxelSettings;
use crate::threads::spawn_job;

/// A 3D Morton code of a cell-ish position (10 bits per axis).
fn morton(p: Vec3, lo: Vec3, size: f32) -> u32 {
    let spread = |v: f32| {
        let mut x = ((v / size).clamp(0.0, 1.0) * 1023.0) as u32;
        x = (x | (x << 16)) & 0x0300_00ff;
        x = (x | (x << 8)) & 0x0300_f00f;
        x = (x | (x << 4)) & 0x030c_30c3;
        (x | (x << 2)) & 0x0924_9249
    };
    let q = p - lo;
    spread(q.x) | spread(q.y) << 1 | spread(q.z) << 2
}

/// Sorts targets per the assignment so slot i of the old layout flies to a nearby rank of the new one (keys
/// computed once per target, sorted in parallel; equal keys keep their order).
pub fn order_targets(targets: &mut [VoxelTarget], assignment: Assignment) {
    match assignment {
        Assignment::Grid => {}
        Assignment::Height => {
            let angle = |p: Vec3| p.z.atan2(p.x);
            sort_by_key(targets, |t| (ordered(t.position.y), ordered(angle(t.position))));
        }
        Assignment::Morton => {
            let lo = targets.iter().fold(Vec3::splat(f32::MAX), |m, t| m.min(t.position));
            let hi = targets.iter().fold(Vec3::splat(f32::MIN), |m, t| m.max(t.position));
            let size = (hi - lo).max_element().max(1e-6);
            sort_by_key(targets, |t| morton(t.position, lo, size));
        }
    }
}

/// A float's bits in an order that agrees with `f32::total_cmp`.
fn ordered(f: f32) -> u32 {
    let bits = f.to_bits();
    if bits >> 31 == 1 { !bits } else { bits | 1 << 31 }
}

/// Sorts `targets` by `key`, stably.
fn sort_by_key<K: Ord + Send>(targets: &mut [VoxelTarget], key: impl Fn(&VoxelTarget) -> K + Sync) {
    let mut keyed: Vec<(K, u32)> = targets.par_iter().enumerate().map(|(i, t)| (key(t), i as u32)).collect();
    keyed.par_sort_unstable();
    let sorted: Vec<VoxelTarget> = keyed.iter().map(|(_, i)| targets[*i as usize]).collect();
    targets.copy_from_slice(&sorted);
}

/// The layout a model is shown with (ordered per the assignment).
pub fn layout(model: &VoxelModelAsset, settings: &VoxelSettings, transition: &TransitionSettings) -> Vec<VoxelTarget> {
    let mut targets = targets_for(model, settings.box_size, settings.hollow);
    order_targets(&mut targets, transition.assignment);
    targets
}

/// What a layout depends on besides its model's contents: the model, the box size, hollow, the assignment.
type LayoutKey = (AssetId<VoxelModelAsset>, u32, bool, Assignment);

/// Layouts of more voxels than this are made in a task, off the frame (a million take 0.2–0.3 s on two cores);
/// smaller ones in the frame that asks.
pub const MADE_OFF_FRAME_ABOVE: usize = 1 << 16;

/// The last few layouts made (a morph back to a model, a recolour and the animation's map reuse them), each
/// forgotten when its model changes, and the big one being made.
#[derive(Resource, Default)]
pub struct Layouts {
    kept: Vec<(LayoutKey, Arc<[VoxelTarget]>)>,
    making: Option<(LayoutKey, Task<Option<Arc<[VoxelTarget]>>>)>,
}

impl Layouts {
    /// Layouts kept.
    const KEPT: usize = 3;

    /// The key of model `id`'s layout with these settings.
    fn key(id: AssetId<VoxelModelAsset>, settings: &VoxelSettings, transition: &TransitionSettings) -> LayoutKey {
        (id, settings.box_size.to_bits(), settings.hollow, transition.assignment)
    }

    /// The layout kept under `key`.
    fn kept(&self, key: LayoutKey) -> Option<Arc<[VoxelTarget]>> {
        self.kept.iter().find(|(k, _)| *k == key).map(|(_, kept)| kept.clone())
    }

    /// Keeps `made` under `key` (forgetting the oldest kept when there are enough).
    fn keep(&mut self, key: LayoutKey, made: Arc<[VoxelTarget]>) -> Arc<[VoxelTarget]> {
        if self.kept.len() == Self::KEPT {
            self.kept.remove(0);
        }
        self.kept.push((key, made.clone()));
        made
    }

    /// Model `id`'s layout (`model`) with these settings, made now if it is not kept.
    pub fn of(
        &mut self,
        id: AssetId<VoxelModelAsset>,
        model: &VoxelModelAsset,
        settings: &VoxelSettings,
        transition: &TransitionSettings,
    ) -> Arc<[VoxelTarget]> {
        let key = Self::key(id, settings, transition);
        self.kept(key).unwrap_or_else(|| self.keep(key, layout(model, settings, transition).into()))
    }

    /// Model `id`'s layout if it is ready: kept, small enough to make now, or made by the task an earlier call
    /// started (`None` while a task makes it; a task for another big layout replaces it).
    pub fn ready(
        &mut self,
        id: AssetId<VoxelModelAsset>,
        model: &VoxelModelAsset,
        settings: &VoxelSettings,
        transition: &TransitionSettings,
    ) -> Option<Arc<[VoxelTarget]>> {
        let key = Self::key(id, settings, transition);
        if let Some(kept) = self.kept(key) {
            return Some(kept);
        }
        if let Some((making, task)) = &mut self.making
            && *making == key
        {
            let made = check_ready(task)?;
            self.making = None;
            // (A task that panicked leaves the layout to this frame.)
            let made = made.unwrap_or_else(|| layout(model, settings, transition).into());
            return Some(self.keep(key, made));
        }
        if model.shown_count(settings.hollow) <= MADE_OFF_FRAME_ABOVE {
            return Some(self.keep(key, layout(model, settings, transition).into()));
        }
        // The model is a bit a cell and its visible cells' colours: a copy is cheap next to its layout.
        let (model, settings, transition) = (model.clone(), settings.clone(), transition.clone());
        self.making = Some((key, spawn_job(move || Arc::from(layout(&model, &settings, &transition)))));
        None
    }

    /// Forgets the layouts of the models that changed or went.
    pub(super) fn forget(&mut self, events: &mut MessageReader<AssetEvent<VoxelModelAsset>>) {
        for event in events.read() {
            if let AssetEvent::Modified { id } | AssetEvent::Removed { id } | AssetEvent::Unused { id } = event {
                self.forget_model(*id);
            }
        }
    }

    /// Forgets model `id`'s layouts, the one being made too (its colours changed this frame: its asset event
    /// comes later).
    pub(super) fn forget_model(&mut self, id: AssetId<VoxelModelAsset>) {
        self.kept.retain(|((model, ..), _)| *model != id);
        if self.making.as_ref().is_some_and(|((model, ..), _)| *model == id) {
            self.making = None;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orders_put_layers_and_neighbourhoods_together() {
        let mut t: Vec<VoxelTarget> = [[0.0, 2.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 1.0]]
            .map(|p| VoxelTarget { position: Vec3::from(p), scale: Vec3::ONE, color: [0; 4], part: 0 })
            .to_vec();
        order_targets(&mut t, Assignment::Height);
        assert_eq!(t.iter().map(|t| t.position.y).collect::<Vec<_>>(), vec![0.0, 1.0, 2.0]);
        assert_eq!(morton(Vec3::ZERO, Vec3::ZERO, 1.0), 0);
        assert!(
            morton(Vec3::new(0.01, 0.01, 0.01), Vec3::ZERO, 1.0) < morton(Vec3::new(0.9, 0.0, 0.0), Vec3::ZERO, 1.0)
        );
    }

    #[test]
    fn a_big_layout_is_made_in_a_task_then_kept() {
        use voxel_core::{GridSize, TriangleSoup, VoxelizeOptions, shapes::cuboid, voxelize};
        bevy::tasks::AsyncComputeTaskPool::get_or_init(bevy::tasks::TaskPool::default);
        let soup = TriangleSoup::from_mesh(&cuboid([0.0; 3], [1.0; 3]), [0.5, 0.6, 0.9, 1.0]);
        let options = VoxelizeOptions { grid: GridSize::Resolution(42), hollow: false, ..Default::default() };
        let model = VoxelModelAsset(voxelize(&soup, &options).expect("a cube voxelizes"));
        let settings = VoxelSettings { hollow: false, ..Default::default() };
        let transition = TransitionSettings::default();
        let id = AssetId::<VoxelModelAsset>::default();
        let mut layouts = Layouts::default();
        assert!(model.shown_count(false) > MADE_OFF_FRAME_ABOVE);
        assert!(layouts.ready(id, &model, &settings, &transition).is_none(), "the first ask starts the task");
        let made = (0..10_000)
            .find_map(|_| {
                std::thread::sleep(std::time::Duration::from_millis(1));
                layouts.ready(id, &model, &settings, &transition)
            })
            .expect("the task sorts the layout within 10 s");
        assert_eq!(&*made, &layout(&model, &settings, &transition)[..], "the task's order is the frame's");
        assert!(Arc::ptr_eq(&made, &layouts.of(id, &model, &settings, &transition)), "and it is kept");
    }
}
