//! One object's sources at one level, held within a memory budget (issue 47): every triangle's
//! [`Summary`] (its moments as a whole, a few hundred bytes), and its full grid and pyramid
//! (megabytes at the finest levels) only while a receiver's quadrature needs it.
//!
//! The grids that fit the budget stay from the pass that made the summaries; the others are
//! ray cast again, a chunk at a time, when a block of receivers needs them, and dropped after.
//! Ray casting is deterministic, so a grid made twice has the same bits, and the truth does not
//! depend on the budget.

use super::caster::{Caster, Shadows, TrianglePlan};
use super::source::{Source, Summary, grid_points};
use crate::mesh::Mesh;
use rayon::prelude::*;
use std::ops::Range;

/// An object's sources at one level: the lit triangles' summaries, and what was kept of each.
pub(super) struct Sources<'a> {
    /// The lit triangles (flux in some channel), in triangle order.
    pub(super) lit: Vec<Summary>,
    /// Per lit triangle, what was kept of it from the first pass.
    kept: Vec<Kept>,
    kept_bytes: u64,
    /// Bytes the grids may take at once: kept and made again together.
    budget: u64,
    /// `E_t` grid points over every triangle of the object (lit or not).
    pub(super) points: usize,
    caster: &'a Caster<'a>,
    mesh: &'a Mesh,
    plan: &'a [TrianglePlan],
    level: u32,
}

/// What the first pass keeps of a triangle's source.
enum Kept {
    /// All of it.
    Whole(Box<Source>),
    /// Its rays' verdicts, to make it again without a ray.
    Shadows(Shadows),
    /// Nothing: it is ray cast again.
    Nothing,
}

impl<'a> Sources<'a> {
    /// Ray cast every triangle's grid at `level` and keep its summary, and as much more as
    /// three quarters of `budget` hold: every triangle's [`Shadows`] first (a few bits a grid
    /// point, where a source takes 40 bytes), then whole sources; in triangle order, so what is
    /// kept does not depend on the threads. The last quarter is room to make the rest again,
    /// many at a time. (Keeping half made a level 1.2 GiB whole under 1 GiB 1.46 times slower
    /// than holding it all: the grids made again cost what casting them did.)
    pub(super) fn build(
        caster: &'a Caster<'a>,
        mesh: &'a Mesh,
        plan: &'a [TrianglePlan],
        level: u32,
        budget: u64,
    ) -> Sources<'a> {
        let keep = plan_keeping(plan, level, budget - budget / 4);
        let made: Vec<(Summary, Kept)> = plan
            .par_iter()
            .enumerate()
            .map(|(t, p)| {
                let (s, shadows) = caster.source_and_shadows(mesh, t, p, level, keep[t] == Keep::Shadows);
                let summary = s.summary(t);
                let kept = match (keep[t], shadows) {
                    (Keep::Whole, _) => Kept::Whole(Box::new(s)),
                    (_, Some(shadows)) => Kept::Shadows(shadows),
                    _ => Kept::Nothing,
                };
                (summary, kept)
            })
            .collect();
        let points = made.iter().map(|(s, _)| s.points).sum();
        let (lit, kept): (Vec<Summary>, Vec<Kept>) =
            made.into_iter().filter(|(s, _)| s.flux.iter().any(|&f| f > 0.0)).unzip();
        let kept_bytes = kept.iter().zip(&lit).map(|(k, s)| k.bytes(s, plan, level)).sum();
        Sources { lit, kept, kept_bytes, budget, points, caster, mesh, plan, level }
    }

    /// Bytes of lit triangle `i`'s source made again.
    fn bytes(&self, i: u32) -> u64 {
        match self.kept[i as usize] {
            Kept::Whole(_) => 0,
            _ => Source::bytes(self.lit[i as usize].depth),
        }
    }

    /// `needed` (sorted lit indices) cut into consecutive runs whose sources that are not kept
    /// fit together beside the kept ones; a source too large for what is left is a run alone.
    pub(super) fn chunks(&self, needed: &[u32]) -> Vec<Range<usize>> {
        let room = self.budget.saturating_sub(self.kept_bytes);
        let (mut runs, mut start, mut used) = (Vec::new(), 0, 0u64);
        for (k, &i) in needed.iter().enumerate() {
            let extra = self.bytes(i);
            if used + extra > room && k > start {
                runs.push(start..k);
                (start, used) = (k, 0);
            }
            used += extra;
        }
        if start < needed.len() {
            runs.push(start..needed.len());
        }
        runs
    }

    /// The sources of `ids` (sorted lit indices) that were not kept whole, made again: from
    /// their shadows where kept, else ray cast.
    pub(super) fn make(&self, ids: &[u32]) -> Made {
        let sources = ids
            .par_iter()
            .filter_map(|&i| {
                let t = self.lit[i as usize].triangle;
                let (plan, level) = (&self.plan[t], self.level);
                let s = match &self.kept[i as usize] {
                    Kept::Whole(_) => return None,
                    Kept::Shadows(shadows) => self.caster.source_again(self.mesh, t, plan, level, Some(shadows)),
                    Kept::Nothing => self.caster.source_again(self.mesh, t, plan, level, None),
                };
                Some((i, s))
            })
            .collect();
        Made { sources }
    }

    /// Lit triangle `i`'s source: kept, or in `made`.
    pub(super) fn get<'s>(&'s self, i: u32, made: &'s Made) -> &'s Source {
        match &self.kept[i as usize] {
            Kept::Whole(s) => s,
            _ => {
                let k = made.sources.binary_search_by_key(&i, |(j, _)| *j).expect("a chunk's sources are made first");
                &made.sources[k].1
            }
        }
    }
}

/// Bytes a level's [`Sources`] take a triangle besides what it keeps of it: its summary and
/// its entry of what is kept.
pub(super) const PER_TRIANGLE: usize = size_of::<Summary>() + size_of::<Kept>();

impl Kept {
    fn bytes(&self, s: &Summary, plan: &[TrianglePlan], level: u32) -> u64 {
        match self {
            Kept::Whole(_) => Source::bytes(s.depth),
            Kept::Shadows(_) => Shadows::bytes(s.points, plan[s.triangle].known(level).trace),
            Kept::Nothing => 0,
        }
    }
}

/// What to keep of each triangle.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Keep {
    Whole,
    Shadows,
    Nothing,
}

/// What [`Sources::build`] keeps of each triangle of `plan` within `room` bytes: every
/// triangle's shadows if they fit, then whole sources in what is left; else shadows in order.
fn plan_keeping(plan: &[TrianglePlan], level: u32, room: u64) -> Vec<Keep> {
    let shadows: Vec<u64> =
        plan.iter().map(|p| Shadows::bytes(grid_points(p.depth(level)), p.known(level).trace)).collect();
    let all: u64 = shadows.iter().sum();
    let mut used = 0u64;
    if all > room {
        return shadows
            .iter()
            .map(|&b| {
                used += b;
                if used <= room { Keep::Shadows } else { Keep::Nothing }
            })
            .collect();
    }
    plan.iter()
        .zip(&shadows)
        .map(|(p, &b)| {
            let more = Source::bytes(p.depth(level)).saturating_sub(b);
            if all + used + more > room {
                return Keep::Shadows;
            }
            used += more;
            Keep::Whole
        })
        .collect()
}

/// Sources ray cast again for one chunk, by lit index (sorted).
pub(super) struct Made {
    sources: Vec<(u32, Source)>,
}
