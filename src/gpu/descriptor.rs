//! Descriptor-set layouts and sets. Each set owns a small pool sized for exactly its bindings:
//! passes create their sets once and reuse them across frames.

use super::buffer::Buffer;
use super::context::Gpu;
use super::error::{GpuError, GpuResult, VkContext};
use ash::vk;
use std::sync::Arc;

/// The kind of one binding, as reflected from a shader's SPIR-V (`shaders::ShaderInterface`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BindingKind {
    /// A std430 storage buffer (STORAGE_BUFFER), bound with `Binding::Buffer`.
    StorageBuffer,
    /// A uniform buffer (UNIFORM_BUFFER), bound with `Binding::Buffer`.
    UniformBuffer,
    /// An image read through a sampler (COMBINED_IMAGE_SAMPLER: `sampler2D`,
    /// `sampler2DArrayShadow`), bound with `Binding::Image`.
    CombinedImageSampler,
    /// An image read and written with imageLoad/imageStore (STORAGE_IMAGE, GENERAL layout), bound
    /// with `Binding::Image`.
    StorageImage,
}

impl BindingKind {
    pub(super) fn vk(self) -> vk::DescriptorType {
        match self {
            BindingKind::StorageBuffer => vk::DescriptorType::STORAGE_BUFFER,
            BindingKind::UniformBuffer => vk::DescriptorType::UNIFORM_BUFFER,
            BindingKind::CombinedImageSampler => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            BindingKind::StorageImage => vk::DescriptorType::STORAGE_IMAGE,
        }
    }

    pub(crate) fn from_reflected(ty: rspirv_reflect::DescriptorType) -> Option<BindingKind> {
        use rspirv_reflect::DescriptorType as T;
        match ty {
            T::STORAGE_BUFFER => Some(BindingKind::StorageBuffer),
            T::UNIFORM_BUFFER => Some(BindingKind::UniformBuffer),
            T::COMBINED_IMAGE_SAMPLER => Some(BindingKind::CombinedImageSampler),
            T::STORAGE_IMAGE => Some(BindingKind::StorageImage),
            _ => None,
        }
    }
}

/// What to bind at one binding; a set is given as a list of `Named` bindings, binding i being
/// the i-th entry.
pub enum Binding<'a> {
    /// A whole buffer (offset 0, VK_WHOLE_SIZE) for a storage or uniform binding.
    Buffer(&'a Buffer),
    /// An image view for a combined-image-sampler or storage-image binding.
    Image {
        /// The view the shader samples or reads and writes.
        view: vk::ImageView,
        /// The layout the image is in whenever the set is used: SHADER_READ_ONLY_OPTIMAL to sample,
        /// GENERAL for storage.
        layout: vk::ImageLayout,
        /// The sampler of a combined image sampler; `vk::Sampler::null()` for a storage image.
        sampler: vk::Sampler,
    },
}

/// One entry of a descriptor set: the GLSL name it is meant for (the block or variable name the
/// shader declares at that binding) and the resource. The name is checked against the shader's
/// reflected one, so two swapped resources fail with both names instead of binding silently.
pub struct Named<'a> {
    /// The GLSL block or variable name, e.g. "Exitance" or "shadow_maps".
    pub name: &'a str,
    /// The resource.
    pub binding: Binding<'a>,
}

/// What a set's bindings must match: each binding's kind and GLSL name, as reflected, and the
/// shader they come from (for messages).
pub(crate) struct SetInterface<'a> {
    pub shader: &'a str,
    pub kinds: &'a [Option<BindingKind>],
    pub names: &'a [Option<String>],
}

impl SetInterface<'_> {
    /// Every declared binding has a resource, and each resource's name is the one the GLSL
    /// declares at its binding. A resource past the declared bindings, or at a number the
    /// optimiser removed as unused, is dropped unchecked.
    fn check(&self, bindings: &[Named<'_>]) -> GpuResult<()> {
        if let Some(missing) = self.kinds.iter().enumerate().skip(bindings.len()).find(|(_, k)| k.is_some()) {
            return Err(GpuError::MissingBinding {
                shader: self.shader.to_string(),
                binding: missing.0,
                given: bindings.len(),
            });
        }
        for (i, given) in bindings.iter().enumerate() {
            let declared = self.names.get(i).and_then(Option::as_deref);
            match declared {
                Some(declared) if self.kinds.get(i).is_some_and(Option::is_some) && declared != given.name => {
                    return Err(GpuError::BindingMismatch {
                        shader: self.shader.to_string(),
                        binding: i as u32,
                        declared: declared.to_string(),
                        given: given.name.to_string(),
                    });
                }
                _ => {}
            }
        }
        Ok(())
    }
}

pub(crate) fn create_set_layout(
    gpu: &Gpu,
    kinds: &[Option<BindingKind>],
    stages: vk::ShaderStageFlags,
) -> GpuResult<vk::DescriptorSetLayout> {
    let bindings: Vec<_> = kinds
        .iter()
        .enumerate()
        .filter_map(|(i, k)| k.map(|k| (i, k)))
        .map(|(i, k)| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(i as u32)
                .descriptor_type(k.vk())
                .descriptor_count(1)
                .stage_flags(stages)
        })
        .collect();
    let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
    // SAFETY: valid create info; the owner destroys the layout.
    unsafe { gpu.device().create_descriptor_set_layout(&info, None) }.vk("vkCreateDescriptorSetLayout")
}

/// One descriptor set for a pipeline's set 0, allocated from a pool of its own sized for exactly
/// its bindings (`ComputePipeline::descriptor_set`, `GraphicsPipeline::descriptor_set`). Destroying
/// the pool on Drop frees the set. It holds an `Arc<Gpu>` but not the resources it points at: they
/// must outlive every use of the set.
pub struct DescriptorSet {
    gpu: Arc<Gpu>,
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
}

impl DescriptorSet {
    pub(crate) fn new(
        gpu: &Arc<Gpu>,
        layout: vk::DescriptorSetLayout,
        interface: &SetInterface<'_>,
        bindings: &[Named<'_>],
    ) -> GpuResult<DescriptorSet> {
        interface.check(bindings)?;
        let kinds = interface.kinds;
        let device = gpu.device();
        let sizes: Vec<_> =
            kinds.iter().flatten().map(|k| vk::DescriptorPoolSize { ty: k.vk(), descriptor_count: 1 }).collect();
        let info = vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes);
        // SAFETY: valid create info; destroyed in Drop.
        let pool = unsafe { device.create_descriptor_pool(&info, None) }.vk("vkCreateDescriptorPool")?;
        let mut out = DescriptorSet { gpu: gpu.clone(), pool, set: vk::DescriptorSet::null() };
        let layouts = [layout];
        let alloc = vk::DescriptorSetAllocateInfo::default().descriptor_pool(pool).set_layouts(&layouts);
        // SAFETY: `pool` was just made for one set, with one descriptor per kind in `kinds`, from
        // which `layout` (live, the pipeline's) was made; the set is freed with the pool in Drop.
        out.set = unsafe { device.allocate_descriptor_sets(&alloc) }.vk("vkAllocateDescriptorSets")?[0];
        out.update(kinds, bindings)?;
        Ok(out)
    }

    /// Point the bindings at other resources (same kinds). Not while the set is in use by the GPU.
    fn update(&mut self, kinds: &[Option<BindingKind>], bindings: &[Named<'_>]) -> GpuResult<()> {
        let mut buffer_infos = Vec::new();
        let mut image_infos = Vec::new();
        for (i, (kind, Named { binding, .. })) in kinds.iter().zip(bindings).enumerate() {
            let Some(kind) = kind else { continue };
            match (kind, binding) {
                (BindingKind::StorageBuffer | BindingKind::UniformBuffer, Binding::Buffer(b)) => buffer_infos
                    .push((i, [vk::DescriptorBufferInfo { buffer: b.raw(), offset: 0, range: vk::WHOLE_SIZE }])),
                (
                    BindingKind::CombinedImageSampler | BindingKind::StorageImage,
                    Binding::Image { view, layout, sampler },
                ) => image_infos.push((
                    i,
                    [vk::DescriptorImageInfo { sampler: *sampler, image_view: *view, image_layout: *layout }],
                )),
                _ => return Err(GpuError::BindingType { binding: i, expected: kind.vk() }),
            }
        }
        let mut writes = Vec::new();
        for (i, info) in &buffer_infos {
            writes.push(
                vk::WriteDescriptorSet::default()
                    .dst_set(self.set)
                    .dst_binding(*i as u32)
                    .descriptor_type(kinds[*i].expect("declared").vk())
                    .buffer_info(info),
            );
        }
        for (i, info) in &image_infos {
            writes.push(
                vk::WriteDescriptorSet::default()
                    .dst_set(self.set)
                    .dst_binding(*i as u32)
                    .descriptor_type(kinds[*i].expect("declared").vk())
                    .image_info(info),
            );
        }
        // SAFETY: every write points at live resources of the declared type.
        unsafe { self.gpu.device().update_descriptor_sets(&writes, &[]) };
        Ok(())
    }

    /// The Vulkan handle, as vkCmdBindDescriptorSets takes it.
    pub fn raw(&self) -> vk::DescriptorSet {
        self.set
    }
}

impl Drop for DescriptorSet {
    fn drop(&mut self) {
        // SAFETY: destroying the pool frees its set; no submission using it is pending.
        unsafe { self.gpu.device().destroy_descriptor_pool(self.pool, None) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(name: &str) -> Named<'_> {
        let binding = Binding::Image {
            view: vk::ImageView::null(),
            layout: vk::ImageLayout::GENERAL,
            sampler: vk::Sampler::null(),
        };
        Named { name, binding }
    }

    #[test]
    fn a_resource_past_the_reflected_bindings_is_dropped_unchecked_not_a_panic() {
        // The optimiser removed binding 1: its name may be reflected, its kind is not.
        let kinds = [Some(BindingKind::StorageImage)];
        let names = [Some("A".to_string()), Some("B".to_string())];
        let set = SetInterface { shader: "t.comp", kinds: &kinds, names: &names };
        assert!(set.check(&[image("A"), image("C")]).is_ok());
        // A swapped name at a binding that is there is still an error naming both.
        let err = set.check(&[image("B")]).unwrap_err().to_string();
        assert!(err.contains('A') && err.contains('B'), "{err}");
    }
}
