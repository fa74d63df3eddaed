//! Per-triangle and per-vertex differential geometry, following Meyer, Desbrun, Schröder and Barr,
//! "Discrete Differential-Geometry Operators for Triangulated 2-Manifolds" (2003):
//! - mixed Voronoi areas (their Fig. 4): the Voronoi share of a vertex in a non-obtuse triangle,
//!   half the triangle when the vertex's angle is obtuse, a quarter otherwise;
//! - the mean curvature normal K(x_i) = 1/(2 A_mixed) sum_j (cot alpha_ij + cot beta_ij)(x_i - x_j)
//!   (their Eq. 8), with H = K . n / 2;
//! - Gaussian curvature as the angle defect (2 pi - sum of angles) / A_mixed (their Eq. 9).
//!
//! Everything is accumulated in f64 from the f32 positions.

use std::f64::consts::{FRAC_PI_2, PI};

use glam::{DVec3, Vec3};

use super::topology::Topology;

pub(super) struct Geometry {
    pub triangle_areas: Vec<f64>,
    pub face_normals: Vec<Vec3>,
    pub vertex_normals: Vec<Vec3>,
    pub mean_curvature: Vec<f64>,
    pub gaussian_curvature: Vec<f64>,
    pub mixed_areas: Vec<f64>,
}

/// Passes of neighbour averaging used to give boundary vertices a curvature; a vertex more than
/// this many edges away from any interior vertex keeps zero.
const BOUNDARY_FILL_PASSES: usize = 4;

pub(super) fn compute(positions: &[Vec3], triangles: &[[u32; 3]], topo: &Topology) -> Geometry {
    let n = positions.len();
    let mut triangle_areas = Vec::with_capacity(triangles.len());
    let mut face_normals = Vec::with_capacity(triangles.len());
    let mut angle_weighted = vec![DVec3::ZERO; n];
    let mut area_weighted = vec![DVec3::ZERO; n];
    let mut laplacian = vec![DVec3::ZERO; n];
    let mut angle_sum = vec![0.0f64; n];
    let mut mixed = vec![0.0f64; n];

    for tri in triangles {
        let v = tri.map(|i| i as usize);
        let p = v.map(|i| positions[i].as_dvec3());
        let cross = (p[1] - p[0]).cross(p[2] - p[0]);
        let twice_area = cross.length();
        let area = 0.5 * twice_area;
        let normal = cross / twice_area;
        triangle_areas.push(area);
        face_normals.push(normal.as_vec3());

        let (angle, cot) = corner_angles(&p, twice_area);

        for k in 0..3 {
            let (j, l) = ((k + 1) % 3, (k + 2) % 3);
            // Edge (j, l) is opposite corner k: cot(angle k) is one of its two cotangent weights.
            let e = p[j] - p[l];
            laplacian[v[j]] += cot[k] * e;
            laplacian[v[l]] -= cot[k] * e;
            angle_sum[v[k]] += angle[k];
            angle_weighted[v[k]] += angle[k] * normal;
            area_weighted[v[k]] += cross;
        }

        let obtuse = angle.iter().position(|&a| a > FRAC_PI_2);
        for k in 0..3 {
            let (j, l) = ((k + 1) % 3, (k + 2) % 3);
            mixed[v[k]] += match obtuse {
                // Voronoi share of corner k: 1/8 (|p_k p_l|^2 cot(angle j) + |p_k p_j|^2 cot(angle l)).
                None => 0.125 * ((p[k] - p[l]).length_squared() * cot[j] + (p[k] - p[j]).length_squared() * cot[l]),
                Some(o) if o == k => 0.5 * area,
                Some(_) => 0.25 * area,
            };
        }
    }

    let vertex_normals = vertex_normals(triangles, &face_normals, &angle_weighted, &area_weighted);

    let mut mean = vec![0.0; n];
    let mut gauss = vec![0.0; n];
    for i in 0..n {
        if mixed[i] > 0.0 && !topo.boundary_vertex[i] {
            mean[i] = laplacian[i].dot(vertex_normals[i].as_dvec3()) / (4.0 * mixed[i]);
            gauss[i] = (2.0 * PI - angle_sum[i]) / mixed[i];
        }
    }
    fill_boundary(&mut mean, &mut gauss, &mixed, topo);

    Geometry {
        triangle_areas,
        face_normals,
        vertex_normals,
        mean_curvature: mean,
        gaussian_curvature: gauss,
        mixed_areas: mixed,
    }
}

/// Angle and cotangent at each corner of the triangle `p` whose `|(p1 - p0) x (p2 - p0)|` is
/// `twice_area`. |u x v| is twice the area at every corner, so the cotangent is dot /
/// twice_area; atan2 keeps small and near-pi angles accurate.
fn corner_angles(p: &[DVec3; 3], twice_area: f64) -> ([f64; 3], [f64; 3]) {
    let mut angle = [0.0; 3];
    let mut cot = [0.0; 3];
    for k in 0..3 {
        let u = p[(k + 1) % 3] - p[k];
        let w = p[(k + 2) % 3] - p[k];
        let d = u.dot(w);
        angle[k] = twice_area.atan2(d);
        cot[k] = d / twice_area;
    }
    (angle, cot)
}

/// Unit vertex normals: the angle-weighted sum of the faces' normals, else the area-weighted
/// one, else any one face's, else +z for a vertex on no face.
fn vertex_normals(
    triangles: &[[u32; 3]],
    face_normals: &[Vec3],
    angle_weighted: &[DVec3],
    area_weighted: &[DVec3],
) -> Vec<Vec3> {
    let n = angle_weighted.len();
    let mut vertex_normals = vec![Vec3::Z; n];
    let mut any_face = vec![u32::MAX; n];
    for (t, tri) in triangles.iter().enumerate() {
        for &i in tri {
            if any_face[i as usize] == u32::MAX {
                any_face[i as usize] = t as u32;
            }
        }
    }
    for i in 0..n {
        // Two triangles folded onto each other cancel; fall back to area weighting, then to any
        // one face, so every vertex normal is a unit vector.
        let nrm = angle_weighted[i]
            .try_normalize()
            .or_else(|| area_weighted[i].try_normalize())
            .map(|d| d.as_vec3())
            .unwrap_or_else(|| face_normals.get(any_face[i] as usize).copied().unwrap_or(Vec3::Z));
        vertex_normals[i] = nrm;
    }
    vertex_normals
}

/// At boundary (and non-manifold) vertices half the one-ring is missing, so the cotangent sum
/// and the angle defect measure the boundary's bending rather than the surface's. Give them the
/// mixed-area-weighted mean of neighbours that have a value, spreading inwards pass by pass.
fn fill_boundary(mean: &mut [f64], gauss: &mut [f64], mixed: &[f64], topo: &Topology) {
    let n = mean.len();
    let mut known: Vec<bool> = (0..n).map(|i| !topo.boundary_vertex[i] && mixed[i] > 0.0).collect();
    let mut pending: Vec<usize> = (0..n).filter(|&i| !known[i]).collect();
    let mut updates = Vec::with_capacity(pending.len());
    for _ in 0..BOUNDARY_FILL_PASSES {
        if pending.is_empty() {
            break;
        }
        updates.clear();
        for &i in &pending {
            let ring = &topo.ring[topo.ring_offsets[i] as usize..topo.ring_offsets[i + 1] as usize];
            let (mut w, mut h, mut k) = (0.0, 0.0, 0.0);
            for &j in ring {
                let j = j as usize;
                if known[j] {
                    w += mixed[j];
                    h += mixed[j] * mean[j];
                    k += mixed[j] * gauss[j];
                }
            }
            if w > 0.0 {
                updates.push((i, h / w, k / w));
            }
        }
        for &(i, h, k) in &updates {
            mean[i] = h;
            gauss[i] = k;
            known[i] = true;
        }
        pending.retain(|&i| !known[i]);
    }
}
