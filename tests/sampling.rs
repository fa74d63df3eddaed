//! Sample placement and area weights: counts, points on the surface, determinism, spacing,
//! curvature-following density, unbiased integrals, hard inputs, and the `translucent sample`
//! command.

mod common;

use common::{asset, load_asset, temp_dir};
use std::collections::BTreeSet;
use std::path::Path;
use std::sync::OnceLock;

use glam::{DVec3, Mat4, Vec3};
use translucent::mesh::{Mesh, MeshError};
use translucent::sampling::feature::{feature_point_count, feature_points};
use translucent::sampling::walk::walk;
use translucent::sampling::weights::{WeightParams, area_weights};
use translucent::sampling::{
    MAX_COUNT, Method, SampleOptions, SampleSet, SamplingError, SpatialHash, SurfacePoint, nearest_neighbour_distances,
    sample,
};

fn bunny() -> &'static Mesh {
    static MESH: OnceLock<Mesh> = OnceLock::new();
    MESH.get_or_init(|| load_asset("bunny-37k.obj"))
}

fn small_bunny() -> &'static Mesh {
    static MESH: OnceLock<Mesh> = OnceLock::new();
    MESH.get_or_init(|| load_asset("bunny-1.8k.obj"))
}

fn run(mesh: &Mesh, method: Method, n: usize, seed: u64) -> SampleSet {
    sample(mesh, &SampleOptions::new(method, n).with_seed(seed)).unwrap_or_else(|e| panic!("{method} N={n}: {e}"))
}

/// Distance from `p` to the triangle `abc` (closest point by region tests, after Ericson,
/// Real-Time Collision Detection, 5.1.5).
fn point_triangle_distance(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return p.distance(a);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return p.distance(b);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return p.distance(a + ab * (d1 / (d1 - d3)));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return p.distance(c);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return p.distance(a + ac * (d2 / (d2 - d6)));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return p.distance(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
    }
    let denom = 1.0 / (va + vb + vc);
    p.distance(a + ab * (vb * denom) + ac * (vc * denom))
}

/// Every property a sample set must have on any mesh.
fn check_set(mesh: &Mesh, set: &SampleSet, n: usize) {
    assert_eq!(set.len(), n, "{}: count", set.method);
    let tol = 1e-5 * mesh.diagonal();
    for (i, p) in set.points.iter().enumerate() {
        let t = p.triangle as usize;
        assert!(t < mesh.triangles().len());
        let [a, b, c] = mesh.corners(t);
        let d = point_triangle_distance(p.position.as_dvec3(), a, b, c);
        assert!(d < tol, "{} point {i} is {d} from its triangle", set.method);
        let bsum: f32 = p.barycentric.iter().sum();
        assert!(p.barycentric.iter().all(|&w| w >= 0.0) && (bsum - 1.0).abs() < 1e-5);
        assert!((p.normal.length() - 1.0).abs() < 1e-5, "{} point {i}: normal {}", set.method, p.normal);
        assert!(p.area >= 0.0 && p.area.is_finite());
    }
    let total = set.total_area();
    assert!(
        (total - mesh.total_area()).abs() <= 1e-6 * mesh.total_area(),
        "{}: weights sum to {total}, area {}",
        set.method,
        mesh.total_area()
    );
}

// ---------------------------------------------------------------------------------------------
// Properties of every sampler

#[test]
fn every_method_gives_exactly_n_points_on_the_surface() {
    for method in Method::ALL {
        for n in [1, 2, 7, 400] {
            check_set(small_bunny(), &run(small_bunny(), method, n, 3), n);
        }
        check_set(bunny(), &run(bunny(), method, 400, 0), 400);
    }
}

#[test]
fn same_seed_same_points_other_seed_other_points() {
    for method in Method::ALL {
        let a = run(small_bunny(), method, 300, 11);
        let b = run(small_bunny(), method, 300, 11);
        let c = run(small_bunny(), method, 300, 12);
        assert_eq!(a, b, "{method}: same seed");
        assert_ne!(a.positions(), c.positions(), "{method}: different seeds");
    }
}

fn min_nn(set: &SampleSet) -> f64 {
    nearest_neighbour_distances(&set.positions()).into_iter().fold(f64::INFINITY, f64::min)
}

#[test]
fn turk_and_poisson_raise_the_minimum_spacing_over_random() {
    for seed in 0..3 {
        let random = min_nn(&run(bunny(), Method::Random, 400, seed));
        let turk = min_nn(&run(bunny(), Method::Turk, 400, seed));
        let poisson = min_nn(&run(bunny(), Method::Poisson, 400, seed));
        eprintln!(
            "seed {seed}: min nearest-neighbour distance random {random:.4}, turk {turk:.4}, poisson {poisson:.4}"
        );
        assert!(turk > 2.0 * random, "seed {seed}: turk {turk} vs random {random}");
        assert!(poisson > 2.0 * random, "seed {seed}: poisson {poisson} vs random {random}");
    }
}

/// Points per unit area in the quarter of the surface (by area) with the highest |H| (the
/// mesh's own per-vertex mean curvature, averaged per triangle), over the same in the rest.
fn high_curvature_density_ratio(mesh: &Mesh, set: &SampleSet) -> f64 {
    let h = mesh.mean_curvature();
    let tri_h: Vec<f64> =
        mesh.triangles().iter().map(|t| t.iter().map(|&v| h[v as usize].abs()).sum::<f64>()).collect();
    let mut order: Vec<usize> = (0..tri_h.len()).collect();
    order.sort_by(|&a, &b| tri_h[b].total_cmp(&tri_h[a]));
    let mut high = vec![false; tri_h.len()];
    let mut area = 0.0;
    for &t in &order {
        if area >= 0.25 * mesh.total_area() {
            break;
        }
        high[t] = true;
        area += mesh.triangle_areas()[t];
    }
    let inside = set.points.iter().filter(|p| high[p.triangle as usize]).count() as f64;
    let outside = set.len() as f64 - inside;
    (inside / area) / (outside / (mesh.total_area() - area))
}

#[test]
fn feature_puts_more_points_where_curvature_is_high() {
    for seed in 0..2 {
        let random = high_curvature_density_ratio(bunny(), &run(bunny(), Method::Random, 1000, seed));
        let feature = high_curvature_density_ratio(bunny(), &run(bunny(), Method::Feature, 1000, seed));
        eprintln!("seed {seed}: density ratio high-|H| / rest: random {random:.3}, feature {feature:.3}");
        assert!(feature > 1.3 * random, "seed {seed}: feature {feature} vs random {random}");
    }
}

/// f(p) = (p - lo) . (1, 2, 3): linear, positive, and not dominated by a constant.
fn linear(mesh: &Mesh) -> impl Fn(DVec3) -> f64 {
    let lo = mesh.bounds().0.as_dvec3();
    move |p| (p - lo).dot(DVec3::new(1.0, 2.0, 3.0))
}

/// The integral of a linear function over a triangle is its area times the value at the centroid.
fn exact_integral(mesh: &Mesh, f: &impl Fn(DVec3) -> f64) -> f64 {
    (0..mesh.triangles().len()).map(|t| mesh.triangle_areas()[t] * f(mesh.point(t, [1.0 / 3.0; 3]))).sum()
}

#[test]
fn weighted_sums_integrate_a_linear_function_within_one_percent() {
    let mesh = bunny();
    let f = linear(mesh);
    let exact = exact_integral(mesh, &f);
    for method in Method::ALL {
        for seed in 0..3 {
            let set = run(mesh, method, 400, seed);
            let estimate: f64 = set.points.iter().map(|p| p.area * f(p.position.as_dvec3())).sum();
            let err = (estimate - exact).abs() / exact;
            eprintln!("{method} seed {seed}: relative error {err:.2e}");
            assert!(err < 0.01, "{method} seed {seed}: relative error {err}");
        }
    }
}

#[test]
fn density_following_weights_beat_equal_weights_when_density_varies() {
    // The feature sampler's density varies by design, so A/N per point is biased; the
    // nearest-sample weights are not.
    let mesh = bunny();
    let f = linear(mesh);
    let exact = exact_integral(mesh, &f);
    let set = run(mesh, Method::Feature, 400, 0);
    let voronoi: f64 = set.points.iter().map(|p| p.area * f(p.position.as_dvec3())).sum();
    let equal: f64 = set.points.iter().map(|p| mesh.total_area() / 400.0 * f(p.position.as_dvec3())).sum();
    let (ev, ee) = ((voronoi - exact).abs() / exact, (equal - exact).abs() / exact);
    eprintln!("feature, N = 400: relative error with nearest-sample weights {ev:.2e}, with A/N {ee:.2e}");
    assert!(ev < 0.25 * ee, "{ev} vs {ee}");
    // Weights vary with spacing: the weight spread of feature exceeds that of turk.
    let cv = |s: &SampleSet| {
        let m = s.total_area() / s.len() as f64;
        (s.points.iter().map(|p| (p.area - m).powi(2)).sum::<f64>() / s.len() as f64).sqrt() / m
    };
    assert!(cv(&set) > cv(&run(mesh, Method::Turk, 400, 0)));
}

// ---------------------------------------------------------------------------------------------
// Area weights, the spatial hash and surface walking, on configurations with known answers

fn unit_square() -> Mesh {
    let pos = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
    Mesh::from_triangles(pos, vec![[0, 1, 2], [0, 2, 3]]).unwrap()
}

/// The surface point of the unit square at (x, y).
fn on_square(x: f64, y: f64) -> SurfacePoint {
    // Triangle 0 is (0,0) (1,0) (1,1), below the diagonal; triangle 1 is (0,0) (1,1) (0,1).
    if y <= x {
        SurfacePoint { triangle: 0, bary: [1.0 - x, x - y, y] }
    } else {
        SurfacePoint { triangle: 1, bary: [1.0 - y, x, y - x] }
    }
}

#[test]
fn weights_are_the_areas_of_the_nearest_sample_cells() {
    let mesh = unit_square();
    // Cells split at x = 0.2 and x = 0.55: areas 0.2, 0.35 and 0.45.
    let pts = [on_square(0.1, 0.5), on_square(0.3, 0.5), on_square(0.8, 0.5)];
    let w = area_weights(&mesh, &pts, &WeightParams::default());
    for (got, want) in w.iter().zip([0.2, 0.35, 0.45]) {
        assert!((got - want).abs() < 5e-3, "{w:?}");
    }
    // Quadrant centres own a quarter each, wherever the diagonal splits the triangles.
    let quads = [on_square(0.25, 0.25), on_square(0.75, 0.25), on_square(0.25, 0.75), on_square(0.75, 0.75)];
    let q = area_weights(&mesh, &quads, &WeightParams::default());
    assert!(q.iter().all(|&a| (a - 0.25).abs() < 5e-3), "{q:?}");
    assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
}

#[test]
fn spatial_hash_agrees_with_brute_force() {
    let mut state = 99u64;
    let mut rnd = || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    // A dense cluster, a sparse cloud and far outliers, including negative coordinates.
    let mut pts: Vec<DVec3> = (0..400).map(|_| DVec3::new(rnd(), rnd(), rnd()) * 0.1).collect();
    pts.extend((0..300).map(|_| DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 4.0));
    pts.push(DVec3::new(50.0, -30.0, 7.0));
    let hash = SpatialHash::new(&pts, 0.05);
    for q in (0..60).map(|i| pts[i * 11] + DVec3::new(0.01, -0.02, 0.005)) {
        // A radius near the cell size walks the cells; a large one falls back to a scan.
        for radius in [0.06, 0.3] {
            let mut got = BTreeSet::new();
            hash.for_each_within(q, radius, |i, _| {
                assert!(got.insert(i), "point {i} visited twice");
            });
            let want: BTreeSet<u32> =
                (0..pts.len() as u32).filter(|&i| pts[i as usize].distance(q) <= radius).collect();
            assert_eq!(got, want);
        }
        let (near, d) = hash.nearest(q, None).unwrap();
        let brute = pts.iter().map(|p| p.distance(q)).fold(f64::INFINITY, f64::min);
        assert!((d - brute).abs() < 1e-12 && (pts[near as usize].distance(q) - brute).abs() < 1e-12);
    }
    // The outlier's nearest other point is far away, across many empty cells.
    let (_, d) = hash.nearest(pts[700], Some(700)).unwrap();
    let brute = pts[..700].iter().map(|p| p.distance(pts[700])).fold(f64::INFINITY, f64::min);
    assert!((d - brute).abs() < 1e-12);
}

#[test]
fn walking_follows_the_surface_across_edges() {
    // Flat: the walk ends where a straight line ends, across many triangles.
    let (pos, tris) = common::grid(12, 0.0, Mat4::IDENTITY);
    let grid = Mesh::from_triangles(pos, tris).unwrap();
    let start = SurfacePoint { triangle: 0, bary: [0.6, 0.3, 0.1] };
    let p0 = start.position(&grid);
    let d = DVec3::new(0.61, 0.37, 0.25); // the z part is off the surface and is dropped
    let end = walk(&grid, start, d);
    assert!(end.position(&grid).distance(p0 + DVec3::new(0.61, 0.37, 0.0)) < 1e-9);

    // Folded: from the middle of a cube's top face over an edge and down the side.
    let cube_pos: Vec<Vec3> =
        (0..8).map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32)).collect();
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let cube_tris: Vec<[u32; 3]> = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
    let cube = Mesh::from_triangles(cube_pos, cube_tris).unwrap();
    // Triangle 2 is the top face's (4, 5, 7): the point (0.6, 0.4, 1).
    let top = SurfacePoint { triangle: 2, bary: [0.4, 0.2, 0.4] };
    assert!(top.position(&cube).distance(DVec3::new(0.6, 0.4, 1.0)) < 1e-12);
    let end = walk(&cube, top, DVec3::new(0.7, 0.0, 0.0));
    assert!(end.position(&cube).distance(DVec3::new(1.0, 0.4, 0.7)) < 1e-9, "{}", end.position(&cube));

    // Open boundary: the point stops on the edge and keeps only the along-edge motion.
    let tri = Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap();
    let inside = SurfacePoint { triangle: 0, bary: [0.6, 0.2, 0.2] };
    let end = walk(&tri, inside, DVec3::new(0.1, -0.5, 0.0));
    let p = end.position(&tri);
    assert!(p.y.abs() < 1e-12 && p.x > 0.2 && p.x <= 0.3 + 1e-12, "{p}");
}

// ---------------------------------------------------------------------------------------------
// The paper's Algorithm 1

#[test]
fn algorithm_1_places_2n_points_in_distinct_top_triangles() {
    let mesh = bunny();
    assert_eq!(feature_point_count(mesh, 400, 0.5), 200);
    assert_eq!(feature_point_count(mesh, 1, 0.5), 0);
    let pts = feature_points(mesh, 200);
    assert_eq!(pts.len(), 200);
    let tris: BTreeSet<u32> = pts.iter().map(|p| p.triangle).collect();
    assert_eq!(tris.len(), 200, "2n distinct triangles");

    let h: Vec<f64> = mesh.mean_curvature().iter().map(|h| h.abs()).collect();
    let curv = |t: u32| mesh.triangles()[t as usize].iter().map(|&v| h[v as usize]).sum::<f64>() / 3.0;
    let chosen_curv: BTreeSet<u32> = pts[..100].iter().map(|p| p.triangle).collect();
    let weakest_chosen = chosen_curv.iter().map(|&t| curv(t)).fold(f64::INFINITY, f64::min);
    let strongest_other =
        (0..mesh.triangles().len() as u32).filter(|t| !chosen_curv.contains(t)).map(curv).fold(0.0, f64::max);
    assert!(weakest_chosen >= strongest_other, "first n are the n most curved triangles");
    let area = |t: u32| mesh.triangle_areas()[t as usize];
    let smallest_chosen = pts[100..].iter().map(|p| area(p.triangle)).fold(f64::INFINITY, f64::min);
    let largest_other = (0..mesh.triangles().len() as u32).filter(|t| !tris.contains(t)).map(area).fold(0.0, f64::max);
    assert!(smallest_chosen >= largest_other, "next n are the largest remaining triangles");

    for p in &pts {
        // Eq. 12 with |H| weights, blended with 5% of the centroid: inside the triangle.
        let w = mesh.triangles()[p.triangle as usize].map(|v| h[v as usize]);
        let s: f64 = w.iter().sum();
        for (k, wk) in w.iter().enumerate() {
            let want = 0.95 * wk / s + 0.05 / 3.0;
            assert!((p.bary[k] - want).abs() < 1e-12);
            assert!(p.bary[k] > 0.0);
        }
    }
}

#[test]
fn algorithm_1_falls_back_to_the_centroid_on_flat_ground() {
    let n = 10;
    let mut pos = Vec::new();
    for i in 0..n {
        for j in 0..n {
            pos.push(Vec3::new(i as f32, j as f32, 0.0));
        }
    }
    let mut tris = Vec::new();
    for i in 0..n - 1 {
        for j in 0..n - 1 {
            let id = |a: usize, b: usize| (a * n + b) as u32;
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let plane = Mesh::from_triangles(pos, tris).unwrap();
    assert!(plane.mean_curvature().iter().all(|&h| h.abs() < 1e-12));
    for p in feature_points(&plane, 20) {
        assert!(p.bary.iter().all(|&b| (b - 1.0 / 3.0).abs() < 1e-12), "{p:?}");
    }
    check_set(&plane, &run(&plane, Method::Feature, 150, 1), 150);
}

// ---------------------------------------------------------------------------------------------
// Hard inputs

#[test]
fn one_triangle_many_points_and_one_point() {
    let tri =
        Mesh::from_triangles(vec![Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.5)], vec![[0, 1, 2]])
            .unwrap();
    for method in Method::ALL {
        for n in [1, 3, 200] {
            let set = run(&tri, method, n, 5);
            check_set(&tri, &set, n);
        }
        let one = run(&tri, method, 1, 0);
        assert!((one.points[0].area - tri.total_area()).abs() < 1e-12);
    }
}

#[test]
fn more_points_than_vertices_and_degenerate_triangles() {
    // A tetrahedron with two extra zero-area triangles: 4 vertices, 100 points.
    let pos = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z, Vec3::new(0.5, 0.0, 0.0)];
    let tris = vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2], [0, 1, 4], [3, 3, 2]];
    let mesh = Mesh::from_triangles(pos, tris).unwrap();
    assert_eq!(mesh.report().degenerate_triangles, 2);
    for method in Method::ALL {
        check_set(&mesh, &run(&mesh, method, 100, 2), 100);
    }
    let spread = run(&mesh, Method::Poisson, 100, 2);
    assert!(min_nn(&spread) > 0.0);
}

#[test]
fn zero_count_too_many_and_no_area_are_clear_errors() {
    let mesh = small_bunny();
    for method in Method::ALL {
        let err = sample(mesh, &SampleOptions::new(method, 0)).unwrap_err();
        assert_eq!(err, SamplingError::ZeroCount);
        assert!(err.to_string().contains("at least 1"));
        let err = sample(mesh, &SampleOptions::new(method, MAX_COUNT + 1)).unwrap_err();
        assert!(matches!(err, SamplingError::TooMany { .. }), "{err}");
    }
    // A mesh without area never reaches a sampler: building it fails and says why.
    let err = Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::X * 3.0], vec![[0, 1, 2]]).unwrap_err();
    assert!(matches!(err, MeshError::NoArea { .. }));
    assert!(err.to_string().contains("no area"), "{err}");
}

#[test]
fn methods_parse_from_their_names() {
    for m in Method::ALL {
        assert_eq!(m.name().parse::<Method>().unwrap(), m);
    }
    assert!("blue".parse::<Method>().unwrap_err().contains("blue"));
}

// ---------------------------------------------------------------------------------------------
// The command line

fn cli(args: &[&str]) -> std::process::Output {
    common::subcommand("sample", args)
}

fn leftovers(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp"))
        .collect()
}

#[test]
fn cli_writes_a_ply_and_prints_statistics() {
    let dir = temp_dir("cli-ok");
    let out = dir.join("points.ply");
    let mesh = asset("bunny-1.8k.obj");
    let result = cli(&[
        mesh.to_str().unwrap(),
        "--method",
        "poisson",
        "--count",
        "50",
        "--seed",
        "4",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(result.status.success(), "{}", String::from_utf8_lossy(&result.stderr));
    let stdout = String::from_utf8_lossy(&result.stdout);
    for word in ["count", "total area", "nn distance", "cv", "time"] {
        assert!(stdout.contains(word), "missing `{word}` in\n{stdout}");
    }
    let ply = std::fs::read_to_string(&out).unwrap();
    let (header, body) = ply.split_once("end_header\n").unwrap();
    assert!(header.starts_with("ply\nformat ascii 1.0\n"));
    assert!(header.contains("element vertex 50\n"));
    for prop in ["x", "y", "z", "nx", "ny", "nz", "area"] {
        assert!(header.contains(&format!("property float {prop}\n")));
    }
    let rows: Vec<Vec<f64>> =
        body.lines().map(|l| l.split_whitespace().map(|v| v.parse().unwrap()).collect()).collect();
    assert_eq!(rows.len(), 50);
    assert!(rows.iter().all(|r| r.len() == 7));
    let total: f64 = rows.iter().map(|r| r[6]).sum();
    let area = small_bunny().total_area();
    assert!((total - area).abs() < 1e-5 * area, "PLY areas sum to {total}, mesh area {area}");
    assert!(leftovers(&dir).is_empty());

    let json = cli(&[mesh.to_str().unwrap(), "--method", "feature", "--count", "20", "--json"]);
    assert!(json.status.success());
    let v: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    assert_eq!(v["count"], 20);
    assert_eq!(v["method"], "feature");
    assert!(v["nn_min"].as_f64().unwrap() > 0.0);
    assert!((v["total_weight"].as_f64().unwrap() - area).abs() < 1e-6 * area);
}

#[test]
fn cli_fails_cleanly_on_bad_input() {
    let dir = temp_dir("cli-bad");
    let missing = dir.join("nowhere.obj");
    let r = cli(&[missing.to_str().unwrap(), "--method", "random", "--count", "10"]);
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("nowhere.obj"));

    let bad = dir.join("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nv 0 1 nan\nf 1 2 3\n").unwrap();
    let r = cli(&[bad.to_str().unwrap(), "--method", "turk", "--count", "10"]);
    assert!(!r.status.success());
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(err.contains("bad.obj:3:"), "{err}");

    let mesh = asset("bunny-1.8k.obj");
    let r = cli(&[mesh.to_str().unwrap(), "--method", "turk", "--count", "0"]);
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("at least 1"));

    // The output path is a directory: the rename fails, and no temporary file is left behind.
    let target = dir.join("taken");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("keep"), "x").unwrap();
    let r = cli(&[mesh.to_str().unwrap(), "--method", "random", "--count", "10", "-o", target.to_str().unwrap()]);
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("taken"));
    assert!(leftovers(&dir).is_empty(), "{:?}", leftovers(&dir));
    assert!(target.join("keep").exists());
}
