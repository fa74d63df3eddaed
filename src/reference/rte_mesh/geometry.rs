//! The closed mesh as the walk sees it: flat triangles with outward face normals, the BVH its
//! flights are tested against and the clearance grid that spares most of those tests.

use crate::mesh::Mesh;
use crate::mesh::bvh::{Bvh, Hit, intersect_uv};
use crate::reference::clearance::{Clearance, Flight};
use glam::DVec3;

/// The object as the walk sees it.
pub(super) struct Geometry<'a> {
    pub(super) mesh: &'a Mesh,
    bvh: Bvh,
    /// Outward unit face normals.
    pub(super) normals: Vec<DVec3>,
    /// Per face, its plane's offset along its normal.
    offsets: Vec<f64>,
    /// A small length, far above the rounding of the hit test: the plane test's slack.
    slack: f64,
    /// A lower bound of the distance to the surface, if the method uses one.
    clearance: Option<Clearance>,
}

impl<'a> Geometry<'a> {
    pub(super) fn new(mesh: &'a Mesh, clearance: bool) -> Geometry<'a> {
        let triangles: Vec<[DVec3; 3]> = (0..mesh.triangles().len()).map(|t| mesh.corners(t)).collect();
        // Six times the enclosed volume: negative when the winding faces inwards.
        let volume: f64 = triangles.iter().map(|[a, b, c]| a.dot(b.cross(*c))).sum();
        let sign = if volume < 0.0 { -1.0 } else { 1.0 };
        let normals: Vec<DVec3> =
            triangles.iter().map(|[a, b, c]| sign * (*b - *a).cross(*c - *a).normalize()).collect();
        let offsets = triangles.iter().zip(&normals).map(|(t, n)| n.dot(t[0])).collect();
        let size = triangles.iter().flatten().fold(0.0f64, |m, p| m.max(p.abs().max_element()));
        let bvh = Bvh::new(triangles);
        let clearance = clearance.then(|| {
            let (min, max) = mesh.positions().iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.as_dvec3()), hi.max(p.as_dvec3()))
            });
            Clearance::new(&bvh, min, max)
        });
        Geometry { mesh, bvh, normals, offsets, slack: 1e-9 * size, clearance }
    }

    /// The first face a flight from `p` along `d` meets within `s`, other than `skip`: what
    /// the BVH's query answers, without it where the clearance grid rules a hit out or lists
    /// the faces the flight can meet.
    pub(super) fn closest_hit(&self, p: DVec3, d: DVec3, s: f64, skip: Option<usize>) -> Option<Hit> {
        match self.clearance.as_ref().map_or(Flight::Far, |c| c.flight(p, s)) {
            Flight::Clear => None,
            Flight::Near(faces) => self.closest_among(faces, p, d, s, skip),
            Flight::Far => self.bvh.closest_hit(p, d, 0.0, s, skip),
        }
    }

    /// [`Geometry::closest_hit`] among `faces`, by the BVH's own hit test. A face whose plane
    /// the flight does not cross within `(0, s)` (give or take the slack) is passed over
    /// first: two dot products instead of the full test, for most of the list.
    fn closest_among(&self, faces: &[u32], p: DVec3, d: DVec3, s: f64, skip: Option<usize>) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut t_far = s;
        for &f in faces {
            let f = f as usize;
            let (n, offset) = (self.normals[f], self.offsets[f]);
            // The plane is met at t = num / den; within (0, s) iff num lies between 0 and s den.
            let (num, den) = (offset - n.dot(p), n.dot(d));
            if (num - 0.5 * s * den).abs() > 0.5 * s * den.abs() + self.slack || skip == Some(f) {
                continue;
            }
            if let Some((t, u, v)) = intersect_uv(self.bvh.triangle(f), p, d)
                && t > 0.0
                && t < t_far
            {
                t_far = t;
                best = Some(Hit { t, triangle: f, u, v });
            }
        }
        best
    }

    /// The first face a ray from `p` along `d` meets within `s`, by the BVH alone.
    pub(super) fn first_hit_within(&self, p: DVec3, d: DVec3, s: f64) -> Option<Hit> {
        self.bvh.closest_hit(p, d, 0.0, s, None)
    }

    /// The first face a ray from `p` along `d` meets, however far.
    pub(super) fn first_hit(&self, p: DVec3, d: DVec3) -> Option<Hit> {
        self.first_hit_within(p, d, f64::INFINITY)
    }

    /// The outward unit shading normal at barycentric coordinates `bary` of `triangle`: the
    /// vertex normals interpolated in f64 (the beam's derivatives are taken by finite
    /// differences, finer than f32 resolves) and turned to the outward face normal's side, or
    /// the face normal where they cancel.
    pub(super) fn shading_normal(&self, triangle: usize, bary: [f64; 3]) -> DVec3 {
        let normals = self.mesh.vertex_normals();
        let n: DVec3 =
            self.mesh.triangles()[triangle].iter().zip(bary).map(|(&v, b)| normals[v as usize].as_dvec3() * b).sum();
        let len = n.length();
        let face = self.normals[triangle];
        if len <= 1e-9 {
            face
        } else if n.dot(face) < 0.0 {
            -n / len
        } else {
            n / len
        }
    }

    /// The barycentric coordinates of `p` (projected on the plane of `triangle`), outside
    /// [0, 1] where it lies outside the triangle.
    pub(super) fn barycentric(&self, triangle: usize, p: DVec3) -> [f64; 3] {
        let [a, b, c] = self.mesh.corners(triangle);
        let (e1, e2, w) = (b - a, c - a, p - a);
        let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (d20, d21) = (w.dot(e1), w.dot(e2));
        let denom = d00 * d11 - d01 * d01;
        let u = (d11 * d20 - d01 * d21) / denom;
        let v = (d00 * d21 - d01 * d20) / denom;
        [1.0 - u - v, u, v]
    }

    /// A lower bound of the distance from `p` to the surface (0 without the clearance grid).
    pub(super) fn clearance_at(&self, p: DVec3) -> f64 {
        self.clearance.as_ref().map_or(0.0, |c| c.at(p))
    }

    /// A small length, far above the rounding of the hit test.
    pub(super) fn slack(&self) -> f64 {
        self.slack
    }

    /// The vertex whose cell holds the point of barycentric coordinates `(1 - u - v, u, v)` on
    /// `triangle`: the corner of the largest.
    pub(super) fn cell_vertex(&self, triangle: usize, u: f64, v: f64) -> usize {
        let w = 1.0 - u - v;
        let corner = if w >= u && w >= v {
            0
        } else if u >= v {
            1
        } else {
            2
        };
        self.mesh.triangles()[triangle][corner] as usize
    }
}
