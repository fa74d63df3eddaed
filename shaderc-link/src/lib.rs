//! Nothing to call: this crate exists for its build script, which links the static glslang and
//! SPIRV-Tools archives that Debian's `libshaderc_combined.a` needs but does not contain.
//! translucent's build script names it (`use translucent_shaderc_link as _;`) so that it is
//! linked. See build.rs for why.
#![no_std]
