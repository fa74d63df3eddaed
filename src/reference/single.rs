//! Single scattering at the vertices, f64: the exitance of light scattered once below the
//! surface, under the local half-space approximation (`optics::single_scatter`).
//!
//! At a vertex with shading normal `n`, each light that reaches it at incidence cosine `cos_i`
//! brings `E_l cos_i F_t(cos_i, eta)` into the medium, of which `R1(cos_i)` leaves after one
//! scattering: `M1(x) = sum_l E_l cos_i F_t(cos_i, eta) V_l(x) R1(albedo', 0, eta, cos_i)` per
//! channel, with the reduced albedo and an isotropic phase function (the medium the
//! radiative-transfer reference walks). Once-scattered light leaves within a few mean free
//! paths of where it entered, so the term is local: the half-space's figure where the surface
//! is flat and evenly lit over a few mean free paths. It is what the renderer would add to the
//! gathered exitance per vertex for `model = dipole + single`; `study --physics` measures it
//! against the radiative-transfer reference (docs/STUDY.md).
//!
//! [`between_points`] keeps what the local term loses on a curved or unevenly lit surface: it
//! integrates the kernel of single scattering between two surface points
//! (`optics::beam_single`) over the object's lit surface, as `reference::directional`
//! integrates the directional dipole, so light carried along a refracted beam leaves where the
//! beam takes it (past a terminator, through a thin part).

use super::{occluders, per_translucent_object, ray_offset, reaching};
use crate::optics::{fresnel, single_scatter};
use crate::scene::build::PreparedScene;
use rayon::prelude::*;

/// Per object (scene order), per vertex, RGB: the single-scattering exitance `M1` (see the
/// module's documentation); zero for opaque objects.
pub fn exitance(scene: &PreparedScene) -> Vec<Vec<[f64; 3]>> {
    let casters = occluders(scene);
    let eps = ray_offset(scene);
    per_translucent_object(scene, |o, dipoles, _| {
        let eta = dipoles[0].eta;
        (0..o.mesh.positions().len())
            .into_par_iter()
            .map(|v| {
                let p = o.mesh.positions()[v].as_dvec3();
                let n = o.mesh.vertex_normals()[v].as_dvec3().normalize();
                let mut m = [0.0; 3];
                for (_, e, cos_i) in scene.lights.iter().filter_map(|l| reaching(l, &casters, p, n, eps)) {
                    let e_t = e * (cos_i * fresnel::fresnel_transmittance(cos_i, eta));
                    for (c, d) in dipoles.iter().enumerate() {
                        m[c] += e_t[c] * single_scatter::reflectance(d.alpha_prime, 0.0, eta, cos_i.min(1.0));
                    }
                }
                m
            })
            .collect()
    })
}

/// Per object (scene order), per vertex, RGB: the exitance of light scattered once, carried
/// along each refracted beam between the surface points (`optics::beam_single`), integrated at
/// `fineness` by `reference::directional`'s quadrature ([`super::directional::FINENESS`] is
/// its usual one); zero for opaque objects.
pub fn between_points(scene: &PreparedScene, fineness: f64) -> Vec<Vec<[f64; 3]>> {
    use crate::optics::beam_single::BeamSingle;
    use crate::optics::directional_dipole::{Diffusion, Strength};
    let kernel = |d: &crate::optics::Dipole, x_i, _n_i, w_12, x_o, n_o| {
        BeamSingle::from_dipole(d).exitance_per_flux(x_i, w_12, x_o, n_o)
    };
    // The kernel grows as 1/d at the receiver: no width. The diffusion and strength only set
    // the directional dipole's, unused with a kernel.
    let custom = super::directional::Custom { kernel: &kernel, width: 0.0 };
    super::directional::exitance_with(scene, Diffusion::Grosjean, Strength::Paper, fineness, Some(custom))
}
