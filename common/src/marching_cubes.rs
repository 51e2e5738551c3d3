//! Marching cubes polygonization of 3D scalar fields (to be written).
