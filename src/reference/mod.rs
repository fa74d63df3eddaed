//! The CPU reference (f64): splat with ray-cast visibility through a BVH and the dipole gather
//! with the f64 kernel of `optics::kernel`. The ground truth for the GPU passes' tests and for
//! the accuracy study. [`rte`] and [`rte_mesh`]: a Monte Carlo reference of the radiative
//! transfer equation, what the dipole model itself approximates.

/// The triangle hierarchy the reference casts its rays into (`mesh::bvh`, shared with the splat).
pub use crate::mesh::bvh;
pub mod clearance;
pub mod directional;
pub(crate) mod json_null;
pub mod rte;
pub mod rte_cache;
pub mod rte_mesh;
pub mod single;
pub mod texture;
pub mod transport_cache;
pub mod tree;
pub mod truth;

use crate::optics::Dipole;
use crate::optics::{fresnel, kernel};
use crate::scene::build::{PreparedObject, PreparedScene, ResolvedMaterial};
use crate::scene::lights::{LightKind, PreparedLight};
use bvh::Bvh;
use glam::DVec3;
use rayon::prelude::*;

/// Occluders of a prepared scene: every triangle of every shadow-casting object
/// (`PreparedScene::occluders`).
pub fn occluders(scene: &PreparedScene) -> Bvh {
    scene.occluders()
}

/// [`occluders`] of `objects` alone (before the scene around them is complete).
pub fn occluders_of(objects: &[PreparedObject]) -> Bvh {
    crate::scene::build::occluders_of(objects)
}

/// Direction towards the light and the irradiance it brings to a surface facing it, and the
/// distance to the light, in f64: the twin of `light_incidence` in glsl/common/lights.glsl.
pub fn light_incidence(light: &PreparedLight, p: DVec3) -> (DVec3, DVec3, f64) {
    let (position, power, spot) = match light.kind {
        LightKind::Directional { direction, irradiance } => {
            return (direction.as_dvec3(), irradiance.as_dvec3(), f64::INFINITY);
        }
        LightKind::Point { position, intensity } => (position, intensity, None),
        LightKind::Spot { position, axis, intensity, cos_outer, cos_inner } => {
            (position, intensity, Some((axis.as_dvec3(), cos_outer as f64, cos_inner as f64)))
        }
    };
    let d = position.as_dvec3() - p;
    let dist2 = d.length_squared().max(1e-24);
    let dist = dist2.sqrt();
    let wi = d / dist;
    let mut irradiance = power.as_dvec3() / dist2;
    if let Some((axis, outer, inner)) = spot {
        let c = (-wi).dot(axis);
        let t = ((c - outer) / (inner - outer)).clamp(0.0, 1.0);
        irradiance *= t * t * (3.0 - 2.0 * t);
    }
    (wi, irradiance, dist)
}

/// Transmitted irradiance at every sample of the scene (scene order), with exact ray-cast
/// visibility for the lights that cast shadows.
pub fn splat(scene: &PreparedScene, occluders: &Bvh) -> Vec<[f64; 3]> {
    let mut jobs = Vec::new();
    for o in &scene.objects {
        if let ResolvedMaterial::Translucent { material, .. } = &o.material {
            for s in &o.samples {
                jobs.push((s, material.eta));
            }
        }
    }
    let eps = ray_offset(scene);
    jobs.par_iter()
        .map(|(s, eta)| {
            let (e, ..) =
                transmitted_irradiance(scene, occluders, s.position.as_dvec3(), s.normal.as_dvec3(), *eta, eps);
            e.to_array()
        })
        .collect()
}

/// Light `l` at surface point `p` with shading normal `n`: its direction, its irradiance and the
/// incidence cosine, where it faces the point and no caster blocks it (a ray cast from `eps`
/// off the surface, for lights that cast shadows); `None` otherwise.
pub(crate) fn reaching(
    l: &PreparedLight,
    occluders: &Bvh,
    p: DVec3,
    n: DVec3,
    eps: f64,
) -> Option<(DVec3, DVec3, f64)> {
    let (wi, e, dist) = light_incidence(l, p);
    let cos_i = n.dot(wi);
    let blocked = || l.shadow_layer.is_some() && occluders.occluded(p + n * eps, wi, eps, dist);
    (cos_i > 0.0 && !blocked()).then_some((wi, e, cos_i))
}

/// How far a visibility ray starts off the surface (`PreparedScene::ray_offset`).
pub fn ray_offset(scene: &PreparedScene) -> f64 {
    scene.ray_offset()
}

/// [`ray_offset`] for a scene whose bounding sphere has radius `radius`.
pub fn ray_offset_within(radius: f32) -> f64 {
    crate::scene::build::ray_offset_within(radius)
}

/// Fresnel-transmitted irradiance `E_t(p) = sum_l E_l cos_i F_t(cos_i, eta) V_l(p)` at a surface
/// point with shading normal `n` (seed Eq. 10's integrand without `R_d`), with two bit masks of
/// the lights (first 64) that face it: those that reach it and those a caster blocks. A light
/// reaching one point and blocked at a nearby one marks a shadow edge between them.
pub fn transmitted_irradiance(
    scene: &PreparedScene,
    occluders: &Bvh,
    p: DVec3,
    n: DVec3,
    eta: f64,
    eps: f64,
) -> (DVec3, u64, u64) {
    transmitted_irradiance_known(scene, occluders, p, n, eta, eps, Visibility::TRACE_ALL)
}

/// Which lights' visibility is already known at a point (the first 64 lights, by bit), so that
/// only the others are ray cast.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Visibility {
    /// Lights to ray cast.
    pub trace: u64,
    /// Of the lights not traced, those known to be blocked (the rest are known to reach).
    pub blocked: u64,
}

impl Visibility {
    /// Nothing known: every light with shadows is ray cast.
    pub const TRACE_ALL: Visibility = Visibility { trace: !0, blocked: 0 };
}

/// [`transmitted_irradiance`] taking the visibility of the lights outside `known.trace` from
/// `known` instead of casting their rays. Lights past the 64th are always traced.
pub fn transmitted_irradiance_known(
    scene: &PreparedScene,
    occluders: &Bvh,
    p: DVec3,
    n: DVec3,
    eta: f64,
    eps: f64,
    known: Visibility,
) -> (DVec3, u64, u64) {
    let mut e = DVec3::ZERO;
    let (reached, blocked) = each_transmitted(scene, occluders, (p, n, eps), known, |_, irradiance, cos_i, _| {
        e += irradiance * (cos_i * fresnel::fresnel_transmittance(cos_i, eta));
    });
    (e, reached, blocked)
}

/// What the transport kernel's entry basis reads at a surface point (`optics::transport`), as
/// `glsl/splat.comp` forms it: the transmitted irradiance `E_t` (as [`transmitted_irradiance`]),
/// the key lights' refracted directions summed weighted by their transmitted flux (the sum
/// over channels), and that flux.
pub fn transmitted_entry(
    scene: &PreparedScene,
    occluders: &Bvh,
    (p, n): (DVec3, DVec3),
    eta: f64,
    eps: f64,
) -> (DVec3, DVec3, f64) {
    let nn = n.normalize();
    let keys = crate::scene::lights::key_light_count(&scene.lights);
    let (mut e, mut d_key, mut w_key) = (DVec3::ZERO, DVec3::ZERO, 0.0);
    each_transmitted(scene, occluders, (p, n, eps), Visibility::TRACE_ALL, |wi, irradiance, cos_i, l| {
        let e_l = irradiance * (cos_i * fresnel::fresnel_transmittance(cos_i, eta));
        e += e_l;
        if l < keys
            && let Some(d) = crate::optics::directional_dipole::refract_in(wi, nn, eta)
        {
            d_key += d * e_l.element_sum();
            w_key += e_l.element_sum();
        }
    });
    (e, d_key, w_key)
}

/// Calls `f` with the direction towards, irradiance, incidence cosine and index of each light that
/// reaches a surface point at `p` with shading normal `n` (rays offset by `eps`), the
/// visibility of the lights outside `known.trace` taken from `known`; returns the bit masks of
/// the first 64 lights that reach it and that a caster blocks.
fn each_transmitted(
    scene: &PreparedScene,
    occluders: &Bvh,
    (p, n, eps): (DVec3, DVec3, f64),
    known: Visibility,
    mut f: impl FnMut(DVec3, DVec3, f64, usize),
) -> (u64, u64) {
    let n = n.normalize();
    let (mut reached, mut blocked) = (0u64, 0u64);
    for (i, l) in scene.lights.iter().enumerate() {
        let (wi, irradiance, dist) = light_incidence(l, p);
        let cos_i = n.dot(wi);
        if cos_i <= 0.0 {
            continue;
        }
        let bit = 1u64 << (i % 64);
        let occluded = if l.shadow_layer.is_none() {
            false
        } else if i < 64 && known.trace & bit == 0 {
            known.blocked & bit != 0
        } else {
            occluders.occluded(p + n * eps, wi, eps, dist)
        };
        if occluded {
            blocked |= bit;
            continue;
        }
        f(wi, irradiance, cos_i, i);
        reached |= bit;
    }
    (reached, blocked)
}

/// Radiant exitance at every vertex of every object (zero for opaque ones), from per-sample
/// transmitted irradiance in scene order: the far kernel summed plus the near field blended
/// over neighbouring samples with each channel's radius (`optics::kernel::far_kernel` explains
/// the split, `near_blend_radii` the radii), times the share of it kept beside an open boundary
/// (`optics::kernel::near_kept_at_edge` for each of the two nearest boundary directions, with
/// `b` from the blend's mean sample area).
pub fn gather(scene: &PreparedScene, irradiance: &[[f64; 3]]) -> Vec<Vec<[f64; 3]>> {
    per_translucent_object(scene, |o, dipoles, first| {
        let samples: Vec<(DVec3, f64, [f64; 3])> =
            o.samples.iter().enumerate().map(|(k, s)| (s.position.as_dvec3(), s.area, irradiance[first + k])).collect();
        // Each sample's near exitance E_i E_near,i, to be blended between samples.
        let near: Vec<(DVec3, f64, [f64; 3])> = samples
            .iter()
            .map(|(p, area, e)| {
                let b = kernel::B_PER_SQRT_AREA * area.sqrt();
                (*p, *area, [0, 1, 2].map(|c| e[c] * kernel::near_energy(&dipoles[c], b)))
            })
            .collect();
        let boundary = o.mesh.boundary_distances();
        let radii = o.near_blend_radii();
        o.mesh
            .positions()
            .par_iter()
            .zip(&boundary)
            .map(|(x, t)| {
                let x = x.as_dvec3();
                let mut far = [0.0; 3];
                for (p, area, e) in &samples {
                    let r = x.distance(*p);
                    for c in 0..3 {
                        far[c] += e[c] * kernel::far_kernel(&dipoles[c], r, *area);
                    }
                }
                let (near, mean_area) = near_blend(x, &near, radii);
                let kept = near_kept(dipoles, mean_area, *t);
                [0, 1, 2].map(|c| far[c] + near[c] * kept[c])
            })
            .collect()
    })
}

/// Per channel, the share of the blended near exitance a receiver keeps beside open boundaries
/// `boundary` away (`mesh::Mesh::boundary_distances`): `kernel::near_kept_at_edge` for each of
/// the two directions, with `b` of the channel's blend's mean sample area; all of it when no
/// blend weight reached (`mean_area` none). The twin of `gather_end` and `gather_near_kept` in
/// glsl/common/gather.glsl.
pub(crate) fn near_kept(dipoles: &[Dipole; 3], mean_area: [Option<f64>; 3], boundary: [f32; 2]) -> [f64; 3] {
    [0, 1, 2].map(|c| {
        mean_area[c].map_or(1.0, |area| {
            let b = kernel::B_PER_SQRT_AREA * area.sqrt();
            boundary.iter().map(|&t| kernel::near_kept_at_edge(&dipoles[c], b, f64::from(t))).product()
        })
    })
}

/// Blend per-sample values to `x` with the near-field Shepard weights
/// (`kernel::near_blend_weight`), value `c` with radius factor `radii[c]`, or take the nearest
/// sample's where no weight reaches: the twin of the blend in glsl/common/gather.glsl and
/// glsl/gather_sparse.comp. Also each value's blend's mean sample area (`sum w A / sum w`), none
/// where no weight reaches. `N` values per sample: the sparse gather blends its far and near
/// parts (six) with one radius.
pub(crate) fn near_blend<const N: usize>(
    x: DVec3,
    values: &[(DVec3, f64, [f64; N])],
    radii: [f64; N],
) -> ([f64; N], [Option<f64>; N]) {
    let (mut sum, mut weight_sum, mut area_sum) = ([0.0; N], [0.0; N], [0.0; N]);
    let (mut nearest_r, mut nearest) = (f64::INFINITY, [0.0; N]);
    for (p, area, v) in values {
        let r = x.distance(*p);
        for c in 0..N {
            let w = kernel::near_blend_weight(r, *area, radii[c]);
            sum[c] += w * v[c];
            weight_sum[c] += w;
            area_sum[c] += w * area;
        }
        if r < nearest_r {
            (nearest_r, nearest) = (r, *v);
        }
    }
    let blended = std::array::from_fn(|c| if weight_sum[c] > 0.0 { sum[c] / weight_sum[c] } else { nearest[c] });
    (blended, std::array::from_fn(|c| (weight_sum[c] > 0.0).then(|| area_sum[c] / weight_sum[c])))
}

/// The sparse gather (`render.gather = "sparse"`, glsl/gather_sparse.comp) in f64: the far sum
/// at each sample, blended to every vertex with the near-field Shepard weights together with
/// the samples' own near exitance, which is scaled by the share kept beside open boundaries
/// ([`near_kept`]).
pub fn gather_sparse(scene: &PreparedScene, irradiance: &[[f64; 3]]) -> Vec<Vec<[f64; 3]>> {
    per_translucent_object(scene, |o, dipoles, first| {
        // Per sample: the far sum there (r, g, b), then its own near exitance (r, g, b).
        let at_samples: Vec<(DVec3, f64, [f64; 6])> = o
            .samples
            .par_iter()
            .enumerate()
            .map(|(j, sj)| {
                let x = sj.position.as_dvec3();
                let mut t = [0.0; 3];
                for (i, si) in o.samples.iter().enumerate() {
                    let r = x.distance(si.position.as_dvec3());
                    for c in 0..3 {
                        t[c] += irradiance[first + i][c] * kernel::far_kernel(&dipoles[c], r, si.area);
                    }
                }
                let b = kernel::B_PER_SQRT_AREA * sj.area.sqrt();
                let near = |c: usize| irradiance[first + j][c] * kernel::near_energy(&dipoles[c], b);
                let values = [t[0].max(0.0), t[1].max(0.0), t[2].max(0.0), near(0), near(1), near(2)];
                (x, sj.area, values)
            })
            .collect();
        let boundary = o.mesh.boundary_distances();
        o.mesh
            .positions()
            .par_iter()
            .zip(&boundary)
            .map(|(x, t)| {
                let x = x.as_dvec3();
                let (m, mean_area) = near_blend(x, &at_samples, [kernel::NEAR_BLEND_RADIUS; 6]);
                let kept = near_kept(dipoles, [mean_area[0]; 3], *t);
                [0, 1, 2].map(|c| m[c] + m[3 + c] * kept[c])
            })
            .collect()
    })
}

/// Run `f` on every translucent object with its dipoles and the index of its first sample in
/// scene order; opaque objects get zero exitance at every vertex.
pub(crate) fn per_translucent_object(
    scene: &PreparedScene,
    f: impl Fn(&PreparedObject, &[Dipole; 3], usize) -> Vec<[f64; 3]>,
) -> Vec<Vec<[f64; 3]>> {
    let mut first = 0;
    scene
        .objects
        .iter()
        .map(|o| {
            let start = first;
            first += o.samples.len();
            match &o.material {
                ResolvedMaterial::Translucent { dipoles, .. } => f(o, dipoles, start),
                ResolvedMaterial::Opaque { .. } => vec![[0.0; 3]; o.mesh.positions().len()],
            }
        })
        .collect()
}
