//! Sample points on a mesh surface, each with an area weight (seed paper section 3).
