//! Which of an object's receivers the gather recomputes this frame. Exitance at a receiver is a
//! sum over the samples, so a receiver gathered under this generation of the object's splat
//! holds its final value: after a change, the hierarchical gather recomputes the receivers on
//! a face the eye may see (`mesh::facing`, and the view frustum widened by the drawn level's
//! longest edge) at once, and the rest in `SWEEP_FRAMES` chunks over the frames that follow without a
//! change. A receiver that comes into view before its chunk is gathered the frame it does, so
//! every image equals a full gather's; the chunks only bound how long the unseen ones wait.

use crate::scene::needs::ObjectFacts;
use crate::scene::{GatherMode, ReceiverPolicy};
use std::fmt;

/// Frames without a change over which the receivers no eye ray reached are gathered, a chunk
/// each: after a light stops, every receiver holds its final exitance this many frames later.
pub const SWEEP_FRAMES: u32 = 8;

/// One chunk of the sweep: receivers `[chunk * n / of, (chunk + 1) * n / of)` of the level's
/// `n`, in the gather's receiver order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Sweep {
    /// This frame's chunk.
    pub chunk: u32,
    /// Chunks in the sweep.
    pub of: u32,
}

impl Sweep {
    /// The whole level in one chunk (a readback that needs every receiver).
    pub const ALL: Sweep = Sweep { chunk: 0, of: 1 };

    /// This chunk's first receiver and count among `n`.
    pub fn range(self, n: u32) -> [u32; 2] {
        let at = |c: u32| (c as u64 * n as u64 / self.of.max(1) as u64) as u32;
        let first = at(self.chunk);
        [first, at(self.chunk + 1) - first]
    }
}

/// Which receivers of an object the gather recomputes this frame (`ObjectPlan::receivers`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(tag = "scope", rename_all = "snake_case")]
pub enum ReceiverScope {
    /// Every receiver of the level drawn, whatever it held.
    Every {
        /// Why not fewer.
        why: EveryReason,
    },
    /// Among those not yet gathered under `generation` of the object's splat: the ones on a
    /// face the eye may see, and this frame's chunk of the sweep.
    VisibleFirst {
        /// The object's splat generation the gathered receivers are marked with.
        generation: u32,
        /// A new generation: the gather's stage 0 aggregates the splat anew, and every
        /// receiver is stale.
        fresh: bool,
        /// This frame's chunk of the receivers no eye ray reached; `None` on a frame of change.
        sweep: Option<Sweep>,
    },
}

/// Why the gather recomputes every receiver of an object.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EveryReason {
    /// `render.receivers = "every"`.
    Asked,
    /// Its gather is not the hierarchical one (`render.gather`).
    GatherMode,
    /// A pass after the gather (single scattering between points) reads or rescales every
    /// receiver's exitance.
    AfterGather,
    /// The host reads the exitance of every vertex (`Renderer::record_exitance`).
    HostReadsExitance,
}

impl ReceiverScope {
    /// The scope for an object with `facts`, gathered with a splat generation `generation`
    /// (`fresh`: new this frame), under `policy` and `gather`.
    pub fn of(
        facts: &ObjectFacts,
        policy: ReceiverPolicy,
        gather: GatherMode,
        generation: u32,
        fresh: bool,
        sweep: Option<Sweep>,
    ) -> Self {
        // A transport kernel's pass keeps what it needs per vertex (`receiver_view`); single
        // scattering between points does not.
        let after_gather = facts.single.iter().any(Option::is_some);
        let why = match () {
            _ if policy == ReceiverPolicy::Every => EveryReason::Asked,
            _ if gather != GatherMode::Hierarchical => EveryReason::GatherMode,
            _ if after_gather => EveryReason::AfterGather,
            _ => return ReceiverScope::VisibleFirst { generation, fresh, sweep },
        };
        ReceiverScope::Every { why }
    }

    /// Whether the gather's stage 0 aggregates the splat this frame.
    pub fn fresh(self) -> bool {
        match self {
            ReceiverScope::Every { .. } => true,
            ReceiverScope::VisibleFirst { fresh, .. } => fresh,
        }
    }
}

impl fmt::Display for ReceiverScope {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ReceiverScope::Every { why } => write!(f, "every receiver: {why}"),
            ReceiverScope::VisibleFirst { generation, sweep: None, .. } => write!(
                f,
                "the receivers on faces the eye may see (splat generation {generation}); the rest over the next {SWEEP_FRAMES} frames without a change"
            ),
            ReceiverScope::VisibleFirst { generation, sweep: Some(s), .. } => write!(
                f,
                "the stale receivers on faces the eye may see, and chunk {} of {} of the rest (splat generation {generation})",
                s.chunk + 1,
                s.of
            ),
        }
    }
}

impl fmt::Display for EveryReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            EveryReason::Asked => "render.receivers = \"every\"",
            EveryReason::GatherMode => "only the hierarchical gather keeps receivers between frames",
            EveryReason::AfterGather => "a pass after the gather reads every receiver's exitance",
            EveryReason::HostReadsExitance => "the host reads every vertex's exitance",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The chunks of a sweep cover every receiver once, whatever the count.
    #[test]
    fn the_chunks_of_a_sweep_cover_every_receiver_once() {
        for n in [0u32, 1, 7, 8, 9, 4715, 37706] {
            let mut next = 0;
            for chunk in 0..SWEEP_FRAMES {
                let [first, count] = Sweep { chunk, of: SWEEP_FRAMES }.range(n);
                assert_eq!(first, next);
                next += count;
            }
            assert_eq!(next, n);
            assert_eq!(Sweep::ALL.range(n), [0, n]);
        }
    }
}
