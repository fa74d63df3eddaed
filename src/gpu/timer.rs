//! `GpuTimer`: per-pass GPU time from timestamp queries, in milliseconds.
//!
//! Record `reset` once at the start of a command buffer, then `begin(name)`/`end(name)` around
//! each pass; after the submission has finished, `results` converts tick differences with the
//! device's timestampPeriod (ns per tick) and masks to timestampValidBits.

use super::context::Gpu;
use super::error::{GpuError, GpuResult, VkContext};
use ash::vk;
use std::sync::Arc;

/// Timestamp queries for up to `max_passes` named passes per command buffer: two per pass, start
/// and end, both written at ALL_COMMANDS. The query pool is destroyed on Drop. Needs a queue whose
/// timestampValidBits is above 0.
pub struct GpuTimer {
    gpu: Arc<Gpu>,
    pool: vk::QueryPool,
    capacity: u32,
    names: Vec<String>,
    open: Option<usize>,
}

impl GpuTimer {
    /// A timer for up to `max_passes` named passes per submission.
    pub fn new(gpu: &Arc<Gpu>, max_passes: u32) -> GpuResult<GpuTimer> {
        let (_, valid_bits) = gpu.timestamp_info();
        if valid_bits == 0 {
            return Err(GpuError::NoTimestamps { device: gpu.info().name.clone() });
        }
        let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(2 * max_passes);
        // SAFETY: valid create info; Drop destroys it.
        let pool = unsafe { gpu.device().create_query_pool(&info, None) }.vk("vkCreateQueryPool")?;
        Ok(GpuTimer { gpu: gpu.clone(), pool, capacity: max_passes, names: Vec::new(), open: None })
    }

    /// Record the reset of every query; forgets the names of the previous submission.
    pub fn reset(&mut self, cmd: vk::CommandBuffer) {
        // SAFETY: `cmd` is recording, outside a render pass.
        unsafe { self.gpu.device().cmd_reset_query_pool(cmd, self.pool, 0, 2 * self.capacity) };
        self.names.clear();
        self.open = None;
    }

    /// Record the start timestamp of pass `name`, then a barrier so that the pass starts after
    /// it (and after all earlier work).
    pub fn begin(&mut self, cmd: vk::CommandBuffer, name: &str) {
        assert!(self.open.is_none(), "GpuTimer: pass {name:?} begun inside another pass");
        assert!((self.names.len() as u32) < self.capacity, "GpuTimer: more than {} passes", self.capacity);
        let index = self.names.len();
        self.names.push(name.to_string());
        self.open = Some(index);
        // SAFETY: query 2*index was reset in this command buffer.
        unsafe {
            self.gpu.device().cmd_write_timestamp2(
                cmd,
                vk::PipelineStageFlags2::ALL_COMMANDS,
                self.pool,
                2 * index as u32,
            );
            // Lavapipe takes a timestamp when it next flushes its rasteriser's work, while a
            // compute dispatch runs at once: without this barrier (which flushes there) a pass's
            // start was stamped after its dispatches had run, and the gather read 0.2 ms
            // against 33 ms alone. With it the two agree (README, "Performance"). Elsewhere it
            // only keeps the pass from overlapping the work before it, which is what timing one
            // pass means.
            let barrier = [vk::MemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
                .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
            self.gpu.device().cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&barrier));
        };
    }

    /// Record the end timestamp of the open pass.
    pub fn end(&mut self, cmd: vk::CommandBuffer) {
        let index = self.open.take().expect("GpuTimer::end without begin");
        // SAFETY: as in `begin`.
        unsafe {
            self.gpu.device().cmd_write_timestamp2(
                cmd,
                vk::PipelineStageFlags2::ALL_COMMANDS,
                self.pool,
                2 * index as u32 + 1,
            )
        };
    }

    /// (name, milliseconds) of each pass of the finished submission, in recording order;
    /// waits for the submission (it must have been submitted).
    pub fn results(&self) -> GpuResult<Vec<(String, f64)>> {
        Ok(self.read(true)?.unwrap_or_default())
    }

    /// As `results`, without waiting: `None` while a query is not yet written (the submission
    /// has not finished, or was never made).
    pub fn results_if_done(&self) -> GpuResult<Option<Vec<(String, f64)>>> {
        self.read(false)
    }

    fn read(&self, wait: bool) -> GpuResult<Option<Vec<(String, f64)>>> {
        if self.names.is_empty() {
            return Ok(Some(Vec::new()));
        }
        let mut ticks = vec![0u64; 2 * self.names.len()];
        let flags = if wait { vk::QueryResultFlags::WAIT } else { vk::QueryResultFlags::empty() };
        // SAFETY: the queries were reset in a recorded command buffer; without WAIT, Vulkan
        // answers NOT_READY until every one of them is written.
        let read = unsafe {
            self.gpu.device().get_query_pool_results(self.pool, 0, &mut ticks, vk::QueryResultFlags::TYPE_64 | flags)
        };
        match read {
            Err(vk::Result::NOT_READY) if !wait => return Ok(None),
            other => other.vk("vkGetQueryPoolResults")?,
        }
        let (period_ns, valid_bits) = self.gpu.timestamp_info();
        let mask = if valid_bits >= 64 { u64::MAX } else { (1u64 << valid_bits) - 1 };
        Ok(Some(
            self.names
                .iter()
                .enumerate()
                .map(|(i, name)| {
                    let start = ticks[2 * i] & mask;
                    let end = ticks[2 * i + 1] & mask;
                    // Wrapping difference within the valid bits handles a counter that rolled over.
                    let delta = end.wrapping_sub(start) & mask;
                    (name.clone(), delta as f64 * period_ns / 1.0e6)
                })
                .collect(),
        ))
    }
}

impl Drop for GpuTimer {
    fn drop(&mut self) {
        // SAFETY: no pending submission writes this pool.
        unsafe { self.gpu.device().destroy_query_pool(self.pool, None) };
    }
}

/// Median of per-frame timings, for benchmarks ("median of several frames after warm-up").
pub fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 { values[n / 2] } else { 0.5 * (values[n / 2 - 1] + values[n / 2]) }
}
