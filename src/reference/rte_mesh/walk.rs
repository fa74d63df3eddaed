//! One photon's life: its entry through the surface, then a random walk per channel inside the
//! mesh until it leaves or dies.

use super::beam::refract_in;
use super::geometry::Geometry;
use super::sources::{Lighting, Sources};
use super::tally::{Exit, merge_photon};
use crate::mesh::bvh::Hit;
use crate::optics::fresnel;
use crate::reference::reaching;
use crate::reference::rte::{Medium, after_collision, after_reflection, sample_hg_cos};
use glam::DVec3;
use rand::RngExt;
use rand_pcg::Pcg64;

/// What every photon of one object's walk shares: the object as the walk sees it, where its
/// photons start, the scene's lights and casters, its three channels' media and how the walk is
/// done.
#[derive(Clone, Copy)]
pub(super) struct ObjectWalk<'a> {
    pub(super) geometry: &'a Geometry<'a>,
    pub(super) sources: &'a Sources,
    pub(super) lighting: &'a Lighting<'a>,
    pub(super) media: &'a [Medium; 3],
    /// Expected-value splitting at the boundary (`Method::split`).
    pub(super) split: bool,
}

impl ObjectWalk<'_> {
    /// One photon: an entry point, then a walk per channel; its exits are pushed to `exits`
    /// (one per vertex and channel, [`merge_photon`]), the walks that met the surface from
    /// outside are counted in `lost`.
    pub(super) fn photon(&self, rng: &mut Pcg64, exits: &mut Vec<Exit>, lost: &mut [u64; 3]) {
        let ObjectWalk { geometry, sources, lighting, media, split } = *self;
        let ((l, t), p_pair) = sources.pick(rng.random::<f64>());
        let (r1, r2) = (rng.random::<f64>().sqrt(), rng.random::<f64>());
        let bary = [1.0 - r1, r1 * (1.0 - r2), r1 * r2];
        let p = geometry.mesh.point(t, bary);
        let n = geometry.normals[t];
        let light = &lighting.lights[l];
        let Some((wi, e, cos_i)) = reaching(light, lighting.occluders, p, n, lighting.eps) else {
            return;
        };
        let eta = media[0].eta;
        let f_t = fresnel::fresnel_transmittance(cos_i, eta);
        if f_t <= 0.0 {
            return;
        }
        let Some((d, _)) = refract_in(wi, n, eta) else { return };
        let density = p_pair / geometry.mesh.triangle_areas()[t];
        let first = exits.len();
        for (channel, medium) in media.iter().enumerate() {
            let weight = e[channel] * cos_i * f_t / density;
            let start = Start { p, d, triangle: t, channel, weight };
            if weight > 0.0 && walk(geometry, medium, &start, split, rng, exits) {
                lost[channel] += 1;
            }
        }
        merge_photon(exits, first);
    }
}

/// Where one channel's walk starts: at `p` on `triangle`, inwards along `d`, with `weight`
/// (scene units).
pub(super) struct Start {
    pub(super) p: DVec3,
    pub(super) d: DVec3,
    pub(super) triangle: usize,
    pub(super) channel: usize,
    pub(super) weight: f64,
}

/// One channel's walk from `start`: its exits are pushed to `exits`; true if it met the surface
/// from outside (and was dropped there). With `split`, expected-value splitting at the boundary
/// (see the module's documentation), else the analog choice between reflecting and leaving.
pub(super) fn walk(
    geometry: &Geometry,
    medium: &Medium,
    start: &Start,
    split: bool,
    rng: &mut Pcg64,
    exits: &mut Vec<Exit>,
) -> bool {
    let (sigma_t, albedo) = (medium.sigma_t(), medium.albedo());
    // The split walk's weights are relative to the entry's (see the module's documentation).
    let (scale, mut weight) = if split { (start.weight, 1.0) } else { (1.0, start.weight) };
    let (mut p, mut d, mut skip) = (start.p, start.d, Some(start.triangle));
    loop {
        let s = -(1.0 - rng.random::<f64>()).ln() / sigma_t;
        let Some(Hit { t, triangle, u, v }) = geometry.closest_hit(p, d, s, skip) else {
            p += d * s;
            skip = None;
            let Some(w) = after_collision(weight, albedo, rng) else { return false };
            weight = w;
            d = scatter(d, medium.g, rng);
            continue;
        };
        p += d * t;
        skip = Some(triangle);
        let n = geometry.normals[triangle];
        let cos = d.dot(n);
        if cos <= 0.0 {
            return true;
        }
        let r = fresnel::fresnel_reflectance(cos, 1.0 / medium.eta);
        let channel = start.channel;
        if split {
            if r < 1.0 {
                exits.push(Exit {
                    vertex: geometry.cell_vertex(triangle, u, v),
                    channel,
                    weight: scale * weight * (1.0 - r),
                });
            }
            let Some(w) = after_reflection(weight, r, albedo, rng) else { return false };
            weight = w;
        } else if rng.random::<f64>() >= r {
            exits.push(Exit { vertex: geometry.cell_vertex(triangle, u, v), channel, weight });
            return false;
        }
        d -= n * (2.0 * cos);
    }
}

/// The direction after a scattering of `d` by the Henyey-Greenstein phase function of mean
/// cosine `g`. Isotropic (`g` 0, every reduced medium's, `Medium::reduced`) it does not depend
/// on `d`: a uniform direction by Marsaglia's method (1972), without the sine and cosine of an
/// azimuth that were a tenth of the walk's time in marble.
pub(super) fn scatter(d: DVec3, g: f64, rng: &mut Pcg64) -> DVec3 {
    if g == 0.0 {
        loop {
            let (x, y) = (2.0 * rng.random::<f64>() - 1.0, 2.0 * rng.random::<f64>() - 1.0);
            let s = x * x + y * y;
            if s < 1.0 {
                let r = 2.0 * (1.0 - s).sqrt();
                return DVec3::new(x * r, y * r, 1.0 - 2.0 * s);
            }
        }
    }
    let cos = sample_hg_cos(g, rng.random::<f64>());
    let (a, b) = d.any_orthonormal_pair();
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = std::f64::consts::TAU * rng.random::<f64>();
    (d * cos + (a * phi.cos() + b * phi.sin()) * sin).normalize()
}
