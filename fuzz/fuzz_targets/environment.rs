//! The environment-map decoder (`Environment::from_bytes`, what `Environment::load` runs on a
//! file's bytes): Radiance .hdr and OpenEXR through the `image` crate, then the texel checks.
//! An accepted map must be at least 2x2, finite and non-negative, and its median cut must give
//! finite lights.
#![no_main]

use libfuzzer_sys::fuzz_target;
use translucent::scene::lights::Environment;

/// Maps up to 1024x1024: the size limit itself is tested in tests/bad_input.rs, and a header
/// claiming 8K is slow to decode under the sanitizer without being a defect.
const MAX_TEXELS: usize = 1 << 20;

fuzz_target!(|data: &[u8]| {
    let Ok(env) = Environment::from_bytes_within(data, "fuzz.hdr", MAX_TEXELS) else { return };
    assert!(env.width * env.height <= MAX_TEXELS);
    assert!(env.width >= 2 && env.height >= 2);
    assert_eq!(env.radiance.len(), env.width * env.height);
    assert!(env.radiance.iter().all(|l| l.is_finite() && l.min_element() >= 0.0));
    // The median cut walks the whole map per split: keep it to small maps so a run stays fast.
    if env.width * env.height <= 64 * 64 {
        for (direction, irradiance) in env.median_cut(16) {
            assert!(direction.is_finite() && irradiance.is_finite(), "{direction} {irradiance}");
        }
    }
});
