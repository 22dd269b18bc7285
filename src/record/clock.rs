//! When a recording takes its frames and how long each one shows. A recording at `fps` frames a second has one
//! slot every 1/fps s; a frame is taken at the first app frame that reaches a slot (a quarter slot early
//! counts, so the fixed 1/60 s step of a headless run lands on every other frame at 30 fps, whatever the
//! rounding of its time). GIF delays are whole centiseconds: slot k starts at ⌊100·k / fps⌋ cs, so at 30 fps the
//! delays run 3, 3, 4, 3, 3, 4… (exactly 30 frames in a second). A frame that covers several slots (a renderer
//! slower than `fps` in the window) shows for all of them, so the GIF keeps the recording's length.

use std::time::Duration;

/// The slots of one recording.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FrameClock {
    fps: u32,
    slots: u32,
    next: u32,
}

impl FrameClock {
    /// A recording of `slots` frames at `fps` frames a second.
    pub fn new(fps: u32, slots: u32) -> Self {
        Self { fps: fps.max(1), slots: slots.max(1), next: 0 }
    }

    /// The number of slots in `seconds` at `fps` (at least one).
    pub fn slots_in(fps: u32, seconds: f32) -> u32 {
        (f64::from(seconds) * f64::from(fps)).round().clamp(1.0, f64::from(u32::MAX)) as u32
    }

    /// Whether a frame is due `elapsed` after the recording began; if so, its delay in centiseconds (the slots
    /// it covers).
    pub fn tick(&mut self, elapsed: Duration) -> Option<u16> {
        if self.done() {
            return None;
        }
        let reached = (elapsed.as_secs_f64() * f64::from(self.fps) + 0.25).floor();
        if reached < f64::from(self.next) {
            return None;
        }
        let last = (reached as u32).min(self.slots - 1);
        let delay = self.centiseconds(last + 1) - self.centiseconds(self.next);
        self.next = last + 1;
        Some(u16::try_from(delay).unwrap_or(u16::MAX))
    }

    /// Whether every slot has its frame.
    pub fn done(&self) -> bool {
        self.next >= self.slots
    }

    /// When slot `slot` starts, in whole centiseconds.
    fn centiseconds(&self, slot: u32) -> u64 {
        u64::from(slot) * 100 / u64::from(self.fps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ticks at every multiple of `step` until the clock is done; the delays of the frames taken.
    fn run(clock: &mut FrameClock, step: Duration) -> Vec<u16> {
        let mut delays = Vec::new();
        let mut now = Duration::ZERO;
        while !clock.done() {
            delays.extend(clock.tick(now));
            now += step;
        }
        delays
    }

    #[test]
    fn the_fixed_headless_step_takes_every_other_frame_with_delays_of_3_3_4() {
        let step = crate::schedule::FIXED_STEP;
        let mut clock = FrameClock::new(30, FrameClock::slots_in(30, 1.0));
        let delays = run(&mut clock, step);
        assert_eq!(delays.len(), 30);
        assert_eq!(&delays[..6], &[3, 3, 4, 3, 3, 4]);
        assert_eq!(delays.iter().map(|&d| u32::from(d)).sum::<u32>(), 100);
        // Frames are taken on even app frames only.
        let mut clock = FrameClock::new(30, 4);
        let taken: Vec<bool> = (0..8).map(|n| clock.tick(step * n).is_some()).collect();
        assert_eq!(taken, [true, false, true, false, true, false, true, false]);
    }

    #[test]
    fn a_slow_renderer_covers_several_slots_and_the_length_is_kept() {
        // 12 frames a second recorded at 30: after the first, each frame covers two or three slots.
        let mut clock = FrameClock::new(30, FrameClock::slots_in(30, 2.0));
        let delays = run(&mut clock, Duration::from_secs_f64(1.0 / 12.0));
        assert_eq!(delays.len(), 25);
        assert_eq!(delays[0], 3);
        assert!(delays[1..].iter().all(|&d| (6..=10).contains(&d)), "{delays:?}");
        assert_eq!(delays.iter().map(|&d| u32::from(d)).sum::<u32>(), 200);
        assert_eq!(clock.tick(Duration::from_secs(9)), None, "a finished clock takes nothing");
    }

    #[test]
    fn slots_round_to_the_nearest_frame() {
        assert_eq!(FrameClock::slots_in(30, 4.0), 120);
        assert_eq!(FrameClock::slots_in(30, 0.01), 1);
        assert_eq!(FrameClock::slots_in(30, 0.36), 11);
    }
}
