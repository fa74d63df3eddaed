//! Sample points on a mesh surface, each with an area weight (seed paper section 3).
//!
//! Four placements, all giving exactly N points for a budget N and the same points for the same
//! seed:
//! - [`Method::Random`]: uniform by area.
//! - [`Method::Turk`]: Turk's point repulsion (1992) from a random start ([`turk`]).
//! - [`Method::Feature`]: the seed paper's Algorithm 1 and Eq. 12, then repulsion with a density
//!   that follows curvature ([`feature`], whose documentation states how the paper is read).
//! - [`Method::Poisson`]: blue noise by weighted sample elimination (Yuksel 2015, [`poisson`]).
//!
//! Every point then gets the area of the surface nearer to it than to any other sample
//! ([`weights`]), so the weights sum to the mesh area and follow the local density.

pub mod density;
pub mod feature;
pub mod hash;
pub mod poisson;
pub mod random;
pub mod stats;
pub mod tree;
pub mod turk;
pub mod walk;
pub mod weights;

use glam::Vec3;
use rand::SeedableRng;
use rand_pcg::Pcg64;

pub use feature::FeatureParams;
pub use hash::SpatialHash;
pub use poisson::PoissonParams;
pub use stats::{SampleStats, nearest_neighbour_distances};
pub use tree::{Cuts, NODE_ITEM, RECEIVER_GROUP_SIZE, ReceiverGroups, SampleTree, TreeNode};
pub use turk::TurkParams;
pub use walk::SurfacePoint;
pub use weights::WeightParams;

use crate::mesh::Mesh;

/// Largest sample count accepted; far above what a dipole gather can use, low enough that a
/// typo cannot exhaust memory.
pub const MAX_COUNT: usize = 1 << 24;

/// How sample points are placed: `sampling.method` in a scene, `--sampler` and `--method` on
/// the command line (lowercase names in both).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Uniform by area
    Random,
    /// Turk's point repulsion (1992)
    Turk,
    /// The seed paper's geometric feature sampling (Algorithm 1, Eq. 12), then curvature-adaptive repulsion
    Feature,
    /// Poisson-disk blue noise by sample elimination (Yuksel 2015)
    Poisson,
}

named_choices!(Method, "sampling method", {
    Random => "random",
    Turk => "turk",
    Feature => "feature",
    Poisson => "poisson",
});

/// Errors of the samplers.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SamplingError {
    /// A sample count of 0.
    #[error("the sample count must be at least 1, got 0")]
    ZeroCount,
    /// A sample count above [`MAX_COUNT`].
    #[error("the sample count {count} is above the limit of {max}")]
    TooMany {
        /// The count asked for.
        count: usize,
        /// The limit, [`MAX_COUNT`].
        max: usize,
    },
    /// The mesh's total area is zero, NaN or infinite.
    #[error("the mesh has no surface area to sample (total area {area})")]
    NoArea {
        /// The mesh's total area.
        area: f64,
    },
    /// [`sample_in_frame`] given a frame whose triangles are not the mesh's.
    #[error("the frame to place samples in has other triangles than the mesh")]
    FrameTopology,
}

/// Everything a sampler needs; [`SampleOptions::new`] fills in the defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct SampleOptions {
    /// How points are placed.
    pub method: Method,
    /// How many points (exactly; 1 to [`MAX_COUNT`]).
    pub count: usize,
    /// Seed of the random generator (PCG64); the same seed gives the same points.
    pub seed: u64,
    /// Repulsion settings of [`Method::Turk`].
    pub turk: TurkParams,
    /// Settings of [`Method::Feature`], its repulsion included.
    pub feature: FeatureParams,
    /// Settings of [`Method::Poisson`].
    pub poisson: PoissonParams,
    /// Settings of the area weights, for every method.
    pub weights: WeightParams,
}

impl SampleOptions {
    /// `count` points by `method`, seed 0, every other setting at its default.
    pub fn new(method: Method, count: usize) -> SampleOptions {
        SampleOptions {
            method,
            count,
            seed: 0,
            turk: TurkParams::default(),
            feature: FeatureParams::default(),
            poisson: PoissonParams::default(),
            weights: WeightParams::default(),
        }
    }

    /// The same options with another seed.
    pub fn with_seed(mut self, seed: u64) -> SampleOptions {
        self.seed = seed;
        self
    }
}

/// One sample point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamplePoint {
    /// Position on the surface (the mesh's space).
    pub position: Vec3,
    /// Unit shading normal (interpolated vertex normals).
    pub normal: Vec3,
    /// Index of the mesh triangle it lies on.
    pub triangle: u32,
    /// Weights of the triangle's three corners, non-negative, summing to one.
    pub barycentric: [f32; 3],
    /// The surface area this sample stands for.
    pub area: f64,
}

/// The result of a sampler.
#[derive(Clone, Debug, PartialEq)]
pub struct SampleSet {
    /// How the points were placed.
    pub method: Method,
    /// The seed they were placed with.
    pub seed: u64,
    /// The points with their area weights.
    pub points: Vec<SamplePoint>,
}

impl SampleSet {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Sum of the area weights (the mesh area, up to rounding).
    pub fn total_area(&self) -> f64 {
        self.points.iter().map(|p| p.area).sum()
    }

    /// The points' positions, in order.
    pub fn positions(&self) -> Vec<Vec3> {
        self.points.iter().map(|p| p.position).collect()
    }
}

fn check(mesh: &Mesh, count: usize) -> Result<(), SamplingError> {
    if count == 0 {
        return Err(SamplingError::ZeroCount);
    }
    if count > MAX_COUNT {
        return Err(SamplingError::TooMany { count, max: MAX_COUNT });
    }
    let area = mesh.total_area();
    if area.is_nan() || area <= 0.0 || !area.is_finite() {
        return Err(SamplingError::NoArea { area });
    }
    Ok(())
}

/// Place `options.count` points by `options.method`, without weights.
pub fn place(mesh: &Mesh, options: &SampleOptions) -> Result<Vec<SurfacePoint>, SamplingError> {
    let n = options.count;
    check(mesh, n)?;
    let mut rng = Pcg64::seed_from_u64(options.seed);
    let points = match options.method {
        Method::Random => random::random_points(mesh, n, &mut rng),
        Method::Turk => {
            let mut pts = random::random_points(mesh, n, &mut rng);
            turk::relax(mesh, &mut pts, turk::Radius::Uniform(turk::turk_radius(mesh.total_area(), n)), &options.turk);
            pts
        }
        Method::Feature => {
            let two_n = feature::feature_point_count(mesh, n, options.feature.feature_fraction);
            let mut pts = feature::feature_points(mesh, two_n);
            pts.extend(random::random_points(mesh, n - two_n, &mut rng));
            feature::relax_by_curvature(mesh, &mut pts, &options.feature);
            pts
        }
        Method::Poisson => {
            let m = n.saturating_mul(options.poisson.candidate_factor.max(1));
            let candidates = random::random_points(mesh, m, &mut rng);
            poisson::eliminate(mesh, &candidates, n)
        }
    };
    debug_assert_eq!(points.len(), n);
    let mut points = points;
    spatial_order(mesh, &mut points);
    Ok(points)
}

/// Sort `points` along a Morton (Z-order) curve through the mesh's bounding box, so that
/// neighbours on the surface are mostly neighbours in the list: the GPU's lanes then take
/// similar paths (the splat's shadow rays walk the same boxes) and read nearby memory.
fn spatial_order(mesh: &Mesh, points: &mut [SurfacePoint]) {
    let key = morton_key(mesh);
    points.sort_by_cached_key(|p| key(p));
}

/// A point's position along a Morton (Z-order) curve through `mesh`'s bounding box.
fn morton_key(mesh: &Mesh) -> impl Fn(&SurfacePoint) -> u64 + '_ {
    let (lo, hi) = mesh.bounds();
    let (lo, extent) = (lo.as_dvec3(), (hi - lo).as_dvec3().max(glam::DVec3::splat(1e-30)));
    // 21 bits per axis: a 63-bit key.
    let spread = |x: f64| -> u64 {
        let mut v = (x.clamp(0.0, 1.0) * ((1u64 << 21) - 1) as f64) as u64;
        v = (v | v << 32) & 0x1f00000000ffff;
        v = (v | v << 16) & 0x1f0000ff0000ff;
        v = (v | v << 8) & 0x100f00f00f00f00f;
        v = (v | v << 4) & 0x10c30c30c30c30c3;
        (v | v << 2) & 0x1249249249249249
    };
    move |p| {
        let u = (p.position(mesh) - lo) / extent;
        spread(u.x) | spread(u.y) << 1 | spread(u.z) << 2
    }
}

/// Turn placed points into samples with positions, normals and the given area weights.
pub fn finish(mesh: &Mesh, points: &[SurfacePoint], areas: &[f64]) -> Vec<SamplePoint> {
    points
        .iter()
        .zip(areas)
        .map(|(p, &area)| SamplePoint {
            position: p.position(mesh).as_vec3(),
            normal: mesh.normal_at(p.triangle as usize, p.bary),
            triangle: p.triangle,
            barycentric: p.bary.map(|b| b as f32),
            area,
        })
        .collect()
}

/// Place points and weigh them: the whole pipeline behind `translucent sample`.
pub fn sample(mesh: &Mesh, options: &SampleOptions) -> Result<SampleSet, SamplingError> {
    sample_in_frame(mesh, mesh, options)
}

/// Place and weigh points on `frame`, and put them on `mesh`, the same triangles after a
/// similarity transform (uniform scale, rotation, translation): each point keeps its triangle
/// and barycentric weights, and its area is scaled by `mesh`'s total area over `frame`'s.
///
/// Why: the relaxing samplers (Turk's repulsion, the feature sampler) are chaotic in the last
/// bits of the positions, since a point that crosses an edge or not goes on differently. The
/// same object at another scale or place differs in those bits after its transform, so it
/// would get other samples. Placed in the object's own frame (the mesh as loaded), it gets the
/// same ones in any units and at any position.
pub fn sample_in_frame(frame: &Mesh, mesh: &Mesh, options: &SampleOptions) -> Result<SampleSet, SamplingError> {
    if frame.triangles() != mesh.triangles() {
        return Err(SamplingError::FrameTopology);
    }
    let points = place(frame, options)?;
    // Exactly 1 where the two are one mesh.
    let scale = mesh.total_area() / frame.total_area();
    let mut areas = weights::area_weights(frame, &points, &options.weights);
    areas.iter_mut().for_each(|a| *a *= scale);
    Ok(SampleSet { method: options.method, seed: options.seed, points: finish(mesh, &points, &areas) })
}
