//! The SPIR-V that build.rs compiled from `glsl/`, embedded in the binary.

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
