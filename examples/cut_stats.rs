use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene};
fn main() {
    for count in [400usize, 6400] {
        let p =
            PreparedScene::new(&Scene::builtin(), &Overrides { samples: Some(count), ..Default::default() }).unwrap();
        let o = p.objects.iter().find(|o| !o.samples.is_empty()).unwrap();
        let tree = o.sample_tree();
        let groups = o.receiver_groups();
        for eps in [0.1, 0.5, 1.0, 2.0, 4.0] {
            let cuts = o.gather_cuts(&tree, &groups, eps);
            let items: usize = cuts.iter().map(|c| c.len()).sum();
            let nodes: usize = cuts.iter().map(|c| c.iter().filter(|&&i| i & (1 << 31) != 0).count()).sum();
            println!(
                "N {count} eps {eps}: mean items/group {:.1} (nodes {:.1}), groups {}",
                items as f64 / cuts.len() as f64,
                nodes as f64 / cuts.len() as f64,
                cuts.len()
            );
        }
        let mean_r: f64 = groups.bounds.iter().map(|b| b.1 as f64).sum::<f64>() / groups.bounds.len() as f64;
        let area: f64 = o.samples.iter().map(|s| s.area).sum();
        println!(
            "group radius mean {mean_r:.3e}, sample spacing {:.3e}, leaf radius mean {:.3e}",
            (area / count as f64).sqrt(),
            tree.nodes.iter().filter(|n| n.leaf).map(|n| n.radius as f64).sum::<f64>()
                / tree.nodes.iter().filter(|n| n.leaf).count() as f64
        );
    }
}
