//! Pipeline barriers (synchronization2) written as named accesses, after vk-sync: a pass says
//! what it just did to a resource (`Access::ComputeWrite`) and what comes next
//! (`Access::VertexAttributeRead`), and the stages, access masks and image layouts follow from
//! the names, so no pass spells out raw stage and access pairs.

use ash::vk;

/// One way the GPU (or the host) touches a buffer or an image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// Nothing before (first use; an image's contents are discarded).
    Nothing,
    /// Storage-buffer or storage-image writes in a compute shader.
    ComputeWrite,
    /// Storage-buffer reads in a compute shader.
    ComputeRead,
    /// Storage-buffer reads and writes in a compute shader (atomics).
    ComputeReadWrite,
    /// Sampled-image reads in a compute shader.
    ComputeSampledRead,
    /// Storage-image reads and writes in a compute shader (GENERAL layout).
    ComputeImageReadWrite,
    /// Sampled-image reads in a fragment shader.
    FragmentSampledRead,
    /// Storage-buffer reads in a fragment shader.
    FragmentRead,
    /// Vertex-buffer reads by the input assembler.
    VertexAttributeRead,
    /// Colour-attachment writes.
    ColorAttachmentWrite,
    /// Depth-attachment tests and writes.
    DepthAttachmentReadWrite,
    /// Clears and copies into the resource.
    TransferWrite,
    /// Copies out of the resource.
    TransferRead,
    /// Host reads of mapped memory after the submission's fence.
    HostRead,
}

impl Access {
    /// Whether the access writes (its results must be made visible to what follows).
    pub fn writes(self) -> bool {
        matches!(
            self,
            Access::ComputeWrite
                | Access::ComputeReadWrite
                | Access::ComputeImageReadWrite
                | Access::ColorAttachmentWrite
                | Access::DepthAttachmentReadWrite
                | Access::TransferWrite
        )
    }

    pub(crate) fn stage(self) -> vk::PipelineStageFlags2 {
        use vk::PipelineStageFlags2 as S;
        match self {
            Access::Nothing => S::NONE,
            Access::ComputeWrite
            | Access::ComputeRead
            | Access::ComputeReadWrite
            | Access::ComputeSampledRead
            | Access::ComputeImageReadWrite => S::COMPUTE_SHADER,
            Access::FragmentSampledRead | Access::FragmentRead => S::FRAGMENT_SHADER,
            Access::VertexAttributeRead => S::VERTEX_ATTRIBUTE_INPUT,
            Access::ColorAttachmentWrite => S::COLOR_ATTACHMENT_OUTPUT,
            Access::DepthAttachmentReadWrite => S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
            // CLEAR covers vkCmdFillBuffer and image clears, COPY the copies.
            Access::TransferWrite => S::CLEAR | S::COPY,
            Access::TransferRead => S::COPY,
            Access::HostRead => S::HOST,
        }
    }

    pub(crate) fn access(self) -> vk::AccessFlags2 {
        use vk::AccessFlags2 as A;
        match self {
            Access::Nothing => A::NONE,
            Access::ComputeWrite => A::SHADER_STORAGE_WRITE,
            Access::ComputeRead | Access::FragmentRead => A::SHADER_STORAGE_READ,
            Access::ComputeSampledRead | Access::FragmentSampledRead => A::SHADER_SAMPLED_READ,
            Access::ComputeImageReadWrite | Access::ComputeReadWrite => {
                A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE
            }
            Access::VertexAttributeRead => A::VERTEX_ATTRIBUTE_READ,
            Access::ColorAttachmentWrite => A::COLOR_ATTACHMENT_WRITE,
            Access::DepthAttachmentReadWrite => A::DEPTH_STENCIL_ATTACHMENT_READ | A::DEPTH_STENCIL_ATTACHMENT_WRITE,
            Access::TransferWrite => A::TRANSFER_WRITE,
            Access::TransferRead => A::TRANSFER_READ,
            Access::HostRead => A::HOST_READ,
        }
    }

    /// The image layout this access needs.
    pub(crate) fn layout(self) -> vk::ImageLayout {
        use vk::ImageLayout as L;
        match self {
            Access::Nothing => L::UNDEFINED,
            Access::ComputeWrite
            | Access::ComputeImageReadWrite
            | Access::ComputeReadWrite
            | Access::ComputeRead
            | Access::FragmentRead
            | Access::HostRead => L::GENERAL,
            Access::ComputeSampledRead | Access::FragmentSampledRead => L::SHADER_READ_ONLY_OPTIMAL,
            Access::VertexAttributeRead => L::GENERAL,
            Access::ColorAttachmentWrite => L::COLOR_ATTACHMENT_OPTIMAL,
            Access::DepthAttachmentReadWrite => L::DEPTH_ATTACHMENT_OPTIMAL,
            Access::TransferWrite => L::TRANSFER_DST_OPTIMAL,
            Access::TransferRead => L::TRANSFER_SRC_OPTIMAL,
        }
    }
}

fn masks(accesses: &[Access]) -> (vk::PipelineStageFlags2, vk::AccessFlags2) {
    accesses
        .iter()
        .fold((vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE), |(s, a), x| (s | x.stage(), a | x.access()))
}

/// The one layout a set of image accesses shares (they must agree).
fn layout(accesses: &[Access]) -> vk::ImageLayout {
    let first = accesses.first().map_or(vk::ImageLayout::UNDEFINED, |a| a.layout());
    debug_assert!(accesses.iter().all(|a| a.layout() == first), "image accesses need different layouts: {accesses:?}");
    first
}

/// One image's transition as Vulkan takes it: from layout `old` to `new`, waiting for `src`
/// (stages, accesses) and holding back `dst`, over `range`. Every image barrier is built here
/// (`ImageBarrier`, `Hazards::before`, a host's declared states).
pub(crate) fn image_transition(
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    (old, new): (vk::ImageLayout, vk::ImageLayout),
    src: (vk::PipelineStageFlags2, vk::AccessFlags2),
    dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
) -> vk::ImageMemoryBarrier2<'static> {
    vk::ImageMemoryBarrier2::default()
        .image(image)
        .old_layout(old)
        .new_layout(new)
        .src_stage_mask(src.0)
        .src_access_mask(src.1)
        .dst_stage_mask(dst.0)
        .dst_access_mask(dst.1)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .subresource_range(range)
}

/// Every mip level and array layer of `aspect`.
pub(crate) fn whole_image(aspect: vk::ImageAspectFlags) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange::default()
        .aspect_mask(aspect)
        .level_count(vk::REMAINING_MIP_LEVELS)
        .layer_count(vk::REMAINING_ARRAY_LAYERS)
}

/// Make the `previous` accesses to any memory available and visible to the `next` ones.
pub fn memory_barrier(device: &ash::Device, cmd: vk::CommandBuffer, previous: &[Access], next: &[Access]) {
    let (src_stage, src_access) = masks(previous);
    let (dst_stage, dst_access) = masks(next);
    let barrier = [vk::MemoryBarrier2::default()
        .src_stage_mask(src_stage)
        .src_access_mask(src_access)
        .dst_stage_mask(dst_stage)
        .dst_access_mask(dst_access)];
    // SAFETY: `cmd` is in the recording state (every caller records inside a command buffer).
    unsafe { device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&barrier)) };
}

/// One image (all mips and layers of `aspect`) moving from its `previous` accesses to the
/// `next` ones, with the layout change they imply. `Access::Nothing` before, or `discard`,
/// drops the contents (old layout UNDEFINED) while still waiting for the previous accesses.
#[derive(Clone, Copy, Debug)]
pub struct ImageBarrier<'a> {
    /// The image whose layout and accesses the barrier covers.
    pub image: vk::Image,
    /// The aspect the barrier covers: COLOR, or DEPTH for depth formats (`aspect_of`).
    pub aspect: vk::ImageAspectFlags,
    /// The accesses before the barrier: its source stages and access masks, and the old layout.
    pub previous: &'a [Access],
    /// The accesses after it: its destination stages and access masks, and the new layout.
    pub next: &'a [Access],
    /// Drop the contents: the old layout is UNDEFINED whatever `previous` implies.
    pub discard: bool,
}

impl<'a> ImageBarrier<'a> {
    /// A barrier that keeps the image's contents.
    pub fn new(image: vk::Image, aspect: vk::ImageAspectFlags, previous: &'a [Access], next: &'a [Access]) -> Self {
        ImageBarrier { image, aspect, previous, next, discard: false }
    }

    /// Whether the contents may be dropped (old layout UNDEFINED).
    pub fn discard(self, discard: bool) -> Self {
        ImageBarrier { discard, ..self }
    }

    /// Record it.
    pub fn record(&self, device: &ash::Device, cmd: vk::CommandBuffer) {
        let old = if self.discard { vk::ImageLayout::UNDEFINED } else { layout(self.previous) };
        let barrier = [image_transition(
            self.image,
            whole_image(self.aspect),
            (old, layout(self.next)),
            masks(self.previous),
            masks(self.next),
        )];
        // SAFETY: as for `memory_barrier`; the image is alive while the command buffer is.
        unsafe { device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&barrier)) };
    }
}

/// Make a transfer's writes (a copy into a readback buffer) visible to host reads.
pub fn transfer_to_host(device: &ash::Device, cmd: vk::CommandBuffer) {
    memory_barrier(device, cmd, &[Access::TransferWrite], &[Access::HostRead]);
}
