//! The SPIR-V that build.rs compiled from `glsl/`, embedded in the binary.

use super::descriptor::BindingKind;
use super::error::{GpuError, GpuResult};

mod generated {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}

/// Paths (under `glsl/`) of every embedded shader.
pub fn names() -> impl Iterator<Item = &'static str> {
    generated::SHADERS.iter().map(|(name, ..)| *name)
}

/// The embedded entry of `name`: its SPIR-V, and the same shader with its debug names.
fn entry(name: &str) -> GpuResult<(&'static [u8], &'static [u8])> {
    generated::SHADERS
        .iter()
        .find(|(n, ..)| *n == name)
        .map(|(_, code, named)| (*code, *named))
        .ok_or_else(|| GpuError::UnknownShader(name.into()))
}

/// The SPIR-V words of the shader at `name` (its path under `glsl/`, e.g. "smoke.comp").
pub fn spirv(name: &str) -> GpuResult<Vec<u32>> {
    let (bytes, _) = entry(name)?;
    // read_spv copies into u32 words, so the bytes' alignment does not matter.
    ash::util::read_spv(&mut std::io::Cursor::new(bytes))
        .map_err(|source| GpuError::NotSpirv { shader: name.into(), source })
}

/// A shader's interface as its SPIR-V declares it: set 0's bindings, the push-constant block
/// and the workgroup size. Pipelines are built from this, so no Rust code restates them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShaderInterface {
    /// Binding kinds of set 0, indexed by binding number (`None` for a number not declared, or
    /// eliminated as unused by the optimiser in release builds).
    pub bindings: Vec<Option<BindingKind>>,
    /// The GLSL name of each binding of set 0, indexed as `bindings`: a buffer's block name
    /// (`Exitance` in `buffer Exitance { vec4 exitance[]; }`), else the variable's (`shadow_maps`).
    /// Descriptor sets are matched against these (`DescriptorSet::new`).
    pub names: Vec<Option<String>>,
    /// Bytes of the push-constant block (0 without one).
    pub push_bytes: u32,
    /// `local_size` of a compute shader; [1, 1, 1] for other stages.
    pub local_size: [u32; 3],
}

impl ShaderInterface {
    /// Reflect the embedded shader `name`.
    pub fn of(name: &str) -> GpuResult<ShaderInterface> {
        let (bytes, named) = entry(name)?;
        let reflect = |source| GpuError::Reflection { shader: name.into(), source };
        let reflection = rspirv_reflect::Reflection::new_from_spirv(bytes).map_err(reflect)?;
        let sets = reflection.get_descriptor_sets().map_err(reflect)?;
        if let Some(&set) = sets.keys().find(|s| **s != 0) {
            return Err(GpuError::DescriptorSetNumber { shader: name.into(), set });
        }
        let mut bindings = Vec::new();
        for (binding, info) in sets.get(&0).into_iter().flatten() {
            let kind = BindingKind::from_reflected(info.ty).ok_or_else(|| GpuError::DescriptorType {
                shader: name.into(),
                binding: *binding,
                descriptor_type: info.ty,
            })?;
            let i = *binding as usize;
            if bindings.len() <= i {
                bindings.resize(i + 1, None);
            }
            bindings[i] = Some(kind);
        }
        let push_bytes = reflection.get_push_constant_range().map_err(reflect)?.map_or(0, |p| p.offset + p.size);
        let local_size = reflection.get_compute_group_size().map_or([1, 1, 1], |(x, y, z)| [x, y, z]);
        let names = binding_names(named).map_err(reflect)?;
        Ok(ShaderInterface { bindings, names, push_bytes, local_size })
    }

    /// The interface of several stages sharing one layout (vertex + fragment): the union of
    /// their bindings, which must agree where both declare one, and the larger push block.
    pub fn merge(stages: &[ShaderInterface]) -> GpuResult<ShaderInterface> {
        let mut merged =
            ShaderInterface { bindings: Vec::new(), names: Vec::new(), push_bytes: 0, local_size: [1, 1, 1] };
        for s in stages {
            if merged.bindings.len() < s.bindings.len() {
                merged.bindings.resize(s.bindings.len(), None);
            }
            if merged.names.len() < s.names.len() {
                merged.names.resize(s.names.len(), None);
            }
            for (i, name) in s.names.iter().enumerate() {
                match (&merged.names[i], name) {
                    (Some(a), Some(b)) if a != b => {
                        return Err(GpuError::StageBindingNames { binding: i, first: a.clone(), second: b.clone() });
                    }
                    (None, Some(b)) => merged.names[i] = Some(b.clone()),
                    _ => {}
                }
            }
            for (i, kind) in s.bindings.iter().enumerate() {
                match (merged.bindings[i], kind) {
                    (Some(a), Some(b)) if a != *b => {
                        return Err(GpuError::StageBindingTypes { binding: i, first: a.vk(), second: b.vk() });
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

/// The GLSL name of every set-0 binding of a SPIR-V module that kept its debug names, by binding
/// number: for a buffer block the block's type name (an anonymous instance has an empty
/// variable name), otherwise the variable's name.
fn binding_names(named: &[u8]) -> Result<Vec<Option<String>>, rspirv_reflect::ReflectError> {
    use rspirv_reflect::rspirv::dr::Operand;
    use rspirv_reflect::spirv::{Decoration, Op};
    let module = rspirv_reflect::Reflection::new_from_spirv(named)?.0;
    let name_of = |id: u32| {
        module.debug_names.iter().find_map(|i| match (i.class.opcode, i.operands.as_slice()) {
            (Op::Name, [Operand::IdRef(target), Operand::LiteralString(name), ..]) if *target == id => {
                Some(name.clone()).filter(|n| !n.is_empty())
            }
            _ => None,
        })
    };
    let decoration = |id: u32, wanted: Decoration| {
        module.annotations.iter().find_map(|i| match (i.class.opcode, i.operands.as_slice()) {
            (Op::Decorate, [Operand::IdRef(target), Operand::Decoration(d), Operand::LiteralBit32(v), ..])
                if *target == id && *d == wanted =>
            {
                Some(*v)
            }
            _ => None,
        })
    };
    // Pointer type id -> its pointee.
    let pointee = |ty: u32| {
        module.types_global_values.iter().find_map(|i| match (i.class.opcode, i.result_id, i.operands.as_slice()) {
            (Op::TypePointer, Some(id), [_, Operand::IdRef(inner)]) if id == ty => Some(*inner),
            _ => None,
        })
    };
    let mut names = Vec::new();
    for var in module.types_global_values.iter().filter(|i| i.class.opcode == Op::Variable) {
        let (Some(id), Some(ty)) = (var.result_id, var.result_type) else { continue };
        let (Some(0), Some(binding)) = (decoration(id, Decoration::DescriptorSet), decoration(id, Decoration::Binding))
        else {
            continue;
        };
        let name = name_of(id).or_else(|| pointee(ty).and_then(name_of));
        let i = binding as usize;
        if names.len() <= i {
            names.resize(i + 1, None);
        }
        names[i] = name;
    }
    Ok(names)
}
