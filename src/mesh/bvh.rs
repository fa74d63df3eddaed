//! A bounding-volume hierarchy over triangles for shadow rays (any-hit) and the radiative-transfer
//! walk's closest hits. Built by median split on the longest axis of the centroid bounds; f64
//! throughout, so the CPU reference's visibility is limited by geometry, not by rounding. The
//! splat casts its rays into the same hierarchy on the GPU, flattened to f32 (`Bvh::flat`,
//! glsl/common/rays.glsl).

use glam::DVec3;

#[derive(Clone, Copy, Debug)]
struct Aabb {
    min: DVec3,
    max: DVec3,
}

impl Aabb {
    fn empty() -> Self {
        Aabb { min: DVec3::splat(f64::INFINITY), max: DVec3::splat(f64::NEG_INFINITY) }
    }
    fn grow(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    /// The squared distance from `p` to the box (0 inside).
    fn distance2(&self, p: DVec3) -> f64 {
        let d = (self.min - p).max(p - self.max).max(DVec3::ZERO);
        d.length_squared()
    }
    /// Slab test: does the ray origin + t dir, t in (0, t_max), touch the box?
    fn hit(&self, origin: DVec3, inv_dir: DVec3, t_max: f64) -> bool {
        let t0 = (self.min - origin) * inv_dir;
        let t1 = (self.max - origin) * inv_dir;
        let near = t0.min(t1).max_element().max(0.0);
        let far = t0.max(t1).min_element().min(t_max);
        near <= far
    }
}

#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    /// Leaf: first triangle in `order`, count > 0. Inner: index of the left child (right = +1), count 0.
    first: u32,
    count: u32,
}

/// Triangles of a whole scene (world space) with a BVH for occlusion queries.
pub struct Bvh {
    triangles: Vec<[DVec3; 3]>,
    nodes: Vec<Node>,
    order: Vec<u32>,
}

const LEAF_SIZE: usize = 4;

impl Bvh {
    /// Build the hierarchy over `triangles` (world space, f64): median split on the longest
    /// axis of the centroid bounds, down to leaves of at most 4 triangles (more only where
    /// their centroids coincide).
    pub fn new(triangles: Vec<[DVec3; 3]>) -> Bvh {
        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let centroids: Vec<DVec3> = triangles.iter().map(|t| (t[0] + t[1] + t[2]) / 3.0).collect();
        let mut nodes = Vec::with_capacity(2 * triangles.len() / LEAF_SIZE + 1);
        nodes.push(Node { bounds: Aabb::empty(), first: 0, count: 0 });
        if !triangles.is_empty() {
            // Explicit stack: (node index, start, end) over `order`.
            let mut stack = vec![(0usize, 0usize, triangles.len())];
            while let Some((node, start, end)) = stack.pop() {
                let mut bounds = Aabb::empty();
                let mut cbounds = Aabb::empty();
                for &t in &order[start..end] {
                    for p in triangles[t as usize] {
                        bounds.grow(p);
                    }
                    cbounds.grow(centroids[t as usize]);
                }
                nodes[node].bounds = bounds;
                let extent = cbounds.max - cbounds.min;
                if end - start <= LEAF_SIZE || extent.max_element() <= 0.0 {
                    nodes[node].first = start as u32;
                    nodes[node].count = (end - start) as u32;
                    continue;
                }
                let axis = if extent.x >= extent.y && extent.x >= extent.z {
                    0
                } else if extent.y >= extent.z {
                    1
                } else {
                    2
                };
                let mid = (start + end) / 2;
                order[start..end].select_nth_unstable_by(mid - start, |a, b| {
                    centroids[*a as usize][axis].total_cmp(&centroids[*b as usize][axis])
                });
                let left = nodes.len();
                nodes.push(Node { bounds: Aabb::empty(), first: 0, count: 0 });
                nodes.push(Node { bounds: Aabb::empty(), first: 0, count: 0 });
                nodes[node].first = left as u32;
                nodes[node].count = 0;
                stack.push((left, start, mid));
                stack.push((left + 1, mid, end));
            }
        }
        Bvh { triangles, nodes, order }
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Is anything hit along origin + t dir for t in (t_min, t_max)? `dir` need not be unit.
    pub fn occluded(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> bool {
        let mut hit = false;
        self.walk(origin, dir, t_max, |t, _| {
            hit = intersect(&self.triangles[t], origin, dir).is_some_and(|t_hit| t_hit > t_min && t_hit < t_max);
            hit
        });
        hit
    }

    /// The first triangle hit along origin + t dir for t in (t_min, t_max), other than
    /// `skip` (the triangle a ray leaves from, which a flat triangle cannot hit again): what
    /// the radiative-transfer walk (`reference::rte_mesh`) needs to leave a closed mesh.
    pub fn closest_hit(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64, skip: Option<usize>) -> Option<Hit> {
        let mut best = None;
        self.walk(origin, dir, t_max, |t, t_far| {
            if skip != Some(t)
                && let Some((t_hit, u, v)) = intersect_uv(&self.triangles[t], origin, dir)
                && t_hit > t_min
                && t_hit < *t_far
            {
                *t_far = t_hit;
                best = Some(Hit { t: t_hit, triangle: t, u, v });
            }
            false
        });
        best
    }

    /// The distance from `p` to the nearest triangle (infinite if there is none): a
    /// branch-and-bound descent, nearer child first, pruning every box farther than the nearest
    /// triangle found so far. What `reference::clearance` builds its grid from.
    pub fn distance(&self, p: DVec3) -> f64 {
        let mut best2 = f64::INFINITY;
        if self.triangles.is_empty() {
            return best2;
        }
        // A growing stack: a subtree dropped for want of room would make the distance too large,
        // and the clearance grid's bound unsafe.
        let mut stack = vec![0u32];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            if node.bounds.distance2(p) >= best2 {
                continue;
            }
            if node.count > 0 {
                for &t in &self.order[node.first as usize..(node.first + node.count) as usize] {
                    best2 = best2.min(point_triangle_distance2(&self.triangles[t as usize], p));
                }
            } else {
                let (a, b) = (node.first, node.first + 1);
                // The nearer child is pushed last, so it is searched first.
                let near_a = self.nodes[a as usize].bounds.distance2(p) <= self.nodes[b as usize].bounds.distance2(p);
                stack.extend(if near_a { [b, a] } else { [a, b] });
            }
        }
        best2.sqrt()
    }

    /// Appends to `out` every triangle within `radius` of `p` (by its nearest point).
    pub fn within(&self, p: DVec3, radius: f64, out: &mut Vec<u32>) {
        let r2 = radius * radius;
        let mut stack = vec![0u32];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            if self.triangles.is_empty() || node.bounds.distance2(p) > r2 {
                continue;
            }
            if node.count > 0 {
                let leaf = &self.order[node.first as usize..(node.first + node.count) as usize];
                out.extend(leaf.iter().filter(|&&t| point_triangle_distance2(&self.triangles[t as usize], p) <= r2));
            } else {
                stack.extend([node.first, node.first + 1]);
            }
        }
    }

    /// The hierarchy as the GPU's ray cast walks it (`glsl/common/rays.glsl`): the nodes in
    /// order, with f32 boxes rounded outward (so a ray the f64 box admits stays admitted), and
    /// the triangles in leaf order, so that a leaf's `first` indexes them directly.
    pub fn flat(&self) -> (Vec<FlatNode>, Vec<[[f32; 3]; 3]>) {
        let down = |v: DVec3| v.to_array().map(|x| (x as f32).next_down());
        let up = |v: DVec3| v.to_array().map(|x| (x as f32).next_up());
        let nodes = self
            .nodes
            .iter()
            .map(|n| FlatNode { min: down(n.bounds.min), max: up(n.bounds.max), first: n.first, count: n.count })
            .collect();
        let triangles =
            self.order.iter().map(|&t| self.triangles[t as usize].map(|p| p.as_vec3().to_array())).collect();
        (nodes, triangles)
    }

    /// Triangle `t` as given to [`Bvh::new`].
    pub fn triangle(&self, t: usize) -> &[DVec3; 3] {
        &self.triangles[t]
    }

    /// The triangles of every leaf whose box the ray origin + t dir meets before `t_far`, each
    /// given to `leaf` with the current `t_far`, which it may shorten (a closest hit prunes the
    /// boxes behind it); `leaf` returning true ends the walk (any hit will do).
    fn walk(&self, origin: DVec3, dir: DVec3, mut t_far: f64, mut leaf: impl FnMut(usize, &mut f64) -> bool) {
        if self.triangles.is_empty() {
            return;
        }
        let inv = DVec3::ONE / dir;
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if !node.bounds.hit(origin, inv, t_far) {
                continue;
            }
            if node.count > 0 {
                for &t in &self.order[node.first as usize..(node.first + node.count) as usize] {
                    if leaf(t as usize, &mut t_far) {
                        return;
                    }
                }
            } else if top + 2 <= stack.len() {
                stack[top] = node.first;
                stack[top + 1] = node.first + 1;
                top += 2;
            }
        }
    }
}

/// One node of [`Bvh::flat`]: a leaf's triangles are `first .. first + count` of the flat
/// triangle list; an inner node (count 0) has its children at `first` and `first + 1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlatNode {
    /// The box's lower corner, rounded down to f32.
    pub min: [f32; 3],
    /// The box's upper corner, rounded up to f32.
    pub max: [f32; 3],
    /// A leaf's first triangle, or an inner node's left child.
    pub first: u32,
    /// A leaf's triangle count; 0 for an inner node.
    pub count: u32,
}

/// Where a ray first meets a triangle ([`Bvh::closest_hit`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f64,
    /// The triangle's index in the list given to [`Bvh::new`].
    pub triangle: usize,
    /// Barycentric coordinate of the triangle's corner 1 at the hit.
    pub u: f64,
    /// Barycentric coordinate of the triangle's corner 2 at the hit (corner 0's is `1 - u - v`).
    pub v: f64,
}

/// The squared distance from `p` to the triangle: its closest point by the Voronoi regions of
/// the corners, edges and face (Ericson 2005, Real-Time Collision Detection, 5.1.5).
fn point_triangle_distance2(tri: &[DVec3; 3], p: DVec3) -> f64 {
    let [a, b, c] = *tri;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.length_squared();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return bp.length_squared();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return (ap - ab * (d1 / (d1 - d3))).length_squared();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return cp.length_squared();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return (ap - ac * (d2 / (d2 - d6))).length_squared();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (bp - (c - b) * w).length_squared();
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (ap - ab * v - ac * w).length_squared()
}

/// Möller-Trumbore ray-triangle intersection (Möller and Trumbore 1997): the ray parameter t.
fn intersect(tri: &[DVec3; 3], origin: DVec3, dir: DVec3) -> Option<f64> {
    intersect_uv(tri, origin, dir).map(|(t, ..)| t)
}

/// [`intersect`] with the barycentric coordinates `(u, v)` of corners 1 and 2 at the hit.
pub(crate) fn intersect_uv(tri: &[DVec3; 3], origin: DVec3, dir: DVec3) -> Option<(f64, f64, f64)> {
    let e1 = tri[1] - tri[0];
    let e2 = tri[2] - tri[0];
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - tri[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some((e2.dot(q) * inv, u, v))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Uniform numbers in [0, 1) from a 64-bit LCG seeded with `state`.
    fn uniform(mut state: u64) -> impl FnMut() -> f64 {
        move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn occlusion_matches_brute_force() {
        // A grid of small triangles; rays from random points must agree with a linear scan.
        let mut tris = Vec::new();
        for i in 0..20 {
            for j in 0..20 {
                let o = DVec3::new(i as f64, (i * j % 7) as f64 * 0.3, j as f64);
                tris.push([o, o + DVec3::new(0.9, 0.1, 0.0), o + DVec3::new(0.0, 0.2, 0.9)]);
            }
        }
        let bvh = Bvh::new(tris.clone());
        let mut rnd = uniform(12345);
        let mut hits = 0;
        for _ in 0..2000 {
            let origin = DVec3::new(rnd() * 22.0 - 1.0, rnd() * 4.0 - 1.0, rnd() * 22.0 - 1.0);
            let dir = DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
            let brute = tris.iter().any(|t| intersect(t, origin, dir).is_some_and(|t| t > 1e-9 && t < 5.0));
            assert_eq!(bvh.occluded(origin, dir, 1e-9, 5.0), brute);
            hits += brute as u32;
        }
        assert!(hits > 50, "the test must exercise hits too ({hits})");
    }

    #[test]
    fn distance_matches_brute_force_and_bounds_the_triangles() {
        let mut tris = Vec::new();
        for i in 0..10 {
            for j in 0..10 {
                let o = DVec3::new(i as f64, (i * j % 5) as f64 * 0.4, j as f64);
                tris.push([o, o + DVec3::new(1.3, 0.2, 0.1), o + DVec3::new(0.1, 0.3, 1.4)]);
            }
        }
        let bvh = Bvh::new(tris.clone());
        let mut rnd = uniform(99);
        for _ in 0..2000 {
            let p = DVec3::new(rnd() * 14.0 - 2.0, rnd() * 6.0 - 2.0, rnd() * 14.0 - 2.0);
            let brute = tris.iter().map(|t| point_triangle_distance2(t, p)).fold(f64::INFINITY, f64::min).sqrt();
            let d = bvh.distance(p);
            assert!((d - brute).abs() <= 1e-12 * (1.0 + brute), "{d} vs {brute}");
            // No point of any triangle is nearer: sample the triangles' points.
            for t in &tris {
                let (u, v) = (rnd(), rnd());
                let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
                let q = t[0] * (1.0 - u - v) + t[1] * u + t[2] * v;
                assert!(q.distance(p) >= d - 1e-12, "a point at {} is nearer than {d}", q.distance(p));
            }
        }
    }

    #[test]
    fn closest_hit_matches_brute_force() {
        let mut tris = Vec::new();
        for i in 0..12 {
            for j in 0..12 {
                let o = DVec3::new(i as f64, (i * j % 5) as f64 * 0.4, j as f64);
                tris.push([o, o + DVec3::new(1.3, 0.2, 0.1), o + DVec3::new(0.1, 0.3, 1.4)]);
            }
        }
        let bvh = Bvh::new(tris.clone());
        let mut rnd = uniform(777);
        let mut hits = 0;
        for _ in 0..2000 {
            let origin = DVec3::new(rnd() * 14.0 - 1.0, rnd() * 4.0 - 1.0, rnd() * 14.0 - 1.0);
            let dir = DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
            let brute = (0..tris.len())
                .filter(|&k| k != 3)
                .filter_map(|k| intersect(&tris[k], origin, dir).filter(|t| *t > 1e-9 && *t < 5.0).map(|t| (t, k)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let hit = bvh.closest_hit(origin, dir, 1e-9, 5.0, Some(3));
            assert_eq!(hit.map(|h| (h.t, h.triangle)), brute);
            if let Some(h) = hit {
                let [a, b, c] = tris[h.triangle];
                let p = a * (1.0 - h.u - h.v) + b * h.u + c * h.v;
                assert!(p.distance(origin + dir * h.t) < 1e-9);
                hits += 1;
            }
        }
        assert!(hits > 50, "the test must exercise hits too ({hits})");
    }
}
