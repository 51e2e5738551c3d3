//! Mesh bvh (to be written).
