//! One mesh triangle as a source of the truth's kernel integral: its transmitted irradiance
//! `E_t` on a grid, linear in each cell, and the exact moments of every coarser piece (a
//! pyramid), with the triangle quadrature they are integrated by.

use glam::DVec3;

/// One mesh triangle as a source: its transmitted irradiance on a grid of `4^depth` cells.
pub(super) struct Source {
    corners: [DVec3; 3],
    pub(super) depth: u32,
    /// `E_t` at grid point `(i, j)` (`u = i/n`, `v = j/n`, `n = 2^depth`), at [`grid_index`].
    pub(super) grid: Vec<DVec3>,
    pub(super) area: f64,
    /// Exact moments of every piece coarser than a grid cell by more than [`PYRAMID_SKIP`]
    /// splits, in the order `quadrature::Quadrature::piece` splits (node `k`'s children are
    /// `4k + 1 ..= 4k + 4`, the root is the whole triangle), so a piece spanning many cells can
    /// stand as one monopole once the kernel is smooth over it. The finer pieces' moments are
    /// summed from their cells when asked ([`Source::moments`]).
    pyramid: Vec<Moments>,
}

/// What the cluster tree and a receiver's first look need of a triangle at one level: its
/// moments as a whole and its bounding sphere (a few hundred bytes, where its grid and pyramid
/// may take megabytes).
#[derive(Clone, Copy, Debug)]
pub(super) struct Summary {
    /// The mesh triangle.
    pub(super) triangle: usize,
    /// Its grid's depth and point count.
    pub(super) depth: u32,
    pub(super) points: usize,
    /// Flux `integral E_t dA` per channel and its `E_t`-weighted centroid.
    pub(super) flux: [f64; 3],
    pub(super) centroid: [DVec3; 3],
    /// Second moment `integral (y - c)(y - c)^T E_t dA` about each channel's centroid `c`:
    /// xx, yy, zz, xy, xz, yz.
    pub(super) quadrupole: [[f64; 6]; 3],
    /// Bounding sphere of the triangle (centre of its corners).
    pub(super) centre: DVec3,
    pub(super) radius: f64,
}

/// The pyramid leaves out the pieces this many splits above a grid cell (4 cells each): its
/// last level held 3/4 of it, twice the grid's own memory, and a receiver asks for those
/// pieces only where the kernel is not smooth over them. (Leaving out two levels saved a third
/// more memory but made each level about 1.5 times slower.)
const PYRAMID_SKIP: u32 = 1;

/// Points of a triangle's grid at `depth`.
pub(super) fn grid_points(depth: u32) -> usize {
    let n = 1usize << depth;
    (n + 1) * (n + 2) / 2
}

/// Nodes of a triangle's moment pyramid whose grid is at `depth`.
fn pyramid_nodes(depth: u32) -> usize {
    ((1usize << (2 * depth.saturating_sub(PYRAMID_SKIP))) - 1) / 3
}

/// Flux `integral E_t dA` and first moment `integral y E_t dA` of a piece of surface, per channel.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Moments {
    pub(super) flux: [f64; 3],
    pub(super) moment: [DVec3; 3],
}

impl Moments {
    pub(super) fn add(&mut self, o: &Moments) {
        for c in 0..3 {
            self.flux[c] += o.flux[c];
            self.moment[c] += o.moment[c];
        }
    }

    /// Each channel's `E_t`-weighted centroid (`fallback` where the piece is dark).
    pub(super) fn centroid(&self, fallback: DVec3) -> [DVec3; 3] {
        [0, 1, 2].map(|c| if self.flux[c] > 0.0 { self.moment[c] / self.flux[c] } else { fallback })
    }
}

/// The four children of the piece with corners `uv`, in the order of [`Source::pyramid`].
pub(super) fn split(uv: [[f64; 2]; 3]) -> [[[f64; 2]; 3]; 4] {
    let mid = |a: [f64; 2], b: [f64; 2]| [(a[0] + b[0]) * 0.5, (a[1] + b[1]) * 0.5];
    let (ab, bc, ca) = (mid(uv[0], uv[1]), mid(uv[1], uv[2]), mid(uv[2], uv[0]));
    [[uv[0], ab, ca], [ab, uv[1], bc], [ca, bc, uv[2]], [ab, bc, ca]]
}

/// The whole triangle in `(u, v)`.
pub(super) const WHOLE: [[f64; 2]; 3] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];

/// Index of grid point `(i, j)`, `i + j <= n`, in a triangle's grid (rows of `i`).
pub(super) fn grid_index(i: usize, j: usize, n: usize) -> usize {
    i * (n + 1) - i * i.saturating_sub(1) / 2 + j
}

/// The point at `(u, v)` of the triangle with `corners`.
pub(super) fn triangle_point(corners: &[DVec3; 3], u: f64, v: f64) -> DVec3 {
    corners[0] + (corners[1] - corners[0]) * u + (corners[2] - corners[0]) * v
}

impl Source {
    pub(super) fn point(&self, u: f64, v: f64) -> DVec3 {
        triangle_point(&self.corners, u, v)
    }

    /// Exact moments of the piece `uv` at split depth `depth <= self.depth`: a grid cell's from
    /// its linear `E_t`, a coarser piece's as the sum of its children's (stored in `pyramid`
    /// at `node` where the pyramid keeps it). Returns the piece's moments.
    fn build_pyramid(&mut self, uv: [[f64; 2]; 3], depth: u32, node: usize) -> Moments {
        if node >= self.pyramid.len() {
            return self.summed_moments(uv, depth);
        }
        let mut sum = Moments::default();
        for (k, child) in split(uv).into_iter().enumerate() {
            sum.add(&self.build_pyramid(child, depth + 1, 4 * node + 1 + k));
        }
        self.pyramid[node] = sum;
        sum
    }

    /// The moments of the piece `uv` at split depth `depth`, pyramid node `node`: stored, or
    /// summed from its cells in the order `build_pyramid` sums them (so the same bits).
    pub(super) fn moments(&self, uv: [[f64; 2]; 3], depth: u32, node: usize) -> Moments {
        self.pyramid.get(node).copied().unwrap_or_else(|| self.summed_moments(uv, depth))
    }

    /// The moments of the piece `uv` at split depth `depth <= self.depth`, summed from its cells.
    fn summed_moments(&self, uv: [[f64; 2]; 3], depth: u32) -> Moments {
        if depth == self.depth {
            let y = uv.map(|[u, v]| self.point(u, v));
            let e = uv.map(|[u, v]| self.irradiance(u, v));
            let (flux, moment) = linear_moments(&y, &e, self.area * 0.25f64.powi(depth as i32));
            return Moments { flux, moment };
        }
        let mut sum = Moments::default();
        for child in split(uv) {
            sum.add(&self.summed_moments(child, depth + 1));
        }
        sum
    }

    /// This source as a whole, for triangle `triangle`: its flux and centroid from the
    /// pyramid's root, its second moments from the grid, its bounding sphere from its corners.
    pub(super) fn summary(&self, triangle: usize) -> Summary {
        let centre = (self.corners[0] + self.corners[1] + self.corners[2]) / 3.0;
        let radius = self.corners.iter().map(|p| p.distance(centre)).fold(0.0, f64::max);
        let whole = self.moments(WHOLE, 0, 0);
        let centroid = whole.centroid(centre);
        Summary {
            triangle,
            depth: self.depth,
            points: self.grid.len(),
            flux: whole.flux,
            centroid,
            quadrupole: self.second_moments(&centroid),
            centre,
            radius,
        }
    }

    /// Heap and inline bytes of a source whose grid is at `depth`.
    pub(super) fn bytes(depth: u32) -> u64 {
        (grid_points(depth) * std::mem::size_of::<DVec3>()
            + pyramid_nodes(depth) * std::mem::size_of::<Moments>()
            + std::mem::size_of::<Source>()) as u64
    }

    /// `E_t` at `(u, v)`, linear in each grid cell.
    pub(super) fn irradiance(&self, u: f64, v: f64) -> DVec3 {
        let n = 1usize << self.depth;
        let (s, t) = (u * n as f64, v * n as f64);
        let i = (s.floor().max(0.0) as usize).min(n - 1);
        let j = (t.floor().max(0.0) as usize).min(n - 1 - i);
        let (a, b) = (s - i as f64, t - j as f64);
        let e = |i, j| self.grid[grid_index(i, j, n)];
        if a + b <= 1.0 || i + j + 2 > n {
            e(i, j) * (1.0 - a - b) + e(i + 1, j) * a + e(i, j + 1) * b
        } else {
            e(i + 1, j + 1) * (a + b - 1.0) + e(i + 1, j) * (1.0 - b) + e(i, j + 1) * (1.0 - a)
        }
    }
}

/// Call `f` with the grid points of every cell of a triangle's grid of side `n`: the `n^2`
/// triangles of its uniform subdivision, pointing up and down.
fn for_each_cell(n: usize, mut f: impl FnMut([(usize, usize); 3])) {
    for i in 0..n {
        for j in 0..n - i {
            f([(i, j), (i + 1, j), (i, j + 1)]);
            if i + j + 2 <= n {
                f([(i + 1, j), (i + 1, j + 1), (i, j + 1)]);
            }
        }
    }
}

/// Flux and first moment of a linear `E` over a triangle of `area` with corners `y` and
/// values `e`: `integral E dA = A mean(E)`, `integral y E dA = (A/12)(sum y_i E_i + sum y_i sum E_i)`.
pub(super) fn linear_moments(y: &[DVec3; 3], e: &[DVec3; 3], area: f64) -> ([f64; 3], [DVec3; 3]) {
    let ys = y[0] + y[1] + y[2];
    let mut flux = [0.0; 3];
    let mut moment = [DVec3::ZERO; 3];
    for c in 0..3 {
        let es = e[0][c] + e[1][c] + e[2][c];
        flux[c] = area * es / 3.0;
        moment[c] = (y[0] * e[0][c] + y[1] * e[1][c] + y[2] * e[2][c] + ys * es) * (area / 12.0);
    }
    (flux, moment)
}

impl Source {
    /// A triangle's source from its `E_t` grid at `depth`, with its moment pyramid (what
    /// [`Source::moments`] and [`Source::irradiance`] need; [`Source::summary`] the rest).
    pub(super) fn new(corners: [DVec3; 3], depth: u32, grid: Vec<DVec3>, area: f64) -> Source {
        let mut s = Source { corners, depth, grid, area, pyramid: vec![Moments::default(); pyramid_nodes(depth)] };
        s.build_pyramid(WHOLE, 0, 0);
        s
    }

    /// `integral (y - c)(y - c)^T E_t dA` about each channel's centroid, cell by cell: Radon's
    /// rule is exact for the cubic `(y - c)^2 E_t`.
    fn second_moments(&self, centroid: &[DVec3; 3]) -> [[f64; 6]; 3] {
        let n = 1usize << self.depth;
        let cell_area = self.area / (n * n) as f64;
        let mut q = [[0.0; 6]; 3];
        for_each_cell(n, |cell| {
            let y = cell.map(|(i, j)| self.point(i as f64 / n as f64, j as f64 / n as f64));
            let e = cell.map(|(i, j)| self.grid[grid_index(i, j, n)]);
            for (b, w) in RADON {
                let p = y[0] * b[0] + y[1] * b[1] + y[2] * b[2];
                let ep = e[0] * b[0] + e[1] * b[1] + e[2] * b[2];
                for ch in 0..3 {
                    let r = p - centroid[ch];
                    let we = w * cell_area * ep[ch];
                    let terms = [r.x * r.x, r.y * r.y, r.z * r.z, r.x * r.y, r.x * r.z, r.y * r.z];
                    for (qk, t) in q[ch].iter_mut().zip(terms) {
                        *qk += we * t;
                    }
                }
            }
        });
        q
    }
}

/// Radon's 7-point degree-5 rule on a triangle: barycentric coordinates and weights (summing
/// to one). Published constants: `a = (6 -+ sqrt 15)/21`, `w = (155 -+ sqrt 15)/1200`.
pub(super) const RADON: [([f64; 3], f64); 7] = {
    const A1: f64 = 0.101_286_507_323_456_3;
    const B1: f64 = 0.797_426_985_353_087_4;
    const W1: f64 = 0.125_939_180_544_827_1;
    const A2: f64 = 0.470_142_064_105_115_1;
    const B2: f64 = 0.059_715_871_789_769_8;
    const W2: f64 = 0.132_394_152_788_506_2;
    [
        ([1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0], 0.225),
        ([A1, A1, B1], W1),
        ([A1, B1, A1], W1),
        ([B1, A1, A1], W1),
        ([A2, A2, B2], W2),
        ([A2, B2, A2], W2),
        ([B2, A2, A2], W2),
    ]
};
