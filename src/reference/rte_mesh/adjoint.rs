//! The radiative-transfer reference walked backwards: the exitance at chosen receivers, each
//! to its own precision, where the photon walk (`rte_mesh::exitance`) spreads its photons over
//! every vertex.
//!
//! The exitance at a surface point `x` with outward shading normal `n` is
//! `M(x) = int (1 - R(cos)) L(x, w) cos dw` over the directions `w` leaving through the surface
//! from inside, `L` the radiance inside and `R` the Fresnel reflectance from inside. A walk draws
//! `w` by its cosine (density `cos / pi`), so it scores `pi (1 - R) L(x, w)`, and estimates `L`
//! by walking backwards from `x` along `-w` through the same medium the photon walk sees:
//! exponential flights, isotropic scattering with the albedo, internal reflection at the flat
//! faces (its share `R` under `rte::after_reflection`, as the photon walk splits).
//!
//! Light enters only through refraction of the scene's lights, which are points or directions:
//! a walk that meets the surface never looks straight at one. So at every collision `q` the
//! walk scores the light scattered there out of the lights' uncollided beams (next-event
//! estimation): `albedo p(cos) E_beam(q) exp(-sigma_t s)`, `p` the phase function, `E_beam` one
//! light's beam through `q` ([`beam`](super::beam)), the light drawn half by what it brings
//! the receiver and half by its irradiance at the object. Light that crosses the object without scattering and leaves at `x`
//! is added once per receiver, exactly; the same light after internal reflections (a few
//! percent of an `exp(-sigma_t L)` across the object) is left out.
//!
//! Each walk's score gives the mean and standard error per receiver and channel; the budget
//! stops on the per-vertex noise: per channel, the RMS over the lit receivers of each one's
//! relative standard error.

use super::beam::{Beam, Beams, Entry, Way};
use super::geometry::Geometry;
use super::sources::Lighting;
use super::walk::scatter;
use super::{MeshOptions, ObjectExitance};
use crate::mesh::Mesh;
use crate::optics::fresnel;
use crate::optics::single_scatter::henyey_greenstein;
use crate::reference::light_incidence;
use crate::reference::rte::{Medium, Progress, RteError, RteProgress, after_collision, after_reflection, chunk_rng};
use crate::reference::truth::LIT_FLOOR;
use crate::scene::lights::PreparedLight;
use glam::DVec3;
use rand::RngExt;
use rand_pcg::Pcg64;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Walks per receiver and channel in the first round; each round doubles it up to [`MAX_ROUND`].
const FIRST_ROUND: u64 = 16;
/// The most walks per receiver and channel in one round.
const MAX_ROUND: u64 = 1024;
/// The chance that a collision at the surface takes a next event; `c` mean free paths deeper
/// (by the clearance grid's bound) the chance is `e^-c` times this (see `Adjoint::next_event`).
/// Measured by the noise at equal time (`examples/adjoint_noise.rs`, 100 walks per receiver,
/// lavapipe's 2-core VM): on the built-in scene every next event within two free paths gave
/// a per-vertex noise of 26.9% in 41.9 s of walks, this quarter 30.5% in 11 to 12 s (2.8
/// times as much precision per second), `e^-1.5` 31.8% in 11.6 s; on the 2 cm marble sphere
/// the first 34.3% in 3.4 s, the last 35.8% in 1.2 s. The walk's flights cost the same either
/// way; the next events' beams were four fifths of the walk.
const SURFACE_CHANCE: f64 = 0.25;

/// Where a receiver's walks start: just inside its vertex, with the vertex's outward shading
/// normal; the light that reaches it without scattering (per channel, exitance); and per light
/// the chance its walks' next events pick it ([`Adjoint::receiver_chances`]).
struct Receiver {
    p: DVec3,
    n: DVec3,
    direct: [f64; 3],
    chances: Vec<f64>,
}

/// What every walk of one object shares.
struct Adjoint<'a> {
    geometry: &'a Geometry<'a>,
    beams: Beams<'a>,
    lights: &'a [PreparedLight],
    /// Per light, its chance at the object (by its irradiance at the object's centre).
    chances: Vec<f64>,
    media: &'a [Medium; 3],
    /// How light enters: refracted for the reference.
    entry: Entry,
}

/// One object's exitance at the vertices `receivers` (see the module's documentation), under
/// the budget of `options`: walks per receiver, the per-vertex noise, the time.
pub(super) fn object_adjoint(
    mesh: &Mesh,
    media: &[Medium; 3],
    light: &Lighting,
    receivers: Vec<usize>,
    (options, entry): (&MeshOptions, Entry),
    progress: Progress,
) -> Result<ObjectExitance, RteError> {
    if options.budget.max_photons == 0 {
        return Err(RteError::NoPhotons);
    }
    let start = std::time::Instant::now();
    let geometry = Geometry::new(mesh, true);
    let beams = Beams { geometry: &geometry, occluders: light.occluders, eps: light.eps };
    let adjoint = Adjoint {
        chances: chances(mesh, light.lights),
        geometry: &geometry,
        beams,
        lights: light.lights,
        media,
        entry,
    };
    // Each vertex's first triangle and its corner there, once (not a search per receiver).
    let mut corners = vec![None; mesh.positions().len()];
    for (t, tri) in mesh.triangles().iter().enumerate() {
        for (k, &v) in tri.iter().enumerate() {
            corners[v as usize].get_or_insert((t, k));
        }
    }
    let starts: Vec<Receiver> = receivers
        .par_iter()
        .map(|&v| adjoint.receiver(v, corners[v].expect("a vertex of a closed mesh is a corner of some triangle")))
        .collect();
    let n = starts.len();
    let (mut sum, mut sum2, mut lost) = (vec![[0.0; 3]; n], vec![[0.0; 3]; n], [0u64; 3]);
    let (mut walks, mut round, mut batch) = (0u64, 0u64, FIRST_ROUND);
    let budget = options.budget;
    let mut summary = summarize(&sum, &sum2, &starts, 0);
    while walks < budget.max_photons {
        let mut k = batch.min(budget.max_photons - walks);
        // A round that would run past the time budget (at the pace so far) is cut to fit.
        if let Some(limit) = budget.max_seconds
            && walks > 0
        {
            let pace = start.elapsed().as_secs_f64() / walks as f64;
            let left = (limit - start.elapsed().as_secs_f64()).max(0.0);
            k = k.min(((left / pace) as u64).max(1));
        }
        let tallies: Vec<([f64; 3], [f64; 3], [u64; 3])> = starts
            .par_iter()
            .enumerate()
            .map(|(i, r)| {
                let mut rng = chunk_rng(options.seed, (round << 32) | i as u64);
                adjoint.receiver_walks(r, k, &mut rng)
            })
            .collect();
        for (i, (s, s2, l)) in tallies.into_iter().enumerate() {
            (0..3).for_each(|c| {
                sum[i][c] += s[c];
                sum2[i][c] += s2[c];
                lost[c] += l[c];
            });
        }
        walks += k;
        round += 1;
        batch = (2 * batch).min(MAX_ROUND);
        summary = summarize(&sum, &sum2, &starts, walks);
        let noise = summary.2.into_iter().fold(0.0, f64::max);
        let seconds = start.elapsed().as_secs_f64();
        progress(RteProgress { photons: walks, max_photons: budget.max_photons, relative_stderr: noise, seconds });
        if budget.relative_stderr.is_some_and(|t| noise <= t) || budget.max_seconds.is_some_and(|t| seconds >= t) {
            break;
        }
    }
    let (exitance, stderr, noise) = summary;
    Ok(ObjectExitance {
        exitance,
        stderr,
        receivers: Some(receivers),
        photons: walks,
        relative_stderr: noise.into_iter().fold(0.0, f64::max),
        lost,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// Per light, the chance a next event picks it: its irradiance (summed over channels) at the
/// centre of the object's bounds, over the sum; even where every light is zero there.
fn chances(mesh: &Mesh, lights: &[PreparedLight]) -> Vec<f64> {
    let (lo, hi) = mesh.bounds();
    let centre = (0.5 * (lo + hi)).as_dvec3();
    let weights: Vec<f64> = lights.iter().map(|l| light_incidence(l, centre).1.element_sum()).collect();
    let total: f64 = weights.iter().sum();
    if total > 0.0 {
        weights.iter().map(|w| w / total).collect()
    } else {
        vec![1.0 / lights.len().max(1) as f64; lights.len()]
    }
}

/// Per receiver and channel, the mean score and its standard error (the walks' own added to
/// each receiver's exact direct part), and the per-vertex noise per channel.
fn summarize(
    sum: &[[f64; 3]],
    sum2: &[[f64; 3]],
    receivers: &[Receiver],
    walks: u64,
) -> (Vec<[f64; 3]>, Vec<[f64; 3]>, [f64; 3]) {
    let nf = walks.max(1) as f64;
    let mut exitance = vec![[0.0; 3]; sum.len()];
    let mut stderr = vec![[0.0; 3]; sum.len()];
    for i in 0..sum.len() {
        for c in 0..3 {
            let mean = sum[i][c] / nf;
            let var = ((sum2[i][c] / nf - mean * mean) * nf / (nf - 1.0).max(1.0)).max(0.0);
            exitance[i][c] = mean + receivers[i].direct[c];
            stderr[i][c] = if walks == 0 { f64::INFINITY } else { (var / nf).sqrt() };
        }
    }
    let noise = [0, 1, 2].map(|c| per_vertex_noise(&exitance, &stderr, c));
    (exitance, stderr, noise)
}

/// The RMS over the lit receivers of `stderr / exitance` in channel `c` (0 where none is lit).
pub(crate) fn per_vertex_noise(exitance: &[[f64; 3]], stderr: &[[f64; 3]], c: usize) -> f64 {
    let floor = LIT_FLOOR * exitance.iter().map(|m| m[c]).fold(0.0, f64::max);
    let (mut n, mut sum) = (0usize, 0.0);
    for (m, s) in exitance.iter().zip(stderr) {
        if m[c] > 0.0 && m[c] >= floor {
            n += 1;
            sum += (s[c] / m[c]).powi(2);
        }
    }
    if n == 0 { 0.0 } else { (sum / n as f64).sqrt() }
}

impl Adjoint<'_> {
    /// Receiver `v`, corner `corner` of triangle `t`: its start and its direct light.
    fn receiver(&self, v: usize, (t, corner): (usize, usize)) -> Receiver {
        let geometry = self.geometry;
        let mut bary = [0.0; 3];
        bary[corner] = 1.0;
        let n = geometry.shading_normal(t, bary);
        let p = geometry.mesh.positions()[v].as_dvec3() - n * (1e3 * geometry.slack());
        let mut direct = [0.0; 3];
        for light in self.lights {
            for (c, m) in self.media.iter().enumerate() {
                if let Some(beam) = self.beams.at(light, p, Way { eta: m.eta, entry: self.entry })
                    && beam.d.dot(n) > 0.0
                {
                    let cos = beam.d.dot(n);
                    let t_out = 1.0 - fresnel::fresnel_reflectance(cos, 1.0 / m.eta);
                    direct[c] += beam.irradiance[c] * (-m.sigma_t() * beam.s).exp() * cos * t_out;
                }
            }
        }
        let chances = self.receiver_chances(p, n);
        Receiver { p, n, direct, chances }
    }

    /// Per light, the chance a next event of a walk from the vertex at `p` (outward normal `n`)
    /// picks it: half by the light's share of what reaches the vertex itself (irradiance times
    /// the cosine, where unshadowed), since most of a walk's score is gathered near its start,
    /// half by the object's chances, so that every light that reaches the object somewhere
    /// keeps a chance (unbiased). With no light at the vertex, the object's chances.
    fn receiver_chances(&self, p: DVec3, n: DVec3) -> Vec<f64> {
        let local: Vec<f64> = self
            .lights
            .iter()
            .map(|l| crate::reference::reaching(l, self.beams.occluders, p, n, self.beams.eps))
            .map(|r| r.map_or(0.0, |(_, e, cos)| e.element_sum() * cos))
            .collect();
        let total: f64 = local.iter().sum();
        if total <= 0.0 {
            return self.chances.clone();
        }
        local.iter().zip(&self.chances).map(|(l, g)| 0.5 * l / total + 0.5 * g).collect()
    }

    /// `k` walks from `r` in every channel: per channel the sums of the scores and of their
    /// squares, and the walks lost.
    fn receiver_walks(&self, r: &Receiver, k: u64, rng: &mut Pcg64) -> ([f64; 3], [f64; 3], [u64; 3]) {
        let (mut sum, mut sum2, mut lost) = ([0.0; 3], [0.0; 3], [0; 3]);
        for _ in 0..k {
            for c in 0..3 {
                match self.walk(r, c, rng) {
                    Some(score) => {
                        sum[c] += score;
                        sum2[c] += score * score;
                    }
                    None => lost[c] += 1,
                }
            }
        }
        (sum, sum2, lost)
    }

    /// One walk from `r` in channel `c`: its score, or `None` if it met the surface from
    /// outside (a crack), which scores 0 and is counted.
    fn walk(&self, r: &Receiver, c: usize, rng: &mut Pcg64) -> Option<f64> {
        let medium = &self.media[c];
        let (sigma_t, albedo) = (medium.sigma_t(), medium.albedo());
        let (mut d, cos) = cosine_inwards(r.n, rng);
        let mut w = PI * (1.0 - fresnel::fresnel_reflectance(cos, 1.0 / medium.eta));
        let (mut p, mut skip, mut score) = (r.p, None, 0.0);
        loop {
            let s = -(1.0 - rng.random::<f64>()).ln() / sigma_t;
            let Some(hit) = self.geometry.closest_hit(p, d, s, skip) else {
                p += d * s;
                skip = None;
                score += w * albedo * self.next_event(p, d, (c, &r.chances), rng);
                let Some(next) = after_collision(w, albedo, rng) else { return Some(score) };
                w = next;
                d = scatter(d, medium.g, rng);
                continue;
            };
            p += d * hit.t;
            skip = Some(hit.triangle);
            let face = self.geometry.normals[hit.triangle];
            let cos_face = d.dot(face);
            if cos_face <= 0.0 {
                return None;
            }
            let n = self.geometry.shading_normal(hit.triangle, [1.0 - hit.u - hit.v, hit.u, hit.v]);
            let cos = d.dot(n);
            let reflectance = if cos > 0.0 { fresnel::fresnel_reflectance(cos, 1.0 / medium.eta) } else { 1.0 };
            let Some(next) = after_reflection(w, reflectance, albedo, rng) else { return Some(score) };
            w = next;
            // Reflected about the face, so that the walk stays inside the flat mesh.
            d -= face * (2.0 * cos_face);
        }
    }

    /// The light scattered at `q` towards `-d` (the walk looks along `d`) out of one light's
    /// uncollided beam, the light drawn by the receiver's `chances`, over its chance; per unit
    /// of the walk's weight times the albedo, in channel `c`.
    fn next_event(&self, q: DVec3, d: DVec3, (c, chances): (usize, &[f64]), rng: &mut Pcg64) -> f64 {
        let medium = &self.media[c];
        // Every beam reaching q has crossed at least the clearance: its attenuation is at most
        // exp(-sigma_t clearance). The next event is taken with that bound's chance (times
        // SURFACE_CHANCE) and weighted by its inverse: unbiased, each taken event worth at most
        // 1 / SURFACE_CHANCE of its beam, and the search for beams spared where they are dim.
        let chance = SURFACE_CHANCE * (-medium.sigma_t() * self.geometry.clearance_at(q)).exp();
        if rng.random::<f64>() >= chance {
            return 0.0;
        }
        let Some(l) = pick(chances, rng.random::<f64>()) else { return 0.0 };
        let way = Way { eta: medium.eta, entry: self.entry };
        let Some(Beam { irradiance, s, d: along }) = self.beams.at(&self.lights[l], q, way) else { return 0.0 };
        irradiance[c] * (-medium.sigma_t() * s).exp() * henyey_greenstein(along.dot(-d), medium.g)
            / (chances[l] * chance)
    }
}

/// The index at `u` in [0, 1) of the distribution `chances`; `None` if it is empty.
fn pick(chances: &[f64], u: f64) -> Option<usize> {
    let mut acc = 0.0;
    for (i, p) in chances.iter().enumerate() {
        acc += p;
        if u < acc {
            return Some(i);
        }
    }
    chances.len().checked_sub(1)
}

/// A direction into the medium below the outward normal `n`, drawn by its cosine to `-n`
/// (Malley's method), with that cosine.
fn cosine_inwards(n: DVec3, rng: &mut Pcg64) -> (DVec3, f64) {
    let (u1, u2) = (rng.random::<f64>(), rng.random::<f64>());
    let (r, phi) = (u1.sqrt(), std::f64::consts::TAU * u2);
    let cos = (1.0 - u1).max(0.0).sqrt();
    let (a, b) = n.any_orthonormal_pair();
    ((a * (r * phi.cos()) + b * (r * phi.sin()) - n * cos).normalize(), cos)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::rte::Budget;
    use crate::scene::lights::LightKind;
    use glam::{Mat4, Vec3};
    use std::collections::HashMap;

    fn quiet(_: RteProgress) {}

    /// A box of half-extents `half`, each face a `k` x `k` grid of square pairs of triangles
    /// wound outwards, so that the shading normals are the face's own away from its rim.
    fn slab(half: DVec3, k: i64) -> Mesh {
        let (mut positions, mut index, mut triangles) = (Vec::new(), HashMap::new(), Vec::new());
        for axis in 0..3 {
            for sign in [-1i64, 1] {
                let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
                let mut id = |i: i64, j: i64| -> u32 {
                    let mut g = [0i64; 3];
                    (g[axis], g[b], g[c]) = (sign * k, 2 * i - k, 2 * j - k);
                    *index.entry(g).or_insert_with(|| {
                        let p = DVec3::new(g[0] as f64, g[1] as f64, g[2] as f64) * half / k as f64;
                        positions.push(p.as_vec3());
                        positions.len() as u32 - 1
                    })
                };
                for i in 0..k {
                    for j in 0..k {
                        let q = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
                        let mut pair = [[q[0], q[1], q[2]], [q[0], q[2], q[3]]];
                        if sign < 0 {
                            pair.iter_mut().for_each(|t| t.swap(1, 2));
                        }
                        triangles.extend(pair);
                    }
                }
            }
        }
        Mesh::from_triangles(positions, triangles).unwrap()
    }

    fn directional(towards: DVec3) -> PreparedLight {
        PreparedLight {
            kind: LightKind::Directional { direction: towards.normalize().as_vec3(), irradiance: Vec3::ONE },
            environment: false,
            casts_shadow: false,
            shadow_layer: None,
            shadow_matrix: Mat4::IDENTITY,
            shadow_texel: 0.0,
            normal_offset: 0.0,
            source: 0,
        }
    }

    /// The vertex at `p`.
    fn vertex_at(mesh: &Mesh, p: DVec3) -> usize {
        mesh.positions().iter().position(|v| v.as_dvec3().distance(p) < 1e-6).unwrap()
    }

    /// The exitance at the centre of the top of a wide, deep slab (lengths in mean free paths)
    /// of three media under one directional light towards `towards`. Each face is cut 32 times
    /// along each side, so the shading normals tilt only in the outer 2.5 free paths.
    fn top_centre(media: [Medium; 3], towards: DVec3, walks: u64) -> ObjectExitance {
        top_centre_entering(media, towards, walks, Entry::Refracted)
    }

    fn top_centre_entering(media: [Medium; 3], towards: DVec3, walks: u64, entry: Entry) -> ObjectExitance {
        let half = DVec3::new(40.0, 40.0, 25.0);
        let mesh = slab(half, 32);
        let lights = [directional(towards)];
        let occluders = crate::mesh::bvh::Bvh::new(Vec::new());
        let lighting = Lighting { lights: &lights, occluders: &occluders, eps: 1e-6 };
        let receiver = vertex_at(&mesh, DVec3::new(0.0, 0.0, half.z));
        let options = MeshOptions {
            budget: Budget::photons(walks),
            seed: 7,
            walk: super::super::Walk::Adjoint { receivers: None },
        };
        object_adjoint(&mesh, &media, &lighting, vec![receiver], (&options, entry), &quiet).unwrap()
    }

    #[test]
    fn the_adjoint_walk_gives_chandrasekhars_half_space_albedo_at_the_top_of_a_wide_slab() {
        // Index-matched, isotropic, normal incidence: R = 1 - H(1) sqrt(1 - a) (Chandrasekhar
        // 1960, section 24), 0.1152, 0.4149 and 0.7527 for albedos 0.5, 0.9 and 0.99.
        let media = [0.5, 0.9, 0.99].map(|a| Medium::new(1.0 - a, a, 0.0, 1.0).unwrap());
        let result = top_centre(media, DVec3::Z, 40_000);
        for (c, expected) in [0.1152, 0.4149, 0.7527].into_iter().enumerate() {
            let (m, se) = (result.exitance[0][c], result.stderr[0][c]);
            assert!(se < 0.01 * expected, "channel {c}: the test must measure something ({se})");
            assert!((m - expected).abs() < 4.0 * se + 0.002 * expected, "channel {c}: {m} ± {se}, exact {expected}");
        }
        assert_eq!(result.lost, [0; 3]);
    }

    #[test]
    fn the_adjoint_walk_agrees_with_the_photon_walk_in_a_half_space_at_oblique_incidence() {
        // Each channel its own albedo and index, light at cosine 0.6: the exitance is E cos_i F_t(cos_i) times the
        // half-space's reflectance per transmitted flux, which `rte::half_space_reflectance`
        // walks forwards.
        let media = [(0.8, 1.3), (0.95, 1.3), (0.95, 1.5)].map(|(a, eta)| Medium::new(1.0 - a, a, 0.0, eta).unwrap());
        let towards = DVec3::new(0.8, 0.0, 0.6);
        let result = top_centre(media, towards, 100_000);
        for (c, medium) in media.iter().enumerate() {
            let forward =
                crate::reference::rte::half_space_reflectance(medium, 0.6, &Budget::photons(400_000), 11, &quiet)
                    .unwrap();
            let entering = 0.6 * fresnel::fresnel_transmittance(0.6, medium.eta);
            let (expected, se_f) = (entering * forward.mean, entering * forward.stderr);
            let (m, se) = (result.exitance[0][c], result.stderr[0][c]);
            let combined = (se * se + se_f * se_f).sqrt();
            assert!(
                combined < 0.01 * expected,
                "channel {c}: the test must measure something ({se}, {se_f} of {expected})"
            );
            assert!(
                (m - expected).abs() < 4.0 * combined,
                "channel {c}: adjoint {m} ± {se}, photons {expected} ± {se_f}"
            );
        }
    }

    #[test]
    fn light_entering_along_the_normal_is_the_refracted_light_at_normal_incidence_and_at_its_depth_on_a_slab() {
        // The same walks: at normal incidence on a flat face the two entries are one beam, so
        // the scores agree (to 2e-4: under the slab's rim, 37.5 to 40 free paths away, the
        // shading normals tilt and the two beams part); at cosine 0.6 the refracted beam runs shallower and
        // leaves more light near the entry (eta 1.3: cos_t 0.79), which the normal entry misses.
        let media = [0.5, 0.9, 0.99].map(|a| Medium::new(1.0 - a, a, 0.0, 1.3).unwrap());
        let run = |towards, entry| top_centre_entering(media, towards, 2000, entry);
        let (refracted, normal) = (run(DVec3::Z, Entry::Refracted), run(DVec3::Z, Entry::Normal));
        for c in 0..3 {
            let (a, b) = (refracted.exitance[0][c], normal.exitance[0][c]);
            assert!((a - b).abs() <= 2e-4 * a, "channel {c}: {a} against {b}");
        }
        let towards = DVec3::new(0.8, 0.0, 0.6);
        let (refracted, normal) = (run(towards, Entry::Refracted), run(towards, Entry::Normal));
        let (a, b) = (refracted.exitance[0][0], normal.exitance[0][0]);
        assert!(a > b * 1.02, "albedo 0.5 at cosine 0.6: refracted {a}, normal {b}");
        // Under uniform light on a flat face the beam's fluence depends on depth alone, so the
        // slanted entry's equals the refracted one's at every point, and so do the scores.
        let slanted = run(towards, Entry::Slanted);
        for c in 0..3 {
            let (a, b) = (refracted.exitance[0][c], slanted.exitance[0][c]);
            assert!((a - b).abs() <= 2e-4 * a, "channel {c}: refracted {a}, slanted {b}");
        }
    }

    #[test]
    fn a_beam_through_a_flat_face_is_the_collimated_transmitted_irradiance() {
        // Under a flat face the refracted beam is parallel: E cos_i F_t / cos_t across it, and
        // the point at depth h is s = h / cos_t along it.
        let half = DVec3::new(4.0, 4.0, 2.0);
        let mesh = slab(half, 8);
        let geometry = Geometry::new(&mesh, false);
        let occluders = crate::mesh::bvh::Bvh::new(Vec::new());
        let eta = 1.4;
        let beams = Beams { geometry: &geometry, occluders: &occluders, eps: 1e-6 };
        let towards = DVec3::new(0.6, 0.0, 0.8);
        let way = Way { eta, entry: Entry::Refracted };
        let beam = beams.at(&directional(towards), DVec3::new(0.1, 0.2, half.z - 0.5), way).unwrap();
        let cos_t = (1.0 - 0.36 / (eta * eta)).sqrt();
        let expected = 0.8 * fresnel::fresnel_transmittance(0.8, eta) / cos_t;
        assert!((beam.irradiance.x - expected).abs() < 1e-6 * expected, "{} against {expected}", beam.irradiance.x);
        assert!((beam.s - 0.5 / cos_t).abs() < 1e-7, "{}", beam.s);
        // The light's direction is stored in f32.
        assert!((beam.d.z + cos_t).abs() < 1e-6 && beam.d.x < 0.0, "{:?}", beam.d);
    }

    #[test]
    fn a_sphere_focuses_its_beam_without_creating_or_losing_light() {
        // Under light from +z, the flux crossing the section z = r/2 of a unit sphere inside is
        // the flux that entered above it: each beam's irradiance times |d_z| over the section
        // (a polar grid) against E cos_i F_t over the faces above (the refraction bends the
        // beams towards the axis, and the spread J(s) must follow them).
        let mesh = crate::mesh::shapes::sphere(1.0, 48).unwrap();
        let geometry = Geometry::new(&mesh, false);
        let occluders = crate::mesh::bvh::Bvh::new(Vec::new());
        let eta = 1.5;
        let beams = Beams { geometry: &geometry, occluders: &occluders, eps: 1e-6 };
        let light = directional(DVec3::Z);
        let z0 = 0.5;
        let rim = (1.0f64 - z0 * z0).sqrt() * 0.999;
        let (rings, sectors) = (120, 24);
        let mut crossing = 0.0;
        for i in 0..rings {
            let (r0, r1) = (rim * i as f64 / rings as f64, rim * (i + 1) as f64 / rings as f64);
            let r = 0.5 * (r0 + r1);
            for j in 0..sectors {
                let phi = std::f64::consts::TAU * (j as f64 + 0.5) / sectors as f64;
                let q = DVec3::new(r * phi.cos(), r * phi.sin(), z0);
                let way = Way { eta, entry: Entry::Refracted };
                let beam = beams.at(&light, q, way).expect("every point of the section is lit");
                let area = 0.5 * (r1 * r1 - r0 * r0) * std::f64::consts::TAU / sectors as f64;
                crossing += beam.irradiance.x * (-beam.d.z) * area;
            }
        }
        let mut entered = 0.0;
        for t in 0..mesh.triangles().len() {
            // The centroids of the face cut into 16 triangles, those above the section.
            let n = 4;
            let upward = (0..n).flat_map(|a| (0..n - a).map(move |b| (a as f64 + 1.0 / 3.0, b as f64 + 1.0 / 3.0)));
            let downward =
                (0..n - 1).flat_map(|a| (0..n - 1 - a).map(move |b| (a as f64 + 2.0 / 3.0, b as f64 + 2.0 / 3.0)));
            for (a, b) in upward.chain(downward) {
                {
                    let (u, v) = (a / n as f64, b / n as f64);
                    let bary = [1.0 - u - v, u, v];
                    let p = mesh.point(t, bary);
                    let cos = geometry.shading_normal(t, bary).z;
                    if p.z > z0 && cos > 0.0 {
                        let weight = mesh.triangle_areas()[t] / (n * n) as f64;
                        entered += cos * fresnel::fresnel_transmittance(cos, eta) * weight;
                    }
                }
            }
        }
        assert!((crossing - entered).abs() < 0.01 * entered, "crossing {crossing}, entered {entered}");
    }
}
