//! The truth cached by content: a file `truth-KEY.json` per scene content and options, its
//! checksum checked when read back, so a truth of hours is computed once.

use super::{Progress, Truth, TruthError, TruthOptions, VERSION, compute, receiver_subset};
use crate::scene::build::{PreparedScene, ResolvedMaterial};
use std::path::{Path, PathBuf};

impl Truth {
    /// A hash (FNV-1a, hex) of its key, version, subset, convergence and every exitance value's
    /// bits.
    pub fn digest(&self) -> String {
        let mut h = Fnv(0xcbf2_9ce4_8422_2325);
        h.bytes(self.key.as_bytes());
        h.u64(u64::from(self.version));
        h.u64(self.subset.map_or(u64::MAX, |m| m as u64));
        h.u64(u64::from(self.converged));
        for o in &self.exitance {
            h.u64(o.len() as u64);
            o.iter().flatten().for_each(|&v| h.f64(v));
        }
        format!("{:016x}", h.0)
    }

    /// Why this truth, read from a cache file, cannot be the truth of `scene` under `options`
    /// (`None`: it can): a foreign key or version, a checksum that does not match its values, a
    /// vertex count other than the mesh's, or a value that is negative, infinite, or NaN at a
    /// vertex the receivers include.
    pub fn unusable_for(&self, scene: &PreparedScene, options: &TruthOptions, key: &str) -> Option<String> {
        if self.key != key || self.version != VERSION {
            return Some(format!("made for other content (key {}, version {})", self.key, self.version));
        }
        if self.checksum.as_deref() != Some(self.digest().as_str()) {
            return Some("its checksum does not match its values (edited or damaged)".into());
        }
        if self.exitance.len() != scene.objects.len() {
            return Some(format!("{} objects, the scene has {}", self.exitance.len(), scene.objects.len()));
        }
        for (i, (m, o)) in self.exitance.iter().zip(&scene.objects).enumerate() {
            let vertices = o.mesh.positions().len();
            if m.len() != vertices {
                return Some(format!("object {i} has {} values, its mesh {vertices} vertices", m.len()));
            }
            for v in receiver_subset(vertices, options.receivers) {
                if m[v].iter().any(|x| !x.is_finite() || *x < 0.0) {
                    return Some(format!("object {i}, vertex {v}: {:?} is not a finite non-negative exitance", m[v]));
                }
            }
        }
        None
    }
}

/// The truth of `scene` from `dir` if an earlier run left it there (same content key and
/// quadrature version), else computed and stored there. Returns it and whether it was cached.
pub fn cached(
    scene: &PreparedScene,
    options: &TruthOptions,
    dir: &Path,
    progress: Progress,
) -> Result<(Truth, bool), TruthError> {
    let key = content_key(scene, options);
    let path = dir.join(format!("truth-{key}.json"));
    let usable = |t: &Truth| t.unusable_for(scene, options, &key);
    if let Some(truth) = read_cached(&path, ("truth cache", "computing it anew"), usable) {
        return Ok((truth, true));
    }
    // A folder the truth cannot be written to is found before the truth is computed.
    writable_folder(dir)?;
    let truth = compute(scene, options, progress)?;
    let json = serde_json::to_vec(&truth).map_err(|error| TruthError::Json { path: path.clone(), error })?;
    write_replacing(&path, &json).map_err(|error| TruthError::Io { path: path.clone(), error })?;
    Ok((truth, false))
}

/// `dir`, made if missing, is a folder a file can be written in (a file of its own is made and
/// removed); otherwise what stands in the way.
fn writable_folder(dir: &Path) -> Result<(), TruthError> {
    match folder_problem(dir) {
        None => Ok(()),
        Some(why) => Err(TruthError::Folder { path: dir.to_path_buf(), why }),
    }
}

/// The value cached at `path`, if the file is there, parses, and `unusable` finds nothing
/// wrong with it. An unreadable, foreign, edited or damaged file is never trusted: a warning
/// names `cache` (which cache), the file and why, and that it is `instead` (done anew).
pub(crate) fn read_cached<T: serde::de::DeserializeOwned>(
    path: &Path,
    (cache, instead): (&str, &str),
    unusable: impl FnOnce(&T) -> Option<String>,
) -> Option<T> {
    let bytes = std::fs::read(path).ok()?;
    match serde_json::from_slice::<T>(&bytes) {
        Ok(value) => match unusable(&value) {
            None => return Some(value),
            Some(why) => log::warn!("{cache} {}: {why}; {instead}", path.display()),
        },
        Err(e) => log::warn!("{cache} {}: unreadable ({e}); {instead}", path.display()),
    }
    None
}

/// `bytes` written to `path` through a hidden temporary beside it (`.NAME.PID-N.tmp`), renamed
/// into place, so a run cut short never leaves half a file behind. The temporary is this
/// writer's own: two processes storing the same result at once each rename a whole file of
/// their own (the last one wins), where a shared name let one rename the other's away.
pub(crate) fn write_replacing(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    static WRITES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = WRITES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let name = path.file_name().map_or_else(Default::default, |n| n.to_string_lossy().into_owned());
    let tmp = path.with_file_name(format!(".{name}.{}-{n}.tmp", std::process::id()));
    let written = std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, path));
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

/// What keeps `dir` (made if missing) from being a folder a file can be written in, if
/// anything: a file of its own is made and removed to find out.
pub(crate) fn folder_problem(dir: &Path) -> Option<FolderProblem> {
    if let Some(existing) = dir.ancestors().find(|a| a.exists())
        && !existing.is_dir()
    {
        return Some(FolderProblem::IsAFile(existing.to_path_buf()));
    }
    if let Err(e) = std::fs::create_dir_all(dir) {
        return Some(FolderProblem::Create(e));
    }
    let probe = dir.join(format!(".truth-probe-{}.tmp", std::process::id()));
    match std::fs::write(&probe, b"") {
        Ok(()) => {
            let _ = std::fs::remove_file(&probe);
            None
        }
        Err(e) => Some(FolderProblem::Write(e)),
    }
}

/// Why a cache folder cannot hold a cached result.
#[derive(Debug, thiserror::Error)]
pub enum FolderProblem {
    /// A path on the way to it is a file.
    #[error("{} is a file, not a folder", .0.display())]
    IsAFile(PathBuf),
    /// It could not be made.
    #[error("cannot make the folder ({0})")]
    Create(#[source] std::io::Error),
    /// No file can be written in it.
    #[error("cannot write a file in the folder ({0})")]
    Write(#[source] std::io::Error),
}

/// Where truths are cached unless told otherwise: `$XDG_CACHE_HOME/translucent/truth`, else
/// `$HOME/.cache/translucent/truth`, else the system's temporary folder.
pub fn default_cache_dir() -> PathBuf {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").filter(|v| !v.is_empty()).map(|h| PathBuf::from(h).join(".cache")))
        .unwrap_or_else(std::env::temp_dir);
    base.join("translucent").join("truth")
}

/// A hash (FNV-1a, 64 bits, hex) of everything the truth depends on: each object's placed mesh
/// and dipoles, which objects cast shadows, the prepared lights, the options and the quadrature
/// version. Sample points, the camera and the gather are left out: the truth does not depend
/// on them.
pub fn content_key(scene: &PreparedScene, options: &TruthOptions) -> String {
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    h.u64(u64::from(VERSION));
    h.f64(options.tolerance);
    h.u64(u64::from(options.max_level));
    // Only a subset changes the key, so the caches of whole truths stay valid.
    if let Some(m) = options.receivers {
        h.u64(m as u64);
    }
    for o in &scene.objects {
        h.u64(o.mesh.positions().len() as u64);
        for p in o.mesh.positions() {
            p.to_array().iter().for_each(|c| h.u64(u64::from(c.to_bits())));
        }
        for t in o.mesh.triangles() {
            t.iter().for_each(|&i| h.u64(u64::from(i)));
        }
        h.u64(u64::from(o.casts_shadow));
        match &o.material {
            ResolvedMaterial::Translucent { material, dipoles, .. } => {
                h.f64(material.eta);
                for d in dipoles {
                    [d.sigma_a, d.sigma_s_prime, d.eta].iter().for_each(|&v| h.f64(v));
                }
            }
            ResolvedMaterial::Opaque { .. } => h.u64(0),
        }
    }
    for l in &scene.lights {
        h.bytes(format!("{:?} {}", l.kind, l.shadow_layer.is_some()).as_bytes());
    }
    format!("{:016x}", h.0)
}

/// FNV-1a, 64 bits: the content keys and checksums of the cached references.
pub(crate) struct Fnv(pub(crate) u64);

impl Fnv {
    /// The FNV-1a offset basis: an empty hash.
    pub(crate) fn new() -> Fnv {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    pub(crate) fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    pub(crate) fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
    pub(crate) fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
}

#[cfg(test)]
mod tests {
    use super::write_replacing;

    /// Many writers storing the same file at once (the tests' parallel renders of one scene)
    /// all succeed, and the file left is one writer's whole file, not a mix.
    #[test]
    fn writers_storing_one_file_at_once_all_succeed_and_leave_one_whole_file() {
        let dir = std::env::temp_dir().join(format!("translucent-write-race-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("kernel.json");
        let writers: Vec<_> = (0..8u8)
            .map(|k| {
                let path = path.clone();
                std::thread::spawn(move || {
                    (0..50).map(|_| write_replacing(&path, &vec![b'a' + k; 100_000])).collect::<Vec<_>>()
                })
            })
            .collect();
        for writer in writers {
            for result in writer.join().unwrap() {
                result.unwrap();
            }
        }
        let left = std::fs::read(&path).unwrap();
        assert_eq!(left.len(), 100_000);
        assert!(left.iter().all(|&b| b == left[0]), "the file mixes two writers' bytes");
        let others = std::fs::read_dir(&dir).unwrap().count();
        assert_eq!(others, 1, "temporaries left beside the file");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
