//! When a headless capture (`--screenshot`, `--record`) begins: once the first model has settled, or with
//! `--then M`, once the morph to model M has begun. A [`Cue`] is polled every frame; it fails, saying why,
//! when no model can be shown (every file failed, or none settles within [`MAX_WAIT_FRAMES`]) and when
//! `--then` names no model of the list.

use bevy::ecs::system::SystemParam;
use bevy::prelude::*;

use crate::library::LibraryRequest;
use crate::model::{ModelLibrary, ModelStatus};
use crate::transition::{TransitionFinished, TransitionStarted};

/// Frames allowed for the first model to appear before giving up.
pub const MAX_WAIT_FRAMES: u32 = 3_000;

/// What a cue reads and asks for: the list, the morphs' starts and ends, and the switch to `--then`'s model.
#[derive(SystemParam)]
pub struct CueParams<'w, 's> {
    library: Res<'w, ModelLibrary>,
    started: MessageReader<'w, 's, TransitionStarted>,
    finished: MessageReader<'w, 's, TransitionFinished>,
    requests: MessageWriter<'w, LibraryRequest>,
}

/// Where a cue is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CueState {
    /// Not yet.
    Waiting,
    /// The capture begins (and stays begun).
    Ready,
    /// It never will: the reason.
    Failed(String),
}

/// Waits for the moment a capture begins (see the module documentation).
#[derive(Default, Debug)]
pub struct Cue {
    waited: u32,
    settled: bool,
    switched: bool,
    ready: bool,
}

impl Cue {
    /// Looks at this frame: with `then`, switches to that model once the first has settled and is ready when
    /// the morph to it has begun; without, is ready once the first model has settled.
    pub fn poll(&mut self, params: &mut CueParams, then: Option<usize>) -> CueState {
        if let Some(reason) = cannot_show(&params.library, then) {
            return CueState::Failed(reason);
        }
        let morph_began = params.started.read().count() > 0;
        self.settled |= params.finished.read().count() > 0;
        if self.ready {
            return CueState::Ready;
        }
        self.ready = match then {
            None => self.settled,
            Some(next) if !self.switched => {
                if self.settled {
                    params.requests.write(LibraryRequest::Select(next));
                    self.switched = true;
                }
                false
            }
            Some(_) => morph_began,
        };
        if self.ready {
            return CueState::Ready;
        }
        self.waited += 1;
        if self.waited > MAX_WAIT_FRAMES {
            return CueState::Failed(format!("no model was shown after {MAX_WAIT_FRAMES} frames"));
        }
        CueState::Waiting
    }
}

/// Why no capture can be taken, if it cannot: `then` names no model of the list, or every model failed.
fn cannot_show(library: &ModelLibrary, then: Option<usize>) -> Option<String> {
    let n = library.entries.len();
    if let Some(then) = then.filter(|&t| t >= n) {
        return Some(format!("--then {then}: the list has {n} models (0 to {})", n.saturating_sub(1)));
    }
    if library.entries.iter().all(|e| matches!(e.status, ModelStatus::Failed(_))) {
        let reasons: Vec<String> = library
            .entries
            .iter()
            .filter_map(|e| match &e.status {
                ModelStatus::Failed(reason) => Some(format!("{}: {reason}", e.path.display())),
                _ => None,
            })
            .collect();
        return Some(if reasons.is_empty() {
            "no models to show".to_owned()
        } else {
            format!("no model could be shown ({})", reasons.join("; "))
        });
    }
    None
}
