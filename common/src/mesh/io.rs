//! Mesh io (to be written).
