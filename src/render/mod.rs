//! GPU passes: each is one module here and one GLSL file of the same name in `glsl/`. Beside
//! them: the frame's resources and the barriers their declarations give (`graph`), the frame
//! targets (`targets`), the two-stage gathers' shared shape (`group_gather`), the scene's GPU
//! data (`gpu_scene`, `records`), the planner and the `Renderer`.

pub mod beam_gather;
pub mod edit;
pub mod gather;
pub mod gather_pixel;
pub mod gather_sparse;
pub mod gather_texture;
pub mod gather_tree;
pub mod gpu_scene;
pub mod graph;
pub mod group_gather;
pub mod host;
pub mod local_exitance;
pub mod pass;
pub mod plan;
pub mod records;
pub mod renderer;
pub mod shade;
pub mod shadow;
pub mod smoke;
pub mod splat;
pub mod targets;
pub mod tonemap;
pub mod vertex_light;
