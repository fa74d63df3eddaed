//! Perceptual image error with NVIDIA's FLIP (through the `nv-flip` bindings).
//!
//! Both images must already be tone mapped to sRGB display values: FLIP models what a viewer sees on a screen.
//! The viewing condition is nv-flip's default of 67 pixels per degree (roughly a 0.7 m wide 3840-pixel monitor
//! seen from 0.7 m), the value FLIP's authors use, so figures are comparable with other FLIP numbers.

use nv_flip::{DEFAULT_PIXELS_PER_DEGREE, FlipImageFloat, FlipImageRgb8};

use super::plot::{PlotError, rgb_to_rgba};

/// Checks the sizes and drops alpha, which FLIP does not use.
fn to_rgb(image: &'static str, rgba: &[u8], width: u32, height: u32) -> Result<Vec<u8>, PlotError> {
    let expected = width as usize * height as usize * 4;
    if width == 0 || height == 0 {
        return Err(PlotError::EmptyImage { image, width, height });
    }
    if rgba.len() != expected {
        return Err(PlotError::ImageBytes { image, bytes: rgba.len(), width, height, expected });
    }
    Ok(rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect())
}

fn error_map(reference: &[u8], test: &[u8], width: u32, height: u32) -> Result<FlipImageFloat, PlotError> {
    let reference = FlipImageRgb8::with_data(width, height, &to_rgb("reference", reference, width, height)?);
    let test = FlipImageRgb8::with_data(width, height, &to_rgb("test", test, width, height)?);
    Ok(nv_flip::flip(reference, test, DEFAULT_PIXELS_PER_DEGREE))
}

/// Mean of the FLIP error map (0 identical, 1 maximally different) of two sRGB RGBA8 images of the same size.
///
/// The mean is the single figure FLIP's authors recommend; it is summed here in f64 from the map itself rather
/// than read from nv-flip's histogram pool, so it is exact.
pub fn flip_mean(reference: &[u8], test: &[u8], width: u32, height: u32) -> Result<f64, PlotError> {
    let map = error_map(reference, test, width, height)?.to_vec();
    Ok(map.iter().map(|&v| f64::from(v)).sum::<f64>() / map.len() as f64)
}

/// The FLIP error map coloured with FLIP's magma lookup table, as RGBA8, for looking at where the error is.
pub fn flip_map(reference: &[u8], test: &[u8], width: u32, height: u32) -> Result<Vec<u8>, PlotError> {
    let coloured = error_map(reference, test, width, height)?.apply_color_lut(&nv_flip::magma_lut());
    Ok(rgb_to_rgba(&coloured.to_vec()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: u32, height: u32, f: impl Fn(u32, u32) -> [u8; 3]) -> Vec<u8> {
        (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .flat_map(|(x, y)| {
                let [r, g, b] = f(x, y);
                [r, g, b, 255]
            })
            .collect()
    }

    #[test]
    fn identical_images_have_no_error() {
        let a = image(32, 24, |x, y| [(x * 8) as u8, (y * 10) as u8, 128]);
        assert!(flip_mean(&a, &a, 32, 24).unwrap() < 1e-6);
    }

    #[test]
    fn black_and_white_differ_a_lot() {
        let black = image(16, 16, |_, _| [0, 0, 0]);
        let white = image(16, 16, |_, _| [255, 255, 255]);
        assert!(flip_mean(&black, &white, 16, 16).unwrap() > 0.5);
        let map = flip_map(&black, &white, 16, 16).unwrap();
        assert_eq!(map.len(), 16 * 16 * 4);
    }

    #[test]
    fn size_mismatch_is_an_error() {
        let a = image(16, 16, |_, _| [0, 0, 0]);
        assert!(flip_mean(&a, &a[..100], 16, 16).is_err());
        assert!(flip_mean(&a, &a, 16, 8).is_err());
        assert!(flip_mean(&[], &[], 0, 0).is_err());
    }
}
