//! Print the exact-integral truth's refinement levels for a scene: `cargo run --release
//! --example truth_levels -- SCENE|default [MAX_LEVEL] [CACHE_DIR]` (with a cache folder the truth is
//! also stored there, as `translucent study` would).
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = match args[1].as_str() {
        "default" => translucent::scene::Scene::builtin(),
        path => translucent::scene::Scene::load(std::path::Path::new(path)).unwrap(),
    };
    let prepared = translucent::scene::build::PreparedScene::new(&scene, &Default::default()).unwrap();
    let max_level = args.get(2).map_or(4, |a| a.parse().unwrap());
    let options = translucent::reference::truth::TruthOptions { max_level, ..Default::default() };
    let progress = |level: u32, done: usize, of: usize| {
        if done == of {
            eprintln!("level {level}: {of} receivers");
        }
    };
    let t = match args.get(3) {
        Some(dir) => {
            translucent::reference::truth::cached(&prepared, &options, std::path::Path::new(dir), &progress).unwrap().0
        }
        None => translucent::reference::truth::compute(&prepared, &options, &progress).unwrap(),
    };
    for l in &t.levels {
        println!("{l:?}");
    }
}
