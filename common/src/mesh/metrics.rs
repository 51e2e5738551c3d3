//! Mesh metrics (to be written).
