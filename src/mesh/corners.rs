//! What a file gives per triangle corner besides the position: texture coordinates (OBJ `vt`,
//! glTF `TEXCOORD_0`) and normals (OBJ `vn`, glTF `NORMAL`). Kept per corner because welding
//! joins vertices by position alone: a seam's two texture coordinates, or a crease's two normals,
//! stay on their own triangles. Each kind is all or nothing: `None` unless every triangle has it.

use glam::{Mat3, Mat4, Vec2, Vec3};

/// Per triangle, its corners' attributes, in the triangles' order and winding.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Corners {
    /// Texture coordinates.
    pub uvs: Option<Vec<[Vec2; 3]>>,
    /// Normals, any length (normalised when a vertex's are summed).
    pub normals: Option<Vec<[Vec3; 3]>>,
}

impl Corners {
    /// Nothing per corner.
    pub const NONE: Corners = Corners { uvs: None, normals: None };

    /// Both kinds, each empty, to be extended primitive by primitive (`keep_if` drops a kind a
    /// primitive lacks).
    pub fn collecting() -> Corners {
        Corners { uvs: Some(Vec::new()), normals: Some(Vec::new()) }
    }

    /// Drop a kind that does not cover `triangles` triangles or holds a non-finite value.
    pub fn checked(mut self, triangles: usize) -> Corners {
        if self.uvs.as_ref().is_some_and(|c| c.len() != triangles || c.iter().flatten().any(|v| !v.is_finite())) {
            self.uvs = None;
        }
        if self.normals.as_ref().is_some_and(|c| c.len() != triangles || c.iter().flatten().any(|v| !v.is_finite())) {
            self.normals = None;
        }
        self
    }

    /// Swap every triangle's second and third corners, as its winding is swapped.
    pub fn swap_winding(&mut self) {
        self.uvs.iter_mut().flatten().for_each(|c| c.swap(1, 2));
        self.normals.iter_mut().flatten().for_each(|c| c.swap(1, 2));
    }

    /// Keep the triangles whose `keep` is true.
    pub fn retain(&mut self, keep: &[bool]) {
        fn retain<T>(v: &mut Vec<T>, keep: &[bool]) {
            let mut k = keep.iter();
            v.retain(|_| *k.next().unwrap_or(&false));
        }
        if let Some(uvs) = self.uvs.as_mut() {
            retain(uvs, keep);
        }
        if let Some(normals) = self.normals.as_mut() {
            retain(normals, keep);
        }
    }

    /// The normals turned by `m` as its surface is (the inverse transpose of its linear part).
    pub fn transform_normals(&mut self, m: Mat4) {
        let turn = Mat3::from_mat4(m).inverse().transpose();
        self.normals.iter_mut().flatten().flatten().for_each(|n| *n = turn * *n);
    }

    /// Each vertex's normal as the sum of its corners' normals, normalised; `computed` where
    /// the file gives none or they cancel (`triangles` index the vertices).
    pub fn vertex_normals(&self, triangles: &[[u32; 3]], computed: Vec<Vec3>) -> Vec<Vec3> {
        let Some(normals) = &self.normals else { return computed };
        let mut sums = vec![Vec3::ZERO; computed.len()];
        for (t, corners) in triangles.iter().zip(normals) {
            for (&v, n) in t.iter().zip(corners) {
                sums[v as usize] += n.normalize_or_zero();
            }
        }
        sums.iter().zip(computed).map(|(s, c)| s.try_normalize().unwrap_or(c)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_vertex_takes_the_mean_of_its_corners_normals_and_the_computed_one_where_they_cancel() {
        let triangles = [[0, 1, 2], [0, 2, 3]];
        let up = Vec3::Y;
        let corners = Corners { uvs: None, normals: Some(vec![[up, up, -up], [Vec3::X, up, up]]) };
        let normals = corners.vertex_normals(&triangles, vec![Vec3::Z; 4]);
        assert!((normals[0] - (Vec3::X + up).normalize()).length() < 1e-6);
        assert_eq!(normals[1], up);
        assert_eq!(normals[2], Vec3::Z, "up and down cancel: the computed normal");
        assert_eq!(normals[3], up);
    }

    #[test]
    fn normals_turn_with_a_stretch_as_the_surface_does() {
        // A plane x = y stretched twice along x: its normal leans towards y.
        let mut corners = Corners { uvs: None, normals: Some(vec![[Vec3::new(1.0, -1.0, 0.0); 3]]) };
        corners.transform_normals(Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0)));
        let n = corners.normals.unwrap()[0][0].normalize();
        // The stretched plane is x = 2y: its normal is (1, -2, 0) normalised.
        assert!((n - Vec3::new(1.0, -2.0, 0.0).normalize()).length() < 1e-6, "{n}");
    }
}
