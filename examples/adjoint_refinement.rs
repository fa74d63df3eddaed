//! The adjoint reference under mesh refinement: `adjoint_refinement SCENE WALKS RECEIVERS DIV...`
//! rewrites the scene's `divisions = 24` to each DIV (coarsest first; a UV sphere's refinement
//! by 2 keeps its vertices), walks its first object backwards (seed 1, WALKS walks per receiver)
//! from the same RECEIVERS points on every mesh, and prints per channel and band of the cosine
//! to the first light the mean over the band's lit receivers of each mesh's exitance over the
//! finest's, with the standard error of that mean.
use translucent::reference::rte::{Budget, RteProgress};
use translucent::reference::rte_mesh::{self, MeshOptions, Walk};
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene};

const BANDS: [(f64, f64); 6] = [(0.8, 1.01), (0.5, 0.8), (0.2, 0.5), (0.0, 0.2), (-0.4, 0.0), (-1.01, -0.4)];

fn quiet(_: RteProgress) {}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let text = std::fs::read_to_string(&args[1]).unwrap();
    let walks: u64 = args[2].parse().unwrap();
    let count: usize = args[3].parse().unwrap();
    let options = MeshOptions { budget: Budget::photons(walks), seed: 1, walk: Walk::Photons };
    let mut runs = Vec::new();
    let mut points: Vec<glam::Vec3> = Vec::new();
    for div in &args[4..] {
        let scene = Scene::parse(&text.replace("divisions = 24", &format!("divisions = {div}")), "refined.toml", None).unwrap();
        let scene = PreparedScene::new(&scene, &Overrides::default()).unwrap();
        let mesh = &scene.objects[0].mesh;
        // The coarsest mesh's receivers, found again in each refinement (its vertices are theirs).
        if points.is_empty() {
            let subset = translucent::scene::accuracy::receiver_subset(mesh.positions().len(), Some(count));
            points = subset.iter().map(|&v| mesh.positions()[v]).collect();
        }
        let receivers: Vec<usize> = points
            .iter()
            .map(|p| mesh.positions().iter().position(|q| q.distance(*p) < 1e-6).expect("a refinement keeps the vertices"))
            .collect();
        let o = rte_mesh::adjoint_at(&scene, 0, receivers.clone(), &options, &quiet).unwrap();
        let cos: Vec<f64> = receivers.iter().map(|&v| translucent::study::physics::light_cosines(&scene)[0][v]).collect();
        println!("divisions {div}: {} vertices, {:.0} s", mesh.positions().len(), o.seconds);
        runs.push((div.clone(), o, cos));
    }
    let (_, finest, cos) = runs.last().unwrap();
    for (div, o, _) in &runs[..runs.len() - 1] {
        for &(lo, hi) in &BANDS {
            let cells: Vec<String> = (0..3)
                .map(|c| {
                    let max = finest.exitance.iter().map(|m| m[c]).fold(0.0, f64::max);
                    let pairs: Vec<(f64, f64)> = (0..cos.len())
                        .filter(|&k| cos[k] >= lo && cos[k] < hi && finest.exitance[k][c] >= 0.01 * max)
                        .map(|k| {
                            let (a, f) = (o.exitance[k][c], finest.exitance[k][c]);
                            let rel = ((o.stderr[k][c] / a).powi(2) + (finest.stderr[k][c] / f).powi(2)).sqrt();
                            (a / f, a / f * rel)
                        })
                        .collect();
                    let n = pairs.len().max(1) as f64;
                    let mean = pairs.iter().map(|x| x.0).sum::<f64>() / n;
                    let se = pairs.iter().map(|x| x.1 * x.1).sum::<f64>().sqrt() / n;
                    format!("{:+.2}% ± {:.2} ({})", 100.0 * (mean - 1.0), 100.0 * se, pairs.len())
                })
                .collect();
            println!("divisions {div} against {}, cos [{lo:+.1}, {hi:+.1}): {}", runs.last().unwrap().0, cells.join(", "));
        }
    }
}
