//! Placing the voxels at home each frame: home cell + bubble wobble + repel spring, turned with the model.
//!
//! The voxels are walked as whole component slices (Bevy's contiguous query iteration), split over the
//! cores with `rayon::join`. With 100k voxels a per-entity `par_iter` closure cost more than the work it
//! wrapped (3.4 ms against 1.2 ms for the same loop over plain slices, README "Repel"), and every voxel
//! the cursor leaves alone costs one distance test.

use bevy::ecs::change_detection::{ContiguousMut, Tick};
use bevy::ecs::system::SystemChangeTick;
use bevy::math::{Mat3A, Vec3A};
use bevy::prelude::*;

use super::Style;
use crate::instancing::{RepelOffset, VoxelHome, VoxelPool, VoxelSlot, voxel_global};
use crate::settings::{RepelSettings, VoxelSettings};
use crate::style::CursorRay;
use crate::transition::ActiveTransition;

use super::AtHome;
use super::bubbles::{Bubble, BubbleSettings};
use super::repel::{RepelActive, repel_target};

/// Voxels one task places (smaller runs are not split further).
const PIECE: usize = 4096;

/// Everything placing needs besides the voxels: the model's turn, the cursor and the clock.
#[derive(Clone, Debug)]
pub struct Placement {
    /// The model's rotation.
    pub rotation: Quat,
    /// The cursor ray in the cloud's frame (`None`: no cursor, or repel off).
    pub ray: Option<Ray3d>,
    /// Repel radius (world units).
    pub radius: f32,
    /// Repel strength (push on the ray = radius × strength).
    pub strength: f32,
    /// Spring time step (seconds).
    pub dt: f32,
    /// Animation time for the bubble wobble (seconds, scaled by the speed setting).
    pub time: f32,
    /// Slots below this belong to the model shown; the rest are spares.
    pub in_model: usize,
    /// Bubble timings and wobble.
    pub bubbles: BubbleSettings,
    /// This system run's change tick (set on the transforms and visibilities written).
    pub now: Tick,
}

/// Voxels lying side by side in one table: their components as parallel slices (same length), with the
/// change ticks of the components other systems watch.
pub struct VoxelRun<'a> {
    /// Pool slots.
    pub slots: &'a [VoxelSlot],
    /// Home cells.
    pub homes: &'a [VoxelHome],
    /// Repel springs.
    pub repels: &'a mut [RepelOffset],
    /// Bubbles, when the table's voxels have them.
    pub bubbles: Option<&'a [Bubble]>,
    /// Transforms (written without change detection, as everywhere voxels are placed).
    pub transforms: &'a mut [Transform],
    /// Global transforms (what the renderer reads) …
    pub globals: &'a mut [GlobalTransform],
    /// … and their change ticks.
    pub global_ticks: &'a mut [Tick],
    /// Visibilities (bubbles vanish while burst) …
    pub visibilities: &'a mut [Visibility],
    /// … and their change ticks.
    pub visibility_ticks: &'a mut [Tick],
}

impl<'a> VoxelRun<'a> {
    /// Number of voxels.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// Whether the run is empty.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// The first `mid` voxels and the rest.
    fn split_at(self, mid: usize) -> (VoxelRun<'a>, VoxelRun<'a>) {
        let (slots, slots_b) = self.slots.split_at(mid);
        let (homes, homes_b) = self.homes.split_at(mid);
        let (repels, repels_b) = self.repels.split_at_mut(mid);
        let (bubbles, bubbles_b) = self.bubbles.map(|b| b.split_at(mid)).unzip();
        let (transforms, transforms_b) = self.transforms.split_at_mut(mid);
        let (globals, globals_b) = self.globals.split_at_mut(mid);
        let (global_ticks, global_ticks_b) = self.global_ticks.split_at_mut(mid);
        let (visibilities, visibilities_b) = self.visibilities.split_at_mut(mid);
        let (visibility_ticks, visibility_ticks_b) = self.visibility_ticks.split_at_mut(mid);
        (
            VoxelRun {
                slots,
                homes,
                repels,
                bubbles,
                transforms,
                globals,
                global_ticks,
                visibilities,
                visibility_ticks,
            },
            VoxelRun {
                slots: slots_b,
                homes: homes_b,
                repels: repels_b,
                bubbles: bubbles_b,
                transforms: transforms_b,
                globals: globals_b,
                global_ticks: global_ticks_b,
                visibilities: visibilities_b,
                visibility_ticks: visibility_ticks_b,
            },
        )
    }
}

impl Placement {
    /// Places every voxel of `run` that moves (all of them with bubbles; otherwise those the cursor reaches
    /// or whose spring still moves), over all cores. Returns whether any voxel is still off its cell.
    pub fn place(&self, run: VoxelRun) -> bool {
        if run.len() <= PIECE {
            return self.place_piece(run);
        }
        let half = run.len() / 2;
        let (a, b) = run.split_at(half);
        let (displaced_a, displaced_b) = rayon::join(|| self.place(a), || self.place(b));
        displaced_a || displaced_b
    }

    fn place_piece(&self, run: VoxelRun) -> bool {
        let turn = Mat3A::from_quat(self.rotation);
        let mut displaced = false;
        for i in 0..run.len() {
            if run.slots[i].0 as usize >= self.in_model {
                continue;
            }
            let home = &run.homes[i];
            let repel = &mut run.repels[i];
            let bubble = run.bubbles.map(|b| &b[i]);
            let target = repel_target(home.position, self.ray, self.radius, self.strength);
            let still = target == Vec3::ZERO && repel.is_rest();
            if still && bubble.is_none() {
                continue;
            }
            if !still {
                let next = repel.stepped(target, self.dt);
                displaced |= !next.is_rest();
                // Held at its target by a still cursor: nothing changes, nothing to write.
                if next == *repel && bubble.is_none() {
                    continue;
                }
                *repel = next;
            }
            let (wobble, grow, shown) = match bubble {
                Some(b) => {
                    let (grow, shown) = b.scale(&self.bubbles);
                    (b.wobble(self.time, home.part, self.bubbles.wobble) * home.scale.max_element(), grow, shown)
                }
                None => (Vec3::ZERO, 1.0, true),
            };
            let translation = Vec3::from(turn * Vec3A::from(home.position + wobble + repel.offset));
            let scale = home.scale * grow;
            // As in the transition step: the global transform is written directly (the renderer reads it; its
            // tick tells extraction it changed) and the Transform is kept in step without change detection.
            run.transforms[i] = Transform { translation, rotation: self.rotation, scale };
            run.globals[i] = voxel_global(turn, scale, translation);
            run.global_ticks[i] = self.now;
            if bubble.is_some() {
                let visibility = if shown { Visibility::Inherited } else { Visibility::Hidden };
                if run.visibilities[i] != visibility {
                    run.visibilities[i] = visibility;
                    run.visibility_ticks[i] = self.now;
                }
            }
        }
        displaced
    }
}

/// Places the voxels at home: home cell + bubble wobble + repel offset, turned with the model; bubble scale and
/// visibility. The repel springs are stepped in the same pass, and nothing runs while nothing moves.
pub(super) fn place_at_home(
    time: Res<Time>,
    settings: Res<VoxelSettings>,
    repel: Res<RepelSettings>,
    style: Res<State<Style>>,
    timing: Res<BubbleSettings>,
    cursor: Res<CursorRay>,
    active: Res<ActiveTransition>,
    pool: Res<VoxelPool>,
    mut voxels: Query<
        (
            &VoxelSlot,
            &VoxelHome,
            &mut RepelOffset,
            Option<&Bubble>,
            &mut Transform,
            &mut GlobalTransform,
            &mut Visibility,
        ),
        AtHome,
    >,
    mut springs: ResMut<RepelActive>,
    ticks: SystemChangeTick,
) {
    let ray = cursor.0.filter(|_| repel.enabled);
    if *style.get() != Style::Bubbles && ray.is_none() && !springs.0 {
        return;
    }
    let rotation = active.turn();
    let placement = Placement {
        rotation,
        // The cursor ray in the cloud's frame: homes and offsets live there, so idle voxels need no turning.
        ray: ray.map(|r| Ray3d { origin: rotation.inverse() * r.origin, direction: rotation.inverse() * r.direction }),
        radius: repel.radius,
        strength: repel.strength,
        dt: time.delta_secs().min(1.0 / 20.0),
        time: time.elapsed_secs() * settings.speed,
        in_model: pool.visible,
        bubbles: timing.clone(),
        now: ticks.this_run(),
    };
    let mut displaced = false;
    let runs = voxels.contiguous_iter_mut().expect("voxel components are stored in tables");
    for (slots, homes, repels, bubbles, transforms, globals, visibilities) in runs {
        let (repels, _) = ContiguousMut::bypass_change_detection_split(repels);
        let (transforms, _) = ContiguousMut::bypass_change_detection_split(transforms);
        let (globals, mut global_ticks) = ContiguousMut::bypass_change_detection_split(globals);
        let (visibilities, mut visibility_ticks) = ContiguousMut::bypass_change_detection_split(visibilities);
        let run = VoxelRun {
            slots,
            homes,
            repels,
            bubbles,
            transforms,
            globals,
            global_ticks: global_ticks.changed_mut(),
            visibilities,
            visibility_ticks: visibility_ticks.changed_mut(),
        };
        displaced |= placement.place(run);
    }
    springs.0 = displaced;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::style::bubbles::BubbleState;

    /// `n` voxels in a row along x (one cell apart, slot = index) with their components.
    struct Voxels {
        slots: Vec<VoxelSlot>,
        homes: Vec<VoxelHome>,
        repels: Vec<RepelOffset>,
        bubbles: Option<Vec<Bubble>>,
        transforms: Vec<Transform>,
        globals: Vec<GlobalTransform>,
        global_ticks: Vec<Tick>,
        visibilities: Vec<Visibility>,
        visibility_ticks: Vec<Tick>,
    }

    impl Voxels {
        fn row(n: usize, bubbles: Option<BubbleState>) -> Self {
            Voxels {
                slots: (0..n as u32).map(VoxelSlot).collect(),
                homes: (0..n).map(|i| VoxelHome { position: Vec3::X * i as f32, scale: Vec3::ONE, part: 0 }).collect(),
                repels: vec![RepelOffset::default(); n],
                bubbles: bubbles.map(|state| vec![Bubble { phase: 0.0, state }; n]),
                transforms: vec![Transform::default(); n],
                globals: vec![GlobalTransform::default(); n],
                global_ticks: vec![Tick::new(1); n],
                visibilities: vec![Visibility::Inherited; n],
                visibility_ticks: vec![Tick::new(1); n],
            }
        }

        fn run(&mut self) -> VoxelRun<'_> {
            VoxelRun {
                slots: &self.slots,
                homes: &self.homes,
                repels: &mut self.repels,
                bubbles: self.bubbles.as_deref(),
                transforms: &mut self.transforms,
                globals: &mut self.globals,
                global_ticks: &mut self.global_ticks,
                visibilities: &mut self.visibilities,
                visibility_ticks: &mut self.visibility_ticks,
            }
        }
    }

    /// A cursor straight down onto x = `at`, the model turned a quarter about y.
    fn placement(at: f32, in_model: usize) -> Placement {
        Placement {
            rotation: Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
            ray: Some(Ray3d::new(Vec3::new(at, 10.0, 0.0), Dir3::NEG_Y)),
            radius: 1.5,
            strength: 0.8,
            dt: 1.0 / 60.0,
            time: 0.0,
            in_model,
            bubbles: BubbleSettings::default(),
            now: Tick::new(7),
        }
    }

    #[test]
    fn only_voxels_the_cursor_reaches_move_and_are_marked_changed() {
        let mut voxels = Voxels::row(6, None);
        let p = placement(2.0, 5);
        assert!(p.place(voxels.run()));
        for i in 0..6 {
            let reached = (1..=3).contains(&i);
            assert_eq!(voxels.global_ticks[i] == Tick::new(7), reached, "voxel {i}");
            assert_eq!(voxels.repels[i].is_rest(), !reached, "voxel {i}");
        }
        // Voxel 1 is pushed towards −x, voxel 3 towards +x (cloud frame); the one under the cursor sideways.
        assert!(voxels.repels[1].offset.x < 0.0 && voxels.repels[3].offset.x > 0.0);
        // Placed in the turned cloud: home + offset, rotated a quarter turn about y.
        let expected = p.rotation * (voxels.homes[3].position + voxels.repels[3].offset);
        assert!(voxels.transforms[3].translation.distance(expected) < 1e-5);
        assert!(voxels.globals[3].translation().distance(expected) < 1e-5);
        assert_eq!(voxels.transforms[3].rotation, p.rotation);
    }

    #[test]
    fn voxels_held_off_by_a_still_cursor_stop_being_rewritten() {
        let mut voxels = Voxels::row(6, None);
        let p = placement(2.0, 5);
        for _ in 0..120 {
            p.place(voxels.run());
        }
        let held = voxels.repels[3];
        assert!(held.velocity == Vec3::ZERO && held.offset.length() > 0.1, "{held:?}");
        let later = Placement { now: Tick::new(9), ..p };
        assert!(later.place(voxels.run()), "held voxels are still off their cells");
        assert!(voxels.global_ticks.iter().all(|t| *t != Tick::new(9)), "held voxels rewritten");
    }

    #[test]
    fn spares_are_left_alone_and_springs_come_to_rest_without_a_cursor() {
        let mut voxels = Voxels::row(6, None);
        let p = placement(5.0, 5);
        assert!(p.place(voxels.run()));
        assert!(voxels.repels[5].is_rest(), "a spare slot moved");
        assert_eq!(voxels.global_ticks[5], Tick::new(1));
        let gone = Placement { ray: None, ..p };
        for _ in 0..120 {
            gone.place(voxels.run());
        }
        assert!(!gone.place(voxels.run()), "springs still moving after 2 s");
        assert!(voxels.transforms[4].translation.distance(gone.rotation * voxels.homes[4].position) < 1e-5);
    }

    #[test]
    fn long_runs_split_over_tasks_place_every_voxel_like_one_piece() {
        let n = 3 * PIECE + 17;
        let p = Placement { radius: n as f32, ..placement(n as f32 / 2.0, n) };
        let mut split = Voxels::row(n, None);
        p.place(split.run());
        let mut whole = Voxels::row(n, None);
        p.place_piece(whole.run());
        assert_eq!(split.repels, whole.repels);
        assert_eq!(split.transforms, whole.transforms);
        assert!(split.global_ticks.iter().all(|t| *t == Tick::new(7)));
    }

    #[test]
    fn burst_bubbles_are_hidden_and_whole_ones_wobble() {
        let mut gone = Voxels::row(3, Some(BubbleState::Gone(0.5)));
        let far = Placement { ray: None, time: 0.7, ..placement(0.0, 3) };
        far.place(gone.run());
        assert!(gone.visibilities.iter().all(|v| *v == Visibility::Hidden));
        assert!(gone.visibility_ticks.iter().all(|t| *t == Tick::new(7)));
        let mut whole = Voxels::row(3, Some(BubbleState::Whole));
        far.place(whole.run());
        assert!(whole.visibilities.iter().all(|v| *v == Visibility::Inherited));
        assert!(whole.visibility_ticks.iter().all(|t| *t == Tick::new(1)), "unchanged visibility marked changed");
        let off_cell = whole.transforms[1].translation.distance(far.rotation * whole.homes[1].position);
        assert!(off_cell > 1e-3 && off_cell < 0.3, "wobble {off_cell}");
    }
}
