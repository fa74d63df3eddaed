//! GPU passes: each is one module here and one GLSL file of the same name in `glsl/`.

pub mod smoke;
