//! A binary tree over an object's lit triangles, each node carrying the moments of the
//! triangles below it, so that a receiver takes a far group of them as one multipole.

use super::source::{Moments, Summary};
use glam::DVec3;

/// A node of the tree of lit triangles: their moments about each channel's centroid and a
/// bounding sphere.
pub(super) struct Cluster {
    pub(super) moments: Moments,
    pub(super) centroid: [DVec3; 3],
    /// Second moments about `centroid`, as [`Summary::quadrupole`].
    pub(super) quadrupole: [[f64; 6]; 3],
    pub(super) centre: DVec3,
    pub(super) radius: f64,
    /// The triangle (index into the lit sources) of a leaf.
    pub(super) source: Option<usize>,
    /// Children of an inner node.
    children: [usize; 2],
}

/// A binary tree over the lit triangles (median split on the longest axis of their centres),
/// so a receiver takes a far group of triangles as one multipole instead of visiting each: the
/// cost per receiver grows with the log of the triangle count, not with it.
pub(super) struct Clusters {
    nodes: Vec<Cluster>,
}

impl Clusters {
    pub(super) fn new(lit: &[Summary]) -> Clusters {
        let mut nodes = Vec::with_capacity(2 * lit.len());
        let mut members: Vec<usize> = (0..lit.len()).collect();
        Self::build(lit, &mut members, &mut nodes);
        Clusters { nodes }
    }

    /// Append the subtree over `members` (post-order) and return its root's index.
    fn build(lit: &[Summary], members: &mut [usize], nodes: &mut Vec<Cluster>) -> usize {
        if let [only] = members {
            let s = &lit[*only];
            nodes.push(Cluster {
                moments: Moments { flux: s.flux, moment: [0, 1, 2].map(|c| s.centroid[c] * s.flux[c]) },
                centroid: s.centroid,
                quadrupole: s.quadrupole,
                centre: s.centre,
                radius: s.radius,
                source: Some(*only),
                children: [0; 2],
            });
            return nodes.len() - 1;
        }
        let (lo, hi) = members.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &i| {
            (lo.min(lit[i].centre), hi.max(lit[i].centre))
        });
        let axis = (hi - lo).max_position();
        let half = members.len() / 2;
        members.select_nth_unstable_by(half, |&a, &b| lit[a].centre[axis].total_cmp(&lit[b].centre[axis]));
        let (left, right) = members.split_at_mut(half);
        let children = [Self::build(lit, left, nodes), Self::build(lit, right, nodes)];
        let [a, b] = children.map(|k| &nodes[k]);
        let mut moments = a.moments;
        moments.add(&b.moments);
        let centre = (a.centre + b.centre) * 0.5;
        let centroid = moments.centroid(centre);
        // Parallel axes: each child's second moment moved from its centroid to the parent's.
        let mut quadrupole = [[0.0; 6]; 3];
        for child in [a, b] {
            for c in 0..3 {
                let (f, r) = (child.moments.flux[c], child.centroid[c] - centroid[c]);
                let shift = [r.x * r.x, r.y * r.y, r.z * r.z, r.x * r.y, r.x * r.z, r.y * r.z];
                for k in 0..6 {
                    quadrupole[c][k] += child.quadrupole[c][k] + f * shift[k];
                }
            }
        }
        let radius = [a, b].iter().map(|n| n.centre.distance(centre) + n.radius).fold(0.0, f64::max);
        nodes.push(Cluster { moments, centroid, quadrupole, centre, radius, source: None, children });
        nodes.len() - 1
    }

    /// Visit the tree from the root: `take` a node that is a leaf or `whole(node)`, else go
    /// down to its children.
    pub(super) fn walk(&self, whole: impl Fn(&Cluster) -> bool, mut take: impl FnMut(&Cluster)) {
        let mut stack = vec![self.nodes.len() - 1];
        while let Some(k) = stack.pop() {
            let node = &self.nodes[k];
            if node.source.is_some() || whole(node) {
                take(node);
            } else {
                stack.extend(node.children);
            }
        }
    }
}
