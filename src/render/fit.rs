//! Whether a scene fits the device, checked before any GPU work: dispatch sizes, image sizes and
//! layers, storage-buffer ranges, memory, and the host's formats. Each refusal names the scene
//! setting and the device limit (`RenderError::DoesNotFit`).

use super::error::{Quantity, RenderError};
use crate::gpu::{Gpu, ShaderInterface};
use crate::scene::GatherMode;
use crate::scene::build::PreparedScene;
use ash::vk;

/// An error naming the scene setting when the scene needs more than the device allows, before
/// any GPU work: dispatch sizes, image sizes and layers, storage-buffer ranges, and memory (the
/// largest single allocation against `maxMemoryAllocationSize`, the total against the largest
/// device-local heap).
pub(in crate::render) fn check_fits(gpu: &Gpu, scene: &PreparedScene) -> Result<(), RenderError> {
    let mut checks = dispatch_checks(gpu, scene)?;
    checks.extend(memory_checks(gpu, scene));
    for (setting, value, limit_name, limit) in checks {
        if value > limit {
            return Err(RenderError::DoesNotFit { setting, value, limit_name, limit });
        }
    }
    Ok(())
}

/// (what is measured, its value, the device limit's name, the limit).
type Check = (Quantity, u64, &'static str, u64);

/// Dispatch sizes, image sides and layers, and storage ranges against the device's limits.
fn dispatch_checks(gpu: &Gpu, scene: &PreparedScene) -> Result<Vec<Check>, RenderError> {
    let limits = &gpu.properties().limits;
    // Vertex- and sample-wide passes dispatch along x only.
    let dispatchable = |shader: &str| -> Result<u64, RenderError> {
        Ok(limits.max_compute_work_group_count[0] as u64 * ShaderInterface::of(shader)?.local_size[0] as u64)
    };
    let dispatch = "maxComputeWorkGroupCount x local size";
    let image_side = limits.max_image_dimension2_d as u64;
    let file = &scene.scene.file;
    let [width, height] = file.camera.resolution.map(u64::from);
    let range = limits.max_storage_buffer_range as u64;
    // With epsilon 0 the hierarchical gather lists every sample for every group of receivers.
    let flat_lists: u64 = if file.render.gather == GatherMode::Hierarchical && file.render.gather_epsilon == 0.0 {
        let group = crate::sampling::RECEIVER_GROUP_SIZE as u64;
        let per_object = |o: &crate::scene::build::PreparedObject| {
            (o.mesh.positions().len() as u64).div_ceil(group) * o.samples.len() as u64 * 4
        };
        scene.objects.iter().map(per_object).sum()
    } else {
        0
    };
    Ok(vec![
        (
            Quantity::FlatGatherLists,
            flat_lists,
            "maxStorageBufferRange",
            range,
        ),
        (Quantity::Vertices, scene.vertex_count() as u64, dispatch, dispatchable("vertex_light.comp")?),
        (
            Quantity::Samples,
            scene.sample_count() as u64,
            dispatch,
            dispatchable("splat.comp")?,
        ),
        (Quantity::ResolutionSide, width.max(height), "maxImageDimension2D", image_side),
        (
            Quantity::ToneMapped,
            4 * width * height,
            "maxStorageBufferRange",
            range,
        ),
        (Quantity::ShadowMapSize, file.render.shadow_map_size as u64, "maxImageDimension2D", image_side),
        (
            Quantity::ShadowLayers,
            scene.shadow_layers as u64,
            "maxImageArrayLayers",
            limits.max_image_array_layers as u64,
        ),
    ])
}

/// The large allocations against `maxMemoryAllocationSize`, and the whole scene against the
/// largest device-local heap.
fn memory_checks(gpu: &Gpu, scene: &PreparedScene) -> Vec<Check> {
    let file = &scene.scene.file;
    let [width, height] = file.camera.resolution.map(u64::from);
    let pixels = width * height;
    let (map, layers) = (file.render.shadow_map_size as u64, scene.shadow_layers.max(1) as u64);
    let (max_allocation, heap) = memory_limits(gpu);
    // The HDR image (and the surface image of the pixel gather), 16 bytes a pixel, and the
    // shadow-map array, 2 bytes a texel, are the large allocations; the rest is counted whole.
    let hdr_bytes = 16 * pixels;
    let shadow_bytes = 2 * map * map * layers;
    let vertex_bytes = 56 * scene.vertex_count() as u64 + 64 * scene.sample_count() as u64;
    let surface = if file.render.gather == GatherMode::Pixel { hdr_bytes } else { 0 };
    // HDR, surface, depth (4), tone-mapped output (4) and the EXR readback (16) per pixel.
    let total = hdr_bytes + surface + 24 * pixels + shadow_bytes + vertex_bytes;
    vec![
        (
            Quantity::HdrBytes([width, height]),
            hdr_bytes,
            "maxMemoryAllocationSize",
            max_allocation,
        ),
        (
            Quantity::ShadowBytes { layers, size: map },
            shadow_bytes,
            "maxMemoryAllocationSize",
            max_allocation,
        ),
        (
            Quantity::SceneBytes { resolution: [width, height], layers, size: map },
            total,
            "largest device-local memory heap",
            heap,
        ),
    ]
}

/// A host target's formats must be renderable: colour attachment (optimal tiling) for the colour
/// format, depth-stencil attachment with a depth aspect for the depth format.
pub(in crate::render) fn check_host_formats(gpu: &Gpu, color: vk::Format, depth: vk::Format) -> Result<(), RenderError> {
    let features = |format| {
        // SAFETY: a plain query on the device in use.
        unsafe { gpu.instance().get_physical_device_format_properties(gpu.physical_device(), format) }
            .optimal_tiling_features
    };
    if !features(color).contains(vk::FormatFeatureFlags::COLOR_ATTACHMENT) {
        return Err(RenderError::Format { which: "colour", format: color });
    }
    let has_depth = crate::gpu::aspect_of(depth).contains(vk::ImageAspectFlags::DEPTH);
    if !has_depth || !features(depth).contains(vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT) {
        return Err(RenderError::Format { which: "depth", format: depth });
    }
    Ok(())
}

/// `maxMemoryAllocationSize` and the size of the largest device-local heap.
fn memory_limits(gpu: &Gpu) -> (u64, u64) {
    let mut maintenance3 = ash::vk::PhysicalDeviceMaintenance3Properties::default();
    let mut properties = ash::vk::PhysicalDeviceProperties2::default().push_next(&mut maintenance3);
    // SAFETY: plain queries on the device in use (Vulkan 1.1 core).
    let memory = unsafe {
        gpu.instance().get_physical_device_properties2(gpu.physical_device(), &mut properties);
        gpu.instance().get_physical_device_memory_properties(gpu.physical_device())
    };
    let heaps = &memory.memory_heaps[..memory.memory_heap_count as usize];
    let local = heaps.iter().filter(|h| h.flags.contains(ash::vk::MemoryHeapFlags::DEVICE_LOCAL));
    (maintenance3.max_memory_allocation_size, local.map(|h| h.size).max().unwrap_or(u64::MAX))
}
