//! Writing results: PNG, EXR and PLY, each to a temporary file in the destination folder that
//! is renamed into place only when complete, so a failure never leaves a half-written file; an
//! `OutputSet` renames a command's outputs only when all of them were written. Errors name the
//! destination, never the temporary file.

use std::io::Write;
use std::path::{Path, PathBuf};

/// Why an output file was not written; every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The path has no file name (e.g. it ends in `..` or is a root).
    #[error("{} is not a file path", path.display())]
    NotAFilePath {
        /// The destination.
        path: PathBuf,
    },
    // The underlying error is the source (shown by `{:#}` and error reporters), not repeated here.
    /// The destination's folder does not exist.
    #[error("cannot write {}: the folder {} does not exist", path.display(), folder.display())]
    NoFolder {
        /// The destination.
        path: PathBuf,
        /// Its folder.
        folder: PathBuf,
    },
    /// A folder is where the file should go.
    #[error("cannot write {}: it is a folder", path.display())]
    IsAFolder {
        /// The destination.
        path: PathBuf,
    },
    /// Renaming the temporary file onto the destination failed.
    #[error("cannot put {} in place", path.display())]
    Rename {
        /// The destination.
        path: PathBuf,
        /// Why the rename failed.
        source: std::io::Error,
    },
    /// The pixel buffer's length does not match the image size (four values per pixel).
    #[error("{}: image size mismatch: {values} values for {width}x{height} pixels", path.display())]
    SizeMismatch {
        /// The destination.
        path: PathBuf,
        /// Image width in pixels.
        width: u32,
        /// Image height in pixels.
        height: u32,
        /// Length of the buffer given.
        values: usize,
    },
    /// The image encoder failed (PNG or EXR).
    #[error("cannot write {}", path.display())]
    Image {
        /// The destination.
        path: PathBuf,
        /// The encoder's error.
        source: image::ImageError,
    },
    /// The temporary file could not be created.
    #[error("cannot create {}", path.display())]
    Create {
        /// The destination.
        path: PathBuf,
        /// Why creating failed.
        source: std::io::Error,
    },
    /// Writing the temporary file failed.
    #[error("cannot write {}", path.display())]
    Io {
        /// The destination.
        path: PathBuf,
        /// Why writing failed.
        source: std::io::Error,
    },
}

/// The hidden temporary file `path` is written to before it is renamed into place:
/// `.NAME.partial` beside it, so the rename never crosses file systems.
pub fn temporary_path(path: &Path) -> Result<PathBuf, OutputError> {
    let name = path.file_name().ok_or_else(|| OutputError::NotAFilePath { path: path.to_path_buf() })?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(".partial");
    Ok(path.with_file_name(tmp_name))
}

/// Whether `path` can receive an output: its folder exists and `path` is not itself a folder.
pub fn check_destination(path: &Path) -> Result<(), OutputError> {
    let folder = path.parent().filter(|f| !f.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if !folder.is_dir() {
        return Err(OutputError::NoFolder { path: path.to_path_buf(), folder: folder.to_path_buf() });
    }
    if path.is_dir() {
        return Err(OutputError::IsAFolder { path: path.to_path_buf() });
    }
    Ok(())
}

/// Outputs that appear together or not at all: each is written to its temporary file first,
/// and `commit` renames them into place only once every one was written. Dropping the set
/// without committing (an error on the way) removes the temporaries and leaves every
/// destination as it was.
#[derive(Default)]
pub struct OutputSet {
    /// (temporary, destination) of every file written so far.
    staged: Vec<(PathBuf, PathBuf)>,
}

impl OutputSet {
    /// An empty set.
    pub fn new() -> OutputSet {
        OutputSet::default()
    }

    /// Write `path`'s content through `write` (given the temporary path) and stage it.
    pub fn stage(
        &mut self,
        path: &Path,
        write: impl FnOnce(&Path) -> Result<(), OutputError>,
    ) -> Result<(), OutputError> {
        let tmp = temporary_path(path)?;
        if let Err(e) = write(&tmp) {
            let _ = std::fs::remove_file(&tmp);
            return Err(e);
        }
        self.staged.push((tmp, path.to_path_buf()));
        Ok(())
    }

    /// An 8-bit RGBA image (rows top to bottom) as PNG.
    pub fn png(&mut self, path: &Path, width: u32, height: u32, rgba8: &[u8]) -> Result<(), OutputError> {
        let mismatch = || OutputError::SizeMismatch { path: path.to_path_buf(), width, height, values: rgba8.len() };
        let img = image::RgbaImage::from_raw(width, height, rgba8.to_vec()).ok_or_else(mismatch)?;
        self.stage(path, |tmp| {
            img.save_with_format(tmp, image::ImageFormat::Png)
                .map_err(|source| OutputError::Image { path: path.to_path_buf(), source })
        })
    }

    /// A linear RGBA f32 image as OpenEXR.
    pub fn exr(&mut self, path: &Path, width: u32, height: u32, rgba: &[f32]) -> Result<(), OutputError> {
        let mismatch = || OutputError::SizeMismatch { path: path.to_path_buf(), width, height, values: rgba.len() };
        let img = image::Rgba32FImage::from_raw(width, height, rgba.to_vec()).ok_or_else(mismatch)?;
        self.stage(path, |tmp| {
            image::DynamicImage::ImageRgba32F(img)
                .save_with_format(tmp, image::ImageFormat::OpenExr)
                .map_err(|source| OutputError::Image { path: path.to_path_buf(), source })
        })
    }

    /// An ASCII PLY of points with RGB radiant exitance: `x y z exitance_r exitance_g exitance_b`.
    pub fn exitance_ply(&mut self, path: &Path, points: &[([f32; 3], [f32; 3])]) -> Result<(), OutputError> {
        self.stage(path, |tmp| {
            let file = std::fs::File::create(tmp)
                .map_err(|source| OutputError::Create { path: path.to_path_buf(), source })?;
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

    /// Rename every staged file into place; returns the destinations.
    pub fn commit(mut self) -> Result<Vec<PathBuf>, OutputError> {
        // A folder in a destination's place would fail its rename after others succeeded.
        for (_, path) in &self.staged {
            check_destination(path)?;
        }
        let staged = std::mem::take(&mut self.staged);
        let mut done = Vec::new();
        for (i, (tmp, path)) in staged.iter().enumerate() {
            if let Err(source) = std::fs::rename(tmp, path) {
                // What is not yet in place is dropped; what is, stays (a rename cannot be undone).
                for (tmp, _) in &staged[i..] {
                    let _ = std::fs::remove_file(tmp);
                }
                return Err(OutputError::Rename { path: path.clone(), source });
            }
            done.push(path.clone());
        }
        Ok(done)
    }
}

impl Drop for OutputSet {
    fn drop(&mut self) {
        for (tmp, _) in &self.staged {
            let _ = std::fs::remove_file(tmp);
        }
    }
}

/// An 8-bit RGBA image (rows top to bottom) as PNG, alone.
pub fn write_png(path: &Path, width: u32, height: u32, rgba8: &[u8]) -> Result<(), OutputError> {
    let mut set = OutputSet::new();
    set.png(path, width, height, rgba8)?;
    set.commit().map(drop)
}

/// A linear RGBA f32 image as OpenEXR, alone.
pub fn write_exr(path: &Path, width: u32, height: u32, rgba: &[f32]) -> Result<(), OutputError> {
    let mut set = OutputSet::new();
    set.exr(path, width, height, rgba)?;
    set.commit().map(drop)
}

/// An exitance PLY (`OutputSet::exitance_ply`), alone.
pub fn write_exitance_ply(path: &Path, points: &[([f32; 3], [f32; 3])]) -> Result<(), OutputError> {
    let mut set = OutputSet::new();
    set.exitance_ply(path, points)?;
    set.commit().map(drop)
}
