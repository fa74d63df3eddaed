//! Meshes built in memory: the scene format's built-in shapes (`shape = { type = "plane" }`,
//! `{ type = "sphere" }`), also what tests build their surfaces from.

use super::{Mesh, MeshError};
use glam::Vec3;

/// A square in the xz plane at y = 0, facing +y.
pub fn plane(size: f32, divisions: u32) -> Result<Mesh, MeshError> {
    let n = divisions as usize;
    let mut positions = Vec::with_capacity((n + 1) * (n + 1));
    for j in 0..=n {
        for i in 0..=n {
            let u = i as f32 / n as f32 - 0.5;
            let v = j as f32 / n as f32 - 0.5;
            positions.push(Vec3::new(u * size, 0.0, v * size));
        }
    }
    let mut triangles = Vec::with_capacity(2 * n * n);
    let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    for j in 0..n {
        for i in 0..n {
            // Counter-clockwise seen from +y.
            triangles.push([at(i, j), at(i, j + 1), at(i + 1, j)]);
            triangles.push([at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)]);
        }
    }
    Mesh::from_triangles(positions, triangles)
}

/// A UV sphere centred at the origin (outward-facing).
pub fn sphere(radius: f32, divisions: u32) -> Result<Mesh, MeshError> {
    let rings = divisions.max(3) as usize;
    let segments = 2 * rings;
    let mut positions = vec![Vec3::new(0.0, radius, 0.0)];
    for r in 1..rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = 2.0 * std::f32::consts::PI * s as f32 / segments as f32;
            positions.push(radius * Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()));
        }
    }
    positions.push(Vec3::new(0.0, -radius, 0.0));
    let bottom = (positions.len() - 1) as u32;
    let ring = |r: usize, s: usize| (1 + (r - 1) * segments + s % segments) as u32;
    let mut triangles = Vec::new();
    for s in 0..segments {
        triangles.push([0, ring(1, s + 1), ring(1, s)]);
        triangles.push([bottom, ring(rings - 1, s), ring(rings - 1, s + 1)]);
    }
    for r in 1..rings - 1 {
        for s in 0..segments {
            triangles.push([ring(r, s), ring(r, s + 1), ring(r + 1, s)]);
            triangles.push([ring(r, s + 1), ring(r + 1, s + 1), ring(r + 1, s)]);
        }
    }
    Mesh::from_triangles(positions, triangles)
}
