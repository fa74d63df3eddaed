//! Moving a point over the surface: a straight step inside its triangle that, on reaching an
//! edge, continues on the neighbouring triangle with the rest of the step unfolded about the
//! shared edge (Turk 1992 moves points across edges onto adjacent polygons in the same way).

use glam::DVec3;

use crate::mesh::{Mesh, NO_NEIGHBOUR};

/// A point on the mesh: a triangle and barycentric weights of its three corners (non-negative,
/// summing to one).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Index of the mesh triangle.
    pub triangle: u32,
    /// Barycentric weights of the triangle's three corners.
    pub bary: [f64; 3],
}

impl SurfacePoint {
    /// The point in 3D (f64), in the mesh's space.
    pub fn position(&self, mesh: &Mesh) -> DVec3 {
        mesh.point(self.triangle as usize, self.bary)
    }
}

/// Edge crossings allowed for one step; a step this long only happens when a point circles a
/// vertex, and stopping there is harmless.
const MAX_HOPS: usize = 64;

/// Barycentric velocity of displacement `d` (assumed in the plane of the triangle with corners
/// `p`): the change of the three weights per unit of `d`.
#[inline]
fn bary_delta(p: &[DVec3; 3], d: DVec3) -> [f64; 3] {
    let e1 = p[1] - p[0];
    let e2 = p[2] - p[0];
    let (a, b, c) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let det = a * c - b * b;
    if det <= 0.0 {
        return [0.0; 3];
    }
    let (r1, r2) = (d.dot(e1), d.dot(e2));
    let du = (c * r1 - b * r2) / det;
    let dv = (a * r2 - b * r1) / det;
    [-du - dv, du, dv]
}

#[inline]
fn clean(mut b: [f64; 3]) -> [f64; 3] {
    for w in &mut b {
        *w = w.max(0.0);
    }
    let s = b[0] + b[1] + b[2];
    if s > 0.0 { b.map(|w| w / s) } else { [1.0 / 3.0; 3] }
}

/// Move `start` by the 3D displacement `d`, projected on the plane of its triangle. At an open
/// boundary or a non-manifold edge the point slides along the edge with the along-edge part of
/// the step instead of leaving the surface.
pub fn walk(mesh: &Mesh, start: SurfacePoint, d: DVec3) -> SurfacePoint {
    let tris = mesh.triangles();
    let normals = mesh.face_normals();
    let mut t = start.triangle as usize;
    let mut b = start.bary;
    let n = normals[t].as_dvec3();
    let mut d = d - d.dot(n) * n;
    // The corner whose weight just became zero by entering through the opposite edge; the exit
    // search skips it so rounding cannot bounce the point straight back.
    let mut entered: Option<usize> = None;

    for _ in 0..MAX_HOPS {
        if d.length_squared() == 0.0 {
            break;
        }
        let p = mesh.corners(t);
        let db = bary_delta(&p, d);
        let mut s_exit = 1.0;
        let mut k_exit = None;
        for k in 0..3 {
            if Some(k) != entered && db[k] < 0.0 {
                let s = b[k].max(0.0) / -db[k];
                if s < s_exit {
                    s_exit = s;
                    k_exit = Some(k);
                }
            }
        }
        for k in 0..3 {
            b[k] += s_exit * db[k];
        }
        let Some(k) = k_exit else { break };
        b[k] = 0.0;
        b = clean(b);
        let rest = d * (1.0 - s_exit);
        // The edge opposite corner k runs from corner e = k + 1 to corner k + 2.
        let e = (k + 1) % 3;
        let (ia, ib) = (e, (e + 1) % 3);
        let (va, vb) = (tris[t][ia], tris[t][ib]);
        let axis = (p[ib] - p[ia]).normalize_or_zero();
        let along = rest.dot(axis);
        let across = (rest - along * axis).length();
        let next = mesh.neighbours()[t][e];
        if next == NO_NEIGHBOUR {
            // Boundary: keep only the motion along the edge, staying in this triangle.
            d = along * axis;
            entered = Some(k);
            continue;
        }
        let u = next as usize;
        let tri_u = tris[u];
        let (Some(ja), Some(jb)) = (tri_u.iter().position(|&v| v == va), tri_u.iter().position(|&v| v == vb)) else {
            break;
        };
        let jo = 3 - ja - jb;
        let q = mesh.corners(u);
        // Unfold: the same angle to the shared edge, now pointing into the neighbour.
        let to_opposite = q[jo] - q[ja];
        let inward = (to_opposite - to_opposite.dot(axis) * axis).normalize_or_zero();
        let mut nb = [0.0; 3];
        nb[ja] = b[ia];
        nb[jb] = b[ib];
        t = u;
        b = nb;
        d = along * axis + across * inward;
        entered = Some(jo);
    }
    SurfacePoint { triangle: t as u32, bary: clean(b) }
}
