//! One-shot command submission: record, submit, wait on a fence with a timeout.

use super::context::Gpu;
use super::error::{GpuError, GpuResult, VkContext};
use ash::vk;

/// Command pool and fence of one submission, destroyed on every path out.
struct Transient<'a> {
    gpu: &'a Gpu,
    pool: vk::CommandPool,
    fence: vk::Fence,
}

impl Drop for Transient<'_> {
    fn drop(&mut self) {
        // SAFETY: the fence was waited on (or the device is idle after a failed wait), so the
        // command buffer is no longer pending; destroying the pool frees it.
        unsafe {
            let device = self.gpu.device();
            if self.fence != vk::Fence::null() {
                device.destroy_fence(self.fence, None);
            }
            device.destroy_command_pool(self.pool, None);
        }
    }
}

impl Gpu {
    /// Record commands with `record`, submit them, and block until they finish (at most
    /// `self.timeout()`). `what` names the work in errors.
    pub fn one_shot<R>(&self, what: &str, record: impl FnOnce(vk::CommandBuffer) -> R) -> GpuResult<R> {
        let device = self.device();
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(self.queue_family())
            .flags(vk::CommandPoolCreateFlags::TRANSIENT);
        // SAFETY: valid device; the pool is destroyed by `Transient`.
        let pool = unsafe { device.create_command_pool(&pool_info, None) }.vk("vkCreateCommandPool")?;
        let mut transient = Transient { gpu: self, pool, fence: vk::Fence::null() };
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: allocation from a pool owned by this thread.
        let cmd = unsafe { device.allocate_command_buffers(&alloc) }.vk("vkAllocateCommandBuffers")?[0];
        let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: `cmd` was just allocated from `pool`, which only this call uses, so it is in
        // the initial state and not accessed from another thread.
        unsafe { device.begin_command_buffer(cmd, &begin) }.vk("vkBeginCommandBuffer")?;
        let result = record(cmd);
        // SAFETY: `cmd` is in the recording state (begun above); `record` only appends commands
        // and ends any rendering it begins.
        unsafe { device.end_command_buffer(cmd) }.vk("vkEndCommandBuffer")?;

        // SAFETY: default create info on a live device; `Transient` destroys the fence.
        transient.fence = unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None) }.vk("vkCreateFence")?;
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds)];
        {
            let queue = self.queue();
            // SAFETY: the queue is externally synchronised by the guard; `cmd` is fully recorded.
            unsafe { device.queue_submit2(*queue, &submit, transient.fence) }.vk("vkQueueSubmit2")?;
        }
        let timeout_ns = u64::try_from(self.timeout().as_nanos()).unwrap_or(u64::MAX);
        // SAFETY: waiting on a fence we own.
        match unsafe { device.wait_for_fences(&[transient.fence], true, timeout_ns) } {
            Ok(()) => Ok(result),
            Err(vk::Result::TIMEOUT) => {
                // The pool must not be destroyed while the work is pending.
                // SAFETY: the device is live while `self` is. vkDeviceWaitIdle also wants every
                // queue externally synchronised, and the queue guard was dropped after the submit:
                // this relies on no other thread submitting meanwhile.
                let _ = unsafe { device.device_wait_idle() };
                Err(GpuError::Timeout { what: what.to_string(), seconds: self.timeout().as_secs_f64() })
            }
            Err(result) => {
                // SAFETY: as for the timeout above: a live device, and no concurrent submit
                // assumed (the queue guard is not held); `Transient` then frees the idle pool.
                let _ = unsafe { device.device_wait_idle() };
                Err(GpuError::Vk { what: "vkWaitForFences", result })
            }
        }
    }
}
