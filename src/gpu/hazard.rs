//! Barriers derived from declared accesses. Each resource (a key of the caller's, e.g. a pass
//! graph's resource names) remembers its last write and the reads since; `Hazards::before` is
//! given the accesses a command is about to make and records the one barrier they need: a
//! read waits for the last write (read after write), a write waits for the last write and for
//! every read since (write after write, write after read), and an image moves to the layout its
//! next access needs. Nothing is known about who comes next, so a producer never names its
//! consumers, and nothing waits on everything. The state outlives a command buffer: submissions
//! on one queue must be submitted in the order they were recorded.

use super::barrier::{Access, image_transition, whole_image};
use ash::vk;
use std::collections::HashMap;
use std::hash::Hash;

/// One access a command is about to make to resource `K`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Use<K> {
    /// The resource.
    pub resource: K,
    /// How the command touches it (its stages, access mask and image layout follow).
    pub access: Access,
    /// Whether the command writes it: the barriers order later accesses after a write, and a
    /// write after every earlier read (`Hazards::before`).
    pub writes: bool,
    /// A write that overwrites all of an image: its old contents are dropped (old layout
    /// UNDEFINED), while earlier accesses are still waited for.
    pub discard: bool,
}

impl<K> Use<K> {
    /// `access` reads `resource`. A read through an access that writes is a contract violation,
    /// caught in debug builds (`Hazards::before`).
    pub const fn read(resource: K, access: Access) -> Use<K> {
        Use { resource, access, writes: false, discard: false }
    }
    /// `access` writes `resource`, keeping its contents where it does not write.
    pub const fn write(resource: K, access: Access) -> Use<K> {
        Use { resource, access, writes: true, discard: false }
    }
    /// A write that overwrites all of `resource` (`discard`).
    pub const fn overwrite(resource: K, access: Access) -> Use<K> {
        Use { resource, access, writes: true, discard: true }
    }
}

/// What is known of one resource: its last write, the reads since, and, for an image, its
/// handle and current layout.
#[derive(Clone, Debug, Default)]
struct State {
    write: Option<Access>,
    reads: Vec<Access>,
    image: Option<(vk::Image, vk::ImageAspectFlags)>,
    layout: Option<vk::ImageLayout>,
}

/// One barrier's two sides, accumulated over the uses of one `before` call.
#[derive(Clone, Copy, Default)]
struct Sides {
    src_stage: vk::PipelineStageFlags2,
    src_access: vk::AccessFlags2,
    dst_stage: vk::PipelineStageFlags2,
    dst_access: vk::AccessFlags2,
}

impl Sides {
    fn add(&mut self, previous: &[Access], write: Option<Access>, next: Access) {
        for a in previous {
            self.src_stage |= a.stage();
        }
        if let Some(w) = write {
            self.src_stage |= w.stage();
            self.src_access |= w.access();
        }
        self.dst_stage |= next.stage();
        self.dst_access |= next.access();
    }
    fn is_empty(&self) -> bool {
        self.src_stage.is_empty()
    }
}

/// The tracked state of every resource (keys `K`) and the barriers that follow from it.
#[derive(Clone, Debug)]
pub struct Hazards<K> {
    states: HashMap<K, State>,
}

impl<K: Copy + Eq + Hash + std::fmt::Debug> Default for Hazards<K> {
    fn default() -> Self {
        Hazards { states: HashMap::new() }
    }
}

impl<K: Copy + Eq + Hash + std::fmt::Debug> Hazards<K> {
    /// No resource accessed yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// `resource` is the image `image` (its `aspect`), idle (no GPU work pending on it, as its
    /// creation or a waited-for submission left it) in the layout `current` needs
    /// (`Access::Nothing`: UNDEFINED).
    pub fn image(&mut self, resource: K, image: vk::Image, aspect: vk::ImageAspectFlags, current: Access) {
        let state = self.states.entry(resource).or_default();
        state.image = Some((image, aspect));
        state.layout = Some(current.layout());
        state.write = None;
        state.reads.clear();
    }

    /// `resource` is an image the caller cannot name by handle (only views, e.g. a host's
    /// attachment) that stays in the layout of `current`, last accessed so: its barriers are
    /// memory barriers.
    pub fn external(&mut self, resource: K, current: Access) {
        let state = self.states.entry(resource).or_default();
        state.write = Some(current);
        state.reads.clear();
    }

    /// `resource` was written outside any tracked command (a host write, or a staged copy in a
    /// submission of its own): its next reader waits on a transfer write.
    pub fn written_outside(&mut self, resource: K) {
        let state = self.states.entry(resource).or_default();
        state.write = Some(Access::TransferWrite);
        state.reads.clear();
    }

    /// Forget `resource`: it was replaced by a new, idle one (e.g. a buffer made anew).
    pub fn forget(&mut self, resource: K) {
        self.states.remove(&resource);
    }

    /// The last access to `resource`: its last write, or the last read since.
    pub fn last_access(&self, resource: K) -> Access {
        self.states.get(&resource).and_then(|s| s.reads.last().copied().or(s.write)).unwrap_or(Access::Nothing)
    }

    /// Record into `cmd` the one barrier the `uses` need against what came before, and take them
    /// as done. Buffers share one global memory barrier; each image whose layout changes, or
    /// which is written, gets an image barrier. Nothing is recorded when nothing is needed.
    pub fn before(&mut self, device: &ash::Device, cmd: vk::CommandBuffer, uses: &[Use<K>]) {
        let mut global = Sides::default();
        let mut images = Vec::new();
        for u in uses {
            debug_assert_eq!(
                u.writes,
                u.access.writes(),
                "{:?} declared as a {}",
                u.access,
                ["read", "write"][usize::from(u.writes)]
            );
            let state = self.states.entry(u.resource).or_default();
            let next_layout = state.layout.map(|_| u.access.layout());
            let relayout = u.discard || next_layout.is_some() && next_layout != state.layout;
            // A write or a layout change waits for the last write and every read since; a read
            // waits for the last write unless it already did. The readers that already waited
            // are in the chain too: their stages let a later reader in another stage wait
            // behind an earlier layout change.
            let unseen = state.write.is_some() && !state.reads.contains(&u.access);
            let mut sides = Sides::default();
            if u.writes || relayout || unseen {
                sides.add(&state.reads, state.write, u.access);
            }
            match (state.image, relayout) {
                (Some((image, aspect)), true) => {
                    let old = if u.discard { vk::ImageLayout::UNDEFINED } else { state.layout.unwrap_or_default() };
                    images.push(image_transition(
                        image,
                        whole_image(aspect),
                        (old, u.access.layout()),
                        (sides.src_stage, sides.src_access),
                        (sides.dst_stage, sides.dst_access),
                    ));
                }
                _ if !sides.is_empty() => {
                    global.src_stage |= sides.src_stage;
                    global.src_access |= sides.src_access;
                    global.dst_stage |= sides.dst_stage;
                    global.dst_access |= sides.dst_access;
                }
                _ => {}
            }
            if u.writes {
                state.write = Some(u.access);
                state.reads.clear();
            } else if relayout {
                // The layout change waited for every earlier access: only this reader, which
                // waited for it, is left for later accesses to wait on (with the last write).
                state.reads.clear();
                state.reads.push(u.access);
            } else if !state.reads.contains(&u.access) {
                state.reads.push(u.access);
            }
            if let Some(layout) = next_layout {
                state.layout = Some(layout);
            }
        }
        let memory = [vk::MemoryBarrier2::default()
            .src_stage_mask(global.src_stage)
            .src_access_mask(global.src_access)
            .dst_stage_mask(global.dst_stage)
            .dst_access_mask(global.dst_access)];
        let memory: &[vk::MemoryBarrier2] = if global.is_empty() { &[] } else { &memory };
        if memory.is_empty() && images.is_empty() {
            return;
        }
        let info = vk::DependencyInfo::default().memory_barriers(memory).image_memory_barriers(&images);
        // SAFETY: `cmd` is recording outside rendering; every image is alive while it is.
        unsafe { device.cmd_pipeline_barrier2(cmd, &info) };
    }
}
