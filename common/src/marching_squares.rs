//! Marching squares contouring of 2D scalar fields (to be written).
