//! Writing results: PNG, EXR and PLY, each to a temporary file in the destination folder that
//! is renamed into place only when complete, so a failure never leaves a half-written file.

use std::io::Write;
use std::path::{Path, PathBuf};

/// Why an output file was not written; every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{} is not a file path", path.display())]
    NotAFilePath { path: PathBuf },
    // The underlying error is the source (shown by `{:#}` and error reporters), not repeated here.
    #[error("cannot move {} to {}", tmp.display(), path.display())]
    Rename { tmp: PathBuf, path: PathBuf, source: std::io::Error },
    #[error("{}: image size mismatch: {values} values for {width}x{height} pixels", path.display())]
    SizeMismatch { path: PathBuf, width: u32, height: u32, values: usize },
    #[error("cannot write {}", path.display())]
    Image { path: PathBuf, source: image::ImageError },
    #[error("cannot create {}", path.display())]
    Create { path: PathBuf, source: std::io::Error },
    #[error("cannot write {}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
}

/// Write through `write` into `path.tmp`, then rename to `path`.
pub fn atomic_write(path: &Path, write: impl FnOnce(&Path) -> Result<(), OutputError>) -> Result<(), OutputError> {
    let name = path.file_name().ok_or_else(|| OutputError::NotAFilePath { path: path.to_path_buf() })?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(".partial");
    let tmp = path.with_file_name(tmp_name);
    let result = write(&tmp).and_then(|()| {
        std::fs::rename(&tmp, path).map_err(|source| OutputError::Rename {
            tmp: tmp.clone(),
            path: path.to_path_buf(),
            source,
        })
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// An 8-bit RGBA image (rows top to bottom) as PNG.
pub fn write_png(path: &Path, width: u32, height: u32, rgba8: &[u8]) -> Result<(), OutputError> {
    let mismatch = || OutputError::SizeMismatch { path: path.to_path_buf(), width, height, values: rgba8.len() };
    let img = image::RgbaImage::from_raw(width, height, rgba8.to_vec()).ok_or_else(mismatch)?;
    atomic_write(path, |tmp| {
        img.save_with_format(tmp, image::ImageFormat::Png)
            .map_err(|source| OutputError::Image { path: path.to_path_buf(), source })
    })
}

/// A linear RGBA f32 image as OpenEXR.
pub fn write_exr(path: &Path, width: u32, height: u32, rgba: &[f32]) -> Result<(), OutputError> {
    let mismatch = || OutputError::SizeMismatch { path: path.to_path_buf(), width, height, values: rgba.len() };
    let img = image::Rgba32FImage::from_raw(width, height, rgba.to_vec()).ok_or_else(mismatch)?;
    atomic_write(path, |tmp| {
        image::DynamicImage::ImageRgba32F(img)
            .save_with_format(tmp, image::ImageFormat::OpenExr)
            .map_err(|source| OutputError::Image { path: path.to_path_buf(), source })
    })
}

/// An ASCII PLY of points with RGB radiant exitance: `x y z exitance_r exitance_g exitance_b`.
pub fn write_exitance_ply(path: &Path, points: &[([f32; 3], [f32; 3])]) -> Result<(), OutputError> {
    atomic_write(path, |tmp| {
        let file =
            std::fs::File::create(tmp).map_err(|source| OutputError::Create { path: tmp.to_path_buf(), source })?;
        let write = || -> std::io::Result<()> {
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
            w.flush()
        };
        write().map_err(|source| OutputError::Io { path: path.to_path_buf(), source })
    })
}
