//! The radiative-transfer reference (`reference::rte`) inside a closed mesh: radiant exitance
//! per vertex, with its standard error, from the scene's lights.
//!
//! A photon starts on the surface: a light and a triangle are drawn in proportion to the flux
//! the light brings the triangle (its area times the largest `E cos` at its corners), then a
//! uniform point in it. Its weight is the irradiance there times the cosine to the face, the
//! Fresnel transmittance and the light's visibility (ray cast through the scene's shadow
//! casters, as `reference::transmitted_irradiance` does), over the density it was drawn with.
//! It refracts in by Snell's law and walks each colour channel's medium in turn (one walk per
//! channel from the same entry, with the channel's own random numbers). At the boundary, found
//! with the BVH's closest hit, it reflects internally with the Fresnel reflectance of the face
//! or leaves; where it leaves, its weight is tallied to the vertex whose surface cell holds the
//! exit point.
//!
//! # Geometry
//!
//! The walk sees the mesh as it is: flat triangles with their face normals (oriented outwards
//! by the sign of the enclosed volume), not the interpolated shading normals the dipole truth
//! uses for `cos_i`; the two agree as the mesh is refined.
//!
//! # The tally
//!
//! A vertex's cell is its barycentric dual cell: in each of its triangles, the points whose
//! barycentric coordinate is largest at that vertex (a third of the triangle's area). The
//! exitance at a vertex is the flux leaving through its cell over the cell's area: the cell's
//! mean, which differs from the value at the vertex by the exitance's curvature times the cell's
//! second moment. Each photon leaves at most once per channel, so the per-photon scores' sums
//! and sums of squares give an exact standard error per vertex and channel.
//!
//! Photons whose walk meets the surface from outside (a ray through a crack the f64
//! intersection test leaves between triangles) are dropped and counted in `lost`.

use super::bvh::{Bvh, Hit};
use super::rte::{Budget, Medium, Progress, RteError, after_collision, chunk_rng, run_rounds, sample_hg_cos};
use super::truth::LIT_FLOOR;
use super::{light_incidence, occluders, ray_offset};
use crate::mesh::Mesh;
use crate::optics::fresnel;
use crate::scene::build::{PreparedScene, ResolvedMaterial};
use crate::scene::lights::PreparedLight;
use glam::DVec3;
use rand::RngExt;
use rand_pcg::Pcg64;

/// Photons per chunk (one random stream each).
const CHUNK: u64 = 256;
/// The most chunks walked in parallel between two looks at the budget.
const MAX_CHUNKS_PER_ROUND: u64 = 32;

/// How long to walk and with which random numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshOptions {
    /// Per object: photons (entries, each walked in all three channels), the target relative
    /// standard error ([`ObjectExitance::relative_stderr`]) and the time.
    pub budget: Budget,
    /// The seed of the random streams.
    pub seed: u64,
}

/// One object's radiant exitance by Monte Carlo.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ObjectExitance {
    /// Per vertex, RGB: the mean exitance over the vertex's cell (flux per area).
    pub exitance: Vec<[f64; 3]>,
    /// Per vertex, RGB: its standard error.
    pub stderr: Vec<[f64; 3]>,
    /// Photons walked (each in all three channels).
    pub photons: u64,
    /// The precision reached: per channel, the RMS standard error over the lit vertices
    /// (exitance at least `truth::LIT_FLOOR` of the brightest) over their mean exitance; the
    /// largest of the three (infinite, stored as JSON null, where a channel lights nothing).
    #[serde(with = "super::rte_cache::infinite_as_null")]
    pub relative_stderr: f64,
    /// Walks per channel dropped because they met the surface from outside.
    pub lost: [u64; 3],
    /// Wall time, seconds.
    pub seconds: f64,
}

/// The object as the walk sees it.
struct Geometry<'a> {
    mesh: &'a Mesh,
    bvh: Bvh,
    /// Outward unit face normals.
    normals: Vec<DVec3>,
}

impl<'a> Geometry<'a> {
    fn new(mesh: &'a Mesh) -> Geometry<'a> {
        let triangles: Vec<[DVec3; 3]> = (0..mesh.triangles().len()).map(|t| mesh.corners(t)).collect();
        // Six times the enclosed volume: negative when the winding faces inwards.
        let volume: f64 = triangles.iter().map(|[a, b, c]| a.dot(b.cross(*c))).sum();
        let sign = if volume < 0.0 { -1.0 } else { 1.0 };
        let normals = triangles.iter().map(|[a, b, c]| sign * (*b - *a).cross(*c - *a).normalize()).collect();
        Geometry { mesh, bvh: Bvh::new(triangles), normals }
    }
}

/// Where photons start: (light, triangle) pairs with the cumulative share of the flux.
struct Sources {
    pairs: Vec<(usize, usize)>,
    cdf: Vec<f64>,
    total: f64,
}

impl Sources {
    /// Each pair's weight: the triangle's area times the largest `E cos` (summed over channels)
    /// at its corners. It is zero only where the light cannot reach the face: for a plane
    /// triangle `cos` is affine in the point, so it is nowhere positive if at no corner. (A spot
    /// light's cone narrower than a triangle and between its corners is missed.)
    fn new(geometry: &Geometry, lights: &[PreparedLight]) -> Sources {
        let (mut pairs, mut cdf, mut total) = (Vec::new(), Vec::new(), 0.0);
        for (l, light) in lights.iter().enumerate() {
            for (t, n) in geometry.normals.iter().enumerate() {
                let best = geometry
                    .mesh
                    .corners(t)
                    .iter()
                    .map(|p| {
                        let (wi, e, _) = light_incidence(light, *p);
                        n.dot(wi).max(0.0) * e.element_sum()
                    })
                    .fold(0.0, f64::max);
                let weight = best * geometry.mesh.triangle_areas()[t];
                if weight > 0.0 {
                    total += weight;
                    pairs.push((l, t));
                    cdf.push(total);
                }
            }
        }
        Sources { pairs, cdf, total }
    }

    /// The pair at `u` in [0, 1) and its probability.
    fn pick(&self, u: f64) -> ((usize, usize), f64) {
        let x = u * self.total;
        let k = self.cdf.partition_point(|&c| c <= x).min(self.pairs.len() - 1);
        let below = if k == 0 { 0.0 } else { self.cdf[k - 1] };
        (self.pairs[k], (self.cdf[k] - below) / self.total)
    }
}

/// What a scene's lights and shadow casters are to one object.
struct Lighting<'a> {
    lights: &'a [PreparedLight],
    occluders: &'a Bvh,
    /// Visibility rays start this far off the surface.
    eps: f64,
}

/// Radiant exitance by Monte Carlo at every vertex of every translucent object of `scene`
/// (`None` for opaque objects), each object under the budget of `options`, with the object's
/// index added to the seed.
pub fn exitance(
    scene: &PreparedScene,
    options: &MeshOptions,
    progress: Progress,
) -> Result<Vec<Option<ObjectExitance>>, RteError> {
    let casters = occluders(scene);
    let lighting = Lighting { lights: &scene.lights, occluders: &casters, eps: ray_offset(scene) };
    scene
        .objects
        .iter()
        .enumerate()
        .map(|(i, o)| match &o.material {
            ResolvedMaterial::Translucent { dipoles, .. } => {
                if !o.mesh.report().is_closed_manifold() {
                    return Err(RteError::OpenMesh { name: o.name.clone() });
                }
                let media = dipoles.each_ref().map(Medium::reduced);
                let options = MeshOptions { seed: options.seed.wrapping_add(i as u64), ..*options };
                Ok(Some(object_exitance(&o.mesh, &media, &lighting, &options, progress)?))
            }
            ResolvedMaterial::Opaque { .. } => Ok(None),
        })
        .collect()
}

/// Per vertex and channel, the sums of the photons' scores and of their squares.
struct Tally {
    sum: Vec<[f64; 3]>,
    sum2: Vec<[f64; 3]>,
    lost: [u64; 3],
}

/// One object's exitance (see the module's documentation).
fn object_exitance(
    mesh: &Mesh,
    media: &[Medium; 3],
    lighting: &Lighting,
    options: &MeshOptions,
    progress: Progress,
) -> Result<ObjectExitance, RteError> {
    if options.budget.max_photons == 0 {
        return Err(RteError::NoPhotons);
    }
    let start = std::time::Instant::now();
    let geometry = Geometry::new(mesh);
    let sources = Sources::new(&geometry, lighting.lights);
    let cells = cell_areas(mesh);
    let count = mesh.positions().len();
    if sources.pairs.is_empty() {
        // No light reaches the object: it is dark, exactly.
        let zero = vec![[0.0; 3]; count];
        return Ok(ObjectExitance {
            exitance: zero.clone(),
            stderr: zero,
            photons: 0,
            relative_stderr: 0.0,
            lost: [0; 3],
            seconds: 0.0,
        });
    }
    let walk_chunk = |chunk: u64, _first: u64, n: u64| {
        let mut rng = chunk_rng(options.seed, chunk);
        let mut exits = Vec::new();
        for _ in 0..n {
            photon(&geometry, &sources, lighting, media, &mut rng, &mut exits);
        }
        exits
    };
    // Adding chunks and measuring the precision both need the tally: a cell between them.
    let tally =
        std::cell::RefCell::new(Tally { sum: vec![[0.0; 3]; count], sum2: vec![[0.0; 3]; count], lost: [0; 3] });
    let photons = run_rounds(
        &options.budget,
        CHUNK,
        MAX_CHUNKS_PER_ROUND,
        walk_chunk,
        |exits| add_exits(&mut tally.borrow_mut(), exits),
        |n| summarize(&tally.borrow(), &cells, n).2,
        progress,
    );
    let tally = tally.into_inner();
    let (exitance, stderr, relative_stderr) = summarize(&tally, &cells, photons);
    Ok(ObjectExitance {
        exitance,
        stderr,
        photons,
        relative_stderr,
        lost: tally.lost,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// Adds one chunk's exits to the tally.
fn add_exits(tally: &mut Tally, exits: Vec<Exit>) {
    for e in exits {
        match e {
            Exit::Left { vertex, channel, weight } => {
                tally.sum[vertex][channel] += weight;
                tally.sum2[vertex][channel] += weight * weight;
            }
            Exit::Lost { channel } => tally.lost[channel] += 1,
        }
    }
}

/// Per-vertex exitance and standard error after `n` photons, and the precision reached
/// ([`ObjectExitance::relative_stderr`]).
fn summarize(tally: &Tally, cells: &[f64], n: u64) -> (Vec<[f64; 3]>, Vec<[f64; 3]>, f64) {
    let nf = n.max(1) as f64;
    let mut exitance = vec![[0.0; 3]; cells.len()];
    let mut stderr = vec![[0.0; 3]; cells.len()];
    for v in 0..cells.len() {
        for c in 0..3 {
            let mean = tally.sum[v][c] / nf;
            let var = ((tally.sum2[v][c] / nf - mean * mean) * nf / (nf - 1.0).max(1.0)).max(0.0);
            exitance[v][c] = mean / cells[v];
            stderr[v][c] = (var / nf).sqrt() / cells[v];
        }
    }
    let rel = relative_stderr(&exitance, &stderr);
    (exitance, stderr, rel)
}

/// Per channel, the RMS standard error over the lit vertices over their mean exitance; the
/// largest of the three (infinite where nothing is lit yet).
pub fn relative_stderr(exitance: &[[f64; 3]], stderr: &[[f64; 3]]) -> f64 {
    (0..3)
        .map(|c| {
            let floor = LIT_FLOOR * exitance.iter().map(|m| m[c]).fold(0.0, f64::max);
            let (mut n, mut sum, mut sum2) = (0usize, 0.0, 0.0);
            for (m, s) in exitance.iter().zip(stderr) {
                if m[c] > 0.0 && m[c] >= floor {
                    n += 1;
                    sum += m[c];
                    sum2 += s[c] * s[c];
                }
            }
            if n == 0 { f64::INFINITY } else { (sum2 / n as f64).sqrt() / (sum / n as f64) }
        })
        .fold(0.0, f64::max)
}

/// Each vertex's barycentric dual cell area: a third of each of its triangles.
fn cell_areas(mesh: &Mesh) -> Vec<f64> {
    let mut cells = vec![0.0; mesh.positions().len()];
    for (t, tri) in mesh.triangles().iter().enumerate() {
        for &v in tri {
            cells[v as usize] += mesh.triangle_areas()[t] / 3.0;
        }
    }
    cells
}

/// How one channel's walk ended, when it ended anywhere but in absorption.
enum Exit {
    /// It left through the cell of `vertex` with `weight`.
    Left { vertex: usize, channel: usize, weight: f64 },
    /// It met the surface from outside and was dropped.
    Lost { channel: usize },
}

/// One photon: an entry point, then a walk per channel; its exits are pushed to `exits`.
fn photon(
    geometry: &Geometry,
    sources: &Sources,
    lighting: &Lighting,
    media: &[Medium; 3],
    rng: &mut Pcg64,
    exits: &mut Vec<Exit>,
) {
    let ((l, t), p_pair) = sources.pick(rng.random::<f64>());
    let (r1, r2) = (rng.random::<f64>().sqrt(), rng.random::<f64>());
    let bary = [1.0 - r1, r1 * (1.0 - r2), r1 * r2];
    let p = geometry.mesh.point(t, bary);
    let n = geometry.normals[t];
    let light = &lighting.lights[l];
    let (wi, e, dist) = light_incidence(light, p);
    let cos_i = n.dot(wi);
    let eta = media[0].eta;
    let f_t = fresnel::fresnel_transmittance(cos_i, eta);
    if cos_i <= 0.0 || f_t <= 0.0 {
        return;
    }
    if light.shadow_layer.is_some() && lighting.occluders.occluded(p + n * lighting.eps, wi, lighting.eps, dist) {
        return;
    }
    // Snell: the tangential part shrinks by 1 / eta, the normal part points inwards.
    let cos_t = (1.0 - (1.0 - cos_i * cos_i) / (eta * eta)).max(0.0).sqrt();
    let d = (-wi / eta + n * (cos_i / eta - cos_t)).normalize();
    let density = p_pair / geometry.mesh.triangle_areas()[t];
    for (c, medium) in media.iter().enumerate() {
        let weight = e[c] * cos_i * f_t / density;
        if weight > 0.0
            && let Some(exit) = walk(geometry, medium, p, d, t, weight, rng, c)
        {
            exits.push(exit);
        }
    }
}

/// One channel's walk from `p` on triangle `from` in direction `d` (inwards) with `weight`:
/// where it left, if it did.
#[allow(clippy::too_many_arguments)] // the state of one walk
fn walk(
    geometry: &Geometry,
    medium: &Medium,
    mut p: DVec3,
    mut d: DVec3,
    from: usize,
    mut weight: f64,
    rng: &mut Pcg64,
    channel: usize,
) -> Option<Exit> {
    let (sigma_t, albedo) = (medium.sigma_t(), medium.albedo());
    let mut skip = Some(from);
    loop {
        let s = -(1.0 - rng.random::<f64>()).ln() / sigma_t;
        let Some(Hit { t, triangle, u, v }) = geometry.bvh.closest_hit(p, d, 0.0, s, skip) else {
            p += d * s;
            skip = None;
            weight = after_collision(weight, albedo, rng)?;
            d = scatter(d, sample_hg_cos(medium.g, rng.random::<f64>()), rng.random::<f64>());
            continue;
        };
        p += d * t;
        skip = Some(triangle);
        let n = geometry.normals[triangle];
        let cos = d.dot(n);
        if cos <= 0.0 {
            return Some(Exit::Lost { channel });
        }
        if rng.random::<f64>() < fresnel::fresnel_reflectance(cos, 1.0 / medium.eta) {
            d -= n * (2.0 * cos);
            continue;
        }
        let bary = [1.0 - u - v, u, v];
        let corner = if bary[0] >= bary[1] && bary[0] >= bary[2] {
            0
        } else if bary[1] >= bary[2] {
            1
        } else {
            2
        };
        let vertex = geometry.mesh.triangles()[triangle][corner] as usize;
        return Some(Exit::Left { vertex, channel, weight });
    }
}

/// `d` turned by the scattering angle of cosine `cos`, about it by the azimuth `u` turns.
fn scatter(d: DVec3, cos: f64, u: f64) -> DVec3 {
    let (a, b) = d.any_orthonormal_pair();
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = std::f64::consts::TAU * u;
    (d * cos + (a * phi.cos() + b * phi.sin()) * sin).normalize()
}
