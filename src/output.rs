//! Writing results: PNG, EXR and PLY, each to a temporary file in the destination folder that
//! is renamed into place only when complete, so a failure never leaves a half-written file.

use anyhow::{Context, Result};
use std::io::Write;
use std::path::Path;

/// Write through `write` into `path.tmp`, then rename to `path`.
pub fn atomic_write(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let name = path.file_name().with_context(|| format!("{} is not a file path", path.display()))?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(".partial");
    let tmp = path.with_file_name(tmp_name);
    let result = write(&tmp).and_then(|()| {
        std::fs::rename(&tmp, path).with_context(|| format!("cannot move {} to {}", tmp.display(), path.display()))
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// An 8-bit RGBA image (rows top to bottom) as PNG.
pub fn write_png(path: &Path, width: u32, height: u32, rgba8: &[u8]) -> Result<()> {
    atomic_write(path, |tmp| {
        let img = image::RgbaImage::from_raw(width, height, rgba8.to_vec()).context("image size mismatch")?;
        img.save_with_format(tmp, image::ImageFormat::Png).with_context(|| format!("cannot write {}", path.display()))
    })
}

/// A linear RGBA f32 image as OpenEXR.
pub fn write_exr(path: &Path, width: u32, height: u32, rgba: &[f32]) -> Result<()> {
    atomic_write(path, |tmp| {
        let img = image::Rgba32FImage::from_raw(width, height, rgba.to_vec()).context("image size mismatch")?;
        image::DynamicImage::ImageRgba32F(img)
            .save_with_format(tmp, image::ImageFormat::OpenExr)
            .with_context(|| format!("cannot write {}", path.display()))
    })
}

/// An ASCII PLY of points with RGB radiant exitance: `x y z exitance_r exitance_g exitance_b`.
pub fn write_exitance_ply(path: &Path, points: &[([f32; 3], [f32; 3])]) -> Result<()> {
    atomic_write(path, |tmp| {
        let file = std::fs::File::create(tmp).with_context(|| format!("cannot create {}", tmp.display()))?;
        let mut w = std::io::BufWriter::new(file);
        writeln!(
            w,
            "ply\nformat ascii 1.0\ncomment translucent: radiant exitance per vertex, linear W/m^2, world space"
        )?;
        writeln!(w, "element vertex {}", points.len())?;
        for p in ["x", "y", "z", "exitance_r", "exitance_g", "exitance_b"] {
            writeln!(w, "property float {p}")?;
        }
        writeln!(w, "end_header")?;
        for (p, e) in points {
            writeln!(w, "{} {} {} {} {} {}", p[0], p[1], p[2], e[0], e[1], e[2])?;
        }
        w.flush()?;
        Ok(())
    })
}
