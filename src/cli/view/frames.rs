//! The viewer's frames in flight: per slot a command buffer, the fence its submission signals,
//! the semaphore its acquire signals, and the translucent frame recorded into it (whose
//! timings are read when the slot's fence has passed), plus a host-visible buffer for the
//! screenshot.

use super::host::Host;
use anyhow::Result;
use ash::vk;
use translucent::RecordedFrame;

/// One frame in flight.
pub struct Slot {
    pub cmd: vk::CommandBuffer,
    pub fence: vk::Fence,
    pub acquired: vk::Semaphore,
    pub recorded: Option<RecordedFrame>,
}

/// The ring of frames in flight and their command pool.
pub struct Slots {
    device: ash::Device,
    pool: vk::CommandPool,
    pub slots: Vec<Slot>,
}

impl Slots {
    /// `count` slots, their fences signalled (nothing to wait for before the first frame).
    pub fn new(host: &Host, count: usize) -> Result<Slots> {
        let device = &host.device;
        let info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(host.family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: valid create infos; everything is destroyed in `drop`.
        unsafe {
            let pool = device.create_command_pool(&info, None)?;
            let mut slots = Slots { device: device.clone(), pool, slots: Vec::new() };
            let allocate =
                vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(count as u32);
            for cmd in device.allocate_command_buffers(&allocate)? {
                let signalled = vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED);
                let fence = device.create_fence(&signalled, None)?;
                let acquired = device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None)?;
                slots.slots.push(Slot { cmd, fence, acquired, recorded: None });
            }
            Ok(slots)
        }
    }
}

impl Drop for Slots {
    fn drop(&mut self) {
        // SAFETY: the viewer waits for the device to be idle before dropping its slots.
        unsafe {
            for slot in &self.slots {
                self.device.destroy_fence(slot.fence, None);
                self.device.destroy_semaphore(slot.acquired, None);
            }
            self.device.destroy_command_pool(self.pool, None);
        }
    }
}

/// A host-visible, coherent buffer kept mapped: where the screenshot's copy lands.
pub struct Readback {
    device: ash::Device,
    pub buffer: vk::Buffer,
    memory: vk::DeviceMemory,
    ptr: *const u8,
    pub size: usize,
}

impl Readback {
    pub fn new(host: &Host, size: usize) -> Result<Readback> {
        let device = &host.device;
        let info = vk::BufferCreateInfo::default().size(size as u64).usage(vk::BufferUsageFlags::TRANSFER_DST);
        // SAFETY: valid create infos; destroyed in `drop` (freeing the memory unmaps it).
        unsafe {
            let buffer = device.create_buffer(&info, None)?;
            let req = device.get_buffer_memory_requirements(buffer);
            let flags = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
            let kind = host.memory_type(req.memory_type_bits, flags)?;
            let allocate = vk::MemoryAllocateInfo::default().allocation_size(req.size).memory_type_index(kind);
            let memory = device.allocate_memory(&allocate, None)?;
            device.bind_buffer_memory(buffer, memory, 0)?;
            let ptr = device.map_memory(memory, 0, size as u64, vk::MemoryMapFlags::empty())?.cast::<u8>();
            Ok(Readback { device: device.clone(), buffer, memory, ptr, size })
        }
    }

    /// The buffer's bytes: only after the fence of the submission that copied into it.
    pub fn bytes(&self) -> Vec<u8> {
        // SAFETY: the mapping covers `size` bytes and lives as long as `self`; the caller waited
        // for the copy.
        unsafe { std::slice::from_raw_parts(self.ptr, self.size) }.to_vec()
    }
}

impl Drop for Readback {
    fn drop(&mut self) {
        // SAFETY: the viewer waits for the device to be idle before dropping it.
        unsafe {
            self.device.destroy_buffer(self.buffer, None);
            self.device.free_memory(self.memory, None);
        }
    }
}

/// An image barrier on mip 0, layer 0, from `src` (stages, accesses) to `dst`.
pub fn image_barrier(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    layouts: (vk::ImageLayout, vk::ImageLayout),
    src: (vk::PipelineStageFlags2, vk::AccessFlags2),
    dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
) {
    let aspect = if layouts.1 == vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL {
        vk::ImageAspectFlags::DEPTH
    } else {
        vk::ImageAspectFlags::COLOR
    };
    let barrier = [vk::ImageMemoryBarrier2::default()
        .image(image)
        .old_layout(layouts.0)
        .new_layout(layouts.1)
        .src_stage_mask(src.0)
        .src_access_mask(src.1)
        .dst_stage_mask(dst.0)
        .dst_access_mask(dst.1)
        .subresource_range(vk::ImageSubresourceRange::default().aspect_mask(aspect).level_count(1).layer_count(1))];
    // SAFETY: `cmd` is recording outside any rendering.
    unsafe { device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&barrier)) };
}
