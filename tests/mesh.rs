//! Mesh loading, validation and derived geometry: curvature against analytic surfaces, topology
//! counts, and clear errors for bad OBJ files.

mod common;

use common::{grid, load_asset, temp_dir};
use std::collections::HashMap;
use std::f64::consts::PI;
use std::path::PathBuf;

use glam::{DVec3, Mat4, Vec3};
use translucent::mesh::{LoadOptions, Mesh, MeshError, NO_NEIGHBOUR};

// ---------------------------------------------------------------------------------------------
// Analytic surfaces

/// An icosphere: the icosahedron subdivided `level` times, vertices pushed onto the sphere.
/// Level 5 has 10,242 vertices.
fn icosphere(level: usize, radius: f64) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<DVec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut next = Vec::with_capacity(f.len() * 4);
        let mut midpoint = |a: u32, b: u32, v: &mut Vec<DVec3>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push(((v[a as usize] + v[b as usize]) * 0.5).normalize());
                (v.len() - 1) as u32
            })
        };
        for [a, b, c] in f {
            let ab = midpoint(a, b, &mut v);
            let bc = midpoint(b, c, &mut v);
            let ca = midpoint(c, a, &mut v);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = next;
    }
    (v.iter().map(|p| (*p * radius).as_vec3()).collect(), f)
}

/// A torus around the z axis: major radius `big`, minor radius `small`, `nu` x `nv` vertices.
fn torus(big: f64, small: f64, nu: usize, nv: usize) -> (Vec<Vec3>, Vec<[u32; 3]>, Vec<f64>) {
    let mut pos = Vec::new();
    let mut angle_v = Vec::new();
    for i in 0..nu {
        let u = 2.0 * PI * i as f64 / nu as f64;
        for j in 0..nv {
            let v = 2.0 * PI * j as f64 / nv as f64;
            let rho = big + small * v.cos();
            pos.push(DVec3::new(rho * u.cos(), rho * u.sin(), small * v.sin()).as_vec3());
            angle_v.push(v);
        }
    }
    let id = |i: usize, j: usize| ((i % nu) * nv + (j % nv)) as u32;
    let mut tris = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            // Counter-clockwise seen from outside (normal along +rho at v = 0).
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (pos, tris, angle_v)
}

#[test]
fn sphere_curvature_within_two_percent() {
    let radius = 2.0;
    let (pos, tris) = icosphere(5, radius);
    assert_eq!(pos.len(), 10_242);
    let mesh = Mesh::from_triangles(pos, tris).unwrap();
    assert!(mesh.report().is_closed_manifold());
    let (h_exact, k_exact) = (1.0 / radius, 1.0 / (radius * radius));
    let mut worst_h = 0.0f64;
    let mut worst_k = 0.0f64;
    for v in 0..mesh.positions().len() {
        worst_h = worst_h.max((mesh.mean_curvature()[v] - h_exact).abs() / h_exact);
        worst_k = worst_k.max((mesh.gaussian_curvature()[v] - k_exact).abs() / k_exact);
        // Outward, unit, radial normals.
        let radial = mesh.positions()[v].normalize();
        assert!(mesh.vertex_normals()[v].dot(radial) > 0.9999);
    }
    eprintln!("icosphere level 5: worst relative error H {worst_h:.2e}, K {worst_k:.2e}");
    assert!(worst_h < 0.02, "worst relative error of H = {worst_h}");
    assert!(worst_k < 0.02, "worst relative error of K = {worst_k}");
    // Mixed areas tile the surface; the discrete Gauss-Bonnet theorem holds exactly.
    let mixed: f64 = mesh.mixed_areas().iter().sum();
    assert!((mixed - mesh.total_area()).abs() < 1e-9 * mesh.total_area());
    let total_k: f64 = mesh.gaussian_curvature().iter().zip(mesh.mixed_areas()).map(|(k, a)| k * a).sum();
    assert!((total_k - 4.0 * PI).abs() < 1e-6, "sum K A = {total_k}");
    // The polyhedron's area approaches 4 pi R^2 from below.
    let exact_area = 4.0 * PI * radius * radius;
    assert!(mesh.total_area() < exact_area && mesh.total_area() > 0.995 * exact_area);
}

#[test]
fn inward_winding_flips_the_sign_of_mean_curvature() {
    let (pos, tris) = icosphere(3, 1.0);
    let flipped: Vec<[u32; 3]> = tris.iter().map(|t| [t[0], t[2], t[1]]).collect();
    let mesh = Mesh::from_triangles(pos, flipped).unwrap();
    assert!(mesh.mean_curvature().iter().all(|&h| h < -0.9 && h > -1.1));
    // Gaussian curvature does not depend on orientation.
    assert!(mesh.gaussian_curvature().iter().all(|&k| k > 0.9 && k < 1.1));
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |a, x| a.max(x.abs()))
}

#[test]
fn plane_curvature_is_zero_everywhere() {
    // In the z = 0 plane, with jittered interior vertices (irregular, some obtuse triangles): the
    // Laplacian has no normal component and the angles around each vertex sum to 2 pi, so both
    // curvatures vanish up to f64 rounding, boundary vertices included.
    let (pos, tris) = grid(60, 0.4, Mat4::IDENTITY);
    let mesh = Mesh::from_triangles(pos, tris).unwrap();
    let r = mesh.report();
    assert_eq!(r.boundary_edges, 4 * 59);
    assert_eq!(r.non_manifold_edges, 0);
    assert!((mesh.total_area() - 1.0).abs() < 1e-6);
    assert!(max_abs(mesh.mean_curvature()) < 1e-9, "max |H| = {}", max_abs(mesh.mean_curvature()));
    assert!(max_abs(mesh.gaussian_curvature()) < 1e-6, "max |K| = {}", max_abs(mesh.gaussian_curvature()));
    assert!(mesh.vertex_normals().iter().all(|n| (*n - Vec3::Z).length() < 1e-6));
    // Corners turn by pi/2, but that is the boundary's bending, not the surface's.
    let corner = (0..mesh.positions().len()).find(|&v| mesh.vertex_neighbours(v).len() == 2).unwrap();
    assert!(mesh.is_boundary_vertex(corner));
    assert!(mesh.gaussian_curvature()[corner].abs() < 1e-6);
}

#[test]
fn tilted_plane_curvature_is_zero_up_to_f32_rounding() {
    // Rotated about a skew axis and shifted: every f32 position is now rounded off the plane by
    // about 1e-7, which the curvature sees divided by the squared edge length (1/60)^2, so a few
    // 1e-4. Far below the curvature of anything the size of the plane (about 1).
    let m = Mat4::from_translation(Vec3::new(0.3, -0.2, 0.1))
        * Mat4::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7);
    let (pos, tris) = grid(60, 0.4, m);
    let mesh = Mesh::from_triangles(pos, tris).unwrap();
    let h = max_abs(mesh.mean_curvature());
    let k = max_abs(mesh.gaussian_curvature());
    eprintln!("tilted plane: max |H| {h:.2e}, max |K| {k:.2e}");
    assert!(h < 5e-3, "max |H| on a tilted plane = {h}");
    assert!(k < 5e-3, "max |K| on a tilted plane = {k}");
    let n = m.transform_vector3(Vec3::Z).normalize();
    assert!(mesh.vertex_normals().iter().all(|v| v.dot(n) > 0.99999));
}

#[test]
fn torus_curvature_follows_the_analytic_range() {
    let (big, small) = (3.0, 1.0);
    let (pos, tris, v) = torus(big, small, 240, 80);
    let mesh = Mesh::from_triangles(pos, tris).unwrap();
    assert!(mesh.report().is_closed_manifold());
    // K = cos v / (r (R + r cos v)), H = (R + 2 r cos v) / (2 r (R + r cos v)).
    let k_exact = |v: f64| v.cos() / (small * (big + small * v.cos()));
    let h_exact = |v: f64| (big + 2.0 * small * v.cos()) / (2.0 * small * (big + small * v.cos()));
    let (k_lo, k_hi) = (k_exact(PI), k_exact(0.0));
    let (h_lo, h_hi) = (h_exact(PI), h_exact(0.0));
    let k = mesh.gaussian_curvature();
    let h = mesh.mean_curvature();
    let mut worst_k = 0.0f64;
    let mut worst_h = 0.0f64;
    for i in 0..k.len() {
        worst_k = worst_k.max((k[i] - k_exact(v[i])).abs());
        worst_h = worst_h.max((h[i] - h_exact(v[i])).abs());
    }
    eprintln!(
        "torus: worst |K error| {worst_k:.2e} (range {k_lo:.3}..{k_hi:.3}), worst |H error| {worst_h:.2e} (range {h_lo:.3}..{h_hi:.3})"
    );
    // Errors measured against the spread of each quantity over the torus.
    assert!(worst_k < 0.02 * (k_hi - k_lo), "worst |K error| = {worst_k}, range {k_lo}..{k_hi}");
    assert!(worst_h < 0.02 * (h_hi - h_lo), "worst |H error| = {worst_h}, range {h_lo}..{h_hi}");
    let kmin = k.iter().copied().fold(f64::INFINITY, f64::min);
    let kmax = k.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    assert!((kmin - k_lo).abs() < 0.02 * (k_hi - k_lo) && (kmax - k_hi).abs() < 0.02 * (k_hi - k_lo));
    // Gauss-Bonnet for genus one: total curvature zero (exact for the angle defect).
    let total: f64 = k.iter().zip(mesh.mixed_areas()).map(|(k, a)| k * a).sum();
    assert!(total.abs() < 1e-6, "sum K A on a torus = {total}");
}

#[test]
fn angle_weighted_normals_ignore_how_faces_are_split() {
    // A unit cube whose faces are split along different diagonals: area-weighted normals would
    // lean towards the faces with more triangles at a corner, angle-weighted ones do not.
    let pos: Vec<Vec3> =
        (0..8).map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32)).collect();
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let mut tris = Vec::new();
    for (k, q) in quads.iter().enumerate() {
        if k % 2 == 0 {
            tris.push([q[0], q[1], q[2]]);
            tris.push([q[0], q[2], q[3]]);
        } else {
            tris.push([q[0], q[1], q[3]]);
            tris.push([q[1], q[2], q[3]]);
        }
    }
    let mesh = Mesh::from_triangles(pos.clone(), tris).unwrap();
    assert!(mesh.report().is_closed_manifold());
    for (v, n) in mesh.vertex_normals().iter().enumerate() {
        let expected = (pos[v] - Vec3::splat(0.5)).normalize();
        assert!(n.dot(expected) > 1.0 - 1e-6, "vertex {v}: {n} vs {expected}");
    }
    // Each corner's angle defect is pi/2: total 4 pi.
    let total: f64 = mesh.gaussian_curvature().iter().zip(mesh.mixed_areas()).map(|(k, a)| k * a).sum();
    assert!((total - 4.0 * PI).abs() < 1e-9);
    assert!((mesh.total_area() - 6.0).abs() < 1e-12);
}

/// Check that adjacency is symmetric and that neighbours share the edge's two vertices; returns
/// the number of triangle edges without a neighbour.
fn check_adjacency(mesh: &Mesh) -> usize {
    let tris = mesh.triangles();
    let mut open = 0;
    for (t, nb) in mesh.neighbours().iter().enumerate() {
        for e in 0..3 {
            let u = nb[e];
            if u == NO_NEIGHBOUR {
                open += 1;
                continue;
            }
            let (a, b) = (tris[t][e], tris[t][(e + 1) % 3]);
            let other = tris[u as usize];
            assert!(other.contains(&a) && other.contains(&b), "triangle {t} edge {e}");
            assert!(mesh.neighbours()[u as usize].contains(&(t as u32)));
        }
    }
    open
}

#[test]
fn edge_adjacency_is_symmetric_and_shares_vertices() {
    let mesh = load_asset("bunny-1.8k.obj");
    assert_eq!(check_adjacency(&mesh), 0);
    assert!(mesh.vertex_neighbours(0).windows(2).all(|w| w[0] < w[1]));

    // An icosphere with its top cap cut off: one boundary loop, as many edges as vertices on it.
    let (pos, tris) = icosphere(3, 1.0);
    let kept: Vec<[u32; 3]> = tris.into_iter().filter(|t| t.iter().all(|&i| pos[i as usize].z < 0.7)).collect();
    let open = Mesh::from_triangles(pos, kept).unwrap();
    let r = open.report();
    assert!(r.boundary_edges > 0 && r.non_manifold_edges == 0);
    assert_eq!(check_adjacency(&open), r.boundary_edges);
    let boundary_vertices = (0..open.positions().len()).filter(|&v| open.is_boundary_vertex(v)).count();
    assert_eq!(boundary_vertices, r.boundary_edges);
    // Boundary vertices borrow the interior's curvature: still close to the unit sphere's.
    for v in (0..open.positions().len()).filter(|&v| open.is_boundary_vertex(v)) {
        assert!((open.mean_curvature()[v] - 1.0).abs() < 0.05, "H = {}", open.mean_curvature()[v]);
        assert!((open.gaussian_curvature()[v] - 1.0).abs() < 0.05, "K = {}", open.gaussian_curvature()[v]);
    }
}

#[test]
fn bunnies_load_with_their_documented_sizes() {
    let big = load_asset("bunny-37k.obj");
    assert_eq!(big.positions().len(), 37_706);
    assert_eq!(big.triangles().len(), 75_408);
    assert!(big.report().is_closed_manifold(), "{:?}", big.report());
    // Outward orientation: the area-weighted mean curvature of a closed surface is positive.
    let mean_h: f64 = big.mean_curvature().iter().zip(big.mixed_areas()).map(|(h, a)| h * a).sum();
    assert!(mean_h > 0.0);
    // A closed genus-0 surface: total Gaussian curvature 4 pi.
    let total_k: f64 = big.gaussian_curvature().iter().zip(big.mixed_areas()).map(|(k, a)| k * a).sum();
    assert!((total_k - 4.0 * PI).abs() < 1e-6, "sum K A = {total_k}");
    assert!(big.vertex_normals().iter().all(|n| (n.length() - 1.0).abs() < 1e-5));

    let small = load_asset("bunny-1.8k.obj");
    // Closed after all (Euler characteristic 1,839 - 5,511 + 3,674 = 2), the base included.
    assert_eq!(small.positions().len(), 1_839);
    assert_eq!(small.triangles().len(), 3_674);
    assert!(small.report().is_closed_manifold(), "{:?}", small.report());
}

// ---------------------------------------------------------------------------------------------
// Clean-up and placement

#[test]
fn zero_area_triangles_are_dropped_and_counted() {
    let pos = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(2.0, 0.0, 0.0), // collinear with 0 and 1
        Vec3::new(5.0, 5.0, 5.0), // used only by a degenerate triangle
    ];
    let tris = vec![[0, 1, 2], [1, 3, 2], [0, 1, 4], [2, 2, 3], [5, 5, 5]];
    let mesh = Mesh::from_triangles(pos, tris).unwrap();
    let r = mesh.report();
    assert_eq!(r.degenerate_triangles, 3);
    assert_eq!(mesh.triangles().len(), 2);
    assert_eq!(r.unreferenced_vertices, 2);
    assert_eq!(mesh.positions().len(), 4);
    assert!((mesh.total_area() - 1.0).abs() < 1e-12);
}

#[test]
fn all_degenerate_is_a_no_area_error() {
    let pos = vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
    let err = Mesh::from_triangles(pos, vec![[0, 1, 2], [0, 0, 1]]).unwrap_err();
    assert!(matches!(err, MeshError::NoArea { degenerate: 2, .. }), "{err}");
    assert!(err.to_string().contains("no area"));
}

#[test]
fn non_manifold_and_boundary_edges_are_reported() {
    // Three triangles on one edge (0, 1): a fin.
    let pos = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z, Vec3::new(0.5, -1.0, 0.3)];
    let mesh = Mesh::from_triangles(pos, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap();
    let r = mesh.report();
    assert_eq!(r.non_manifold_edges, 1);
    assert_eq!(r.boundary_edges, 6);
    assert!(mesh.neighbours().iter().all(|n| n.iter().all(|&x| x == NO_NEIGHBOUR)));
    assert!(mesh.mean_curvature().iter().all(|h| h.is_finite()));
}

#[test]
fn inconsistent_winding_is_reported() {
    let pos = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)];
    let mesh = Mesh::from_triangles(pos, vec![[0, 1, 2], [1, 2, 3]]).unwrap();
    assert_eq!(mesh.report().inconsistently_oriented_edges, 1);
}

#[test]
fn memory_meshes_are_validated() {
    let err =
        Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::new(f32::NAN, 0.0, 0.0)], vec![[0, 1, 2]]).unwrap_err();
    assert!(matches!(err, MeshError::NonFinite { vertex: 2, .. }), "{err}");
    let err = Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 3]]).unwrap_err();
    assert!(matches!(err, MeshError::IndexOutOfRange { index: 3, count: 3, .. }), "{err}");
    let err = Mesh::from_triangles(vec![Vec3::ZERO], vec![]).unwrap_err();
    assert!(matches!(err, MeshError::NoFaces { .. }), "{err}");
}

// ---------------------------------------------------------------------------------------------
// OBJ files

fn write_obj(dir: &std::path::Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

const TETRA: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";

#[test]
fn obj_tetrahedron_loads_closed() {
    let dir = temp_dir("tetra");
    let mesh = Mesh::load(write_obj(&dir, "t.obj", TETRA), &LoadOptions::default()).unwrap();
    assert_eq!(mesh.triangles().len(), 4);
    assert!(mesh.report().is_closed_manifold());
    let exact = 1.5 + 3f64.sqrt() / 2.0;
    assert!((mesh.total_area() - exact).abs() < 1e-6);
}

#[test]
fn obj_polygons_are_triangulated_and_split_vertices_welded() {
    let dir = temp_dir("quads");
    // A cube of quads, with a distinct normal index per face: tobj's single index splits every
    // corner into three vertices, which the loader welds back.
    let mut text = String::from("o cube\n");
    for i in 0..8 {
        text += &format!("v {} {} {}\n", i & 1, (i >> 1) & 1, (i >> 2) & 1);
    }
    text += "vn 0 0 -1\nvn 0 0 1\nvn 0 -1 0\nvn 0 1 0\nvn -1 0 0\nvn 1 0 0\n";
    let quads = [[1, 3, 4, 2], [5, 6, 8, 7], [1, 2, 6, 5], [3, 7, 8, 4], [1, 5, 7, 3], [2, 4, 8, 6]];
    for (k, q) in quads.iter().enumerate() {
        text += &format!("f {}//{} {}//{} {}//{} {}//{}\n", q[0], k + 1, q[1], k + 1, q[2], k + 1, q[3], k + 1);
    }
    let mesh = Mesh::load(write_obj(&dir, "cube.obj", &text), &LoadOptions::default()).unwrap();
    assert_eq!(mesh.triangles().len(), 12);
    assert_eq!(mesh.positions().len(), 8);
    assert!(mesh.report().welded_vertices >= 16, "{:?}", mesh.report());
    assert!(mesh.report().is_closed_manifold(), "{:?}", mesh.report());
    assert!((mesh.total_area() - 6.0).abs() < 1e-9);
}

#[test]
fn obj_scale_and_mirroring_transform() {
    let dir = temp_dir("scale");
    let path = write_obj(&dir, "t.obj", TETRA);
    let base = Mesh::load(&path, &LoadOptions::default()).unwrap();
    let scaled = Mesh::load(&path, &LoadOptions::default().with_scale(2.0)).unwrap();
    assert!((scaled.total_area() - 4.0 * base.total_area()).abs() < 1e-9);
    // A mirror keeps normals pointing out of the solid.
    let mirror =
        Mesh::load(&path, &LoadOptions::default().with_transform(Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)))).unwrap();
    let centre = mirror.positions().iter().copied().sum::<Vec3>() / 4.0;
    for (t, tri) in mirror.triangles().iter().enumerate() {
        let c = tri.iter().map(|&i| mirror.positions()[i as usize]).sum::<Vec3>() / 3.0;
        assert!(mirror.face_normals()[t].dot(c - centre) > 0.0);
    }
    let err = Mesh::load(&path, &LoadOptions::default().with_scale(0.0)).unwrap_err();
    assert!(matches!(err, MeshError::InvalidOptions(_)), "{err}");
    let err = Mesh::load(&path, &LoadOptions::default().with_transform(Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0))))
        .unwrap_err();
    assert!(matches!(err, MeshError::InvalidOptions(_)), "{err}");
}

#[test]
fn missing_file_error_names_the_path() {
    let path = temp_dir("missing").join("no-such-mesh.obj");
    let err = Mesh::load(&path, &LoadOptions::default()).unwrap_err();
    assert!(matches!(err, MeshError::Io { .. }));
    assert!(err.to_string().contains("no-such-mesh.obj"), "{err}");
}

/// Load `text` as an OBJ and return the parse error's line and message.
fn parse_failure(test: &str, text: &str) -> (usize, String) {
    let dir = temp_dir(test);
    let path = write_obj(&dir, "bad.obj", text);
    match Mesh::load(&path, &LoadOptions::default()) {
        Err(err @ MeshError::Parse { line, .. }) => {
            let msg = err.to_string();
            assert!(msg.contains("bad.obj"), "message should name the file: {msg}");
            assert!(msg.contains(&format!(":{line}:")), "message should name the line: {msg}");
            (line, msg)
        }
        other => panic!("expected a parse error, got {other:?}"),
    }
}

#[test]
fn malformed_vertex_lines_report_their_line() {
    let (line, msg) = parse_failure("v-text", "# a comment\nv 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n");
    assert_eq!(line, 3);
    assert!(msg.contains("zero"), "{msg}");
    let (line, _) = parse_failure("v-short", "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n");
    assert_eq!(line, 2);
    let (line, _) = parse_failure("w-zero", "v 0 0 0\nv 1 0 0\nv 0 1 0 0\nf 1 2 3\n");
    assert_eq!(line, 3);
    let (line, _) = parse_failure("vn-bad", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 x 1\nf 1 2 3\n");
    assert_eq!(line, 4);
}

#[test]
fn non_finite_coordinates_report_their_line() {
    let (line, msg) = parse_failure("nan", "v 0 0 0\nv 1 0 0\nv NaN 1 0\nf 1 2 3\n");
    assert_eq!(line, 3);
    assert!(msg.contains("NaN"), "{msg}");
    let (line, _) = parse_failure("inf", "v 0 0 0\nv 1 0 inf\nv 0 1 0\nf 1 2 3\n");
    assert_eq!(line, 2);
    // Finite in f64 but not in f32.
    let (line, _) = parse_failure("huge", "v 0 0 0\nv 1 0 0\nv 0 1e39 0\nf 1 2 3\n");
    assert_eq!(line, 3);
}

#[test]
fn bad_face_indices_report_their_line() {
    let (line, msg) = parse_failure("oob", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 7\n");
    assert_eq!(line, 5);
    assert!(msg.contains('7') && msg.contains("out of range"), "{msg}");
    let (line, _) = parse_failure("zero", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
    assert_eq!(line, 4);
    let (line, _) = parse_failure("neg", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n");
    assert_eq!(line, 4);
    let (line, _) = parse_failure("word", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 three\n");
    assert_eq!(line, 4);
    let (line, msg) = parse_failure("two", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n");
    assert_eq!(line, 4);
    assert!(msg.contains("at least 3"), "{msg}");
    let (line, _) = parse_failure("vt-oob", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n");
    assert_eq!(line, 5);
}

#[test]
fn parse_errors_are_typed() {
    use translucent::mesh::{Element, ObjProblem};
    let problem = |text: &str| match Mesh::from_obj_text(text, "m.obj", &LoadOptions::default()) {
        Err(MeshError::Parse { problem, .. }) => problem,
        other => panic!("expected a parse error, got {other:?}"),
    };
    let defined = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    assert_eq!(
        problem(&format!("{defined}f 1 2 7\n")),
        ObjProblem::OutOfRange { element: Element::Vertex, index: 7, defined: 3 }
    );
    assert_eq!(
        problem(&format!("{defined}vn 0 0 1\nf 1//-2 2 3\n")),
        ObjProblem::BeforeFirst { element: Element::Normal, index: -2, defined: 1 }
    );
    assert_eq!(
        problem("vt 1\n"),
        ObjProblem::TooFewNumbers { element: Element::TextureCoordinate, needed: 2, found: 1 }
    );
    assert_eq!(problem("v 0 1e39 0\n"), ObjProblem::NotFinite("1e39".into()));
    assert_eq!(problem(&format!("{defined}f 1 2\n")), ObjProblem::TooFewFaceVertices(2));
}

#[test]
fn relative_and_forward_indices_are_accepted() {
    let dir = temp_dir("relative");
    // Negative indices count back from the latest vertex; positive ones may point forward.
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nf 1 3 4\nv 0 0 1\n";
    let mesh = Mesh::load(write_obj(&dir, "rel.obj", text), &LoadOptions::default()).unwrap();
    assert_eq!(mesh.triangles().len(), 2);
}

#[test]
fn files_without_faces_or_area_are_errors() {
    let dir = temp_dir("empty");
    for (name, text) in
        [("empty.obj", ""), ("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"), ("lines.obj", "v 0 0 0\nv 1 0 0\nl 1 2\n")]
    {
        let err = Mesh::load(write_obj(&dir, name, text), &LoadOptions::default()).unwrap_err();
        assert!(matches!(err, MeshError::NoFaces { .. }), "{name}: {err}");
        assert!(err.to_string().contains(name), "{err}");
    }
    let err = Mesh::load(write_obj(&dir, "flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"), &LoadOptions::default())
        .unwrap_err();
    assert!(matches!(err, MeshError::NoArea { .. }), "{err}");
    assert!(err.to_string().contains("flat.obj"));
}

#[test]
fn each_level_of_detail_halves_the_triangles_of_the_last_and_keeps_a_subset_of_its_vertices() {
    let mesh = load_asset("bunny-1.8k.obj");
    let levels = mesh.levels_of_detail();
    assert!(levels.len() >= 3, "{} levels", levels.len());
    assert_eq!(levels[0].triangles, mesh.triangles(), "level 0 is the mesh itself");
    assert_eq!(levels[0].error, 0.0);
    for pair in levels.windows(2) {
        let (finer, coarser) = (&pair[0], &pair[1]);
        let share = coarser.triangles.len() as f64 / finer.triangles.len() as f64;
        assert!((0.4..=0.8).contains(&share), "{share}");
        // Made of the finer level's vertices: values there carry over unchanged.
        assert!(coarser.vertices.iter().all(|v| finer.vertices.binary_search(v).is_ok()));
        assert!(coarser.triangles.iter().flatten().all(|v| coarser.vertices.binary_search(v).is_ok()));
        assert!(coarser.error >= finer.error && coarser.mean_edge > finer.mean_edge);
        assert!(!coarser.locked);
    }
    assert!(levels.last().unwrap().triangles.len() >= translucent::mesh::MIN_LEVEL_TRIANGLES / 2);
}

#[test]
fn a_flat_grid_is_simplified_only_where_its_vertex_values_do_not_vary() {
    let (positions, triangles) = grid(41, 0.0, Mat4::IDENTITY);
    let mesh = Mesh::from_triangles(positions, triangles).unwrap();
    // A soft dip in one corner (a shadow), flat elsewhere.
    let values: Vec<[f32; 3]> = mesh
        .positions()
        .iter()
        .map(|p| {
            let d = p.truncate().distance(glam::Vec2::new(0.2, 0.2));
            [1.0 - 0.5 * (-d * d / 0.01).exp(); 3]
        })
        .collect();
    let locked = mesh.locks_where_varying(&values, 0.002);
    let count = locked.iter().filter(|&&l| l).count();
    assert!(count > 20 && count < mesh.positions().len() / 2, "{count} locked");
    // A vertex far from the dip is free, one in it is locked.
    let near = |x: f32, y: f32| {
        (0..mesh.positions().len())
            .min_by(|&a, &b| {
                let d = |v: usize| mesh.positions()[v].truncate().distance(glam::Vec2::new(x, y));
                d(a).total_cmp(&d(b))
            })
            .unwrap()
    };
    assert!(locked[near(0.2, 0.2)] && !locked[near(0.5, 0.9)]);
    let levels = mesh.levels_of_detail_locked(&locked);
    let last = levels.last().unwrap();
    assert!(levels.len() > 1 && last.locked);
    assert!(last.triangles.len() * 2 < mesh.triangles().len(), "{} triangles left", last.triangles.len());
    for (v, _) in locked.iter().enumerate().filter(|(_, l)| **l) {
        assert!(last.vertices.binary_search(&(v as u32)).is_ok(), "locked vertex {v} was removed");
    }
    // Flat: the simplifier's error bound stays far under a pixel of anything that shows a
    // unit grid (it bounds more than the distance from the plane, which is zero).
    assert!(last.error < 1e-3, "{}", last.error);
}

// ---------------------------------------------------------------------------------------------
// The file's own normals (OBJ `vn`, glTF `NORMAL`)

/// A unit square in x and z, two triangles, every corner with the normal `n`, as OBJ text.
fn square_with_normals(n: [f32; 3]) -> String {
    format!("v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nvn {} {} {}\nf 1//1 3//1 2//1\nf 1//1 4//1 3//1\n", n[0], n[1], n[2])
}

#[test]
fn a_files_normals_are_the_meshs_vertex_normals_and_turn_with_its_placement() {
    let tilted = Vec3::new(0.0, 0.8, 0.6);
    let mesh =
        Mesh::from_obj_text(&square_with_normals([0.0, 1.6, 1.2]), "square.obj", &LoadOptions::default()).unwrap();
    for n in mesh.vertex_normals() {
        assert!((*n - tilted).length() < 1e-6, "{n}");
    }
    // Without `vn` the normals come from the face: straight up.
    let plain = "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 3 2\nf 1 4 3\n";
    let flat = Mesh::from_obj_text(plain, "plain.obj", &LoadOptions::default()).unwrap();
    assert!(flat.vertex_normals().iter().all(|n| (*n - Vec3::Y).length() < 1e-6), "{:?}", flat.vertex_normals());
    // Placed turned a quarter about x, the file's normal turns with it.
    let placed = mesh.transformed(Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2)).unwrap();
    let turned = Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2).transform_vector3(tilted);
    for n in placed.vertex_normals() {
        assert!((*n - turned).length() < 1e-5, "{n} against {turned}");
    }
    // Loaded mirrored: the winding swaps and the normal mirrors with the surface.
    let mirror = LoadOptions { transform: Mat4::from_scale(Vec3::new(1.0, -1.0, 1.0)), ..LoadOptions::default() };
    let mirrored = Mesh::from_obj_text(&square_with_normals([0.0, 1.6, 1.2]), "square.obj", &mirror).unwrap();
    for n in mirrored.vertex_normals() {
        assert!((*n - Vec3::new(0.0, -0.8, 0.6)).length() < 1e-6, "{n}");
    }
}

#[test]
fn a_glb_primitives_normals_are_read_through_its_nodes_transform() {
    let positions = [[0.0f32, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]];
    let normals = [[0.0f32, 1.0, 0.0]; 3];
    // The node turns the triangle a quarter about z: +y becomes -x.
    let sin_cos_45 = std::f32::consts::FRAC_1_SQRT_2; // a quarter turn's quaternion components
    let node = serde_json::json!({"mesh": 0, "rotation": [0.0, 0.0, sin_cos_45, sin_cos_45]});
    let glb = common::triangle_glb(positions, "NORMAL", "VEC3", normals.as_flattened(), node);
    let mesh = Mesh::from_gltf_slice(&glb, "normals.glb", None, &LoadOptions::default()).unwrap();
    for n in mesh.vertex_normals() {
        assert!((*n - Vec3::NEG_X).length() < 1e-5, "{n}");
    }
}
