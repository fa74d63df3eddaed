//! Shared by the GPU tests: a validated context on lavapipe (or whatever TRANSLUCENT_DEVICE
//! names) that fails the test on any validation message, leaks at device destruction included.
#![allow(dead_code)]

use std::sync::Arc;
use translucent::gpu::{Gpu, GpuOptions};

/// Run `f` with a fresh validated `Gpu`; after it returns, destroy the device and assert that
/// the validation layer said nothing. `f` must not keep clones of the `Arc<Gpu>`.
pub fn with_gpu<R>(f: impl FnOnce(&Arc<Gpu>) -> R) -> R {
    let options =
        GpuOptions { device: std::env::var("TRANSLUCENT_DEVICE").ok(), validation: true, ..GpuOptions::default() };
    let gpu = Gpu::new(&options).unwrap_or_else(|e| {
        panic!(
            "GPU tests need a Vulkan device with validation layers: {e}\n\
             run `bash scripts/setup` (installs mesa-vulkan-drivers and vulkan-validationlayers)"
        )
    });
    let counters = gpu.validation();
    let result = f(&gpu);
    assert_eq!(Arc::strong_count(&gpu), 1, "a GPU resource outlived the test body");
    drop(gpu);
    assert_eq!(
        counters.total(),
        0,
        "Vulkan validation reported {} warnings and {} errors:\n{}",
        counters.warnings(),
        counters.errors(),
        counters.messages().join("\n")
    );
    result
}
