//! Mesh distance (to be written).
