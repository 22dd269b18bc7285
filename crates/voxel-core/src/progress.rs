//! A voxelization watched from another thread: the stage it has reached and a request to stop. The pipeline
//! ([`voxelize_watched`](crate::voxelize::voxelize_watched)) enters each [`Stage`] in turn and stops with
//! [`VoxelError::Cancelled`] at the first stage it enters after [`Progress::cancel`]; a caller that reads the
//! file first (the app) enters [`Stage::Reading`] itself.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};

use crate::error::{Result, VoxelError};

/// The stages of reading and voxelizing a model, in order.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
#[repr(u8)]
pub enum Stage {
    /// Not started.
    #[default]
    Waiting,
    /// Reading the file into a triangle soup.
    Reading,
    /// Fitting the grid and placing the triangles on it.
    Placing,
    /// The fill and the surface shell, side by side.
    Filling,
    /// Combining them, finding the visible cells and sampling their colours.
    Coloring,
    /// Finished.
    Done,
}

impl Stage {
    const ALL: [Stage; 6] =
        [Stage::Waiting, Stage::Reading, Stage::Placing, Stage::Filling, Stage::Coloring, Stage::Done];

    /// What the stage does, in a few words (for a progress display).
    pub fn label(self) -> &'static str {
        match self {
            Stage::Waiting => "waiting",
            Stage::Reading => "reading",
            Stage::Placing => "placing triangles",
            Stage::Filling => "filling",
            Stage::Coloring => "colouring",
            Stage::Done => "done",
        }
    }

    /// The stage's place in the run, 0 (waiting) to 1 (done).
    pub fn fraction(self) -> f32 {
        self as u8 as f32 / Stage::Done as u8 as f32
    }
}

/// A handle shared by a voxelization and whoever watches it (clones share the same state).
#[derive(Clone, Debug, Default)]
pub struct Progress(Arc<State>);

#[derive(Debug, Default)]
struct State {
    stage: AtomicU8,
    cancelled: AtomicBool,
}

impl Progress {
    /// A new handle at [`Stage::Waiting`], not cancelled.
    pub fn new() -> Self {
        Self::default()
    }

    /// The stage the run has reached.
    pub fn stage(&self) -> Stage {
        Stage::ALL[usize::from(self.0.stage.load(Ordering::Relaxed)).min(Stage::ALL.len() - 1)]
    }

    /// Asks the run to stop at its next stage.
    pub fn cancel(&self) {
        self.0.cancelled.store(true, Ordering::Relaxed);
    }

    /// Whether [`Progress::cancel`] was called.
    pub fn is_cancelled(&self) -> bool {
        self.0.cancelled.load(Ordering::Relaxed)
    }

    /// Records that the run enters `stage`, or stops it with [`VoxelError::Cancelled`] if it was cancelled.
    pub fn enter(&self, stage: Stage) -> Result<()> {
        if self.is_cancelled() {
            return Err(VoxelError::Cancelled);
        }
        self.0.stage.store(stage as u8, Ordering::Relaxed);
        Ok(())
    }
}

/// Sets its flag when dropped: the work it guards is over, however it ended (the pipeline's passes, whose part
/// analysis started beside them then stops; the command line's files, whose awake workers then sleep).
pub(crate) struct Settle<'a>(pub(crate) &'a AtomicBool);

impl Drop for Settle<'_> {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stages_are_entered_in_order_until_cancelled() {
        let progress = Progress::new();
        let watcher = progress.clone();
        assert_eq!(watcher.stage(), Stage::Waiting);
        progress.enter(Stage::Reading).unwrap();
        progress.enter(Stage::Filling).unwrap();
        assert_eq!(watcher.stage(), Stage::Filling);
        assert_eq!(watcher.stage().fraction(), 0.6);
        watcher.cancel();
        assert!(matches!(progress.enter(Stage::Coloring), Err(VoxelError::Cancelled)));
        assert_eq!(watcher.stage(), Stage::Filling, "a cancelled run does not advance");
    }
}
