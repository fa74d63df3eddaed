//! What was recorded, counted per pipeline: every dispatch and draw a pipeline records adds one
//! to its shader's count. Tests read it to check what a frame really ran, rather than what the
//! plan says it would; counting is a map update per command, nothing on the GPU.

use std::collections::BTreeMap;
use std::sync::Mutex;

/// Dispatches and draws recorded so far, by the shader that recorded them ("splat.comp",
/// "shade.vert", "shadow.vert").
#[derive(Debug, Default)]
pub struct RecordCounter {
    counts: Mutex<BTreeMap<String, u64>>,
}

impl RecordCounter {
    /// One more command recorded by `shader`'s pipeline.
    pub fn add(&self, shader: &str) {
        if let Ok(mut counts) = self.counts.lock() {
            *counts.entry(shader.to_string()).or_default() += 1;
        }
    }

    /// The counts so far; subtract two snapshots for what happened between them.
    pub fn snapshot(&self) -> RecordCounts {
        RecordCounts(self.counts.lock().map(|c| c.clone()).unwrap_or_default())
    }
}

/// A snapshot of a `RecordCounter`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RecordCounts(pub BTreeMap<String, u64>);

impl RecordCounts {
    /// Commands recorded by `shader`'s pipeline.
    pub fn get(&self, shader: &str) -> u64 {
        self.0.get(shader).copied().unwrap_or(0)
    }

    /// What was recorded after `earlier` was taken.
    pub fn since(&self, earlier: &RecordCounts) -> RecordCounts {
        RecordCounts(self.0.iter().map(|(k, v)| (k.clone(), v - earlier.get(k))).filter(|(_, v)| *v > 0).collect())
    }

    /// Compute dispatches among them (shaders ending in ".comp").
    pub fn dispatches(&self) -> u64 {
        self.0.iter().filter(|(k, _)| k.ends_with(".comp")).map(|(_, v)| v).sum()
    }
}
