//! A Monte Carlo reference of the radiative transfer equation (RTE): what the dipole model
//! approximates, so that the model's own error can be measured.
//!
//! The medium is homogeneous, with absorption `sigma_a`, scattering `sigma_s` and a
//! Henyey-Greenstein phase function of mean cosine `g` ([`Medium`]), behind a smooth dielectric
//! boundary of relative index `eta` (exact Fresnel reflectance, `optics::fresnel`). Photons
//! random-walk it (exponential free paths; absorption analog from albedo 0.5 up, else implicit
//! capture with Russian roulette) and reflect internally or leave with the Fresnel
//! probabilities at the boundary. The measured presets give reduced coefficients only, which are walked with an
//! isotropic phase function and `sigma_s = sigma_s'` ([`Medium::reduced`], the similarity
//! relation the dipole itself rests on).
//!
//! This file holds the medium, the photon budget, the seeded and reproducible parallel driver
//! and the half-space walk ([`half_space_reflectance`]); `rte_mesh` walks closed meshes.
//!
//! # Reproducibility
//!
//! Photons are walked in chunks of fixed size; chunk `k` draws from the PCG64 stream `k` of the
//! seed, and the chunks' tallies are added in chunk order. So the result depends on the seed
//! and on where the budget stops, never on the thread count or the scheduling. A photon or a
//! precision budget stops at the same chunk on every machine; a time budget does not.

use crate::optics::dipole::{check_coefficient, check_eta};
use crate::optics::{Dipole, OpticsError, fresnel};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;
use rayon::prelude::*;
use std::time::Instant;

/// One colour channel of a homogeneous medium, coefficients per scene unit (any unit of
/// length for the half-space, whose reflectance does not depend on the scale).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Medium {
    /// Absorption coefficient.
    pub sigma_a: f64,
    /// Scattering coefficient.
    pub sigma_s: f64,
    /// Henyey-Greenstein mean cosine, in (-1, 1); 0 is isotropic.
    pub g: f64,
    /// Relative index of refraction, inside over outside.
    pub eta: f64,
}

impl Medium {
    /// A medium, refusing coefficients that are negative or not finite, no extinction at all,
    /// `g` outside (-1, 1) and `eta` outside the range `optics` accepts.
    pub fn new(sigma_a: f64, sigma_s: f64, g: f64, eta: f64) -> Result<Medium, OpticsError> {
        check_coefficient("sigma_a", 0, sigma_a)?;
        check_coefficient("sigma_s", 0, sigma_s)?;
        if sigma_a + sigma_s == 0.0 {
            return Err(OpticsError::NoExtinction { channel: 0 });
        }
        if !(g > -1.0 && g < 1.0) {
            return Err(OpticsError::BadG(g));
        }
        check_eta(eta)?;
        Ok(Medium { sigma_a, sigma_s, g, eta })
    }

    /// The medium a dipole channel describes: its reduced coefficients with an isotropic phase
    /// function (`sigma_s = sigma_s'`, `g = 0`), the similarity relation the measured presets
    /// (Jensen et al. 2001) and the dipole both rest on.
    pub fn reduced(d: &Dipole) -> Medium {
        Medium { sigma_a: d.sigma_a, sigma_s: d.sigma_s_prime, g: 0.0, eta: d.eta }
    }

    /// Extinction coefficient `sigma_t = sigma_a + sigma_s`.
    pub fn sigma_t(&self) -> f64 {
        self.sigma_a + self.sigma_s
    }

    /// Diffusion length `1 / sigma_tr`, `sigma_tr = sqrt(3 sigma_a sigma_t')` with the reduced
    /// extinction `sigma_t' = sigma_a + sigma_s (1 - g)`: how far diffuse light runs before it
    /// falls by `e` (infinite without absorption).
    pub fn diffusion_length(&self) -> f64 {
        1.0 / (3.0 * self.sigma_a * (self.sigma_a + self.sigma_s * (1.0 - self.g))).sqrt()
    }

    /// Single-scattering albedo `sigma_s / sigma_t`.
    pub fn albedo(&self) -> f64 {
        self.sigma_s / self.sigma_t()
    }
}

/// When a Monte Carlo estimate stops: after `max_photons`, or earlier once its relative
/// standard error reaches `relative_stderr`, or once `max_seconds` have passed (whichever comes
/// first; the last makes the photon count, and so the result, depend on the machine).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Budget {
    /// The most photons to walk.
    pub max_photons: u64,
    /// Stop once the relative standard error is at most this.
    pub relative_stderr: Option<f64>,
    /// Stop after this much wall time (checked between rounds of chunks).
    pub max_seconds: Option<f64>,
}

impl Budget {
    /// Exactly `n` photons (rounds of chunks permitting: `n` is never exceeded).
    pub fn photons(n: u64) -> Budget {
        Budget { max_photons: n, relative_stderr: None, max_seconds: None }
    }
}

/// A Monte Carlo estimate: the mean, its standard error and the photons it took.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Estimate {
    /// The estimate.
    pub mean: f64,
    /// Its standard error (the sample standard deviation of one photon's score over
    /// `sqrt(photons)`).
    pub stderr: f64,
    /// Photons walked.
    pub photons: u64,
}

impl Estimate {
    /// `stderr / mean` (infinite for a zero mean).
    pub fn relative_stderr(&self) -> f64 {
        if self.mean == 0.0 { f64::INFINITY } else { self.stderr / self.mean.abs() }
    }
}

/// Why the reference cannot be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RteError {
    /// The medium is not a medium.
    #[error(transparent)]
    Optics(#[from] OpticsError),
    /// The incidence cosine is not in (0, 1].
    #[error("the cosine of incidence {0} is not in (0, 1]")]
    BadIncidence(f64),
    /// Total internal reflection outside: no light enters, so reflectance per entering flux
    /// means nothing.
    #[error("no light enters: incidence cosine {cos} is beyond the critical angle of eta = {eta}")]
    NothingEnters {
        /// The cosine of incidence outside.
        cos: f64,
        /// The relative index.
        eta: f64,
    },
    /// The walk needs an inside: the mesh must be closed, manifold and consistently oriented.
    #[error("object {name:?}: the radiative-transfer walk needs a closed, consistently oriented mesh")]
    OpenMesh {
        /// The object's name.
        name: String,
    },
    /// The budget has no photons.
    #[error("the photon budget is 0")]
    NoPhotons,
    /// The object asked for is opaque: there is no transport inside it.
    #[error("object {name:?} is opaque: no light travels inside it")]
    NotTranslucent {
        /// The object's name.
        name: String,
    },
    /// A receiver names a vertex the mesh does not have.
    #[error("object {name:?}: receiver {vertex} is not one of its {vertices} vertices")]
    NoSuchVertex {
        /// The object's name.
        name: String,
        /// The vertex asked for.
        vertex: usize,
        /// How many the mesh has.
        vertices: usize,
    },
}

/// How far a reference computation is, for a progress bar.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RteProgress {
    /// Photons walked so far.
    pub photons: u64,
    /// The budget's most.
    pub max_photons: u64,
    /// Relative standard error reached so far (as the budget measures it).
    pub relative_stderr: f64,
    /// Wall time so far.
    pub seconds: f64,
}

/// Progress callback, called after every round of chunks.
pub type Progress<'a> = &'a (dyn Fn(RteProgress) + Sync);

/// Photons per chunk of the half-space walk (one random stream each).
const HALF_SPACE_CHUNK: u64 = 1024;
/// The most chunks walked in parallel between two looks at the budget (the first round has 4,
/// each next one twice as many up to this, so a cheap estimate stops early).
const MAX_CHUNKS_PER_ROUND: u64 = 256;
/// Below this albedo absorption is implicit (the weight shrinks), at or above it analog (the
/// photon is absorbed with probability `1 - albedo`): implicit capture keeps the few photons
/// that leave a dark medium, but walks a nearly white one for as long as its weight takes to
/// fall (`1 / (1 - albedo)` collisions), most of them spent on photons worth almost nothing.
const ANALOG_ALBEDO: f64 = 0.5;
/// Below this weight a photon plays Russian roulette.
const ROULETTE_WEIGHT: f64 = 0.01;
/// The chance it survives the roulette (its weight divided by it).
const ROULETTE_SURVIVAL: f64 = 0.1;

/// The random stream of chunk `chunk` of a run seeded with `seed`.
pub(crate) fn chunk_rng(seed: u64, chunk: u64) -> Pcg64 {
    // Distinct streams of one state: PCG guarantees they are distinct sequences.
    let state = Pcg64::seed_from_u64(seed).random::<u128>();
    Pcg64::new(state, u128::from(chunk))
}

/// Walks chunks of photons in rounds (4 chunks, then twice as many each round up to
/// `max_chunks_per_round`, in parallel) until the budget stops it: `walk(chunk, first photon, photons)` returns a chunk's tally, `add` takes
/// the tallies in chunk order, `relative_stderr` says where the estimate stands after a round.
/// Returns the photons walked.
pub(crate) fn run_rounds<T: Send>(
    budget: &Budget,
    chunk_photons: u64,
    max_chunks_per_round: u64,
    walk: impl Fn(u64, u64, u64) -> T + Sync,
    mut add: impl FnMut(T),
    mut relative_stderr: impl FnMut(u64) -> f64,
    progress: Progress,
) -> u64 {
    let start = Instant::now();
    let chunks = budget.max_photons.div_ceil(chunk_photons);
    let mut next = 0;
    let mut photons = 0;
    let mut round = 4;
    while next < chunks {
        let end = (next + round).min(chunks);
        round = (2 * round).min(max_chunks_per_round.max(1));
        let tallies: Vec<T> = (next..end)
            .into_par_iter()
            .map(|k| {
                let first = k * chunk_photons;
                walk(k, first, chunk_photons.min(budget.max_photons - first))
            })
            .collect();
        tallies.into_iter().for_each(&mut add);
        photons = (end * chunk_photons).min(budget.max_photons);
        next = end;
        let rel = relative_stderr(photons);
        let seconds = start.elapsed().as_secs_f64();
        progress(RteProgress { photons, max_photons: budget.max_photons, relative_stderr: rel, seconds });
        if budget.relative_stderr.is_some_and(|target| rel <= target)
            || budget.max_seconds.is_some_and(|limit| seconds >= limit)
        {
            break;
        }
    }
    photons
}

/// Cosine of the scattering angle drawn from the Henyey-Greenstein phase function with mean
/// cosine `g` by inverting its CDF (Henyey and Greenstein 1941; the inversion as in pbrt, 15.2),
/// uniform over [-1, 1] for `g` = 0.
pub fn sample_hg_cos(g: f64, u: f64) -> f64 {
    if g.abs() < 1e-3 {
        return 1.0 - 2.0 * u;
    }
    let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
    ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
}

/// The photon's weight after a collision that scatters with probability `albedo`: analog
/// absorption from [`ANALOG_ALBEDO`] up, else implicit capture, then Russian roulette below
/// [`ROULETTE_WEIGHT`] (unbiased: a survivor's weight is divided by its chance). `None`: the
/// photon is gone.
pub(crate) fn after_collision(w: f64, albedo: f64, rng: &mut Pcg64) -> Option<f64> {
    if albedo >= ANALOG_ALBEDO {
        return (rng.random::<f64>() < albedo).then_some(w);
    }
    roulette(w * albedo, rng)
}

/// The photon's weight after an internal reflection of reflectance `r` in a medium of albedo
/// `albedo`, its share `1 - r` having left (expected-value splitting, `rte_mesh`): as
/// [`after_collision`] treats the albedo, so that a walk lives as long in either regime. From
/// [`ANALOG_ALBEDO`] up it reflects with probability `r` and its weight unchanged (a walk in a
/// nearly white medium is long, and carrying every reflected share to the end of it would
/// cost more than the choice's noise); below, its weight is multiplied by `r`, then Russian
/// roulette. `None`: the photon is gone.
pub(crate) fn after_reflection(w: f64, r: f64, albedo: f64, rng: &mut Pcg64) -> Option<f64> {
    if albedo >= ANALOG_ALBEDO {
        return (rng.random::<f64>() < r).then_some(w);
    }
    roulette(w * r, rng)
}

/// Russian roulette below [`ROULETTE_WEIGHT`]: the weight `w` as it is from there up, else
/// `w / ROULETTE_SURVIVAL` with that chance (unbiased: the expected weight is `w`), else `None`.
/// Weights are relative to the photon's at its start (1). A weight of 0 is gone without a draw.
pub(crate) fn roulette(w: f64, rng: &mut Pcg64) -> Option<f64> {
    if w >= ROULETTE_WEIGHT {
        Some(w)
    } else if w > 0.0 && rng.random::<f64>() < ROULETTE_SURVIVAL {
        Some(w / ROULETTE_SURVIVAL)
    } else {
        None
    }
}

/// Total diffuse reflectance of a semi-infinite medium, by Monte Carlo: of the flux that
/// enters the medium through its plane surface, the share that leaves it again through that
/// surface after scattering, internal Fresnel reflections included.
///
/// The light arrives as a collimated beam at incidence cosine `cos_incidence` (1: normal) and
/// refracts in by Snell's law. The specular reflection at the surface is excluded and so is the
/// share it takes: the estimate is per unit flux *transmitted* into the medium, as the dipole's
/// `R_d,total` is (`Dipole::r_d_total`; the renderer multiplies it by the transmitted irradiance
/// `E_t`). At `eta = 1` and normal incidence it is the plane albedo of Chandrasekhar's
/// semi-infinite atmosphere, `1 - H(1) sqrt(1 - albedo)` for isotropic scattering
/// (Chandrasekhar 1960, Radiative Transfer, section 24).
///
/// One photon's score is its weight when it leaves (0 if it never does), so the standard error
/// is exact for the photons walked. Lengths are in mean free paths (only the albedo, `g` and
/// `eta` matter).
pub fn half_space_reflectance(
    medium: &Medium,
    cos_incidence: f64,
    budget: &Budget,
    seed: u64,
    progress: Progress,
) -> Result<Estimate, RteError> {
    half_space_by_order(medium, cos_incidence, budget, seed, progress).map(|o| o.total)
}

/// [`half_space_reflectance`] split by the number of scatterings a photon had when it left.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Orders {
    /// Every photon that left: [`half_space_reflectance`].
    pub total: Estimate,
    /// Those that left after exactly one scattering (`optics::single_scatter` is its closed
    /// form); `None` where the total was not walked (no absorption or no scattering).
    pub single: Option<Estimate>,
    /// Those that left after two or more: what the dipole's diffusion models.
    pub multiple: Option<Estimate>,
}

/// [`half_space_reflectance`] with the photons that left after one scattering tallied apart
/// from those that left after more (the same photons: `total` is the same figure). The budget's
/// precision target applies to the total.
pub fn half_space_by_order(
    medium: &Medium,
    cos_incidence: f64,
    budget: &Budget,
    seed: u64,
    progress: Progress,
) -> Result<Orders, RteError> {
    if !(cos_incidence > 0.0 && cos_incidence <= 1.0) {
        return Err(RteError::BadIncidence(cos_incidence));
    }
    if budget.max_photons == 0 {
        return Err(RteError::NoPhotons);
    }
    let eta = medium.eta;
    let sin2_t = (1.0 - cos_incidence * cos_incidence) / (eta * eta);
    if sin2_t >= 1.0 {
        return Err(RteError::NothingEnters { cos: cos_incidence, eta });
    }
    let given = |mean| Ok(Orders { total: Estimate { mean, stderr: 0.0, photons: 0 }, single: None, multiple: None });
    if medium.sigma_s == 0.0 {
        // Nothing scatters: the beam goes straight in and never turns back.
        return given(0.0);
    }
    if medium.sigma_a == 0.0 {
        // Nothing is absorbed and every walk in a half-space comes back to the surface, where
        // it has a chance to leave, so all of it leaves: exactly 1. (Walked, it would take for
        // ever: the time to return has no mean.)
        return given(1.0);
    }
    let mu0 = (1.0 - sin2_t).sqrt();
    let (albedo, g) = (medium.albedo(), medium.g);
    // Per order (total, single, multiple) the sums of the photons' scores and of their squares,
    // which adding chunks and measuring the precision both need.
    let sums = std::cell::Cell::new(([0.0; 3], [0.0; 3]));
    let photons = run_rounds(
        budget,
        HALF_SPACE_CHUNK,
        MAX_CHUNKS_PER_ROUND,
        |chunk, _, n| {
            let mut rng = chunk_rng(seed, chunk);
            let (mut s, mut s2) = ([0.0; 3], [0.0; 3]);
            for _ in 0..n {
                let (w, scatterings) = half_space_photon(&mut rng, albedo, g, eta, mu0);
                let k = if scatterings == 1 { 1 } else { 2 };
                for i in [0, k] {
                    s[i] += w;
                    s2[i] += w * w;
                }
            }
            (s, s2)
        },
        |(s, s2)| {
            let (mut sum, mut sum2) = sums.get();
            (0..3).for_each(|i| (sum[i], sum2[i]) = (sum[i] + s[i], sum2[i] + s2[i]));
            sums.set((sum, sum2));
        },
        |n| estimate(sums.get().0[0], sums.get().1[0], n).relative_stderr(),
        progress,
    );
    let (sum, sum2) = sums.get();
    let [total, single, multiple] = [0, 1, 2].map(|i| estimate(sum[i], sum2[i], photons));
    Ok(Orders { total, single: Some(single), multiple: Some(multiple) })
}

/// The mean of `n` photons' scores from their sum and sum of squares, with its standard error.
fn estimate(sum: f64, sum2: f64, photons: u64) -> Estimate {
    let n = photons as f64;
    let mean = sum / n;
    let var = ((sum2 / n - mean * mean) * n / (n - 1.0).max(1.0)).max(0.0);
    Estimate { mean, stderr: (var / n).sqrt(), photons }
}

/// One photon's walk in the half-space `z > 0` (depth in mean free paths), starting at the
/// surface with direction cosine `mu0` to the inward normal: its weight when it leaves (0 if it
/// does not) and how many times it scattered. Only the depth and the direction's cosine to the
/// normal matter, so the azimuth is drawn only to turn that cosine.
fn half_space_photon(rng: &mut Pcg64, albedo: f64, g: f64, eta: f64, mu0: f64) -> (f64, u32) {
    let (mut z, mut mu, mut w, mut scatterings) = (0.0f64, mu0, 1.0, 0u32);
    loop {
        let s = -(1.0 - rng.random::<f64>()).ln();
        z += mu * s;
        if z < 0.0 {
            // At the surface going out with cosine -mu (inside over outside: 1 / eta).
            if rng.random::<f64>() >= fresnel::fresnel_reflectance(-mu, 1.0 / eta) {
                return (w, scatterings);
            }
            // Specular reflection: the rest of the flight is the mirror image of its path.
            z = -z;
            mu = -mu;
        }
        w = match after_collision(w, albedo, rng) {
            Some(w) => w,
            None => return (0.0, scatterings),
        };
        scatterings += 1;
        let cos = sample_hg_cos(g, rng.random::<f64>());
        let phi = std::f64::consts::TAU * rng.random::<f64>();
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        mu = (mu * cos + (1.0 - mu * mu).max(0.0).sqrt() * sin * phi.cos()).clamp(-1.0, 1.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quiet(_: RteProgress) {}

    #[test]
    fn henyey_greenstein_samples_have_mean_cosine_g() {
        for g in [-0.6, 0.0, 0.3, 0.9] {
            let mut rng = chunk_rng(3, 0);
            let n = 200_000;
            let mean = (0..n).map(|_| sample_hg_cos(g, rng.random::<f64>())).sum::<f64>() / n as f64;
            // One cosine's variance is at most 1, so 5 standard errors are 5 / sqrt(n).
            assert!((mean - g).abs() < 5.0 / (n as f64).sqrt(), "g {g}: mean cosine {mean}");
        }
    }

    #[test]
    fn half_space_is_reproducible_and_independent_of_the_thread_count() {
        let medium = Medium::new(0.1, 0.9, 0.0, 1.3).unwrap();
        let budget = Budget::photons(100_000);
        let a = half_space_reflectance(&medium, 1.0, &budget, 7, &quiet).unwrap();
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let b = one.install(|| half_space_reflectance(&medium, 1.0, &budget, 7, &quiet).unwrap());
        assert_eq!(a, b);
        assert_eq!(a.photons, 100_000);
        let c = half_space_reflectance(&medium, 1.0, &budget, 8, &quiet).unwrap();
        assert_ne!(a.mean, c.mean, "another seed, other photons");
    }

    #[test]
    fn half_space_without_absorption_returns_everything_that_enters() {
        // Conservative scattering: every photon leaves eventually, so the reflectance is 1
        // whatever the boundary (given, not walked), and nearly so when almost nothing absorbs;
        // without scattering none comes back.
        for eta in [1.0, 1.4] {
            let medium = Medium::new(0.0, 1.0, 0.0, eta).unwrap();
            let e = half_space_reflectance(&medium, 0.6, &Budget::photons(500), 1, &quiet).unwrap();
            assert_eq!((e.mean, e.stderr), (1.0, 0.0), "eta {eta}");
            let medium = Medium::new(1e-7, 1.0, 0.0, eta).unwrap();
            let e = half_space_reflectance(&medium, 0.6, &Budget::photons(500), 1, &quiet).unwrap();
            assert!(e.mean > 0.99 && e.mean <= 1.0, "eta {eta}: {e:?}");
            let medium = Medium::new(1.0, 0.0, 0.0, eta).unwrap();
            let e = half_space_reflectance(&medium, 0.6, &Budget::photons(500), 1, &quiet).unwrap();
            assert_eq!((e.mean, e.stderr), (0.0, 0.0), "eta {eta}");
        }
    }

    #[test]
    fn half_space_refuses_what_it_cannot_measure() {
        let medium = Medium::new(0.1, 0.9, 0.0, 0.5).unwrap();
        let budget = Budget::photons(10);
        assert_eq!(half_space_reflectance(&medium, 0.0, &budget, 1, &quiet), Err(RteError::BadIncidence(0.0)));
        assert!(matches!(
            half_space_reflectance(&medium, 0.5, &budget, 1, &quiet),
            Err(RteError::NothingEnters { .. })
        ));
        assert_eq!(half_space_reflectance(&medium, 1.0, &Budget::photons(0), 1, &quiet), Err(RteError::NoPhotons));
        assert!(Medium::new(0.1, 1.0, 1.0, 1.3).is_err());
    }
}
