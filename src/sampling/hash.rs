//! A spatial hash over points in 3D (uniform cells hashed into a table, as in Teschner et al. 2003,
//! "Optimized Spatial Hashing for Collision Detection of Deformable Objects"), built by a counting
//! sort so that a rebuild reuses its buffers and allocates nothing once warm.
//!
//! Different cells may share a table bucket; each point remembers its own cell, and queries skip
//! bucket entries from other cells, so no point is ever visited twice by one query.

use glam::DVec3;

/// Points in uniform cubic cells, hashed into a table, for radius and nearest-neighbour queries.
/// The default is empty; [`SpatialHash::rebuild`] fills it.
#[derive(Clone, Debug, Default)]
pub struct SpatialHash {
    cell: f64,
    inv_cell: f64,
    mask: u64,
    bucket_start: Vec<u32>,
    entries: Vec<u32>,
    cells: Vec<[i32; 3]>,
    buckets: Vec<u32>,
    positions: Vec<DVec3>,
    lo: [i32; 3],
    hi: [i32; 3],
}

/// Cell coordinates are clamped so that absurd coordinate-to-cell ratios cannot overflow i32,
/// differences of two cell coordinates included.
const CELL_LIMIT: f64 = (1i64 << 29) as f64;

impl SpatialHash {
    /// A hash over `positions` with cubic cells of side `cell` (which must be positive).
    pub fn new(positions: &[DVec3], cell: f64) -> SpatialHash {
        let mut hash = SpatialHash::default();
        hash.rebuild(positions, cell);
        hash
    }

    /// Rebuild over new positions, reusing the buffers.
    pub fn rebuild(&mut self, positions: &[DVec3], cell: f64) {
        self.rebuild_in_order(positions, cell, None);
    }

    /// [`SpatialHash::rebuild`], each bucket listing its points in the order of `fill` (every
    /// index once) rather than by index: a caller that keeps its points permuted visits
    /// neighbours in the same order as without the permutation.
    pub fn rebuild_in_order(&mut self, positions: &[DVec3], cell: f64, fill: Option<&[u32]>) {
        assert!(cell > 0.0 && cell.is_finite(), "spatial hash cell size must be positive, got {cell}");
        let n = positions.len();
        self.cell = cell;
        self.inv_cell = 1.0 / cell;
        let table = (2 * n).next_power_of_two().max(16);
        self.mask = table as u64 - 1;
        self.positions.clear();
        self.positions.extend_from_slice(positions);
        self.cells.clear();
        self.buckets.clear();
        self.lo = [i32::MAX; 3];
        self.hi = [i32::MIN; 3];
        for p in positions {
            let c = self.cell_of(*p);
            for (a, &ca) in c.iter().enumerate() {
                self.lo[a] = self.lo[a].min(ca);
                self.hi[a] = self.hi[a].max(ca);
            }
            self.cells.push(c);
            self.buckets.push(self.bucket(c));
        }
        self.bucket_start.clear();
        self.bucket_start.resize(table + 1, 0);
        for &b in &self.buckets {
            self.bucket_start[b as usize + 1] += 1;
        }
        for i in 0..table {
            self.bucket_start[i + 1] += self.bucket_start[i];
        }
        self.entries.clear();
        self.entries.resize(n, 0);
        // Fill in point order (or `fill`'s) so each bucket lists its points in a fixed order
        // (determinism).
        let mut place = |i: u32| {
            let slot = &mut self.bucket_start[self.buckets[i as usize] as usize];
            self.entries[*slot as usize] = i;
            *slot += 1;
        };
        match fill {
            Some(order) => order.iter().for_each(|&i| place(i)),
            None => (0..n as u32).for_each(place),
        }
        // The fill advanced each start to the next bucket's start; shift back.
        for i in (1..=table).rev() {
            self.bucket_start[i] = self.bucket_start[i - 1];
        }
        self.bucket_start[0] = 0;
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Side of the cubic cells.
    pub fn cell_size(&self) -> f64 {
        self.cell
    }

    /// Position of point `i` (in the order given to the build).
    pub fn position(&self, i: u32) -> DVec3 {
        self.positions[i as usize]
    }

    /// Cell visits beyond which a query scans all points instead.
    #[inline]
    fn brute_force_threshold(&self) -> i64 {
        2 * self.positions.len() as i64 + 64
    }

    #[inline]
    fn cell_of(&self, p: DVec3) -> [i32; 3] {
        let c = (p * self.inv_cell).floor().clamp(DVec3::splat(-CELL_LIMIT), DVec3::splat(CELL_LIMIT));
        [c.x as i32, c.y as i32, c.z as i32]
    }

    #[inline]
    fn bucket(&self, c: [i32; 3]) -> u32 {
        // The primes of Teschner et al., followed by a xor-shift so the low bits mix well.
        let mut h = (c[0] as i64 as u64).wrapping_mul(73_856_093)
            ^ (c[1] as i64 as u64).wrapping_mul(19_349_663)
            ^ (c[2] as i64 as u64).wrapping_mul(83_492_791);
        h ^= h >> 29;
        h = h.wrapping_mul(0xbf58_476d_1ce4_e5b9);
        h ^= h >> 32;
        (h & self.mask) as u32
    }

    #[inline]
    fn visit_cell(&self, c: [i32; 3], mut f: impl FnMut(u32)) {
        let b = self.bucket(c) as usize;
        for &i in &self.entries[self.bucket_start[b] as usize..self.bucket_start[b + 1] as usize] {
            if self.cells[i as usize] == c {
                f(i);
            }
        }
    }

    /// Call `f(index, squared distance)` for every point within `radius` of `p` (inclusive).
    #[inline]
    pub fn for_each_within(&self, p: DVec3, radius: f64, mut f: impl FnMut(u32, f64)) {
        if self.positions.is_empty() {
            return;
        }
        let r2 = radius * radius;
        let a = self.cell_of(p - DVec3::splat(radius));
        let b = self.cell_of(p + DVec3::splat(radius));
        let (a, b) = (
            [a[0].max(self.lo[0]), a[1].max(self.lo[1]), a[2].max(self.lo[2])],
            [b[0].min(self.hi[0]), b[1].min(self.hi[1]), b[2].min(self.hi[2])],
        );
        // A radius much larger than the cells would visit more (mostly empty) cells than there
        // are points: then a plain scan is cheaper.
        let cells: i64 = (0..3).map(|k| (b[k] as i64 - a[k] as i64 + 1).max(0)).product();
        if cells > self.brute_force_threshold() {
            for (i, q) in self.positions.iter().enumerate() {
                let d2 = q.distance_squared(p);
                if d2 <= r2 {
                    f(i as u32, d2);
                }
            }
            return;
        }
        for z in a[2]..=b[2] {
            for y in a[1]..=b[1] {
                for x in a[0]..=b[0] {
                    self.visit_cell([x, y, z], |i| {
                        let d2 = self.positions[i as usize].distance_squared(p);
                        if d2 <= r2 {
                            f(i, d2);
                        }
                    });
                }
            }
        }
    }

    /// Visit cells in growing shells (Chebyshev rings) around the cell of `p`, calling
    /// `visit(index, squared distance)` for their points. After each ring, `done(reach)` is asked
    /// whether to stop, where `reach` is a distance that every point not yet visited exceeds.
    #[inline]
    fn ring_search<S>(
        &self,
        p: DVec3,
        state: &mut S,
        visit: impl Fn(&mut S, u32, f64),
        done: impl Fn(&S, f64) -> bool,
    ) {
        if self.positions.is_empty() {
            return;
        }
        let c = self.cell_of(p);
        let mut max_ring = 0;
        for (a, &ca) in c.iter().enumerate() {
            max_ring = max_ring.max((ca - self.lo[a]).abs()).max((self.hi[a] - ca).abs());
        }
        let mut cells_seen: i64 = 0;
        for k in 0..=max_ring {
            // An isolated query far from every point would sweep ever larger empty shells; once
            // the shells cost more than all the points, scan the points instead (visiting one
            // twice changes nothing for the searches here).
            cells_seen += if k == 0 { 1 } else { 24 * (k as i64) * (k as i64) + 2 };
            if cells_seen > self.brute_force_threshold() {
                for (i, q) in self.positions.iter().enumerate() {
                    visit(state, i as u32, q.distance_squared(p));
                }
                return;
            }
            // Rows outside the occupied box are skipped whole.
            let (z0, z1) = ((-k).max(self.lo[2] - c[2]), k.min(self.hi[2] - c[2]));
            let (y0, y1) = ((-k).max(self.lo[1] - c[1]), k.min(self.hi[1] - c[1]));
            for dz in z0..=z1 {
                for dy in y0..=y1 {
                    let inner = dz.abs() < k && dy.abs() < k;
                    // Inside the shell only the two x faces belong to ring k.
                    let step = if inner { (2 * k).max(1) } else { 1 };
                    let mut dx = -k;
                    while dx <= k {
                        let x = c[0] + dx;
                        if x >= self.lo[0] && x <= self.hi[0] {
                            let cell = [x, c[1] + dy, c[2] + dz];
                            self.visit_cell(cell, |i| visit(state, i, self.positions[i as usize].distance_squared(p)));
                        }
                        dx += step;
                    }
                }
            }
            if done(state, k as f64 * self.cell) {
                return;
            }
        }
    }

    /// The nearest point to `p` other than `exclude`, with its distance.
    pub fn nearest(&self, p: DVec3, exclude: Option<u32>) -> Option<(u32, f64)> {
        let mut best: Option<(u32, f64)> = None;
        self.ring_search(
            p,
            &mut best,
            |best, i, d2| {
                if Some(i) != exclude && better(i, d2, *best) {
                    *best = Some((i, d2));
                }
            },
            |best, reach| best.is_some_and(|(_, bd)| bd <= reach * reach),
        );
        best.map(|(i, d2)| (i, d2.sqrt()))
    }

    /// The nearest point to `p` for which `prefer` holds, unless it lies more than `slack` beyond
    /// the nearest point of all, in which case that one. Used to keep the two sides of a thin
    /// sheet apart: a point on one face prefers samples whose normals face the same way.
    pub fn nearest_preferring(&self, p: DVec3, slack: f64, prefer: impl Fn(u32) -> bool) -> Option<u32> {
        // (nearest of all, nearest preferred).
        let mut state: (Option<Hit>, Option<Hit>) = (None, None);
        self.ring_search(
            p,
            &mut state,
            |(any, good), i, d2| {
                if better(i, d2, *any) {
                    *any = Some((i, d2));
                }
                if better(i, d2, *good) && prefer(i) {
                    *good = Some((i, d2));
                }
            },
            |(any, good), reach| {
                if good.is_some_and(|(_, gd)| gd <= reach * reach) {
                    return true;
                }
                // Nothing preferred within the nearest distance plus the slack: give up on it.
                any.is_some_and(|(_, ad)| reach > ad.sqrt() + slack)
            },
        );
        match state {
            (Some((_, ad)), Some((g, gd))) if gd.sqrt() <= ad.sqrt() + slack => Some(g),
            (any, _) => any.map(|(i, _)| i),
        }
    }
}

/// A point index and its squared distance to the query.
type Hit = (u32, f64);

/// Strictly nearer, or as near with a lower index (so ties resolve the same way every run).
#[inline]
fn better(i: u32, d2: f64, current: Option<Hit>) -> bool {
    current.is_none_or(|(bi, bd)| d2 < bd || (d2 == bd && i < bi))
}
