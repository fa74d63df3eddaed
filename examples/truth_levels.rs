//! Print the exact-integral truth's refinement levels for a scene: `cargo run --release
//! --example truth_levels -- SCENE [MAX_LEVEL]`.
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = translucent::scene::Scene::load(std::path::Path::new(&args[1])).unwrap();
    let prepared = translucent::scene::build::PreparedScene::new(&scene, &Default::default()).unwrap();
    let max_level = args.get(2).map_or(4, |a| a.parse().unwrap());
    let options = translucent::reference::truth::TruthOptions { max_level, ..Default::default() };
    let t = translucent::reference::truth::compute(&prepared, &options, &|_, _, _| {});
    for l in &t.levels {
        println!("{l:?}");
    }
}
