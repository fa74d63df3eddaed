//! A small CPU rasteriser for the false-colour per-vertex error image.
//!
//! The error image is a report artefact, not a frame: doing it on the CPU keeps the report independent of the
//! renderer's pipelines and testable without a GPU. Clip conventions match Vulkan so the renderer's
//! view-projection matrix can be passed unchanged.

use glam::{Mat4, Vec3, Vec4, Vec4Swizzles};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::plot::{PlotError, ensure_font, rgb_to_rgba};

/// Draws triangles with per-vertex colours into an RGBA8 image (rows top to bottom).
///
/// Clip space is Vulkan's: NDC x and y in [-1, 1] with y = -1 at the top row, depth z/w in [0, 1] with smaller
/// nearer. Colours are interpolated perspective-correctly and depth-tested per pixel. Both windings are drawn
/// (no back-face culling), since the error of a surface seen from behind through a hole is still error.
/// Triangles with any vertex at w <= 0 (behind the eye) are skipped rather than clipped; pixels whose depth
/// falls outside [0, 1] are discarded. Colours are display values in [0, 1], written as 8-bit without any
/// transfer function.
pub fn rasterise(
    positions: &[[f32; 3]],
    triangles: &[[u32; 3]],
    colours: &[[f32; 3]],
    view_proj: Mat4,
    width: u32,
    height: u32,
    background: [u8; 3],
) -> Vec<u8> {
    let (w, h) = (width as usize, height as usize);
    let mut rgba: Vec<u8> =
        std::iter::repeat_n([background[0], background[1], background[2], 255], w * h).flatten().collect();
    let mut depth = vec![f32::INFINITY; w * h];
    let clip: Vec<Vec4> = positions.iter().map(|p| view_proj * Vec3::from(*p).extend(1.0)).collect();

    for tri in triangles {
        // Out-of-range indices are a caller bug; skipping the triangle keeps the report going.
        if tri.iter().any(|&i| i as usize >= clip.len().min(colours.len())) {
            continue;
        }
        let idx = *tri;
        let c = idx.map(|i| clip[i as usize]);
        if c.iter().any(|v| v.w <= 0.0 || !v.is_finite()) {
            continue;
        }
        // Screen position in pixels, NDC depth, and 1/w for perspective-correct attributes.
        let inv_w = c.map(|v| 1.0 / v.w);
        let ndc = [c[0].xyz() * inv_w[0], c[1].xyz() * inv_w[1], c[2].xyz() * inv_w[2]];
        let screen = ndc.map(|n| ((n.x * 0.5 + 0.5) * width as f32, (n.y * 0.5 + 0.5) * height as f32));
        let colour = idx.map(|i| Vec3::from(colours[i as usize]));

        let edge = |a: (f32, f32), b: (f32, f32), p: (f32, f32)| (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0);
        let area = edge(screen[0], screen[1], screen[2]);
        if area == 0.0 || !area.is_finite() {
            continue;
        }
        let min_x = screen.iter().map(|s| s.0).fold(f32::INFINITY, f32::min).floor().max(0.0) as usize;
        let max_x = screen.iter().map(|s| s.0).fold(f32::NEG_INFINITY, f32::max).ceil().min(width as f32) as usize;
        let min_y = screen.iter().map(|s| s.1).fold(f32::INFINITY, f32::min).floor().max(0.0) as usize;
        let max_y = screen.iter().map(|s| s.1).fold(f32::NEG_INFINITY, f32::max).ceil().min(height as f32) as usize;

        for y in min_y..max_y {
            for x in min_x..max_x {
                let p = (x as f32 + 0.5, y as f32 + 0.5);
                // Dividing by the signed area makes the weights positive inside for either winding.
                let b = [
                    edge(screen[1], screen[2], p) / area,
                    edge(screen[2], screen[0], p) / area,
                    edge(screen[0], screen[1], p) / area,
                ];
                if b.iter().any(|&v| v < 0.0) {
                    continue;
                }
                let z = b[0] * ndc[0].z + b[1] * ndc[1].z + b[2] * ndc[2].z;
                let at = y * w + x;
                if !(0.0..=1.0).contains(&z) || z >= depth[at] {
                    continue;
                }
                depth[at] = z;
                let pw = [b[0] * inv_w[0], b[1] * inv_w[1], b[2] * inv_w[2]];
                let value = (colour[0] * pw[0] + colour[1] * pw[1] + colour[2] * pw[2]) / (pw[0] + pw[1] + pw[2]);
                rgba[at * 4..at * 4 + 3].copy_from_slice(&to_u8(value.into()));
            }
        }
    }
    rgba
}

/// Display colour to 8-bit; NaN shows as magenta so broken values stand out.
fn to_u8(c: [f32; 3]) -> [u8; 3] {
    if c.iter().any(|v| v.is_nan()) {
        return [255, 0, 255];
    }
    c.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// Viridis sampled at nine evenly spaced points (sRGB display values); perceptually uniform and readable in
/// greyscale and by most colour-blind viewers, which matters for an error map.
const VIRIDIS: [[f32; 3]; 9] = [
    [0.267, 0.005, 0.329],
    [0.283, 0.141, 0.458],
    [0.230, 0.322, 0.546],
    [0.173, 0.449, 0.558],
    [0.128, 0.567, 0.551],
    [0.158, 0.684, 0.502],
    [0.369, 0.789, 0.383],
    [0.678, 0.864, 0.190],
    [0.993, 0.906, 0.144],
];

/// Viridis-like colour for `t` in [0, 1] (clamped), linearly interpolated between nine control points; NaN gives
/// magenta.
pub fn colormap(t: f32) -> [f32; 3] {
    if t.is_nan() {
        return [1.0, 0.0, 1.0];
    }
    let x = t.clamp(0.0, 1.0) * (VIRIDIS.len() - 1) as f32;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f32;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    [a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f, a[2] + (b[2] - a[2]) * f]
}

/// Draws a vertical [`colormap`] bar with three labelled ticks (bottom, middle, top: `labels[0..3]`) on a white
/// panel at the right edge of an RGBA8 image, so the false colours can be read as numbers.
pub fn legend_bar(rgba: &mut [u8], width: u32, height: u32, labels: [&str; 3]) -> Result<(), PlotError> {
    let expected = width as usize * height as usize * 4;
    if rgba.len() != expected {
        return Err(PlotError::ImageBytes { image: "legend", bytes: rgba.len(), width, height, expected });
    }
    const PANEL: i32 = 110;
    if width <= PANEL as u32 || height < 80 {
        return Err(PlotError::LegendTooSmall { width, height });
    }
    ensure_font();
    let (w, h) = (width as i32, height as i32);
    let mut rgb: Vec<u8> = rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (width, height)).into_drawing_area();
        let (top, bottom) = (h / 5, h - h / 5);
        let (left, bar_w) = (w - PANEL + 10, 18);
        root.draw(&Rectangle::new([(w - PANEL, top - 14), (w - 4, bottom + 14)], WHITE.mix(0.85).filled()))?;
        for y in top..bottom {
            let t = (bottom - 1 - y) as f32 / (bottom - top - 1).max(1) as f32;
            let [r, g, b] = to_u8(colormap(t));
            root.draw(&Rectangle::new([(left, y), (left + bar_w, y + 1)], RGBColor(r, g, b).filled()))?;
        }
        root.draw(&Rectangle::new([(left, top), (left + bar_w, bottom)], BLACK.stroke_width(1)))?;
        let style = ("sans-serif", 14).into_font().color(&BLACK).pos(Pos::new(HPos::Left, VPos::Center));
        for (label, y) in labels.iter().zip([bottom - 1, (top + bottom) / 2, top]) {
            root.draw(&PathElement::new([(left + bar_w, y), (left + bar_w + 5, y)], BLACK.stroke_width(1)))?;
            root.draw(&Text::new(label.to_string(), (left + bar_w + 8, y), style.clone()))?;
        }
        root.present()?;
    }
    for (dst, src) in rgba.chunks_exact_mut(4).zip(rgb_to_rgba(&rgb).chunks_exact(4)) {
        dst[..3].copy_from_slice(&src[..3]);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const BG: [u8; 3] = [10, 20, 30];

    fn pixel(image: &[u8], width: u32, x: u32, y: u32) -> [u8; 3] {
        let at = ((y * width + x) * 4) as usize;
        [image[at], image[at + 1], image[at + 2]]
    }

    #[test]
    fn identity_triangle_covers_the_centre() {
        let positions = [[-0.8, 0.8, 0.5], [0.8, 0.8, 0.5], [0.0, -0.8, 0.5]];
        let image = rasterise(&positions, &[[0, 1, 2]], &[[1.0, 0.0, 0.0]; 3], Mat4::IDENTITY, 64, 48, BG);
        assert_eq!(image.len(), 64 * 48 * 4);
        assert_eq!(pixel(&image, 64, 32, 24), [255, 0, 0]);
        assert_eq!(pixel(&image, 64, 0, 0), BG);
        assert_eq!(pixel(&image, 64, 63, 47), BG);
        // NDC y = -0.8 is near the top: the apex row is covered at the centre column, its corners are not.
        assert_eq!(pixel(&image, 64, 32, 6), [255, 0, 0]);
        assert_eq!(pixel(&image, 64, 4, 6), BG);
        // Opposite winding draws too.
        let flipped = rasterise(&positions, &[[0, 2, 1]], &[[0.0, 1.0, 0.0]; 3], Mat4::IDENTITY, 64, 48, BG);
        assert_eq!(pixel(&flipped, 64, 32, 24), [0, 255, 0]);
    }

    #[test]
    fn nearer_triangle_wins() {
        let far = [[-1.0, -1.0, 0.8], [3.0, -1.0, 0.8], [-1.0, 3.0, 0.8]];
        let near = [[-1.0, -1.0, 0.2], [3.0, -1.0, 0.2], [-1.0, 3.0, 0.2]];
        let positions: Vec<[f32; 3]> = far.into_iter().chain(near).collect();
        let colours =
            [[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
        for order in [[[0, 1, 2], [3, 4, 5]], [[3, 4, 5], [0, 1, 2]]] {
            let image = rasterise(&positions, &order, &colours, Mat4::IDENTITY, 16, 16, BG);
            assert_eq!(pixel(&image, 16, 8, 8), [255, 255, 0]);
        }
    }

    #[test]
    fn perspective_projection_and_behind_the_eye() {
        use glam::camera::rh::{proj::vulkan, view::look_at_mat4};
        let view = look_at_mat4(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y);
        let proj = vulkan::perspective(1.0, 1.0, 0.1, 100.0);
        let positions =
            [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 5.0], [1.0, 0.0, 5.0], [0.0, 1.0, 5.0]];
        let colours =
            [[0.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
        let image = rasterise(&positions, &[[0, 1, 2], [3, 4, 5]], &colours, proj * view, 32, 32, BG);
        assert_eq!(pixel(&image, 32, 16, 16), [0, 255, 0]);
        assert_eq!(pixel(&image, 32, 0, 0), BG);
        // The triangle behind the eye is skipped, not drawn mirrored.
        assert!(image.chunks_exact(4).all(|p| p[..3] != [255, 0, 0]));
    }

    #[test]
    fn colormap_ends_and_nan() {
        assert_eq!(colormap(-1.0), VIRIDIS[0]);
        assert_eq!(colormap(2.0), VIRIDIS[8]);
        assert_eq!(colormap(f32::NAN), [1.0, 0.0, 1.0]);
        // Brightness rises along the map.
        let luma = |c: [f32; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        assert!((0..10).all(|i| luma(colormap(i as f32 / 10.0)) < luma(colormap((i + 1) as f32 / 10.0))));
    }

    #[test]
    fn legend_is_drawn() {
        let (w, h) = (320, 200);
        let mut image = rasterise(&[], &[], &[], Mat4::IDENTITY, w, h, [255, 255, 255]);
        legend_bar(&mut image, w, h, ["0 %", "5 %", "10 %"]).unwrap();
        let bar_x = w - 110 + 10 + 9;
        let expected = to_u8(colormap(0.5));
        let got = pixel(&image, w, bar_x, h / 2);
        assert!((0..3).all(|i| got[i].abs_diff(expected[i]) <= 3), "{got:?} vs {expected:?}");
        assert!(legend_bar(&mut image, 100, 100, ["a", "b", "c"]).is_err());
    }
}
