//! `Planner`: what earlier frames left (the pending change, stale objects, gathered levels,
//! whether baked levels of detail are current), the plan a frame gets from it, and the history a
//! recorded frame leaves. Also `needs`, the one place a renderer's `SceneNeeds` are computed.

use super::frame::Frame;
use super::objects::{ObjectHistory, SweepState};
use super::passes::shadow_filter;
use super::receivers::ReceiverScope;
use super::{Change, Pass, Plan, SceneNeeds, View};
use crate::scene::build::PreparedScene;

/// Whether the levels of detail baked from per-vertex sky light (`Renderer::bake_static_levels`)
/// still match the sky light on the GPU.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BakedLevels {
    /// They do (or there are none): the planner may draw them.
    #[default]
    Current,
    /// A frame recomputed the sky light since they were baked: their objects are drawn whole
    /// until they are baked again.
    Withdrawn,
}

/// What the planner weighs for `scene`, drawn into a host's target (`host_target`) or the
/// renderer's own, with its baked levels `baked`: withdrawn levels are left out of the facts, so
/// those objects have one level, the whole mesh. The renderer keeps the result until the scene
/// or `baked` changes.
pub fn needs(scene: &PreparedScene, host_target: bool, baked: BakedLevels) -> SceneNeeds {
    let mut needs = scene.needs();
    needs.host_target = host_target;
    if baked == BakedLevels::Withdrawn {
        // The index buffer keeps them (frames in flight may draw them); they are offered no more.
        for facts in needs.objects.iter_mut().filter(|f| f.levels.iter().any(|l| l.locked)) {
            facts.levels.truncate(1);
        }
    }
    needs
}

/// The frame's history as the planner needs it: what changed since the last recorded frame,
/// which objects' exitance is out of date, at which level each was last gathered, and whether
/// baked levels are current. A renderer marks changes, plans from it, and tells it what it
/// recorded.
#[derive(Clone, Debug)]
pub struct Planner {
    /// What changed since the last recorded frame; `None` when nothing did.
    pending: Option<Change>,
    /// Per object: its gathered exitance is out of date (lights or its material changed while
    /// it was out of view or local), so the next frame that gathers it must splat it first.
    stale: Vec<bool>,
    /// Per object: the finest level of detail whose vertices hold its current exitance
    /// (`usize::MAX`: none yet); a finer level coming into view is gathered again.
    gathered: Vec<usize>,
    /// Per object: the environment's part of its samples' irradiance, kept by the splat, is
    /// current (`SplatLights`).
    environment_kept: Vec<bool>,
    /// Whether levels baked from the sky light are current.
    baked: BakedLevels,
    /// Per object: its splat generation, the mark of the receivers its visible-first gathers
    /// computed (`ReceiverScope::VisibleFirst`); 0 before any.
    generation: Vec<u32>,
    /// Per object: the sweep over the receivers no eye ray reached that its last visible-first
    /// gather left, until it finishes.
    sweep: Vec<Option<SweepState>>,
}

impl Planner {
    /// The history of a renderer of `objects` objects that has drawn nothing: every object
    /// stale and never gathered, and `first` pending (`Change::Everything`; a renderer rebuilt
    /// around a moved object names that geometry change instead).
    pub fn new(objects: usize, first: Change) -> Planner {
        Planner {
            pending: Some(first),
            stale: vec![true; objects],
            gathered: vec![usize::MAX; objects],
            environment_kept: vec![false; objects],
            baked: BakedLevels::Current,
            generation: vec![0; objects],
            sweep: vec![None; objects],
        }
    }

    /// Note `change` for the next frame, folded into what is pending (`Change::and`). A material
    /// change also marks its object stale, and its kept environment irradiance (its Fresnel
    /// transmittance changed), so that folding it into another change loses nothing.
    pub fn mark(&mut self, change: Change) {
        if let Change::Material(i) = change
            && let Some(stale) = self.stale.get_mut(i)
        {
            *stale = true;
            self.environment_kept[i] = false;
        }
        self.pending = Some(self.pending.map_or(change, |old| old.and(change)));
    }

    /// What changed since the last recorded frame (`None`: nothing).
    pub fn pending(&self) -> Option<Change> {
        self.pending
    }

    /// Whether levels baked from the sky light are current (the level state `needs` takes).
    pub fn baked_levels(&self) -> BakedLevels {
        self.baked
    }

    /// The plan of the next frame, for the pending change (a camera frame when nothing changed):
    /// what `Renderer::record_frame` records.
    pub fn plan(&self, needs: &SceneNeeds, view: &View) -> Plan {
        self.plan_for(needs, view, self.pending.unwrap_or(Change::Camera))
    }

    /// The plan a frame after `change` would get, for a scene with `needs` seen from `view`, with
    /// this history (the rules are in the module doc). Changes nothing: a preview, as
    /// `translucent plan` prints.
    pub fn plan_for(&self, needs: &SceneNeeds, view: &View, change: Change) -> Plan {
        let frame = Frame::new(needs, view, change);
        let objects: Vec<_> = needs
            .objects
            .iter()
            .enumerate()
            .map(|(i, facts)| {
                let history = ObjectHistory {
                    stale: self.stale.get(i).copied().unwrap_or(true),
                    gathered: self.gathered.get(i).copied(),
                    environment_kept: self.environment_kept.get(i).copied().unwrap_or(false),
                    generation: self.generation.get(i).copied().unwrap_or(0),
                    sweep: self.sweep.get(i).copied().flatten(),
                };
                frame.object(i, facts, history)
            })
            .collect();
        let (passes, skipped) = frame.passes(&objects);
        let shadow_filter = shadow_filter(needs, view);
        let splat_visibility = passes.iter().any(|(p, _)| *p == Pass::Splat).then_some(needs.splat_visibility);
        Plan {
            change: Some(change),
            passes,
            skipped,
            shadow_light: match change {
                Change::Light(i) => Some(i),
                _ => None,
            },
            objects,
            one_tap_shadows: shadow_filter.is_some_and(|f| f.one_tap),
            shadow_filter,
            skip_terms: 0,
            cull_hidden_faces: true,
            splat_visibility,
        }
    }

    /// A frame of `plan` was recorded: nothing is pending, each object's exitance is as stale as
    /// the plan leaves it, gathered objects hold exitance at the level they were gathered at (at
    /// every vertex unless `gather_by_level`: the vertex and hierarchical gathers work at a
    /// level's vertices), and a frame that recomputed the sky light withdraws the levels baked from it.
    pub fn recorded(&mut self, plan: &Plan, gather_by_level: bool) {
        self.pending = None;
        if plan.runs(Pass::VertexLight) {
            self.baked = BakedLevels::Withdrawn;
        }
        for o in &plan.objects {
            self.stale[o.object] = o.stale_after;
            // A splat that runs keeps the environment's part; otherwise it stays as current as
            // the plan found it.
            self.environment_kept[o.object] = (o.splat && plan.runs(Pass::Splat)) || o.environment_kept;
            if o.gather && plan.runs(Pass::Gather) {
                self.gathered[o.object] = if gather_by_level { o.level } else { 0 };
                self.swept(o.object, o.receivers, o.level);
            }
        }
    }

    /// Object `object` was gathered over `receivers` at `level`: a fresh visible-first gather
    /// marks its generation and leaves a sweep from the first chunk, a chunk moves the sweep on
    /// (or ends it), and a gather of every receiver ends it.
    fn swept(&mut self, object: usize, receivers: ReceiverScope, level: usize) {
        self.sweep[object] = match receivers {
            ReceiverScope::VisibleFirst { generation, fresh: true, .. } => {
                self.generation[object] = generation;
                Some(SweepState { next: 0, level })
            }
            ReceiverScope::VisibleFirst { sweep: Some(s), .. } => {
                (s.chunk + 1 < s.of).then_some(SweepState { next: s.chunk + 1, level })
            }
            ReceiverScope::VisibleFirst { sweep: None, .. } => self.sweep[object],
            ReceiverScope::Every { .. } => None,
        };
    }

    /// `plan` with the splat generations its visible-first gathers mark receivers with taken
    /// from this history, not from when the plan was made: a fresh gather gets the next
    /// generation, a sweep's chunk the current one. So a plan recorded again after later
    /// frames (a caller's own) still recomputes what its splat changed.
    pub fn stamped(&self, plan: &Plan) -> Plan {
        let mut plan = plan.clone();
        for o in &mut plan.objects {
            let current = self.generation.get(o.object).copied().unwrap_or(0);
            if let ReceiverScope::VisibleFirst { generation, fresh, .. } = &mut o.receivers {
                *generation = if *fresh { current.wrapping_add(1).max(1) } else { current };
            }
        }
        plan
    }

    /// Object `object`'s splat generation and whether a sweep over its receivers is still to
    /// run (`Renderer::exitance` finishes it before reading).
    pub fn sweep_pending(&self, object: usize) -> Option<u32> {
        self.sweep.get(object).copied().flatten().map(|_| self.generation[object])
    }

    /// The levels of detail were baked from the sky light as the last vertex-light pass left it.
    pub fn levels_baked(&mut self) {
        self.baked = BakedLevels::Current;
    }

    /// Whether object `object`'s last gather ran at a coarser level of detail than the whole
    /// mesh, so that some of its vertices hold older exitance (`Renderer::exitance` refuses it).
    pub fn gathered_coarser(&self, object: usize) -> bool {
        self.gathered_level(object).is_some_and(|g| g > 0)
    }

    /// The level of detail object `object` was last gathered at (0: the whole mesh), if it was.
    pub fn gathered_level(&self, object: usize) -> Option<usize> {
        self.gathered.get(object).copied().filter(|&g| g != usize::MAX)
    }

    /// Object `object`'s exitance was written at every vertex from outside the frame
    /// (`Renderer::set_exitance`): the whole mesh holds it, as after a gather at level 0.
    pub fn exitance_written(&mut self, object: usize) {
        self.gathered[object] = 0;
        self.sweep[object] = None;
    }

    /// A history with the given stale flags and gathered levels, nothing pending.
    #[cfg(test)]
    pub(super) fn with_history(stale: &[bool], gathered: &[usize]) -> Planner {
        Planner {
            pending: None,
            stale: stale.to_vec(),
            gathered: gathered.to_vec(),
            environment_kept: vec![false; stale.len()],
            baked: BakedLevels::Current,
            generation: vec![0; stale.len()],
            sweep: vec![None; stale.len()],
        }
    }
}
