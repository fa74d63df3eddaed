//! Print the exact-integral truth's refinement levels for a scene: `cargo run --release
//! --example truth_levels -- SCENE|default [MAX_LEVEL] [CACHE_DIR|-] [RECEIVERS]` (with a cache
//! folder the truth is also stored there, as `translucent study` would; `-` for none). Each
//! level's memory estimate is printed first: its floor, and its grids held whole.
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = match args[1].as_str() {
        "default" => translucent::scene::Scene::builtin(),
        path => translucent::scene::Scene::load(std::path::Path::new(path)).unwrap(),
    };
    let prepared = translucent::scene::build::PreparedScene::new(&scene, &Default::default()).unwrap();
    let max_level = args.get(2).map_or(4, |a| a.parse().unwrap());
    let receivers = args.get(4).map(|a| a.parse().unwrap());
    let options = translucent::reference::truth::TruthOptions { max_level, receivers, ..Default::default() };
    for level in 0..=max_level {
        let m = translucent::reference::truth::memory_estimate(&prepared, level);
        let human = translucent::reference::truth::human_bytes;
        println!("level {level}: floor {}, grids whole {}, {} E_t points", human(m.bytes), human(m.whole), m.points);
    }
    let progress = |level: u32, done: usize, of: usize| {
        if done == of {
            eprintln!("level {level}: {of} receivers");
        }
    };
    let t = match args.get(3).filter(|d| d.as_str() != "-") {
        Some(dir) => {
            translucent::reference::truth::cached(&prepared, &options, std::path::Path::new(dir), &progress).unwrap().0
        }
        None => translucent::reference::truth::compute(&prepared, &options, &progress).unwrap(),
    };
    for l in &t.levels {
        println!("{l:?}");
    }
}
