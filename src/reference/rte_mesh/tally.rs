//! The tally: what leaves through each vertex's cell, per photon and channel, summed into the
//! exitance and its standard error.

use crate::reference::truth::LIT_FLOOR;

/// Per vertex and channel, the sums of the photons' scores and of their squares; per channel,
/// the walks lost.
pub(super) struct Tally {
    pub(super) sum: Vec<[f64; 3]>,
    pub(super) sum2: Vec<[f64; 3]>,
    pub(super) lost: [u64; 3],
}

/// Adds one chunk's exits (each photon's score at a vertex and channel once) and lost walks to
/// the tally.
pub(super) fn add_exits(tally: &mut Tally, (exits, lost): (Vec<Exit>, [u64; 3])) {
    for Exit { vertex, channel, weight } in exits {
        tally.sum[vertex][channel] += weight;
        tally.sum2[vertex][channel] += weight * weight;
    }
    (0..3).for_each(|c| tally.lost[c] += lost[c]);
}

/// Per-vertex exitance and standard error after `n` photons, and the precision reached
/// ([`ObjectExitance::relative_stderr`](super::ObjectExitance::relative_stderr)).
pub(super) fn summarize(tally: &Tally, cells: &[f64], n: u64) -> (Vec<[f64; 3]>, Vec<[f64; 3]>, f64) {
    let nf = n.max(1) as f64;
    let mut exitance = vec![[0.0; 3]; cells.len()];
    let mut stderr = vec![[0.0; 3]; cells.len()];
    for v in 0..cells.len() {
        for c in 0..3 {
            let mean = tally.sum[v][c] / nf;
            let var = ((tally.sum2[v][c] / nf - mean * mean) * nf / (nf - 1.0).max(1.0)).max(0.0);
            exitance[v][c] = mean / cells[v];
            stderr[v][c] = (var / nf).sqrt() / cells[v];
        }
    }
    let rel = relative_stderr(&exitance, &stderr);
    (exitance, stderr, rel)
}

/// Per channel, the RMS standard error over the lit vertices over their mean exitance; the
/// largest of the three (infinite where nothing is lit yet).
pub fn relative_stderr(exitance: &[[f64; 3]], stderr: &[[f64; 3]]) -> f64 {
    (0..3)
        .map(|c| {
            let floor = LIT_FLOOR * exitance.iter().map(|m| m[c]).fold(0.0, f64::max);
            let (mut n, mut sum, mut sum2) = (0usize, 0.0, 0.0);
            for (m, s) in exitance.iter().zip(stderr) {
                if m[c] > 0.0 && m[c] >= floor {
                    n += 1;
                    sum += m[c];
                    sum2 += s[c] * s[c];
                }
            }
            if n == 0 { f64::INFINITY } else { (sum2 / n as f64).sqrt() / (sum / n as f64) }
        })
        .fold(0.0, f64::max)
}

pub(super) use crate::mesh::patches::cell_areas;

/// Weight that left through the cell of `vertex` in `channel` (scene units: flux).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Exit {
    pub(super) vertex: usize,
    pub(super) channel: usize,
    pub(super) weight: f64,
}

/// Sums the exits from `first` on (one photon's) that share a vertex and channel into one: the
/// photon's score there, whose square the variance needs.
pub(super) fn merge_photon(exits: &mut Vec<Exit>, first: usize) {
    if exits.len() - first < 2 {
        return;
    }
    exits[first..].sort_unstable_by_key(|e| (e.channel, e.vertex));
    let mut last = first;
    for k in first + 1..exits.len() {
        if (exits[k].channel, exits[k].vertex) == (exits[last].channel, exits[last].vertex) {
            exits[last].weight += exits[k].weight;
        } else {
            last += 1;
            exits[last] = exits[k];
        }
    }
    exits.truncate(last + 1);
}
