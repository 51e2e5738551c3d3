"""Tests of the isomorph Python package: every method's endpoints on
sphere -> torus, errors, cancellation, array and volume round trips, export
and compare. Resolutions are small (32-40) to keep the suite quick."""

import _thread
import json
import signal
import threading
import time

import numpy as np
import pytest

import isomorph

RES = 40


def euler(vertices, faces):
    """V - E + F of a triangle mesh (2 for a sphere, 0 for a torus)."""
    faces = np.asarray(faces)
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    n_edges = len(np.unique(edges, axis=0))
    return len(vertices) - n_edges + len(faces)


# Per method: inputs and small settings that keep each build to a few seconds.
CASES = {
    "baseline": ("sphere", "torus", {"resolution": RES}),
    "level-set": ("sphere", "torus", {"resolution": RES}),
    "rbf": ("sphere", "torus", {"points": 200}),
    "warp": ("sphere", "torus", {"resolution": RES}),
    "tspline": ("sphere", "torus", {}),
    # The BlobTree method takes BlobTree scenes: the built-in sphere and torus scenes.
    "blobtree": ("sphere", "torus", {}),
}


@pytest.fixture(scope="module")
def morphs():
    return {}


def built(morphs, method):
    if method not in morphs:
        source, target, settings = CASES[method]
        morphs[method] = isomorph.morph(source, target, method=method, **settings)
    return morphs[method]


def test_methods_are_listed():
    assert isomorph.methods() == ["baseline", "level-set", "rbf", "warp", "tspline", "blobtree"]
    assert set(CASES) == set(isomorph.methods())


@pytest.mark.parametrize("method", list(CASES))
def test_sphere_to_torus_endpoints(morphs, method):
    m = built(morphs, method)
    assert m.method == method
    v0, f0 = m.frame_mesh(0.0, RES)
    v1, f1 = m.frame_mesh(1.0, RES)
    assert v0.dtype == np.float32 and v0.shape[1] == 3
    assert f0.dtype == np.int64 and f0.shape[1] == 3
    assert euler(v0, f0) == 2, "frame 0 is a sphere"
    assert euler(v1, f1) == 0, "frame 1 is a torus"
    # The torus is flat along one axis, the sphere is not.
    ext0, ext1 = np.ptp(v0, axis=0), np.ptp(v1, axis=0)
    assert ext0.max() / ext0.min() < 1.2
    assert ext1.max() / ext1.min() > 1.8
    lo, hi = np.array(m.world_bounds[0]), np.array(m.world_bounds[1])
    assert np.all(v1 >= lo - 1e-4) and np.all(v1 <= hi + 1e-4)
    report = m.report
    assert report["method"] == method
    assert {"outcome", "converged", "stages", "warnings", "details"} <= set(report)
    json.dumps(report)


@pytest.mark.parametrize("method", ["level-set", "rbf"])
def test_frame_volume_places_the_field(morphs, method):
    m = built(morphs, method)
    vol = m.frame_volume(0.0, 32)
    assert isinstance(vol, isomorph.Volume)
    nz, ny, nx = vol.values.shape
    assert max(nz, ny, nx) == 32 and vol.values.dtype == np.float32
    xs, ys, zs = vol.positions()
    # The sphere is centred at the origin: the node nearest it is inside,
    # the corners are outside.
    i, j, k = (int(np.argmin(np.abs(a))) for a in (xs, ys, zs))
    assert vol.values[k, j, i] > 0
    assert vol.values[0, 0, 0] < 0 and vol.values[-1, -1, -1] < 0
    assert np.asarray(vol).shape == vol.values.shape


def test_volume_round_trip_as_input(morphs):
    vol = built(morphs, "level-set").frame_volume(0.0, 40)
    for given in (vol, {"values": vol.values, "origin": vol.origin, "spacing": vol.spacing}):
        m = isomorph.morph(given, "torus", method="baseline", resolution=32)
        v, f = m.frame_mesh(0.0)
        assert euler(v, f) == 2
        ext = np.ptp(v, axis=0)
        assert 0.5 < ext.max() < 0.7, ext  # the sphere of radius 0.3


def test_mesh_arrays_round_trip(morphs):
    v, f = built(morphs, "baseline").frame_mesh(1.0)
    m = isomorph.morph("sphere", (v, f.astype(np.int32)), method="baseline", resolution=32)
    v1, f1 = m.frame_mesh(1.0)
    assert euler(v1, f1) == 0
    assert np.allclose(np.ptp(v1, axis=0), np.ptp(v, axis=0), atol=0.05)


def test_trimesh_round_trip():
    trimesh = pytest.importorskip("trimesh", reason="trimesh is not installed")
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=0.3)
    torus = trimesh.creation.torus(major_radius=0.3, minor_radius=0.12)
    m = isomorph.morph(sphere, torus, method="baseline", resolution=40)
    for t, genus in ((0.0, 0), (1.0, 1)):
        v, f = m.frame_mesh(t)
        mesh = trimesh.Trimesh(v, f, process=False)
        assert mesh.is_watertight
        assert mesh.euler_number == 2 - 2 * genus
    end = trimesh.Trimesh(*m.frame_mesh(1.0))
    assert np.allclose(end.extents, torus.extents, atol=0.05)


def test_export_writes_what_the_cli_writes(morphs, tmp_path):
    report = built(morphs, "baseline").export(tmp_path, frames=3, resolution=32)
    assert [f["file"] for f in report["frames"]] == ["frame_000.ply", "frame_001.ply", "frame_002.ply"]
    for name in ("frame_000.ply", "frame_002.ply", "contact_sheet.png", "report.json"):
        assert (tmp_path / name).is_file()
    assert json.loads((tmp_path / "report.json").read_text())["morph"]["method"] == "baseline"
    assert report["frames"][0]["genus"] == 0 and report["frames"][-1]["genus"] == 1
    assert report["endpoints"]["source"]["hausdorff_voxels"] < 3


def test_compare_returns_rows_and_writes_files(tmp_path):
    rows = isomorph.compare(
        "sphere", "torus", methods=["baseline", "rbf"], resolution=32, frames=3, out=tmp_path, points=150
    )
    assert [r["method"] for r in rows] == ["baseline", "rbf"]
    assert all(r["status"] == "ok" for r in rows), rows
    assert rows[0]["genus"][0] == 0 and rows[0]["genus"][-1] == 1
    for name in ("compare.png", "compare.json", "compare.md", "compare.html", "baseline/report.json"):
        assert (tmp_path / name).is_file()
    # Without out nothing is kept, and the rows are the same kind.
    rows = isomorph.compare("sphere", "torus", methods=["baseline"], resolution=32, frames=2)
    assert rows[0]["status"] == "ok"


def test_defaults_are_the_rust_defaults():
    d = isomorph.defaults("level-set")
    assert d["max_iterations"] == 20_000 and d["resolution"] == 64 and d["align"] == "none"
    assert d["curvature"] is None
    assert {"points", "separation", "kernel"} <= set(isomorph.defaults("rbf"))
    assert "control_spacing" in isomorph.defaults("warp")
    assert "depth" in isomorph.defaults("tspline")
    assert isomorph.defaults("tspline")["sampler"] == "marching-cubes"


def test_tspline_sampler_reaches_the_evolution():
    m = isomorph.morph(
        "sphere", "torus", method="tspline", sampler="marching-triangulation", sample_edge=0.5, max_steps=2
    )
    assert m.report["details"]["sampler"] == "marching triangulation, edge 0.5 finest cells"
    assert m.report["details"]["first_step_samples"] > 0
    with pytest.raises(ValueError, match="sample_edge"):
        isomorph.morph("sphere", "torus", method="tspline", sample_edge=9)
    with pytest.raises(ValueError, match="sampler"):
        isomorph.morph("sphere", "torus", method="tspline", sampler="random")


def test_tspline_stall_and_far_field_settings_reach_the_evolution():
    d = isomorph.defaults("tspline")
    assert d["stall_steps"] >= 1 and d["far_field_weight"] > 0
    m = isomorph.morph("sphere", "torus", method="tspline", stall_steps=3, far_field_weight=0.5, max_steps=2)
    assert m.report["details"]["stall_steps"] == 3
    assert m.report["details"]["far_field_weight"] == 0.5
    with pytest.raises(ValueError, match="stall_steps"):
        isomorph.morph("sphere", "torus", method="tspline", stall_steps=0)
    with pytest.raises(ValueError, match="far_field_weight"):
        isomorph.morph("sphere", "torus", method="tspline", far_field_weight=-1)


def test_tspline_hold_fraction_reaches_the_evolution():
    assert isomorph.defaults("tspline")["hold_fraction"] == 0.0
    m = isomorph.morph("sphere", "torus", method="tspline", hold_fraction=0.5, max_steps=2)
    assert m.report["details"]["hold_fraction"] == 0.5
    assert m.report["details"]["held_cells"] >= 0
    with pytest.raises(ValueError, match="hold_fraction"):
        isomorph.morph("sphere", "torus", method="tspline", hold_fraction=1.5)


def test_tspline_beta_cells_reaches_the_robust_speed():
    assert isomorph.defaults("tspline")["beta_cells"] > 0
    m = isomorph.morph("sphere", "torus", method="tspline", beta_cells=0.25, max_steps=2)
    assert m.report["details"]["speed"] == "robust (v_max 0.2, beta 0.25 finest cells)"
    with pytest.raises(ValueError, match="beta_cells"):
        isomorph.morph("sphere", "torus", method="tspline", beta_cells=11)
    with pytest.raises(ValueError, match="beta_cells"):
        isomorph.morph("sphere", "torus", method="tspline", speed="paper", beta_cells=0.5)


def test_unknown_setting_is_a_value_error_naming_it():
    with pytest.raises(ValueError, match="bogus"):
        isomorph.morph("sphere", "torus", method="rbf", bogus=1)
    with pytest.raises(isomorph.SettingError, match="points.*applies to rbf"):
        isomorph.morph("sphere", "torus", method="baseline", points=10)
    with pytest.raises(ValueError, match="max_iterations"):
        isomorph.morph("sphere", "torus", method="level-set", max_iterations="many")
    with pytest.raises(ValueError, match="kernel"):
        isomorph.morph("sphere", "torus", method="rbf", kernel="gaussian")
    with pytest.raises(ValueError, match="resolution"):
        isomorph.morph("sphere", "torus", method="baseline", resolution=3)
    with pytest.raises(ValueError, match="method"):
        isomorph.morph("sphere", "torus", method="nope")
    with pytest.raises(ValueError, match="points"):
        isomorph.compare("sphere", "torus", methods=["baseline"], points=10)


def test_rust_errors_keep_their_message(tmp_path, morphs):
    with pytest.raises(isomorph.InputError, match="is neither a built-in shape .* nor an existing file"):
        isomorph.morph(str(tmp_path / "missing.ply"), "torus")
    bad = tmp_path / "bad.ply"
    bad.write_text("this is not a ply file")
    with pytest.raises(ValueError, match="cannot read the mesh"):
        isomorph.morph(bad, "torus", method="baseline")
    with pytest.raises(ValueError, match=r"time 1.5 is outside \[0, 1\]"):
        built(morphs, "baseline").frame_mesh(1.5)
    with pytest.raises(isomorph.InputError, match="index"):
        isomorph.morph((np.zeros((3, 3)), np.array([[0, 1, 7]])), "torus", method="baseline")
    with pytest.raises(TypeError):
        isomorph.morph(42, "torus")
    assert issubclass(isomorph.InputError, isomorph.MorphError)


def test_timeout_cancels_through_the_contract():
    start = time.monotonic()
    with pytest.raises(isomorph.Cancelled):
        isomorph.morph("sphere", "torus", method="level-set", resolution=200, timeout=0.05)
    assert time.monotonic() - start < 60


def test_keyboard_interrupt_cancels_the_build():
    # _thread.interrupt_main() raises the SIGINT handler's KeyboardInterrupt
    # in the main thread at its next signal check, as Ctrl-C does. The build
    # (level set at 200^3) lasts seconds, far longer than the 0.1 s delay.
    # Python's own Ctrl-C handler is installed for the test: a process
    # started in the background by a non-interactive shell inherits SIGINT
    # ignored, and interrupt_main() then does nothing.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.1, _thread.interrupt_main)
    start = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            isomorph.morph("sphere", "torus", method="level-set", resolution=200)
        elapsed = time.monotonic() - start
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)
    # Cancelled through the contract: the call returns long before the build would end.
    assert elapsed < 30


def test_threads_do_not_change_results():
    a = isomorph.morph("sphere", "torus", method="baseline", resolution=32, threads=1)
    b = isomorph.morph("sphere", "torus", method="baseline", resolution=32, threads=2)
    va, fa = a.frame_mesh(0.5)
    vb, fb = b.frame_mesh(0.5)
    assert np.array_equal(va, vb) and np.array_equal(fa, fb)
    with pytest.raises(ValueError, match="threads"):
        isomorph.morph("sphere", "torus", method="baseline", threads=0)


def test_usd_export_opens_in_usd_core(morphs, tmp_path):
    pytest.importorskip("pxr", reason="usd-core is not installed (pip install usd-core)")
    from pxr import Usd, UsdGeom

    report = built(morphs, "baseline").export(tmp_path, frames=3, resolution=32, format="usd")
    assert [f["file"] for f in report["frames"]] == ["morph.usda@0", "morph.usda@1", "morph.usda@2"]
    assert not (tmp_path / "frame_000.ply").exists()
    stage = Usd.Stage.Open(str(tmp_path / "morph.usda"))
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (0, 2)
    assert UsdGeom.GetStageUpAxis(stage) == "Y" and UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/morph/surface"))
    assert list(mesh.GetPointsAttr().GetTimeSamples()) == [0.0, 1.0, 2.0]
    assert mesh.GetNormalsInterpolation() == "vertex"
    for t, frame in enumerate(report["frames"]):
        assert len(mesh.GetPointsAttr().Get(t)) == frame["vertices"]
        assert len(mesh.GetFaceVertexCountsAttr().Get(t)) == frame["triangles"]


def test_landmarks_drive_the_level_set():
    # Breen & Whitaker 6.2: a shift of the sphere's poles as landmark pairs;
    # the target is seen through that warp and the frames end on the ball.
    shift = np.array([0.1, 0.05, 0.0])
    poles = [np.eye(3)[i] * s * 0.3 for i in range(3) for s in (1, -1)]
    pairs = [(tuple(p), tuple(p + shift)) for p in poles]
    m = isomorph.morph("sphere", "ball", method="level-set", resolution=32, landmarks=pairs)
    assert m.report["details"]["warped"] is True
    with pytest.raises(isomorph.SettingError, match="landmarks.*at least 4"):
        isomorph.morph("sphere", "ball", method="level-set", resolution=32, landmarks=pairs[:3])
