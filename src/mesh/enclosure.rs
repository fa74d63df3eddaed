//! Which side of a surface faces out, when it encloses a volume: what lets the shading pass cull
//! the faces no ray from outside can reach (`render::shade`).

use glam::Vec3;

/// Whether triangles enclose a volume, and which way their winding faces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Enclosure {
    /// A boundary edge, an edge of three or more triangles, or inconsistent winding: a ray can
    /// reach either side of a triangle.
    Open,
    /// Closed and consistently wound, counter-clockwise seen from outside (positive volume).
    Outward,
    /// Closed and consistently wound, clockwise seen from outside.
    Inward,
}

/// The enclosure of `triangles` over `positions`: closed when every directed edge (a, b) occurs
/// once and its reverse (b, a) once, which is a closed, manifold, consistently wound surface;
/// the sign of its volume (the divergence theorem, sum of p0 . (p1 x p2) / 6) says which way out.
pub fn enclosure(positions: &[Vec3], triangles: &[[u32; 3]]) -> Enclosure {
    let mut edges: Vec<u64> = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |e| (u64::from(t[e]) << 32) | u64::from(t[(e + 1) % 3])))
        .collect();
    edges.sort_unstable();
    let repeated = edges.windows(2).any(|w| w[0] == w[1]);
    let reversed = |k: &u64| edges.binary_search(&k.rotate_right(32)).is_ok();
    if triangles.is_empty() || repeated || !edges.iter().all(reversed) {
        return Enclosure::Open;
    }
    let volume = signed_volume(positions, triangles);
    if volume > 0.0 {
        Enclosure::Outward
    } else if volume < 0.0 {
        Enclosure::Inward
    } else {
        // Closed but flat (two triangles back to back): both sides are outside.
        Enclosure::Open
    }
}

/// The signed volume a closed surface of `triangles` over `positions` encloses (the divergence
/// theorem: the sum of `p0 . (p1 x p2) / 6`), positive when wound counter-clockwise seen from
/// outside; 0 without triangles. Taken about the first vertex, so that far-off surfaces keep
/// their digits.
pub fn signed_volume(positions: &[Vec3], triangles: &[[u32; 3]]) -> f64 {
    let Some(first) = triangles.first() else { return 0.0 };
    let origin = positions[first[0] as usize].as_dvec3();
    let at = |i: u32| positions[i as usize].as_dvec3() - origin;
    triangles.iter().map(|t| at(t[0]).dot(at(t[1]).cross(at(t[2])))).sum::<f64>() / 6.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit tetrahedron, counter-clockwise seen from outside.
    fn tetrahedron() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        (p, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    }

    #[test]
    fn a_closed_surface_wound_outward_or_inward_says_which() {
        let (p, t) = tetrahedron();
        assert_eq!(enclosure(&p, &t), Enclosure::Outward);
        let flipped: Vec<_> = t.iter().map(|&[a, b, c]| [a, c, b]).collect();
        assert_eq!(enclosure(&p, &flipped), Enclosure::Inward);
        // Far from the origin, the volume's sign still holds.
        let far: Vec<_> = p.iter().map(|&q| q + Vec3::splat(1.0e4)).collect();
        assert_eq!(enclosure(&far, &t), Enclosure::Outward);
    }

    #[test]
    fn a_hole_a_flipped_face_or_a_flat_pair_is_open() {
        let (p, mut t) = tetrahedron();
        assert_eq!(enclosure(&p, &t[..3]), Enclosure::Open);
        t[3] = [1, 3, 2];
        assert_eq!(enclosure(&p, &t), Enclosure::Open);
        // One triangle twice, back to back: closed, but no volume to be outside of.
        assert_eq!(enclosure(&p, &[[0, 1, 2], [0, 2, 1]]), Enclosure::Open);
        assert_eq!(enclosure(&p, &[]), Enclosure::Open);
    }
}
