//! Whether the source overlaps every part of the target (Breen & Whitaker
//! §4: a target part the evolving surface does not start in is never
//! reached), judged on a dense source grid ([`check_overlap`]) or on a
//! source's narrow band and the target's distance evaluated near its surface
//! only ([`check_overlap_sparse`], memory and work ∝ the target's surface).

use crate::stencil::Lattice;
use crate::{LevelSetError, SpeedGrid, SpeedSampler};
use isomorph_common::glam::{UVec3, Vec3};
use isomorph_common::{BRICK, Bricks, Grid3, MissedPart, MorphError};
use rayon::prelude::*;
use std::collections::HashMap;

/// Target nodes within this distance (voxels) outside the target join its
/// parts: a thin feature sampled between nodes, or two parts less than about
/// two voxels apart, stays one part (Breen & Whitaker §4 is about the
/// continuous target, not the pieces its sampling falls into).
const JOIN_VOXELS: f32 = 1.0;

/// How the source overlaps the target's parts ([`check_overlap`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Overlap {
    /// Connected parts of the target: its inside nodes, joined through nodes
    /// less than a voxel outside it.
    pub parts: usize,
    /// The parts whose inside the source's inside does not overlap, largest
    /// first: the evolution never reaches them.
    pub missed: Vec<MissedPart>,
}

impl Overlap {
    /// Share of the target's inside nodes in parts the source misses, in
    /// `[0, 1]`.
    pub fn unreached_share(&self) -> f32 {
        // A fold from +0 (an empty f32 sum is −0).
        self.missed.iter().fold(0.0, |sum, p| sum + p.share)
    }

    /// A sentence for the report when some part is missed.
    pub fn warning(&self) -> Option<String> {
        let largest = self.missed.first()?;
        Some(format!(
            "{} of {} target part(s) do not overlap the source and are not reached ({:.2} % of the \
             target's inside; the largest, {:.2} %, spans {:.3?} .. {:.3?}): the morph ends without them",
            self.missed.len(),
            self.parts,
            100.0 * self.unreached_share(),
            100.0 * largest.share,
            largest.min.to_array(),
            largest.max.to_array(),
        ))
    }
}

/// Whether the source's inside overlaps every connected part of the
/// target's inside (Breen & Whitaker §4: a target part that the source does
/// not touch is never reached). Parts are judged on the target, not on its
/// sampling: inside nodes joined through nodes less than a voxel outside the
/// target are one part, so a thin feature whose nodes fall outside it does
/// not split the target. Missed parts are accepted while their share of the
/// target's inside nodes is at most `max_unreached_share`.
///
/// # Errors
/// [`MorphError::NoOverlap`] with every missed part's size, share of the
/// target's inside and box (world units), largest first, when their total
/// share is over `max_unreached_share`.
pub fn check_overlap(
    source: &Grid3<f32>,
    speed: &SpeedGrid,
    max_unreached_share: f32,
) -> Result<Overlap, LevelSetError> {
    let lattice = Lattice::new(source.dims());
    let u = source.data();
    let reader = speed.reader();
    let v = |n: usize| reader.node(n);
    let joined = |m: usize| v(m) > -JOIN_VOXELS;
    let mut seen = vec![false; u.len()];
    let (mut parts, mut inside) = (0, 0usize);
    let mut missed = Vec::new();
    let mut stack = Vec::new();
    for start in 0..u.len() {
        if seen[start] || v(start) <= 0.0 {
            continue;
        }
        parts += 1;
        let (mut overlaps, mut nodes) = (false, 0usize);
        let (mut lo, mut hi) = (UVec3::MAX, UVec3::ZERO);
        seen[start] = true;
        stack.push(start);
        while let Some(n) = stack.pop() {
            if v(n) > 0.0 {
                overlaps |= u[n] > 0.0;
                nodes += 1;
                let c = source.node_of(n);
                (lo, hi) = (lo.min(c), hi.max(c));
            }
            for m in lattice.neighbours(n).into_iter().flatten() {
                if !seen[m] && joined(m) {
                    seen[m] = true;
                    stack.push(m);
                }
            }
        }
        inside += nodes;
        if !overlaps {
            let (min, max) = (source.position(lo.x, lo.y, lo.z), source.position(hi.x, hi.y, hi.z));
            missed.push(MissedPart { nodes, share: 0.0, min, max });
        }
    }
    judge(parts, missed, inside, max_unreached_share)
}

/// The [`Overlap`] of `parts` target parts holding `inside` inside nodes,
/// of which the parts `missed` (shares not yet set) do not overlap the
/// source; refused when they hold more than `max_unreached_share`.
fn judge(
    parts: usize,
    mut missed: Vec<MissedPart>,
    inside: usize,
    max_unreached_share: f32,
) -> Result<Overlap, LevelSetError> {
    for part in &mut missed {
        part.share = part.nodes as f32 / inside as f32;
    }
    missed.sort_by_key(|p| std::cmp::Reverse(p.nodes));
    let overlap = Overlap { parts, missed };
    if overlap.unreached_share() > max_unreached_share {
        let Overlap { parts: total, missed } = overlap;
        return Err(MorphError::NoOverlap { missed, total, allowed: max_unreached_share }.into());
    }
    Ok(overlap)
}

/// Brick class of [`check_overlap_sparse`]: every node more than
/// [`JOIN_VOXELS`] outside the target (no node joins a part).
const APART: u32 = u32::MAX;
/// Brick class: every node inside the target.
const WITHIN: u32 = u32::MAX - 1;

/// [`check_overlap`] without dense grids: the source's side from its narrow
/// band `source` (world units, positive inside; a [`Bricks::sample_band`]),
/// the target's speed `target` (voxel units at a world point of the
/// lattice of `source`'s dims at `origin` with `spacing`), which changes by
/// at most `lipschitz` voxels per voxel moved (1 for an exact distance; a
/// map's norm with one).
///
/// Each brick is judged by the target at its centre: wholly inside, wholly
/// more than a voxel outside, or evaluated at every node (the
/// bricks near the target's surface). The parts are then the connected
/// components of inside bricks and near nodes, found by union–find; the
/// result equals [`check_overlap`] of the dense grids (up to the order of
/// parts of equal size).
///
/// # Errors
/// As [`check_overlap`]; [`LevelSetError::NonFinite`] for a non-finite
/// target value at an evaluated node; [`LevelSetError::NoSurface`] for a
/// target without an inside node.
pub fn check_overlap_sparse(
    source: &Bricks<f32>,
    (origin, spacing): (Vec3, f32),
    target: &SpeedSampler,
    lipschitz: f32,
    max_unreached_share: f32,
) -> Result<Overlap, LevelSetError> {
    let dims = source.dims();
    let last = dims - UVec3::ONE;
    let side = BRICK as usize;
    let brick_nodes = side * side * side;
    let extent = |brick: usize| {
        let first = source.brick_origin(brick);
        (first, (first + UVec3::splat(BRICK - 1)).min(last))
    };
    // Per brick: APART, WITHIN, or a slot among the bricks evaluated node by node.
    let mut class: Vec<u32> = (0..source.brick_count())
        .into_par_iter()
        .map(|brick| {
            let (first, end) = extent(brick);
            let centre = origin + spacing * 0.5 * (first + end).as_vec3();
            let v = target.at(centre);
            // A margin over the bound for the rounding of the node positions and values.
            let reach = lipschitz * 0.5 * (end - first).as_vec3().length() * 1.001 + 1e-3;
            if v - reach > 0.0 {
                WITHIN
            } else if v + reach <= -JOIN_VOXELS {
                APART
            } else {
                0
            }
        })
        .collect();
    let mut near = Vec::new();
    for (brick, c) in class.iter_mut().enumerate() {
        if *c == 0 {
            *c = near.len() as u32;
            near.push(brick);
        }
    }
    // The target at every node of the near bricks (nodes past the lattice never join).
    let local =
        |l: usize| UVec3::new((l % side) as u32, ((l / side) % side) as u32, (l / (side * side)) as u32);
    let mut values = vec![f32::MIN; near.len() * brick_nodes];
    values.par_chunks_mut(brick_nodes).zip(&near).for_each(|(out, &brick)| {
        let first = source.brick_origin(brick);
        target.on_nodes((origin, spacing), first, UVec3::splat(BRICK), out);
        for (l, v) in out.iter_mut().enumerate() {
            if !(first + local(l)).cmple(last).all() {
                *v = f32::MIN;
            }
        }
    });
    if let Some(i) = values.iter().position(|v| !v.is_finite() && *v != f32::MIN) {
        let c = source.brick_origin(near[i / brick_nodes]) + local(i % brick_nodes);
        return Err(LevelSetError::NonFinite { what: "target", node: source.linear(c) });
    }
    // Union–find over the bricks (a WITHIN brick is one element) and the near bricks' nodes.
    let bricks = source.brick_count();
    let element = |brick: usize, l: usize| -> Option<usize> {
        match class[brick] {
            APART => None,
            WITHIN => (source.brick_origin(brick) + local(l)).cmple(last).all().then_some(brick),
            slot => {
                let e = slot as usize * brick_nodes + l;
                (values[e] > -JOIN_VOXELS).then_some(bricks + e)
            }
        }
    };
    let mut sets = UnionFind::new(bricks + values.len());
    let b = source.brick_dims();
    let step = [1usize, side, side * side];
    for brick in 0..bricks {
        if class[brick] == APART {
            continue;
        }
        let first = source.brick_origin(brick) >> BRICK.trailing_zeros();
        for axis in 0..3 {
            // Within the brick, node to node along the axis.
            if class[brick] != WITHIN {
                for l in 0..brick_nodes {
                    if local(l)[axis] + 1 < BRICK
                        && let (Some(x), Some(y)) = (element(brick, l), element(brick, l + step[axis]))
                    {
                        sets.union(x, y);
                    }
                }
            }
            // Across the face to the next brick along the axis.
            if first[axis] + 1 >= b[axis] {
                continue;
            }
            let next = brick + [1, b.x as usize, (b.x * b.y) as usize][axis];
            if class[next] == APART {
                continue;
            }
            if class[brick] == WITHIN && class[next] == WITHIN {
                sets.union(brick, next);
                continue;
            }
            for l in (0..brick_nodes).filter(|&l| local(l)[axis] == BRICK - 1) {
                if let (Some(x), Some(y)) = (element(brick, l), element(next, l - step[axis] * (side - 1))) {
                    sets.union(x, y);
                }
            }
        }
    }
    // The parts: inside nodes per component, whether the source is inside at one, their box.
    let source_inside_in = |brick: usize| match source.brick_values(brick) {
        None => source.background_of(brick) == Some(true),
        Some(v) => {
            (0..brick_nodes).any(|l| v[l] > 0.0 && (source.brick_origin(brick) + local(l)).cmple(last).all())
        }
    };
    let mut parts: Vec<(usize, bool, UVec3, UVec3)> = Vec::new();
    let mut index: HashMap<usize, usize> = HashMap::new();
    let mut add = |root: usize, nodes: usize, overlaps: bool, lo: UVec3, hi: UVec3| {
        let p = *index.entry(root).or_insert_with(|| {
            parts.push((0, false, UVec3::MAX, UVec3::ZERO));
            parts.len() - 1
        });
        let part = &mut parts[p];
        *part = (part.0 + nodes, part.1 || overlaps, part.2.min(lo), part.3.max(hi));
    };
    for (brick, &kind) in class.iter().enumerate() {
        match kind {
            APART => {}
            WITHIN => {
                let (first, end) = extent(brick);
                let nodes = (end - first + UVec3::ONE).as_u64vec3().element_product() as usize;
                add(sets.find(brick), nodes, source_inside_in(brick), first, end);
            }
            slot => {
                let first = source.brick_origin(brick);
                for l in 0..brick_nodes {
                    let e = slot as usize * brick_nodes + l;
                    if values[e] > 0.0 {
                        let c = first + local(l);
                        add(sets.find(bricks + e), 1, source.get(c) > 0.0, c, c);
                    }
                }
            }
        }
    }
    if parts.is_empty() {
        return Err(LevelSetError::NoSurface("target"));
    }
    let inside = parts.iter().map(|p| p.0).sum();
    let position = |c: UVec3| origin + spacing * c.as_vec3();
    let missed = parts
        .iter()
        .filter(|p| !p.1)
        .map(|&(nodes, _, lo, hi)| MissedPart { nodes, share: 0.0, min: position(lo), max: position(hi) })
        .collect();
    judge(parts.len(), missed, inside, max_unreached_share)
}

/// Disjoint sets of `0..n` (union by size, path halving).
struct UnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        Self { parent: (0..n as u32).collect(), size: vec![1; n] }
    }

    fn find(&mut self, mut x: usize) -> usize {
        while self.parent[x] as usize != x {
            let up = self.parent[self.parent[x] as usize];
            self.parent[x] = up;
            x = up as usize;
        }
        x
    }

    fn union(&mut self, a: usize, b: usize) {
        let (mut a, mut b) = (self.find(a), self.find(b));
        if a == b {
            return;
        }
        if self.size[a] < self.size[b] {
            std::mem::swap(&mut a, &mut b);
        }
        self.parent[b] = a as u32;
        self.size[a] += self.size[b];
    }
}
