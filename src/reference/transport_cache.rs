//! Transport kernels (`optics::transport`) cached by content, as the truth and the
//! radiative-transfer reference are: a walk of a minute is done once per mesh, medium and
//! setting.
//!
//! The file `kernel-KEY.json` sits in the cache folder. Its key hashes what the walk depends
//! on: the object's placed mesh, its three channels' coefficients, the [`KernelSettings`] (the
//! patches the mesh gets) and [`VERSION`]. It carries a checksum of its values. A file that is
//! unreadable, foreign, edited or damaged, or whose patches do not fit the mesh, is never used:
//! it is walked anew and replaced, with a warning naming the file and why.

use super::rte_cache::RteCacheError;
use super::rte_mesh::{KernelSettings, object_kernel};
use super::truth::{Fnv, folder_problem, read_cached, write_replacing};
use crate::optics::transport::TransportKernel;
use crate::scene::build::{PreparedObject, PreparedScene, ResolvedMaterial};
use std::path::Path;

/// The version of the kernel's walk: a change to what it computes bumps it (4: the entry
/// direction's basis, `optics::transport::EntryBasis`, within `ENTRY_REACH`; 5: the channels
/// walk on common random numbers; 6: the walk's wall time is kept, [`CachedKernel::walk_seconds`];
/// 7: `W0` averaged with its reciprocal estimate, `TransportKernel::reciprocal`; 8: the entry
/// point's offset row `Wx`; 9: the entry's rows reach a diffusion length, `entry_reach`).
pub const VERSION: u32 = 9;

/// One object's kernel, as cached.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CachedKernel {
    /// [`VERSION`] of the walk that made it.
    pub version: u32,
    /// The content it belongs to ([`content_key`]).
    pub key: String,
    /// The kernel.
    pub kernel: TransportKernel,
    /// Wall time of the walk that made it, seconds (the precompute a study reports).
    pub walk_seconds: f64,
    /// [`CachedKernel::digest`] of its values.
    pub checksum: String,
}

impl CachedKernel {
    /// A hash (FNV-1a, hex) of its key, version and every value's bits.
    pub fn digest(&self) -> String {
        let mut h = Fnv::new();
        h.bytes(self.key.as_bytes());
        h.u64(u64::from(self.version));
        let k = &self.kernel;
        h.u64(k.walks);
        k.patches.of_vertex.iter().for_each(|&i| h.u64(u64::from(i)));
        k.patches.centres.iter().flatten().for_each(|&x| h.f64(x));
        k.patches.area.iter().chain(&k.patches.cells).for_each(|&x| h.f64(x));
        h.f64(k.patches.radius);
        k.rows().flatten().flatten().for_each(|&x| h.f64(x));
        h.f64(k.mu_mean);
        h.f64(self.walk_seconds);
        format!("{:016x}", h.0)
    }

    /// Why this file's kernel cannot be object `o`'s under `key` (`None`: it can).
    fn unusable_for(&self, o: &PreparedObject, key: &str) -> Option<String> {
        if self.key != key || self.version != VERSION {
            return Some(format!("made for other content (key {}, version {})", self.key, self.version));
        }
        if self.checksum != self.digest() {
            return Some("its checksum does not match its values (edited or damaged)".into());
        }
        let (k, p) = (self.kernel.patches.len(), &self.kernel.patches);
        let vertices = o.mesh.positions().len();
        if p.of_vertex.len() != vertices || p.cells.len() != vertices {
            return Some(format!("{} vertices, the mesh has {vertices}", p.of_vertex.len()));
        }
        if p.area.len() != k || self.kernel.rows().flatten().any(|f| f.len() != k * k) {
            return Some(format!("its tables do not hold {k} patches"));
        }
        if p.of_vertex.iter().any(|&i| i as usize >= k) {
            return Some(format!("a vertex names a patch past its {k}"));
        }
        let bad = |x: &f64| !x.is_finite() || *x < 0.0;
        let rows_bad = self.kernel.flux.iter().flatten().any(bad)
            || self.kernel.rows().flatten().flatten().any(|x| !x.is_finite())
            || !(self.kernel.mu_mean > 0.0 && self.kernel.mu_mean <= 1.0);
        if rows_bad || p.area.iter().any(|a| bad(a) || *a == 0.0) {
            return Some("it holds a negative, zero-area or non-finite value".into());
        }
        None
    }
}

/// A hash (FNV-1a, 64 bits, hex) of what object `o`'s kernel depends on (see the module's
/// documentation).
pub fn content_key(o: &PreparedObject, settings: &KernelSettings) -> String {
    let mut h = Fnv::new();
    h.u64(u64::from(VERSION));
    h.u64(settings.patches_for(o.mesh.positions().len()) as u64);
    h.u64(settings.walks_for(o.mesh.positions().len()));
    h.u64(settings.seed);
    o.mesh.positions().iter().for_each(|p| p.to_array().iter().for_each(|c| h.u64(u64::from(c.to_bits()))));
    o.mesh.vertex_normals().iter().for_each(|p| p.to_array().iter().for_each(|c| h.u64(u64::from(c.to_bits()))));
    o.mesh.triangles().iter().flatten().for_each(|&i| h.u64(u64::from(i)));
    if let ResolvedMaterial::Translucent { dipoles, .. } = &o.material {
        dipoles.iter().for_each(|d| [d.sigma_a, d.sigma_s_prime, d.eta].iter().for_each(|&v| h.f64(v)));
    }
    format!("{:016x}", h.0)
}

/// Object `o`'s kernel from `dir` if an earlier run left it there (same key), else walked and
/// stored there. Returns it and whether it was cached. The folder is checked before the walk.
pub fn cached(
    o: &PreparedObject,
    settings: &KernelSettings,
    dir: &Path,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(TransportKernel, bool), RteCacheError> {
    cached_timed(o, settings, dir, progress).map(|(kernel, cached, _)| (kernel, cached))
}

/// [`cached`], with the wall time of the walk that made the kernel, seconds (this run's, or
/// the one recorded in the file).
pub fn cached_timed(
    o: &PreparedObject,
    settings: &KernelSettings,
    dir: &Path,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(TransportKernel, bool, f64), RteCacheError> {
    let key = content_key(o, settings);
    let path = dir.join(format!("kernel-{key}.json"));
    let usable = |c: &CachedKernel| c.unusable_for(o, &key);
    if let Some(c) = read_cached(&path, ("transport kernel cache", "walking it anew"), usable) {
        return Ok((c.kernel, true, c.walk_seconds));
    }
    if let Some(why) = folder_problem(dir) {
        return Err(RteCacheError::Folder { path: dir.to_path_buf(), why });
    }
    let start = std::time::Instant::now();
    let kernel = object_kernel(o, settings, progress)?;
    let walk_seconds = start.elapsed().as_secs_f64();
    let mut cached = CachedKernel { version: VERSION, key: key.clone(), kernel, walk_seconds, checksum: String::new() };
    cached.checksum = cached.digest();
    let json = serde_json::to_vec(&cached).map_err(|error| RteCacheError::Json { path: path.clone(), error })?;
    write_replacing(&path, &json).map_err(|error| RteCacheError::Io { path: path.clone(), error })?;
    Ok((cached.kernel, false, walk_seconds))
}

/// Attaches a kernel (cached in `dir`, or walked) to every object of `objects` whose material
/// asks for one (`PreparedObject::wants_transport`) and has none; `progress` hears each
/// object's index and its patches done and count. Returns the walks' wall time over the
/// kernels attached, seconds ([`cached_timed`]: the time recorded where a kernel was cached).
pub fn attach(
    objects: &mut [PreparedObject],
    settings: &KernelSettings,
    dir: &Path,
    progress: &(dyn Fn(usize, usize, usize) + Sync),
) -> Result<f64, RteCacheError> {
    let mut seconds = 0.0;
    for (i, o) in objects.iter_mut().enumerate() {
        if o.wants_transport() && o.transport.is_none() {
            let (kernel, _, walked) = cached_timed(o, settings, dir, &|done, of| progress(i, done, of))?;
            o.transport = Some(std::sync::Arc::new(kernel));
            seconds += walked;
        }
    }
    Ok(seconds)
}

/// The transport model's exact exitance per object and vertex (`study --physics --models
/// kernel`): the dipole's `truth` (NaN where not known) scaled by each translucent
/// object's transport kernel at the default settings (cached in `dir`), the f64 model of
/// `optics::transport` with the transmitted flux summed over the vertices' cells. Where the
/// truth is known at some vertices only, the patches' dipole exitance comes from the f64 gather
/// at every vertex.
pub fn model_exitance(
    base: &PreparedScene,
    truth: &[Vec<[f64; 3]>],
    dir: &Path,
    progress: &(dyn Fn(usize, usize, usize) + Sync),
) -> Result<Vec<Vec<[f64; 3]>>, RteCacheError> {
    model_exitance_with(base, truth, &KernelSettings::default(), dir, progress)
}

/// [`model_exitance`] with kernels of other `settings` (more walks, other patches, another
/// seed): how the model converges in the kernel's own walks.
pub fn model_exitance_with(
    base: &PreparedScene,
    truth: &[Vec<[f64; 3]>],
    settings: &KernelSettings,
    dir: &Path,
    progress: &(dyn Fn(usize, usize, usize) + Sync),
) -> Result<Vec<Vec<[f64; 3]>>, RteCacheError> {
    use super::{occluders, ray_offset, transmitted_entry};
    use crate::optics::transport::SampleFlux;
    let casters = occluders(base);
    let partial = truth.iter().flatten().any(|m| !m[0].is_finite());
    let gathered = partial.then(|| super::gather(base, &super::splat(base, &casters)));
    let mut out = Vec::new();
    for (index, (o, truth)) in base.objects.iter().zip(truth).enumerate() {
        let ResolvedMaterial::Translucent { material, .. } = &o.material else {
            out.push(truth.clone());
            continue;
        };
        let (k, _) = cached(o, settings, dir, &|done, of| progress(index, done, of))?;
        let (positions, normals) = (o.mesh.positions(), o.mesh.vertex_normals());
        let eps = ray_offset(base);
        // Each vertex stands for its cell, which the kernel's walks enter uniformly.
        let centroids = crate::mesh::patches::cell_centroids(&o.mesh);
        let points = positions.iter().zip(normals).enumerate().map(|(v, (p, n))| {
            let (p, n) = (p.as_dvec3(), n.as_dvec3().normalize());
            let (e, d_key, w_key) = transmitted_entry(base, &casters, (p, n), material.eta, eps);
            let (patch, area) = (k.patches.of_vertex[v], k.patches.cells[v]);
            SampleFlux::from_splat((patch, centroids[v]), area, e.to_array(), (d_key, w_key), n, k.mu_mean)
        });
        let phi = k.patch_flux(points, &k.patches.entry_centres(&o.mesh));
        let whole = gathered.as_ref().map_or(truth.as_slice(), |g| g[index].as_slice());
        let placed = k.placed(&o.mesh);
        let (f, d) = (k.transport_exitance(&phi, &placed), k.dipole_exitance(whole, &k.patches.cells));
        let near = TransportKernel::vertex_neighbours(&placed, &o.mesh);
        out.push(
            truth
                .iter()
                .zip(&near)
                .map(|(&m, near)| if m[0].is_finite() { TransportKernel::scaled(m, near, &f, &d) } else { m })
                .collect(),
        );
    }
    Ok(out)
}
