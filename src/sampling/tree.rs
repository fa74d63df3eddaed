//! A bounding-sphere hierarchy over one object's sample points, for the hierarchical gather
//! (after Jensen and Buhler 2002, "A Rapid Hierarchical Rendering Technique for Translucent
//! Materials", who cluster the irradiance samples in an octree and let a far cluster stand in
//! for its members).
//!
//! Built once on the CPU when the samples are placed (they move only with the geometry): a binary
//! tree split at the median of the longest axis of each node's bounding box, down to leaves of at
//! most [`LEAF_SIZE`] samples. Nodes are stored depth first, so a node's first child is the next
//! node and `skip` is where the walk continues once the node's subtree is done (used whole,
//! pruned or fully visited): a stackless traversal.
//!
//! Which nodes a receiver uses whole depends only on geometry (and the accuracy knob), and both
//! samples and receivers move only with the geometry, so the walk is done here, once, per group
//! of nearby receivers ([`ReceiverGroups`], [`SampleTree::cut`]): the GPU then sums each group's
//! list of items with the flat gather's tiled loop, which lavapipe runs at the flat gather's
//! throughput, rather than walking per receiver in divergent SIMD lanes (measured 1.8x slower
//! per pair there: loads inside divergent control flow become per-lane gathers). The irradiance
//! each node carries changes every splat and is aggregated on the GPU (`glsl/gather_tree.comp`,
//! stage 0) and in the f64 twin (`reference::tree`); this module knows only geometry.

use glam::DVec3;

/// Most samples in a leaf: a leaf's samples are summed exactly, pair by pair.
pub const LEAF_SIZE: usize = 4;

/// Receivers per group in [`ReceiverGroups`]: the hierarchical and sparse gathers' workgroup
/// size. A group's sphere bounds which samples its receivers must sum one by one, so smaller
/// groups sum fewer; 8 is llvmpipe's SIMD width (AVX2, 8 f32 lanes). Against 32, it made the
/// built-in scene's light-moving gather 1.8 to 2.5 times faster on lavapipe (README,
/// "Accurate by default"); on a GPU with 32-wide warps it leaves lanes idle (not measured).
pub const RECEIVER_GROUP_SIZE: usize = 8;

/// One node of a [`SampleTree`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TreeNode {
    /// Centre of a sphere holding every sample position of the subtree.
    pub center: [f32; 3],
    /// Its radius, rounded up so that the f32 sphere still holds every sample.
    pub radius: f32,
    /// Sum of the samples' areas.
    pub area: f32,
    /// Largest near-field blend radius of its samples (`blend_radius sqrt(dA)`, see
    /// [`SampleTree::new`]): a receiver nearer than `radius + reach` to the centre may get a
    /// Shepard weight from one of them.
    pub reach: f32,
    /// First entry of the subtree's samples in [`SampleTree::order`].
    pub first: u32,
    /// How many samples the subtree holds.
    pub count: u32,
    /// Index of the node after this subtree (depth-first order; the node count for the last).
    pub skip: u32,
    /// Whether it is a leaf (its samples are summed one by one).
    pub leaf: bool,
}

/// The hierarchy over one object's samples: nodes in depth-first order (root first) and the
/// sample indices in leaf order, each node's samples contiguous.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SampleTree {
    /// Nodes, depth first; node 0 is the root (none without samples).
    pub nodes: Vec<TreeNode>,
    /// Sample indices (into the object's samples), grouped so that node `n` holds
    /// `order[n.first .. n.first + n.count]`.
    pub order: Vec<u32>,
    /// A sample's near-field blend radius per square root of its area (the gathers pass
    /// `optics::kernel::NEAR_BLEND_RADIUS`; geometry knows no optics).
    pub blend_radius: f64,
}

impl SampleTree {
    /// The hierarchy over samples at `positions` with areas `areas` (same length), each sample
    /// blending its near field out to `blend_radius sqrt(area)`.
    pub fn new(positions: &[DVec3], areas: &[f64], blend_radius: f64) -> SampleTree {
        assert_eq!(positions.len(), areas.len(), "one area per sample");
        let mut tree = SampleTree { nodes: Vec::new(), order: (0..positions.len() as u32).collect(), blend_radius };
        if !positions.is_empty() {
            let mut order = std::mem::take(&mut tree.order);
            tree.build(positions, areas, &mut order, 0);
            tree.order = order;
        }
        tree
    }

    fn build(&mut self, positions: &[DVec3], areas: &[f64], order: &mut [u32], first: usize) {
        let (lo, hi) =
            order.iter().fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), &i| {
                (lo.min(positions[i as usize]), hi.max(positions[i as usize]))
            });
        let points: Vec<DVec3> = order.iter().map(|&i| positions[i as usize]).collect();
        let (center, radius) = sphere(&points);
        let area: f64 = order.iter().map(|&i| areas[i as usize]).sum();
        let largest = order.iter().map(|&i| areas[i as usize]).fold(0.0, f64::max);
        let index = self.nodes.len();
        let leaf = order.len() <= LEAF_SIZE;
        self.nodes.push(TreeNode {
            center,
            radius,
            area: area as f32,
            reach: ((self.blend_radius * largest.sqrt()) as f32).next_up(),
            first: first as u32,
            count: order.len() as u32,
            skip: 0,
            leaf,
        });
        if !leaf {
            let extent = hi - lo;
            let axis = if extent.x >= extent.y && extent.x >= extent.z {
                0
            } else if extent.y >= extent.z {
                1
            } else {
                2
            };
            let mid = order.len() / 2;
            order.select_nth_unstable_by(mid, |&a, &b| {
                positions[a as usize][axis].total_cmp(&positions[b as usize][axis]).then(a.cmp(&b))
            });
            let (left, right) = order.split_at_mut(mid);
            self.build(positions, areas, left, first);
            self.build(positions, areas, right, first + mid);
        }
        self.nodes[index].skip = self.nodes.len() as u32;
    }
}

/// Marks an item of a [`SampleTree::cut`] as a node (its index in the low bits) rather than a
/// sample.
pub const NODE_ITEM: u32 = 1 << 31;

impl SampleTree {
    /// The cut of the hierarchy for receivers inside the sphere `group` (centre, radius): the
    /// items whose sum stands for the whole object there, in walk order. Walking depth first with
    /// `dist` the nearest any sample of a node can be to any receiver of the group:
    /// - a node whose samples are all beyond their near-blend reach (`dist > reach`) and whose
    ///   area is below the solid-angle bound, `A < epsilon dist^2`, is one item, `NODE_ITEM | n`;
    /// - a leaf otherwise gives its samples, one item each (sample indices);
    /// - an inner node beyond reach that `negligible(node, dist)` says cannot matter is dropped
    ///   with its subtree; otherwise the walk descends.
    ///
    /// `epsilon = 0` takes every sample: the flat sum.
    pub fn cut(&self, group: ([f32; 3], f32), epsilon: f64, negligible: impl Fn(&TreeNode, f64) -> bool) -> Vec<u32> {
        let mut items = Vec::new();
        self.cut_into(group, epsilon, negligible, &mut items);
        items
    }

    /// [`Self::cut`], appended to `items`: many cuts share one buffer instead of an allocation
    /// each, which the allocator's locks made costly on every thread at once.
    pub fn cut_into(
        &self,
        group: ([f32; 3], f32),
        epsilon: f64,
        negligible: impl Fn(&TreeNode, f64) -> bool,
        items: &mut Vec<u32>,
    ) {
        let (center, radius) = (glam::Vec3::from(group.0).as_dvec3(), group.1 as f64);
        let mut i = 0;
        while i < self.nodes.len() {
            let n = &self.nodes[i];
            let dist = center.distance(glam::Vec3::from(n.center).as_dvec3()) - n.radius as f64 - radius;
            let beyond_reach = dist > n.reach as f64;
            if beyond_reach && (n.area as f64) < epsilon * dist * dist {
                items.push(NODE_ITEM | i as u32);
                i = n.skip as usize;
            } else if n.leaf {
                items.extend_from_slice(&self.order[n.first as usize..(n.first + n.count) as usize]);
                i = n.skip as usize;
            } else if beyond_reach && epsilon > 0.0 && negligible(n, dist) {
                i = n.skip as usize;
            } else {
                i += 1;
            }
        }
    }
}

/// Many receivers' cuts ([`SampleTree::cut`]) in one buffer, in receiver order.
#[derive(Clone, Debug, Default)]
pub struct Cuts {
    items: Vec<u32>,
    /// Where each receiver's items end in `items`.
    ends: Vec<usize>,
}

impl Cuts {
    /// Cuts for receivers `0..count`, made by `cut(k, buffer)` appending receiver k's items,
    /// chunks of receivers in parallel and joined in order (the same on any thread count).
    pub fn build(count: usize, cut: impl Fn(usize, &mut Vec<u32>) + Sync) -> Cuts {
        use rayon::prelude::*;
        const CHUNK: usize = 256;
        let chunks: Vec<Cuts> = (0..count.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut part = Cuts::default();
                for k in c * CHUNK..((c + 1) * CHUNK).min(count) {
                    cut(k, &mut part.items);
                    part.ends.push(part.items.len());
                }
                part
            })
            .collect();
        let mut all = Cuts {
            items: Vec::with_capacity(chunks.iter().map(|c| c.items.len()).sum()),
            ends: Vec::with_capacity(count),
        };
        for part in chunks {
            let base = all.items.len();
            all.items.extend_from_slice(&part.items);
            all.ends.extend(part.ends.iter().map(|e| base + e));
        }
        all
    }

    /// Receiver `k`'s items.
    pub fn of(&self, k: usize) -> &[u32] {
        let start = if k == 0 { 0 } else { self.ends[k - 1] };
        &self.items[start..self.ends[k]]
    }

    /// The number of receivers.
    pub fn len(&self) -> usize {
        self.ends.len()
    }

    /// Whether there are no receivers.
    pub fn is_empty(&self) -> bool {
        self.ends.is_empty()
    }
}

impl SampleTree {
    /// The nodes grouped by height, leaves first: every inner node's two children (`i + 1` and
    /// that child's `skip`) lie in earlier groups, so the groups can be aggregated one after
    /// another, each node from its children, in as many steps as the tree is high. Each group
    /// in index order.
    pub fn by_height(&self) -> Vec<Vec<u32>> {
        let mut height = vec![0usize; self.nodes.len()];
        // Depth first: children come after their parent, so a reverse sweep meets them first.
        for i in (0..self.nodes.len()).rev() {
            if !self.nodes[i].leaf {
                let (left, right) = (i + 1, self.nodes[i + 1].skip as usize);
                height[i] = 1 + height[left].max(height[right]);
            }
        }
        let mut groups = vec![Vec::new(); height.iter().max().map_or(0, |h| h + 1)];
        for (i, &h) in height.iter().enumerate() {
            groups[h].push(i as u32);
        }
        groups
    }
}

impl SampleTree {
    /// The samples whose near-field blend radius (`blend_radius sqrt(dA)`, at most the tree's
    /// own; positions and areas in the object's sample order) reaches into the sphere `group`:
    /// every sample that can give a receiver of the group a Shepard weight, found by walking only
    /// the nodes within the tree's reach. The sparse gather blends with a narrower radius than
    /// the widest channel's that the tree is built for.
    pub fn within_reach(
        &self,
        group: ([f32; 3], f32),
        positions: &[DVec3],
        areas: &[f64],
        blend_radius: f64,
    ) -> Vec<u32> {
        let (center, radius) = (glam::Vec3::from(group.0).as_dvec3(), group.1 as f64);
        let mut found = Vec::new();
        let mut i = 0;
        while i < self.nodes.len() {
            let n = &self.nodes[i];
            let dist = center.distance(glam::Vec3::from(n.center).as_dvec3()) - n.radius as f64 - radius;
            if dist >= n.reach as f64 {
                i = n.skip as usize;
            } else if n.leaf {
                for &s in &self.order[n.first as usize..(n.first + n.count) as usize] {
                    // A sample of the leaf is within reach when its own radius reaches the sphere
                    // (f32 rounding is covered by the node's rounded-out reach and radius).
                    if positions[s as usize].distance(center) - radius
                        < blend_radius.min(self.blend_radius) * areas[s as usize].sqrt() * (1.0 + 1e-6)
                    {
                        found.push(s);
                    }
                }
                i = n.skip as usize;
            } else {
                i += 1;
            }
        }
        found
    }
}

/// Receivers (mesh vertices) in a spatially coherent order, cut into groups of
/// [`RECEIVER_GROUP_SIZE`] consecutive ones, each with a bounding sphere.
///
/// The hierarchical gather decides per group, not per receiver ([`SampleTree::cut`]): a node is
/// used whole, opened or pruned by its distance to the group's sphere, a lower bound on its
/// distance to every receiver of the group, so the decisions are conservative, never coarser
/// than a per-receiver walk's. One workgroup gathers one group, every invocation summing the
/// same list of items, as the flat gather's invocations sum the same samples.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReceiverGroups {
    /// Receiver indices in group order (a median-split order, so groups are compact).
    pub order: Vec<u32>,
    /// Per group: centre and radius of a sphere holding its receivers (f32, rounded out).
    pub bounds: Vec<([f32; 3], f32)>,
}

impl ReceiverGroups {
    /// The groups over receivers at `positions`.
    pub fn new(positions: &[DVec3]) -> ReceiverGroups {
        let order = SampleTree::new(positions, &vec![0.0; positions.len()], 0.0).order;
        let bounds = order
            .chunks(RECEIVER_GROUP_SIZE)
            .map(|chunk| {
                let points: Vec<DVec3> = chunk.iter().map(|&i| positions[i as usize]).collect();
                sphere(&points)
            })
            .collect();
        ReceiverGroups { order, bounds }
    }

    /// The bounds of the group of the receiver at `position` in [`Self::order`].
    pub fn group_of(&self, position: usize) -> ([f32; 3], f32) {
        self.bounds[position / RECEIVER_GROUP_SIZE]
    }
}

/// A sphere holding `points` (the centre of their bounding box), rounded out for f32.
fn sphere(points: &[DVec3]) -> ([f32; 3], f32) {
    let (lo, hi) = points
        .iter()
        .fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let center = 0.5 * (lo + hi);
    let radius = points.iter().map(|p| p.distance(center)).fold(0.0, f64::max);
    let center_f32 = center.as_vec3();
    // The f32 centre is off the f64 one by up to half an ulp of each coordinate: add that and a
    // relative margin so the rounded sphere stays conservative.
    let slack = center.distance(center_f32.as_dvec3()) + 1e-6 * radius;
    (center_f32.to_array(), ((radius + slack) as f32).next_up())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn by_height_lists_every_node_once_after_both_its_children() {
        let (positions, areas) = points(1000);
        let t = SampleTree::new(&positions, &areas, BLEND);
        let groups = t.by_height();
        let mut group_of = vec![usize::MAX; t.nodes.len()];
        for (g, nodes) in groups.iter().enumerate() {
            for &n in nodes {
                assert_eq!(group_of[n as usize], usize::MAX, "node {n} listed twice");
                group_of[n as usize] = g;
            }
        }
        assert!(group_of.iter().all(|&g| g != usize::MAX), "every node listed");
        for (i, n) in t.nodes.iter().enumerate() {
            assert_eq!(n.leaf, group_of[i] == 0, "node {i}: leaves first, and only leaves");
            if !n.leaf {
                let (left, right) = (i + 1, t.nodes[i + 1].skip as usize);
                assert!(right < n.skip as usize && left < right, "node {i}: two children inside its subtree");
                assert!(group_of[left] < group_of[i] && group_of[right] < group_of[i], "node {i}");
                assert_eq!(
                    t.nodes[left].count + t.nodes[right].count,
                    n.count,
                    "node {i}: the children hold its samples"
                );
            }
        }
    }

    const BLEND: f64 = 1.5;

    fn points(n: usize) -> (Vec<DVec3>, Vec<f64>) {
        // A deterministic scatter on a curved patch, with uneven areas.
        let p = (0..n)
            .map(|i| {
                let (u, v) = ((i as f64 * 0.618_034).fract(), (i as f64 * 0.414_213_5).fract());
                DVec3::new(u, v, 0.3 * (u * v).sin())
            })
            .collect();
        let a = (0..n).map(|i| 1e-3 * (1.0 + (i % 7) as f64)).collect();
        (p, a)
    }

    #[test]
    fn every_node_bounds_its_samples_and_skips_past_its_subtree() {
        for n in [1, 2, 7, 8, 9, 100, 1000] {
            let (p, a) = points(n);
            let t = SampleTree::new(&p, &a, BLEND);
            let mut sorted = t.order.clone();
            sorted.sort_unstable();
            assert_eq!(sorted, (0..n as u32).collect::<Vec<_>>(), "every sample exactly once");
            assert_eq!(t.nodes[0].count as usize, n);
            assert_eq!(t.nodes[0].skip as usize, t.nodes.len());
            for (i, node) in t.nodes.iter().enumerate() {
                let samples = &t.order[node.first as usize..(node.first + node.count) as usize];
                let c = glam::Vec3::from(node.center);
                for &s in samples {
                    let q = p[s as usize].as_vec3();
                    assert!(q.distance(c) <= node.radius, "node {i} does not hold sample {s}");
                }
                let area: f64 = samples.iter().map(|&s| a[s as usize]).sum();
                assert!((node.area as f64 - area).abs() <= 1e-6 * area);
                assert_eq!(node.leaf, node.count as usize <= LEAF_SIZE);
                if node.leaf {
                    assert_eq!(node.skip as usize, i + 1);
                } else {
                    // Children: the next node, and the node its subtree skips to; they split
                    // the parent's samples.
                    let (l, r) = (&t.nodes[i + 1], &t.nodes[t.nodes[i + 1].skip as usize]);
                    assert_eq!(l.first, node.first);
                    assert_eq!(l.count + r.count, node.count);
                    assert_eq!(r.skip, node.skip);
                }
            }
        }
    }

    #[test]
    fn receiver_groups_hold_their_receivers() {
        let (p, _) = points(1000);
        let g = ReceiverGroups::new(&p);
        assert_eq!(g.bounds.len(), 1000usize.div_ceil(RECEIVER_GROUP_SIZE));
        let mut sorted = g.order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..1000).collect::<Vec<u32>>());
        for (k, &v) in g.order.iter().enumerate() {
            let (c, r) = g.group_of(k);
            assert!(p[v as usize].as_vec3().distance(glam::Vec3::from(c)) <= r);
        }
    }

    #[test]
    fn a_cut_covers_every_sample_once_and_epsilon_zero_takes_them_all() {
        let (p, a) = points(1000);
        let t = SampleTree::new(&p, &a, BLEND);
        let groups = ReceiverGroups::new(&p);
        for epsilon in [0.0, 0.1, 1.0] {
            for &group in &groups.bounds {
                let items = t.cut(group, epsilon, |_, _| false);
                let mut covered: Vec<u32> = items
                    .iter()
                    .flat_map(|&it| {
                        if it & NODE_ITEM != 0 {
                            let n = &t.nodes[(it & !NODE_ITEM) as usize];
                            t.order[n.first as usize..(n.first + n.count) as usize].to_vec()
                        } else {
                            vec![it]
                        }
                    })
                    .collect();
                covered.sort_unstable();
                assert_eq!(covered, (0..1000).collect::<Vec<u32>>(), "epsilon {epsilon}");
                if epsilon == 0.0 {
                    assert!(items.iter().all(|&it| it & NODE_ITEM == 0));
                }
            }
        }
        // A larger epsilon uses bigger nodes: fewer items.
        let size = |e| groups.bounds.iter().map(|&g| t.cut(g, e, |_, _| false).len()).sum::<usize>();
        assert!(size(1.0) < size(0.1) && size(0.1) < size(0.0));
    }

    #[test]
    fn within_reach_finds_exactly_the_samples_whose_blend_radius_reaches_the_group() {
        let (p, a) = points(1000);
        let t = SampleTree::new(&p, &a, BLEND);
        let groups = ReceiverGroups::new(&p);
        // The tree's own radius, and a narrower one (the sparse gather's beside wider channels).
        for radius in [BLEND, 0.6 * BLEND] {
            for &group in &groups.bounds {
                let mut got = t.within_reach(group, &p, &a, radius);
                got.sort_unstable();
                let c = glam::Vec3::from(group.0).as_dvec3();
                let want: Vec<u32> = (0..1000u32)
                    .filter(|&s| p[s as usize].distance(c) - (group.1 as f64) < radius * a[s as usize].sqrt())
                    .collect();
                assert_eq!(got, want);
            }
        }
    }

    #[test]
    fn an_empty_object_has_no_nodes() {
        assert!(SampleTree::new(&[], &[], BLEND).nodes.is_empty());
    }
}
