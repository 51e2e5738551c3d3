//! The conformance suite every [`Morph`] implementation runs (feature
//! `conformance`): one generic check of the contract, so that the methods
//! are held to the same rules.
//!
//! [`check_morph`] builds the morph three times — on one thread, on two
//! threads, and with a progress callback that cancels at its first report —
//! and checks:
//! - frame 0 reproduces the source and frame 1 the target, within the
//!   method's stated tolerance in world voxels;
//! - `t` outside `[0, 1]` and NaN are [`MorphError::InvalidTime`] errors,
//!   for [`Morph::frame`] and [`Morph::frame_mesh`];
//! - frame meshes are closed, consistently oriented and outward (positive
//!   volume), and lie inside [`Morph::world_bounds`];
//! - the report is complete: the method's name, at least one stage with a
//!   finite time, the stored bytes, the expected outcome;
//! - the cancelled build returns an error whose shared kind is
//!   [`MorphError::Cancelled`];
//! - one and two threads give the same frame meshes, bit for bit.
//!
//! Failures panic with the expected and measured figures (it is a test
//! helper).

use crate::TriMesh;
use crate::control::{CancelToken, Control};
use crate::mesh::distance::surface_distance;
use crate::morph::{Morph, MorphError, MorphFailure};

/// What a method promises on one input pair.
#[derive(Debug, Clone)]
pub struct Expectations {
    /// The source surface (world units) frame 0 must reproduce.
    pub source: TriMesh,
    /// The target surface frame 1 must reproduce.
    pub target: TriMesh,
    /// The resolution passed to [`Morph::frame_mesh`]; one world voxel is
    /// the longest edge of [`Morph::world_bounds`] over `resolution − 1`.
    pub resolution: u32,
    /// Largest mean two-sided surface distance at the endpoints (voxels).
    pub mean_voxels: f32,
    /// Largest Hausdorff distance at the endpoints (voxels).
    pub hausdorff_voxels: f32,
    /// Whether the method must report that it converged.
    pub converges: bool,
}

/// What the suite measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Conformance {
    /// World voxel size used for the tolerances.
    pub voxel: f32,
    /// Mean and Hausdorff distance (voxels) of frame 0 to the source.
    pub source: (f32, f32),
    /// Mean and Hausdorff distance (voxels) of frame 1 to the target.
    pub target: (f32, f32),
}

/// Runs the suite on the morph made by `build` (see the [module docs](self)).
///
/// # Panics
/// On every broken rule, with a message naming it.
pub fn check_morph<M, B>(build: B, expect: &Expectations) -> Conformance
where
    M: Morph,
    B: Fn(&Control) -> Result<M, M::Error>,
{
    let one = Control::new().with_threads(1).expect("a one-thread pool");
    let two = Control::new().with_threads(2).expect("a two-thread pool");
    let m1 = build(&one).unwrap_or_else(|e| panic!("building on one thread failed: {e}"));
    let m2 = build(&two).unwrap_or_else(|e| panic!("building on two threads failed: {e}"));
    let name = m1.method();

    // Cancellation at the first progress report.
    let token = CancelToken::new();
    let trip = token.clone();
    let cancelling = Control::new().with_cancel(token).with_progress(move |_| trip.cancel());
    match build(&cancelling) {
        Err(e) => assert!(e.is_cancelled(), "{name}: a cancelled build failed with another error: {e}"),
        Ok(_) => panic!("{name}: a build cancelled at its first progress report finished"),
    }

    // Times outside [0, 1].
    for t in [-0.1, 1.1, f32::NAN] {
        let is_time_error = |e: &M::Error| matches!(e.shared(), Some(MorphError::InvalidTime(_)));
        assert!(
            m1.frame(t).is_err_and(|e| is_time_error(&e)),
            "{name}: frame({t}) is not an InvalidTime error"
        );
        assert!(
            m1.frame_mesh(t, expect.resolution).is_err_and(|e| is_time_error(&e)),
            "{name}: frame_mesh({t}) is not an InvalidTime error"
        );
        assert!(
            m1.world_transform(t).is_err_and(|e| is_time_error(&e)),
            "{name}: world_transform({t}) is not an InvalidTime error"
        );
    }

    // The report.
    let report = m1.report();
    assert_eq!(report.method, name, "{name}: the report names another method");
    assert!(!report.stages.is_empty(), "{name}: the report has no stage times");
    assert!(
        report.stages.iter().all(|s| s.seconds.is_finite() && s.seconds >= 0.0),
        "{name}: bad stage time"
    );
    assert!(report.stored_bytes > 0, "{name}: the report gives no stored bytes");
    assert_eq!(report.converged, report.outcome.succeeded(), "{name}: converged disagrees with the outcome");
    if expect.converges {
        assert!(report.converged, "{name}: expected to converge, outcome {:?}", report.outcome);
    }

    // Frames: closed, oriented, outward, inside the world bounds, and the
    // same on one and two threads.
    let world = m1.world_bounds();
    let voxel = world.size().max_element() / (expect.resolution - 1) as f32;
    assert!(voxel.is_finite() && voxel > 0.0, "{name}: world bounds {world:?} give no voxel size");
    let slack = 1e-3 * world.size().max_element();
    let mut ends = Vec::new();
    for t in [0.0, 0.25, 0.5, 0.75, 1.0] {
        let mesh = m1.frame_mesh(t, expect.resolution).unwrap_or_else(|e| panic!("{name}: frame {t}: {e}"));
        let edges = mesh.edge_stats();
        assert!(!mesh.triangles.is_empty(), "{name}: frame {t} is empty");
        assert_eq!(
            (edges.boundary_edges, edges.nonmanifold_edges, edges.misoriented_edges),
            (0, 0, 0),
            "{name}: frame {t} is not closed and consistently oriented (boundary, non-manifold, misoriented edges)"
        );
        assert!(
            mesh.signed_volume() > 0.0,
            "{name}: frame {t} is inside out (volume {})",
            mesh.signed_volume()
        );
        let b = mesh.bounds();
        assert!(
            world.expanded(slack).contains(b.min) && world.expanded(slack).contains(b.max),
            "{name}: frame {t} ({b:?}) leaves the world bounds {world:?}"
        );
        let placed = m1.frame(t).unwrap_or_else(|e| panic!("{name}: frame {t}: {e}")).transform;
        let transform = m1.world_transform(t).unwrap_or_else(|e| panic!("{name}: world_transform {t}: {e}"));
        assert_eq!(transform, placed, "{name}: world_transform({t}) is not frame({t}).transform");
        let again = m2.frame_mesh(t, expect.resolution).unwrap_or_else(|e| panic!("{name}: frame {t}: {e}"));
        assert!(
            again.positions == mesh.positions && again.triangles == mesh.triangles,
            "{name}: frame {t} differs between one and two threads"
        );
        if t == 0.0 || t == 1.0 {
            ends.push(mesh);
        }
    }

    // Endpoints.
    let measure = |mesh: &TriMesh, reference: &TriMesh, which: &str| {
        let d = surface_distance(mesh, reference, 20_000)
            .unwrap_or_else(|e| panic!("{name}: {which} distance: {e}"));
        let (mean, hausdorff) = (d.mean / voxel, d.hausdorff / voxel);
        assert!(
            mean <= expect.mean_voxels && hausdorff <= expect.hausdorff_voxels,
            "{name}: the {which} endpoint is {mean:.3} voxels off on average and {hausdorff:.3} at most; \
             allowed {} and {}",
            expect.mean_voxels,
            expect.hausdorff_voxels
        );
        (mean, hausdorff)
    };
    Conformance {
        voxel,
        source: measure(&ends[0], &expect.source, "source"),
        target: measure(&ends[1], &expect.target, "target"),
    }
}
