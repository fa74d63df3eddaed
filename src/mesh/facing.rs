//! Which vertices an eye can see the front of, conservatively: per vertex, a cone holding the
//! outward normal of every triangle around it at every level of detail. A triangle is drawn
//! when the eye lies on its outer side (`n_f . (e - x) > 0`, the same for every point `x` of
//! the triangle), so a vertex is needed by some drawn triangle only if some normal in its cone
//! has `n . d > 0`, `d = e - x`: that is `a . d > -sin(theta) |d|` for a cone of axis `a` and
//! half-angle `theta <= 90 degrees`. The gather uses it to skip the receivers of faces no eye
//! ray reaches (`glsl/receiver_view.comp` is the f32 twin of [`faces_eye`]).

use super::Enclosure;
use glam::Vec3;

/// A cone's `w` that passes every eye: the vertex lies on an open level, or its triangles'
/// normals spread over a half-space or more.
pub const ALWAYS: f32 = 2.0;

/// Added to each cone's `sin(theta)`, so that f32 rounding in the twin never drops a vertex a
/// drawn triangle needs.
const MARGIN: f32 = 1e-3;

/// Per vertex of `positions`, its facing cone `[a.x, a.y, a.z, sin(theta) + MARGIN]` over the
/// triangles of every level in `levels` (each with its enclosure: an inward-wound level's
/// normals are turned outward, and an open level's vertices get `ALWAYS`, since either side
/// of an open surface may be drawn). A vertex on no triangle gets `ALWAYS`.
pub fn vertex_cones<'a>(
    positions: &[Vec3],
    levels: impl Iterator<Item = (&'a [[u32; 3]], Enclosure)> + Clone,
) -> Vec<[f32; 4]> {
    let n = positions.len();
    let mut sum = vec![Vec3::ZERO; n];
    let mut always = vec![false; n];
    let outward = |tri: &[u32; 3], enclosure: Enclosure| {
        let [a, b, c] = tri.map(|i| positions[i as usize]);
        let normal = (b - a).cross(c - a).normalize_or_zero();
        if enclosure == Enclosure::Inward { -normal } else { normal }
    };
    for (triangles, enclosure) in levels.clone() {
        for tri in triangles {
            if enclosure == Enclosure::Open {
                tri.iter().for_each(|&i| always[i as usize] = true);
                continue;
            }
            let normal = outward(tri, enclosure);
            tri.iter().for_each(|&i| sum[i as usize] += normal);
        }
    }
    let axis: Vec<Vec3> = sum.iter().map(|s| s.normalize_or_zero()).collect();
    // The least cosine between a vertex's axis and any of its normals.
    let mut least = vec![1.0f32; n];
    for (triangles, enclosure) in levels.filter(|(_, e)| *e != Enclosure::Open) {
        for tri in triangles {
            let normal = outward(tri, enclosure);
            for &i in tri {
                let i = i as usize;
                least[i] = least[i].min(if normal == Vec3::ZERO { 1.0 } else { axis[i].dot(normal) });
            }
        }
    }
    (0..n)
        .map(|i| {
            let a = axis[i];
            if always[i] || a == Vec3::ZERO || least[i] <= 0.0 {
                return [0.0, 0.0, 0.0, ALWAYS];
            }
            let sin = (1.0 - least[i] * least[i]).max(0.0).sqrt();
            [a.x, a.y, a.z, sin + MARGIN]
        })
        .collect()
}

/// The longest edge of `triangles` over `positions`: a vertex of a triangle that meets the view
/// frustum lies at most this far outside it.
pub fn longest_edge(positions: &[Vec3], triangles: &[[u32; 3]]) -> f32 {
    let p = |i: u32| positions[i as usize];
    triangles
        .iter()
        .flat_map(|&[a, b, c]| [p(a).distance(p(b)), p(b).distance(p(c)), p(c).distance(p(a))])
        .fold(0.0, f32::max)
}

/// Whether a vertex at `x` with facing cone `cone` may be on a triangle whose outer side faces
/// the eye: `eye` is `[e, 1]` for a perspective eye at `e`, `[-v, 0]` for an orthographic view
/// along `v` (the direction towards the eye).
pub fn faces_eye(cone: [f32; 4], x: Vec3, eye: [f32; 4]) -> bool {
    if cone[3] >= ALWAYS {
        return true;
    }
    let e = Vec3::new(eye[0], eye[1], eye[2]);
    let d = if eye[3] != 0.0 { e - x } else { e };
    let a = Vec3::new(cone[0], cone[1], cone[2]);
    a.dot(d) > -cone[3] * d.length()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes;

    /// On a closed sphere, every triangle the eye sees the outer side of has each of its
    /// vertices pass, and vertices on the far side do not.
    #[test]
    fn every_vertex_of_a_front_face_passes_and_the_far_side_does_not() {
        let mesh = shapes::sphere(1.0, 16).expect("sphere");
        let (p, t) = (mesh.positions(), mesh.triangles());
        let enclosure = crate::mesh::enclosure(p, t);
        assert_eq!(enclosure, Enclosure::Outward);
        let cones = vertex_cones(p, std::iter::once((t, enclosure)));
        let eye = Vec3::new(0.3, 0.2, 4.0);
        for tri in t {
            let [a, b, c] = tri.map(|i| p[i as usize]);
            if (b - a).cross(c - a).dot(eye - a) > 0.0 {
                for &i in tri {
                    assert!(faces_eye(cones[i as usize], p[i as usize], [eye.x, eye.y, eye.z, 1.0]));
                }
            }
        }
        let far = p.iter().enumerate().filter(|(_, x)| x.z < -0.5).count();
        let passed =
            p.iter().zip(&cones).filter(|(x, c)| x.z < -0.5 && faces_eye(**c, **x, [eye.x, eye.y, eye.z, 1.0]));
        assert!(far > 10 && passed.count() == 0, "far-side vertices should fail");
        // Seen orthographically from +z, the same.
        assert!(p.iter().zip(&cones).filter(|(x, _)| x.z < -0.5).all(|(x, c)| !faces_eye(
            *c,
            *x,
            [0.0, 0.0, 1.0, 0.0]
        )));
    }

    /// An open level's vertices pass from anywhere: either side of it may be drawn.
    #[test]
    fn an_open_surface_passes_from_either_side() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let t = [[0u32, 1, 2]];
        let cones = vertex_cones(&p, std::iter::once((&t[..], Enclosure::Open)));
        assert!(cones.iter().all(|c| faces_eye(*c, Vec3::ZERO, [0.0, 0.0, -5.0, 1.0])));
    }
}
