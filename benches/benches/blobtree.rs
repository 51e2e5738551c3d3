//! Benchmarks of BlobTree evaluation on the rook → queen generic tree at
//! t = 0.5: field evaluation with and without bounding-box pruning (single
//! thread, and in parallel), and polygonizing one frame at 128³; building
//! the frame at t = 0.5 of rook → queen → bear, the queen a Bézier control
//! shape (de Casteljau: a level-2 generic tree per frame) or a chained key
//! shape; building that morph (correspondences and the bounds stage).
//!
//! `cargo bench -p isomorph-benches --bench blobtree -- eval/rook_queen/pruned`

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use isomorph_blobtree::{BlobMorph, BlobTree, KeyShape, MorphSpec, scenes};
use isomorph_common::marching_cubes::polygonize;
use isomorph_common::{Field3, Morph};
use rayon::prelude::*;
use std::hint::black_box;

/// The rook → queen morph and its frame at t = 0.5.
fn rook_queen() -> (BlobMorph, BlobTree) {
    let (a, b, spec) = scenes::demo("rook_queen").expect("built-in demo");
    let morph = BlobMorph::from_trees(&a, &b, &spec).expect("valid demo");
    let frame = morph.frame(0.5).expect("valid time").field;
    (morph, frame)
}

/// A 32³ lattice of query points over the morph's bounds.
fn points(morph: &BlobMorph) -> Vec<Vec3> {
    let b = morph.field_bounds();
    let n = 32;
    let mut v = Vec::with_capacity(n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let t = Vec3::new(i as f32, j as f32, k as f32) / (n - 1) as f32;
                v.push(b.min + (b.max - b.min) * t);
            }
        }
    }
    v
}

fn eval(c: &mut Criterion) {
    let (morph, pruned) = rook_queen();
    let mut unpruned = pruned.clone();
    unpruned.set_pruning(false);
    let pts = points(&morph);
    let mut out = vec![0.0f32; pts.len()];
    let mut group = c.benchmark_group("eval/rook_queen");
    group.throughput(Throughput::Elements(pts.len() as u64));
    group.bench_function("pruned", |b| b.iter(|| pruned.values(black_box(&pts), &mut out)));
    group.bench_function("unpruned", |b| b.iter(|| unpruned.values(black_box(&pts), &mut out)));
    group.bench_function("parallel", |b| {
        b.iter(|| {
            out.par_chunks_mut(1024)
                .zip(pts.par_chunks(1024))
                .for_each(|(o, p)| pruned.values(black_box(p), o))
        })
    });
    group.finish();
}

fn polygonize_frame(c: &mut Criterion) {
    let (morph, frame) = rook_queen();
    let bounds = morph.field_bounds();
    c.bench_function("polygonize/rook_queen/128", |b| {
        b.iter(|| polygonize(black_box(&frame), &bounds, 128, 0.0).expect("grid fits"))
    });
}

/// The rook, and the queen and the bear as key shapes.
fn rook_queen_bear() -> (BlobTree, [KeyShape; 2]) {
    let keys = [
        KeyShape { shape: scenes::queen(), spec: scenes::demo_spec("rook", "queen").expect("built-in pair") },
        KeyShape { shape: scenes::bear(), spec: MorphSpec::default() },
    ];
    (scenes::rook(), keys)
}

fn instantiate(c: &mut Criterion) {
    let (rook, keys) = rook_queen_bear();
    let bezier = BlobMorph::bezier(&rook, &keys).expect("valid shapes");
    let chain = BlobMorph::through(&rook, &keys).expect("valid shapes");
    let mut group = c.benchmark_group("frame/rook_queen_bear");
    group.bench_function("bezier", |b| b.iter(|| bezier.frame(black_box(0.5)).expect("valid time")));
    group.bench_function("chain", |b| b.iter(|| chain.frame(black_box(0.5)).expect("valid time")));
    group.finish();
}

/// Building the morph: correspondences, generic trees, and the bounds
/// stage (65 sampled instants; Bézier: each a de Casteljau tree).
fn build(c: &mut Criterion) {
    let (rook, keys) = rook_queen_bear();
    let mut group = c.benchmark_group("build/rook_queen_bear");
    group.bench_function("bezier", |b| b.iter(|| BlobMorph::bezier(black_box(&rook), &keys).expect("valid")));
    group.bench_function("chain", |b| b.iter(|| BlobMorph::through(black_box(&rook), &keys).expect("valid")));
    group.finish();
}

criterion_group!(benches, eval, polygonize_frame, instantiate, build);
criterion_main!(benches);
