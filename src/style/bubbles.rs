//! Bubbles: every voxel is a glossy sphere wobbling around its cell with its own phase (parts wobble by
//! different amounts); bubbles near the cursor burst — a quick swell, then gone — and re-form at their cell
//! after a short random delay with a pop-in.

use bevy::prelude::*;

use rayon::prelude::*;

use super::Style;
use crate::instancing::{GpuVoxels, Turn, VoxelPool, back_out};
use crate::rng::Rng;
use crate::schedule::StyleSystems;
use crate::settings::{RepelSettings, VoxelSettings};
use crate::style::CursorRay;
use crate::transition::ActiveTransition;

use crate::instancing::spring::away_from_ray;

/// Timings of a burst.
#[derive(Resource, Clone, Debug, PartialEq, Reflect)]
#[reflect(Resource)]
pub struct BubbleSettings {
    /// Seconds a bubble swells before vanishing.
    pub burst: f32,
    /// The shortest wait before it re-forms.
    pub reform_min: f32,
    /// The longest wait before it re-forms.
    pub reform_max: f32,
    /// Seconds the pop-in takes.
    pub form: f32,
    /// Wobble amplitude as a fraction of the cell.
    pub wobble: f32,
}

impl Default for BubbleSettings {
    fn default() -> Self {
        Self { burst: 0.12, reform_min: 0.4, reform_max: 1.5, form: 0.35, wobble: 0.12 }
    }
}

/// Where a bubble is in its life.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BubbleState {
    /// Wobbling at its cell.
    Whole,
    /// Swelling for this many seconds so far.
    Bursting(f32),
    /// Gone; re-forms after this many more seconds.
    Gone(f32),
    /// Popping back in for this many seconds so far.
    Forming(f32),
}

/// A voxel's bubble: its wobble phase and burst state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bubble {
    /// Wobble phase (radians).
    pub phase: f32,
    /// Burst state.
    pub state: BubbleState,
}

impl Bubble {
    /// The wobble offset (fraction of a cell) at time `t` for a voxel of `part`.
    pub fn wobble(&self, t: f32, part: u32, amplitude: f32) -> Vec3 {
        // Per-part motion: parts wobble by different amounts and speeds.
        let a = amplitude * (1.0 + 0.6 * (part % 3) as f32);
        let w = 1.0 + 0.35 * (part % 4) as f32;
        let p = self.phase;
        Vec3::new((t * 1.7 * w + p).sin(), (t * 2.3 * w + p * 1.3).sin(), (t * 1.9 * w + p * 0.7).cos()) * a
    }

    /// Scale factor and visibility now.
    pub fn scale(&self, timing: &BubbleSettings) -> (f32, bool) {
        match self.state {
            BubbleState::Whole => (1.0, true),
            BubbleState::Bursting(t) => (1.0 + 0.6 * (t / timing.burst).min(1.0), true),
            BubbleState::Gone(_) => (0.0, false),
            BubbleState::Forming(t) => (back_out(t / timing.form, 2.0).max(0.0), true),
        }
    }
}

/// Every slot's bubble, by slot (while the style is on).
#[derive(Resource, Debug, Default)]
pub struct Bubbles(pub Vec<Bubble>);

/// Gives a bubble to every slot that has none: all of them on entering the style, then the slots the pool
/// grows by.
fn give_bubbles(mut commands: Commands, pool: Res<VoxelPool>, bubbles: Option<ResMut<Bubbles>>) {
    let new = |slot: usize| {
        let phase = Rng::new(slot as u64 ^ 0xb0bb1e).f32() * std::f32::consts::TAU;
        Bubble { phase, state: BubbleState::Whole }
    };
    match bubbles {
        Some(mut bubbles) if bubbles.0.len() < pool.slots.len() => {
            let have = bubbles.0.len();
            bubbles.0.extend((have..pool.slots.len()).map(new));
        }
        Some(_) => {}
        None => commands.insert_resource(Bubbles((0..pool.slots.len()).map(new).collect())),
    }
}

/// Leaving the style: the bubbles go, and every voxel at home is back on its cell (no wobble, no
/// swell), shown even if it had burst.
fn take_bubbles(
    mut commands: Commands,
    pool: Res<VoxelPool>,
    active: Res<ActiveTransition>,
    mut looks: ResMut<GpuVoxels>,
) {
    commands.remove_resource::<Bubbles>();
    let turn = Turn::new(active.turn());
    // A voxel in flight is placed by its tween; a vacant slot stays hidden.
    for (i, slot) in pool.slots.iter().enumerate().take(pool.visible).filter(|(_, s)| s.at_home()) {
        let look = turn.place(slot.home.position, slot.home.scale, looks.items[i].color);
        looks.set(i, look);
    }
}

/// Advances bursts; whole bubbles near the cursor burst.
fn burst(
    time: Res<Time>,
    settings: Res<VoxelSettings>,
    timing: Res<BubbleSettings>,
    ray: Res<CursorRay>,
    repel: Res<RepelSettings>,
    active: Res<ActiveTransition>,
    pool: Res<VoxelPool>,
    mut bubbles: ResMut<Bubbles>,
    mut frame: Local<u64>,
) {
    *frame += 1;
    let dt = time.delta_secs() * settings.speed;
    let turn = active.turn();
    let radius = repel.radius * 0.6;
    let seed = *frame;
    bubbles.0.par_iter_mut().zip(&pool.slots).enumerate().filter(|(_, (_, s))| s.at_home()).for_each(
        |(slot, (bubble, at))| {
            bubble.state = match bubble.state {
                BubbleState::Whole => {
                    let near = ray.0.is_some_and(|r| away_from_ray(turn * at.home.position, r).length() < radius);
                    if near { BubbleState::Bursting(0.0) } else { BubbleState::Whole }
                }
                BubbleState::Bursting(t) if t + dt >= timing.burst => {
                    let wait = timing.reform_min
                        + (timing.reform_max - timing.reform_min) * Rng::new(seed ^ (slot as u64) << 20).f32();
                    BubbleState::Gone(wait)
                }
                BubbleState::Bursting(t) => BubbleState::Bursting(t + dt),
                BubbleState::Gone(left) if left - dt <= 0.0 => BubbleState::Forming(0.0),
                BubbleState::Gone(left) => BubbleState::Gone(left - dt),
                BubbleState::Forming(t) if t + dt >= timing.form => BubbleState::Whole,
                BubbleState::Forming(t) => BubbleState::Forming(t + dt),
            };
        },
    );
}

pub(super) fn plugin(app: &mut App) {
    app.init_resource::<BubbleSettings>();
    app.add_systems(OnEnter(Style::Bubbles), give_bubbles);
    app.add_systems(OnExit(Style::Bubbles), take_bubbles);
    app.add_systems(
        Update,
        (give_bubbles.in_set(StyleSystems::Give), burst.run_if(resource_exists::<Bubbles>).in_set(StyleSystems::Burst))
            .run_if(in_state(Style::Bubbles)),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_burst_swells_vanishes_and_pops_back() {
        let t = BubbleSettings::default();
        let b = |state| Bubble { phase: 0.0, state };
        assert_eq!(b(BubbleState::Whole).scale(&t), (1.0, true));
        assert!(b(BubbleState::Bursting(t.burst)).scale(&t).0 > 1.5);
        assert_eq!(b(BubbleState::Gone(0.3)).scale(&t), (0.0, false));
        assert!(b(BubbleState::Forming(0.0)).scale(&t).0.abs() < 1e-6);
        assert!((b(BubbleState::Forming(t.form)).scale(&t).0 - 1.0).abs() < 1e-6);
    }

    #[test]
    fn parts_wobble_differently_and_stay_small() {
        let bubble = Bubble { phase: 0.4, state: BubbleState::Whole };
        let a = bubble.wobble(1.0, 0, 0.12);
        let b = bubble.wobble(1.0, 2, 0.12);
        assert!(a.max_element() <= 0.12 + 1e-6 && b.length() > a.length() * 0.5);
        assert_ne!(a, b);
    }
}
