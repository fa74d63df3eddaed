//! Makes `shaderc` link on Debian 12 and Ubuntu from a fresh crate, with no configuration.
//!
//! Why: shaderc-sys's build script, finding Debian's `/usr/lib/x86_64-linux-gnu`, links
//! `libshaderc.so`, whose glslang symbols are undefined (Debian ships glslang only as static
//! archives), so rust-lld refuses the link (`--no-allow-shlib-undefined`); setting
//! `SHADERC_LIB_DIR` gives the same. With shaderc's `prefer-static-linking` (which translucent
//! turns on), it links `libshaderc_combined.a` instead, but Debian's "combined" archive holds
//! only shaderc's own ten objects, not glslang and SPIRV-Tools. This script adds them.
//!
//! They are linked `-bundle`: rustc passes unbundled native libraries after every rlib, so
//! they follow `libshaderc_combined.a` (bundled into shaderc-sys's rlib) even for a linker that
//! reads archives once, in order (GNU ld), and they are not copied into this crate's rlib.
//!
//! Where the archives are missing, the build fails here naming the packages to install, instead
//! of shaderc-sys's linker error. Nothing is linked when shaderc is built from source (feature
//! `from-source`), when `VULKAN_SDK` is set and `SHADERC_LIB_DIR` is not (the SDK's combined
//! archive is complete), or on other systems than Linux.

use std::path::{Path, PathBuf};

/// The archives under `libshaderc_combined.a`, in link order (each uses those after it).
const ARCHIVES: &[&str] = &[
    "glslang",
    "SPIRV",
    "MachineIndependent",
    "GenericCodeGen",
    "OSDependent",
    "OGLCompiler",
    "glslang-default-resource-limits",
    "SPIRV-Tools-opt",
    "SPIRV-Tools",
];

fn main() {
    println!("cargo:rerun-if-env-changed=SHADERC_LIB_DIR");
    println!("cargo:rerun-if-env-changed=VULKAN_SDK");
    let var = |name: &str| std::env::var(name).ok();
    if var("CARGO_FEATURE_FROM_SOURCE").is_some() || var("CARGO_CFG_TARGET_OS").as_deref() != Some("linux") {
        return;
    }
    let explicit = var("SHADERC_LIB_DIR");
    if explicit.is_none() && var("VULKAN_SDK").is_some() {
        return;
    }
    let dir = explicit.map(PathBuf::from).unwrap_or_else(|| {
        let arch = match var("CARGO_CFG_TARGET_ARCH").as_deref() {
            Some("x86") => "i386".to_owned(),
            Some(arch) => arch.to_owned(),
            None => "x86_64".to_owned(),
        };
        PathBuf::from(format!("/usr/lib/{arch}-linux-gnu"))
    });
    let missing: Vec<String> = std::iter::once("shaderc_combined")
        .chain(ARCHIVES.iter().copied())
        .map(|name| format!("lib{name}.a"))
        .filter(|file| !dir.join(file).is_file())
        .collect();
    if !missing.is_empty() {
        fail(&dir, &missing);
    }
    println!("cargo:rustc-link-search=native={}", dir.display());
    for name in ARCHIVES {
        println!("cargo:rustc-link-lib=static:-bundle={name}");
    }
    // glslang and SPIRV-Tools are C++; after them, for a linker that reads in order.
    println!("cargo:rustc-link-lib=dylib=stdc++");
}

/// Exits with what to install or set: a panic would bury it under a backtrace.
fn fail(dir: &Path, missing: &[String]) -> ! {
    eprintln!(
        "\ntranslucent compiles its GLSL with glslang through the `shaderc` crate, linked \
         statically, and {} lacks {}.\n\
         On Debian 12 or Ubuntu: sudo apt-get install libshaderc-dev glslang-dev spirv-tools g++ \
         (translucent's scripts/setup does this).\n\
         Elsewhere: set SHADERC_LIB_DIR to the folder holding libshaderc_combined.a and the \
         static glslang and SPIRV-Tools archives; or set VULKAN_SDK to a Vulkan SDK; or build \
         shaderc from source (CMake, Python, git; over 13 minutes on 2 cores) with translucent's \
         feature `shaderc-from-source`.\n",
        dir.display(),
        missing.join(", ")
    );
    std::process::exit(1);
}
