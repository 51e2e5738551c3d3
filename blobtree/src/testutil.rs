//! Random BlobTrees for property tests.

use crate::{Kernel, NaryOp, Node, Primitive, Skeleton, Warp};
use glam::{Affine3A, Quat, Vec3};
use proptest::prelude::*;

fn v3() -> impl Strategy<Value = Vec3> {
    (-0.6f32..0.6, -0.6f32..0.6, -0.6f32..0.6).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

fn skeleton() -> impl Strategy<Value = Skeleton> {
    prop_oneof![
        v3().prop_map(Skeleton::Point),
        (v3(), v3())
            .prop_filter("distinct", |(a, b)| (*a - *b).length() > 0.05)
            .prop_map(|(a, b)| Skeleton::Segment(a, b)),
        (0.05f32..0.4, 0.05f32..0.4).prop_map(|(a, b)| Skeleton::Polygon(vec![
            Vec3::new(-a, -b, 0.0),
            Vec3::new(a, -b, 0.0),
            Vec3::new(0.0, b, 0.0)
        ])),
        (0.05f32..0.3, 0.05f32..0.3, 0.05f32..0.3).prop_map(|(a, b, c)| Skeleton::cuboid(Vec3::new(a, b, c))),
    ]
}

/// A random primitive (random frame, kernel and metric).
pub fn primitive() -> impl Strategy<Value = Primitive> {
    (
        skeleton(),
        0.3f32..1.5,
        0.3f32..1.0,
        0.0f32..2.0,
        prop_oneof![Just(2.0f32), Just(1.0), Just(3.0), Just(f32::INFINITY)],
        v3(),
        -3.0f32..3.0,
    )
        .prop_map(|(s, i, r, k, p, t, a)| {
            Primitive::new(s, Kernel::new(i, r, k))
                .with_p(p)
                .with_frame(Affine3A::from_rotation_translation(Quat::from_rotation_z(a), t))
        })
}

/// A warp axis: the default z half of the time, else a random direction
/// (not normalized: scene axes need not be).
fn axis() -> impl Strategy<Value = Vec3> {
    prop_oneof![Just(Vec3::Z), v3().prop_filter("a direction", |v| v.length() > 0.05),]
}

/// A bend's `(axis, along)`: the defaults half of the time, else random
/// directions at least 0.3 rad from parallel.
fn bend_axes() -> impl Strategy<Value = (Vec3, Vec3)> {
    prop_oneof![
        Just((Vec3::Z, Vec3::Y)),
        (v3(), v3()).prop_filter("two directions across each other", |(a, b)| {
            a.length() > 0.05 && b.length() > 0.05 && a.normalize().cross(b.normalize()).length() > 0.3
        }),
    ]
}

fn warp() -> impl Strategy<Value = Warp> {
    prop_oneof![
        (-2.0f32..2.0, axis()).prop_map(|(rate, axis)| Warp::Twist { rate, axis }),
        (-0.5f32..0.5, axis()).prop_map(|(slope, axis)| Warp::Taper { slope, axis }),
        (0.1f32..0.8, bend_axes()).prop_map(|(rate, (axis, along))| Warp::Bend {
            rate,
            centre: 0.0,
            min: -0.8,
            max: 0.8,
            axis,
            along
        }),
        (v3(), -1.0f32..1.0, 0.6f32..1.4).prop_map(|(t, a, s)| Warp::Affine(
            Affine3A::from_scale_rotation_translation(Vec3::splat(s), Quat::from_rotation_x(a), t)
        )),
    ]
}

fn nary() -> impl Strategy<Value = NaryOp> {
    prop_oneof![
        Just(NaryOp::Blend),
        Just(NaryOp::Union),
        Just(NaryOp::Intersection),
        (1.0f32..6.0).prop_map(NaryOp::SuperBlend),
    ]
}

/// A random BlobTree of depth ≤ 3 with every node kind; difference levels 0.5.
pub fn tree() -> impl Strategy<Value = Node> {
    let leaf = primitive().prop_map(Node::Primitive);
    leaf.prop_recursive(3, 16, 3, |inner| {
        prop_oneof![
            (nary(), prop::collection::vec(inner.clone(), 1..4))
                .prop_map(|(op, children)| Node::Nary { op, children }),
            (inner.clone(), inner.clone()).prop_map(|(l, r)| Node::difference(l, r, 0.5)),
            (warp(), inner).prop_map(|(w, c)| Node::warp(w, c)),
        ]
    })
}

/// Sample points covering the random trees' region.
pub fn points() -> Vec<Vec3> {
    let mut v = Vec::new();
    for i in 0..9 {
        for j in 0..9 {
            for k in 0..9 {
                v.push(
                    Vec3::new(i as f32 - 4.0, j as f32 - 4.0, k as f32 - 4.0) * 0.3
                        + Vec3::new(0.013, -0.021, 0.007),
                );
            }
        }
    }
    v
}
