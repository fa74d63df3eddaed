//! The SPIR-V that build.rs compiled from `glsl/`, embedded in the binary.

use super::descriptor::BindingKind;
use super::error::{GpuError, GpuResult};

mod generated {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}

/// Paths (under `glsl/`) of every embedded shader.
pub fn names() -> impl Iterator<Item = &'static str> {
    generated::SHADERS.iter().map(|(name, _)| *name)
}

/// The SPIR-V words of the shader at `name` (its path under `glsl/`, e.g. "smoke.comp").
pub fn spirv(name: &str) -> GpuResult<Vec<u32>> {
    let (_, bytes) =
        generated::SHADERS.iter().find(|(n, _)| *n == name).ok_or_else(|| GpuError::UnknownShader(name.into()))?;
    // read_spv copies into u32 words, so the bytes' alignment does not matter.
    ash::util::read_spv(&mut std::io::Cursor::new(bytes))
        .map_err(|e| GpuError::Invalid(format!("embedded shader {name} is not SPIR-V: {e}")))
}

/// A shader's interface as its SPIR-V declares it: set 0's bindings, the push-constant block
/// and the workgroup size. Pipelines are built from this, so no Rust code restates them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShaderInterface {
    /// Binding kinds of set 0, indexed by binding number (`None` for a number not declared, or
    /// eliminated as unused by the optimiser in release builds).
    pub bindings: Vec<Option<BindingKind>>,
    /// Bytes of the push-constant block (0 without one).
    pub push_bytes: u32,
    /// `local_size` of a compute shader; [1, 1, 1] for other stages.
    pub local_size: [u32; 3],
}

impl ShaderInterface {
    /// Reflect the embedded shader `name`.
    pub fn of(name: &str) -> GpuResult<ShaderInterface> {
        let (_, bytes) =
            generated::SHADERS.iter().find(|(n, _)| *n == name).ok_or_else(|| GpuError::UnknownShader(name.into()))?;
        let invalid = |e: &dyn std::fmt::Display| GpuError::Invalid(format!("reflecting shader {name}: {e}"));
        let reflection = rspirv_reflect::Reflection::new_from_spirv(bytes).map_err(|e| invalid(&e))?;
        let sets = reflection.get_descriptor_sets().map_err(|e| invalid(&e))?;
        if let Some(set) = sets.keys().find(|s| **s != 0) {
            return Err(invalid(&format!("uses descriptor set {set}; only set 0 is supported")));
        }
        let mut bindings = Vec::new();
        for (binding, info) in sets.get(&0).into_iter().flatten() {
            let kind = BindingKind::from_reflected(info.ty)
                .ok_or_else(|| invalid(&format!("binding {binding} has unsupported descriptor type {:?}", info.ty)))?;
            let i = *binding as usize;
            if bindings.len() <= i {
                bindings.resize(i + 1, None);
            }
            bindings[i] = Some(kind);
        }
        let push_bytes =
            reflection.get_push_constant_range().map_err(|e| invalid(&e))?.map_or(0, |p| p.offset + p.size);
        let local_size = reflection.get_compute_group_size().map_or([1, 1, 1], |(x, y, z)| [x, y, z]);
        Ok(ShaderInterface { bindings, push_bytes, local_size })
    }

    /// The interface of several stages sharing one layout (vertex + fragment): the union of
    /// their bindings, which must agree where both declare one, and the larger push block.
    pub fn merge(stages: &[ShaderInterface]) -> GpuResult<ShaderInterface> {
        let mut merged = ShaderInterface { bindings: Vec::new(), push_bytes: 0, local_size: [1, 1, 1] };
        for s in stages {
            if merged.bindings.len() < s.bindings.len() {
                merged.bindings.resize(s.bindings.len(), None);
            }
            for (i, kind) in s.bindings.iter().enumerate() {
                match (merged.bindings[i], kind) {
                    (Some(a), Some(b)) if a != *b => {
                        return Err(GpuError::Invalid(format!(
                            "binding {i} is {a:?} in one stage and {b:?} in another"
                        )));
                    }
                    (None, Some(b)) => merged.bindings[i] = Some(*b),
                    _ => {}
                }
            }
            merged.push_bytes = merged.push_bytes.max(s.push_bytes);
        }
        Ok(merged)
    }
}
