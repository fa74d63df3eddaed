//! What preparing a scene warns about, object by object: a camera whose near plane clips an
//! object, and an object so far from the origin that its f32 positions are coarse.

use super::Camera;
use crate::mesh::Mesh;
use glam::{DVec3, Vec3};

/// A warning when the camera's near plane clips `mesh` where the camera looks at it: its
/// nearest point to the eye lies inside the field of view (the cone through the image's
/// corners) and nearer than the near plane, which the scene's depth sets (a camera 1e-5 units
/// from a thin mesh in a large scene sees nothing of it). A grazing part of the mesh that is
/// not its nearest point is not looked for.
pub fn near_plane_warning(camera: &Camera, mesh: &Mesh, bounds: (Vec3, f32)) -> Option<String> {
    let (near, _) = camera.depth_range(bounds.0, bounds.1);
    let eye = Vec3::from(camera.eye).as_dvec3();
    let forward = (Vec3::from(camera.target) - Vec3::from(camera.eye)).as_dvec3().normalize_or_zero();
    let aspect = f64::from(camera.resolution[0]) / f64::from(camera.resolution[1].max(1));
    let tan_corner = (f64::from(camera.fov_y).to_radians() / 2.0).tan() * (1.0 + aspect * aspect).sqrt();
    let nearest = (0..mesh.triangles().len())
        .map(|t| closest_on_triangle(eye, mesh.corners(t)))
        .min_by(|a, b| a.distance_squared(eye).total_cmp(&b.distance_squared(eye)))?;
    let (offset, depth) = (nearest - eye, (nearest - eye).dot(forward));
    let lateral = (offset - forward * depth).length();
    (depth >= 0.0 && lateral <= depth * tan_corner && offset.length() < f64::from(near)).then(|| {
        format!(
            "the camera is {:.3e} units from it, nearer than the near plane ({near:.3e} units, set by the \
             scene's depth), which clips it from the image: move the camera back",
            offset.length()
        )
    })
}

/// The point of the triangle `corners` nearest to `p` (Ericson, Real-Time Collision Detection
/// 5.1.5: by the Voronoi region of `p`).
fn closest_on_triangle(p: DVec3, corners: [DVec3; 3]) -> DVec3 {
    let [a, b, c] = corners;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// Positions are f32 in world space: an object far from the origin compared with its size has
/// its vertices quantised to the f32 spacing there. A warning with the figures when that spacing
/// is above 1e-4 of the object's size (the sample spacing of a few hundred samples is about
/// 5e-2 of it, the dipole kernels' blend widths a fraction of that).
pub fn precision_warning(mesh: &Mesh) -> Option<String> {
    let (lo, hi) = mesh.bounds();
    let size = (hi - lo).max_element();
    let distance = lo.abs().max(hi.abs()).max_element();
    let spacing = distance * f32::EPSILON;
    (size > 0.0 && spacing > 1e-4 * size).then(|| {
        format!(
            "it is {distance:.3e} units from the origin and {size:.3e} across: f32 positions there are \
             quantised to {spacing:.2e} units ({:.2}% of its size); move the scene near the origin",
            100.0 * spacing / size
        )
    })
}
