//! The comparison of every method on the reference pair, end to end as the
//! user runs it: build with the library defaults, then polygonize the
//! frames (`isomorph compare --source sphere --target torus`, without the
//! file writing).

use criterion::{Criterion, criterion_group, criterion_main};
use isomorph_cli::methods::{Method, Settings, build, load_input};
use isomorph_common::Control;
use std::hint::black_box;
use std::time::Duration;

/// Each method: construction plus 9 frames at 64³ (`compare/sphere_torus/64/<method>`).
fn sphere_torus(c: &mut Criterion) {
    let mut group = c.benchmark_group("compare/sphere_torus/64");
    group.sample_size(10).measurement_time(Duration::from_secs(20));
    let control = Control::new();
    for method in Method::ALL {
        let source = load_input(method, "sphere", &Default::default()).expect("built-in");
        let target = load_input(method, "torus", &Default::default()).expect("built-in");
        group.bench_function(method.name(), |b| {
            b.iter(|| {
                let morph = build(method, &source, &target, &Settings::default(), &control).expect("morphs");
                for i in 0..9 {
                    black_box(morph.frame_mesh(i as f32 / 8.0, 64).expect("a frame"));
                }
            });
        });
    }
    group.finish();
}

criterion_group!(benches, sphere_torus);
criterion_main!(benches);
