//! Triangle meshes: OBJ loading, validation and derived geometry.
