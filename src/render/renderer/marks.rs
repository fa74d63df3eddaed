//! `FrameMarks`: how the renderer knows a recorded frame has run. Each frame ends by writing its
//! generation into its slot of a small host-visible buffer, after everything it recorded. A
//! slot that holds the frame's generation proves that frame complete; one that holds an older
//! generation means the frame has not run yet (recorded and not submitted, or in flight), so
//! `read_timings` never answers with the timestamps an earlier frame left in the same slot.

use crate::gpu::{Buffer, BufferDesc, Gpu, GpuResult};
use ash::vk;
use std::sync::Arc;

/// One `u32` per frame-in-flight slot: the low bits of the last generation that ran there.
pub(super) struct FrameMarks {
    buffer: Buffer,
    slots: usize,
}

impl FrameMarks {
    /// Marks for `slots` frames in flight, all zero (no generation 0 is ever recorded).
    pub(super) fn new(gpu: &Arc<Gpu>, slots: usize) -> GpuResult<FrameMarks> {
        let size = 4 * slots.max(1) as u64;
        let mut buffer =
            Buffer::new(gpu, &BufferDesc::readback("frame marks", size, vk::BufferUsageFlags::TRANSFER_DST))?;
        buffer.write(0, &vec![0u32; slots.max(1)])?;
        Ok(FrameMarks { buffer, slots: slots.max(1) })
    }

    /// The slot frame `generation` (from 1) marks.
    pub(super) fn slot(&self, generation: u64) -> usize {
        ((generation - 1) % self.slots as u64) as usize
    }

    /// Record, at the end of frame `generation`, the write of its mark: after every command
    /// recorded before it, and made visible to the host.
    pub(super) fn record(&self, device: &ash::Device, cmd: vk::CommandBuffer, generation: u64) {
        let before = vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .dst_stage_mask(vk::PipelineStageFlags2::CLEAR);
        let after = vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::CLEAR)
            .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::HOST)
            .dst_access_mask(vk::AccessFlags2::HOST_READ);
        let offset = 4 * self.slot(generation) as u64;
        // SAFETY: `cmd` is recording outside any rendering; the buffer is ours and lives as
        // long as the renderer, whose Drop waits for every frame recorded into a host's buffer.
        unsafe {
            device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&[before]));
            device.cmd_fill_buffer(cmd, self.buffer.raw(), offset, 4, generation as u32);
            device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&[after]));
        }
    }

    /// Whether frame `generation` has run: its slot holds its mark.
    pub(super) fn ran(&self, generation: u64) -> GpuResult<bool> {
        let marks: Vec<u32> = self.buffer.read()?;
        Ok(marks[self.slot(generation)] == generation as u32)
    }
}
