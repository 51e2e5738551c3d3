//! Fast marching and closest-point propagation (to be written).
