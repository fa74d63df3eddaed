//! GPU passes: each is one module here and one GLSL file of the same name in `glsl/`.

pub mod gather;
pub mod gather_pixel;
pub mod gather_sparse;
pub mod gather_tree;
pub mod gpu_scene;
pub mod pass;
pub mod plan;
pub mod records;
pub mod renderer;
pub mod shade;
pub mod shadow;
pub mod smoke;
pub mod splat;
pub mod tonemap;
pub mod vertex_light;
