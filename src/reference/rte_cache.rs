//! The radiative-transfer reference of a scene (`rte_mesh::exitance`), cached by content as
//! the dipole truth is (`truth::cached`): a walk of minutes is done once per scene, budget and
//! seed.
//!
//! The file `rte-KEY.json` sits beside the truths. Its key hashes everything the walk depends
//! on: each object's placed mesh and coefficients, which objects cast shadows, the prepared
//! lights, the walk (photons, or adjoint and its receivers), the budget, the seed and
//! [`VERSION`]. It carries a checksum of its values; a file
//! that is unreadable, foreign, edited or damaged, or whose vertex counts are not the meshes',
//! is walked anew and replaced, with a warning naming the file and why.
//!
//! A time budget makes the photon count, and so the values, depend on the machine: the cache
//! then keeps the first machine's walk for that key.

use super::rte::{Progress, RteError};
use super::rte_mesh::{self, MeshOptions, ObjectExitance, Walk};
use super::truth::{Fnv, FolderProblem, folder_problem, read_cached, write_replacing};
use crate::scene::build::{PreparedScene, ResolvedMaterial};
use std::path::{Path, PathBuf};

/// The version of the walk: a change to what `rte_mesh` computes bumps it, so older files are
/// walked anew.
pub const VERSION: u32 = 6;

/// The reference of every object of a scene, as cached.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RteReference {
    /// [`VERSION`] of the walk that made it.
    pub version: u32,
    /// The scene content, budget and seed it belongs to ([`content_key`]).
    pub key: String,
    /// Per object (scene order): its exitance and standard error per vertex; `None` for an
    /// opaque object.
    pub objects: Vec<Option<ObjectExitance>>,
    /// [`RteReference::digest`] of its values, written with the file and checked when read.
    pub checksum: String,
}

impl RteReference {
    /// A hash (FNV-1a, hex) of its key, version and every value's bits.
    pub fn digest(&self) -> String {
        let mut h = Fnv::new();
        h.bytes(self.key.as_bytes());
        h.u64(u64::from(self.version));
        for o in &self.objects {
            match o {
                None => h.u64(0),
                Some(o) => {
                    h.u64(o.exitance.len() as u64);
                    h.u64(o.photons);
                    o.receivers.iter().flatten().for_each(|&v| h.u64(v as u64));
                    o.exitance.iter().chain(&o.stderr).flatten().for_each(|&v| h.f64(v));
                }
            }
        }
        format!("{:016x}", h.0)
    }

    /// Why this reference, read from a file, cannot be the one of `scene` under `key` (`None`:
    /// it can).
    fn unusable_for(&self, scene: &PreparedScene, key: &str) -> Option<String> {
        if self.key != key || self.version != VERSION {
            return Some(format!("made for other content (key {}, version {})", self.key, self.version));
        }
        if self.checksum != self.digest() {
            return Some("its checksum does not match its values (edited or damaged)".into());
        }
        if self.objects.len() != scene.objects.len() {
            return Some(format!("{} objects, the scene has {}", self.objects.len(), scene.objects.len()));
        }
        for (i, (m, o)) in self.objects.iter().zip(&scene.objects).enumerate() {
            let translucent = matches!(o.material, ResolvedMaterial::Translucent { .. });
            let vertices = o.mesh.positions().len();
            let expected = |m: &ObjectExitance| m.receivers.as_ref().map_or(vertices, Vec::len);
            match m {
                None if translucent => return Some(format!("object {i} is translucent but has no values")),
                Some(m) if m.exitance.len() != expected(m) || m.stderr.len() != expected(m) => {
                    return Some(format!("object {i} has {} values for {} vertices", m.exitance.len(), expected(m)));
                }
                Some(m) if m.receivers.iter().flatten().any(|&v| v >= vertices) => {
                    return Some(format!("object {i} names a receiver past its mesh's {vertices} vertices"));
                }
                Some(m) if m.exitance.iter().chain(&m.stderr).flatten().any(|x| !x.is_finite() || *x < 0.0) => {
                    return Some(format!("object {i} holds a negative or non-finite value"));
                }
                _ => {}
            }
        }
        None
    }
}

/// Why the cached reference could not be had.
#[derive(Debug, thiserror::Error)]
#[allow(missing_docs)] // each variant names the file or folder, or carries the walk's error
pub enum RteCacheError {
    #[error(transparent)]
    Rte(#[from] RteError),
    #[error("radiative-transfer cache {}: {why}", path.display())]
    Folder { path: PathBuf, why: FolderProblem },
    #[error("radiative-transfer cache {}: {error}", path.display())]
    Io { path: PathBuf, error: std::io::Error },
    #[error("radiative-transfer cache {}: {error}", path.display())]
    Json { path: PathBuf, error: serde_json::Error },
}

/// A hash (FNV-1a, 64 bits, hex) of everything the walk depends on (see the module's
/// documentation). Sample points, the camera, the gather and the shading normals are left out.
pub fn content_key(scene: &PreparedScene, options: &MeshOptions) -> String {
    let mut h = Fnv::new();
    h.u64(u64::from(VERSION));
    h.u64(options.seed);
    let b = &options.budget;
    h.u64(b.max_photons);
    h.f64(b.relative_stderr.unwrap_or(-1.0));
    h.f64(b.max_seconds.unwrap_or(-1.0));
    match options.resolved(scene).walk {
        Walk::Photons | Walk::Auto { .. } => h.u64(0),
        Walk::Adjoint { receivers } => {
            h.u64(1);
            h.u64(receivers.map_or(u64::MAX, |r| r as u64));
        }
    }
    for o in &scene.objects {
        h.u64(o.mesh.positions().len() as u64);
        o.mesh.positions().iter().for_each(|p| p.to_array().iter().for_each(|c| h.u64(u64::from(c.to_bits()))));
        o.mesh.triangles().iter().flatten().for_each(|&i| h.u64(u64::from(i)));
        h.u64(u64::from(o.casts_shadow));
        match &o.material {
            ResolvedMaterial::Translucent { dipoles, .. } => {
                dipoles.iter().for_each(|d| [d.sigma_a, d.sigma_s_prime, d.eta].iter().for_each(|&v| h.f64(v)));
            }
            ResolvedMaterial::Opaque { .. } => h.u64(0),
        }
    }
    for l in &scene.lights {
        h.bytes(format!("{:?} {}", l.kind, l.shadow_layer.is_some()).as_bytes());
    }
    format!("{:016x}", h.0)
}

/// The reference of `scene` from `dir` if an earlier run left it there (same key), else walked
/// (`rte_mesh::exitance`) and stored there. Returns it and whether it was cached. The folder
/// is checked before the walk, so a folder that cannot be written in fails at once.
pub fn cached(
    scene: &PreparedScene,
    options: &MeshOptions,
    dir: &Path,
    progress: Progress,
) -> Result<(RteReference, bool), RteCacheError> {
    let key = content_key(scene, options);
    let path = dir.join(format!("rte-{key}.json"));
    let usable = |r: &RteReference| r.unusable_for(scene, &key);
    if let Some(r) = read_cached(&path, ("radiative-transfer cache", "walking it anew"), usable) {
        return Ok((r, true));
    }
    if let Some(why) = folder_problem(dir) {
        return Err(RteCacheError::Folder { path: dir.to_path_buf(), why });
    }
    let objects = rte_mesh::exitance(scene, options, progress)?;
    let mut reference = RteReference { version: VERSION, key: key.clone(), objects, checksum: String::new() };
    reference.checksum = reference.digest();
    let json = serde_json::to_vec(&reference).map_err(|error| RteCacheError::Json { path: path.clone(), error })?;
    write_replacing(&path, &json).map_err(|error| RteCacheError::Io { path: path.clone(), error })?;
    Ok((reference, false))
}
