//! Smoke pass (`glsl/smoke.comp`): `out[i] = 2 in[i] + i` over a buffer. It proves that upload,
//! dispatch, timing and readback work on the chosen device before anything larger runs.
//!
//! Bindings: 0 = input f32 (storage, read), 1 = output f32 (storage, write). Push: u32 count.

use crate::gpu::{
    Access, Binding, Buffer, BufferDesc, ComputePipeline, Gpu, GpuResult, GpuTimer, Named, memory_barrier,
};
use ash::vk;
use std::sync::Arc;

/// What the smoke dispatch produced.
pub struct SmokeResult {
    /// The output buffer, read back; `expected` gives what it must hold.
    pub output: Vec<f32>,
    /// GPU time of the dispatch, from timestamp queries.
    pub gpu_ms: f64,
}

/// The values the shader must produce, computed on the CPU.
pub fn expected(input: &[f32]) -> Vec<f32> {
    input.iter().enumerate().map(|(i, v)| 2.0 * v + i as f32).collect()
}

/// Upload `input`, dispatch glsl/smoke.comp over it in one timed one-shot submission, and read the
/// output back.
pub fn run(gpu: &Arc<Gpu>, input: &[f32]) -> GpuResult<SmokeResult> {
    let count = input.len() as u32;
    let pipeline = ComputePipeline::new(gpu, "smoke.comp")?;
    let src = Buffer::from_slice(gpu, "smoke input", input, vk::BufferUsageFlags::STORAGE_BUFFER)?;
    let dst = Buffer::new(
        gpu,
        &BufferDesc::readback("smoke output", 4 * count as u64, vk::BufferUsageFlags::STORAGE_BUFFER),
    )?;
    let set = pipeline.descriptor_set(&[
        Named { name: "Input", binding: Binding::Buffer(&src) },
        Named { name: "Output", binding: Binding::Buffer(&dst) },
    ])?;
    let mut timer = GpuTimer::new(gpu, 1)?;
    gpu.one_shot("smoke dispatch", |cmd| {
        timer.reset(cmd);
        timer.begin(cmd, "smoke");
        pipeline.dispatch(cmd, &set, &count, [count, 1, 1]);
        timer.end(cmd);
        memory_barrier(gpu.device(), cmd, &[Access::ComputeWrite], &[Access::HostRead]);
    })?;
    let gpu_ms = timer.results()?.first().map(|(_, ms)| *ms).unwrap_or(0.0);
    Ok(SmokeResult { output: dst.read()?, gpu_ms })
}
