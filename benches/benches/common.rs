//! Benchmarks of the shared core (filled in below).
fn main() {}
