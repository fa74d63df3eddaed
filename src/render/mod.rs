//! The render floor. From the bottom up:
//! - the host-facing types and decisions: `target` (where shading draws, the host's
//!   attachments), `camera`, `options`, `error`, `frame` (what recording gives back), `edit`;
//! - the frame's resources, declared once (`resource`), and the passes' list (`registry`);
//! - the scene's GPU data (`records`, `ranges`, `beam_tables`, `gpu_scene`), the frame targets
//!   (`targets`), and the registry binding both by name (`graph`);
//! - the planner (`plan`), and the checks of the device and the host's target (`fit`, `host`);
//! - the passes: each one module here and one GLSL file of the same name in `glsl/`, built and
//!   recorded through `pass`; `cull` and `group_gather` are what several of them share;
//! - the `Renderer`, which records them.

pub mod beam_gather;
pub mod beam_tables;
pub mod camera;
pub mod cull;
pub mod edit;
pub mod error;
pub mod fit;
pub mod frame;
pub mod gather;
pub mod gather_choice;
pub mod gather_pixel;
pub mod gather_sparse;
pub mod gather_texture;
pub mod gather_tree;
pub mod gpu_scene;
pub mod graph;
pub mod group_gather;
pub mod host;
pub mod local_exitance;
pub mod options;
pub mod pass;
pub mod plan;
#[cfg(test)]
mod probe;
pub mod ranges;
pub mod receiver_view;
pub mod records;
pub mod registry;
pub mod renderer;
pub mod resource;
pub mod shade;
pub mod shadow;
pub mod smoke;
pub mod splat;
pub mod target;
pub mod targets;
pub mod tonemap;
pub mod transport;
pub mod transport_tables;
pub mod vertex_light;
