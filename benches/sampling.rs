//! Sampling speed on bunny-37k: every method at 400 and 10,000 points, printed as a table.
//! Run with `cargo bench --bench sampling` (a release build). Each row is the median of
//! `RUNS` runs; "place" is point placement, "weights" the nearest-sample area weights.

use std::time::Instant;

use translucent::mesh::{LoadOptions, Mesh};
use translucent::sampling::{self, Method, SampleOptions, SampleStats};

const RUNS: usize = 3;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/bunny-37k.obj");
    let loads: Vec<f64> = (0..RUNS)
        .map(|_| {
            let t = Instant::now();
            let mesh = Mesh::load(path, &LoadOptions::default()).expect("bunny-37k loads");
            std::hint::black_box(&mesh);
            t.elapsed().as_secs_f64()
        })
        .collect();
    let mesh = Mesh::load(path, &LoadOptions::default()).expect("bunny-37k loads");
    println!(
        "bunny-37k: {} vertices, {} triangles; load + curvature {:.3} s (median of {RUNS}); {} rayon threads",
        mesh.positions().len(),
        mesh.triangles().len(),
        median(loads),
        rayon::current_num_threads()
    );
    println!();
    println!("| method | N | place (s) | weights (s) | total (s) | nn min | nn mean | weight cv |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|");
    for n in [400, 10_000] {
        for method in Method::ALL {
            let options = SampleOptions::new(method, n);
            let mut place = Vec::new();
            let mut weigh = Vec::new();
            let mut last = None;
            for _ in 0..RUNS {
                let t0 = Instant::now();
                let placed = sampling::place(&mesh, &options).expect("sampling succeeds");
                let t1 = Instant::now();
                let areas = sampling::weights::area_weights(&mesh, &placed, &options.weights);
                let t2 = Instant::now();
                place.push((t1 - t0).as_secs_f64());
                weigh.push((t2 - t1).as_secs_f64());
                last = Some(sampling::finish(&mesh, &placed, &areas));
            }
            let stats = SampleStats::compute(&last.expect("at least one run"), mesh.total_area());
            let (p, w) = (median(place.clone()), median(weigh.clone()));
            let total = median(place.iter().zip(&weigh).map(|(a, b)| a + b).collect());
            println!(
                "| {method} | {n} | {p:.3} | {w:.3} | {total:.3} | {:.4} | {:.4} | {:.3} |",
                stats.nn_min.unwrap_or(0.0),
                stats.nn_mean.unwrap_or(0.0),
                stats.weight_cv
            );
        }
    }
}
