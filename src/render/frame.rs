//! What recording a frame gives back: the frame's handle (`RecordedFrame`), its timings, and
//! the readbacks' shapes (`LevelExitance`, `NonFinite`).

use super::plan::Pass;

/// Non-finite values one pass left on one object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NonFinite {
    /// `Pass::Splat` (at the samples) or `Pass::Gather` (at the vertices).
    pub pass: Pass,
    /// Index of the object in the scene.
    pub object: usize,
    /// Samples (splat) or vertices (gather) with a NaN or infinite value.
    pub count: usize,
}

/// Per-pass GPU milliseconds of one frame, in recording order.
#[derive(Clone, Debug, Default)]
pub struct FrameTimings {
    /// (pass, GPU milliseconds) per recorded pass.
    pub passes: Vec<(Pass, f64)>,
}

impl FrameTimings {
    /// Sum over the passes, in milliseconds.
    pub fn total(&self) -> f64 {
        self.passes.iter().map(|(_, ms)| ms).sum()
    }
    /// Milliseconds of `pass`, if it was recorded.
    pub fn get(&self, pass: Pass) -> Option<f64> {
        self.passes.iter().find(|(p, _)| *p == pass).map(|(_, ms)| *ms)
    }
}

/// A frame recorded into a command buffer: which passes, and where its timings will be.
#[derive(Clone, Debug)]
pub struct RecordedFrame {
    /// The passes recorded, in order (what the plan ran, counted as recorded).
    pub passes: Vec<Pass>,
    /// Slot of the timer ring that holds its timestamps.
    pub(in crate::render) slot: Option<usize>,
    /// Its number among the frames its renderer recorded, from 1.
    pub(in crate::render) generation: u64,
    /// The renderer that recorded it (`Renderer::id`).
    pub(in crate::render) renderer: usize,
}

impl RecordedFrame {
    /// Its number among the frames its renderer recorded, from 1: `read_timings` refuses a
    /// frame whose timer slot a later generation reused.
    pub fn generation(&self) -> u64 {
        self.generation
    }
}

/// An object's exitance where its last gather computed it (`Renderer::exitance_at_level`).
#[derive(Clone, Debug, PartialEq)]
pub struct LevelExitance {
    /// The level of detail gathered at (0: the whole mesh).
    pub level: usize,
    /// That level's vertices, object-relative, ascending.
    pub vertices: Vec<u32>,
    /// Their RGB exitance, in the same order.
    pub values: Vec<[f32; 3]>,
}

