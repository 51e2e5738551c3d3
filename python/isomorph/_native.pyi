"""Type stubs of ``isomorph._native`` (re-exported by ``isomorph``)."""

import os
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from ._volume import Volume

__version__: str

PathLike = Union[str, "os.PathLike[str]"]
#: A name or path, a ``(vertices, faces)`` pair, an object with ``.vertices``
#: and ``.faces``, a :class:`Volume`, or a dict/object with ``values``,
#: ``origin``, ``spacing`` (and optionally ``iso``).
Input = Union[PathLike, Tuple[npt.ArrayLike, npt.ArrayLike], Volume, Dict[str, Any], Any]
Bounds = Tuple[Tuple[float, float, float], Tuple[float, float, float]]

class Morph:
    """A morph from a source to a target (made by :func:`morph`)."""

    @property
    def method(self) -> str:
        """The method's name (``"level-set"``, ...)."""
    @property
    def report(self) -> Dict[str, Any]:
        """The method's ``MorphReport`` as a dict (outcome, converged, iterations,
        residual, rcond, stages, stored_bytes, peak_bytes, warnings, details)."""
    @property
    def world_bounds(self) -> Bounds:
        """A world box containing every frame mesh: ``((xmin, ymin, zmin), (xmax, ymax, zmax))``."""
    @property
    def inputs(self) -> Tuple[str, str]:
        """The source and target as given (names, paths, or a description of arrays)."""
    def frame_mesh(
        self, t: float, resolution: Optional[int] = None
    ) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.int64]]:
        """The frame at ``t`` in [0, 1] as ``(vertices float32[n, 3], faces int64[m, 3])``,
        world space, outward, with ``resolution`` nodes along the longest edge of the
        morph's bounds (default: the morph's ``resolution``, else 64)."""
    def frame_volume(self, t: float, resolution: Optional[int] = None) -> Volume:
        """The frame at ``t`` sampled on a world grid: ``values`` float32 ``[k, j, i]``,
        node ``(i, j, k)`` at ``origin + spacing * (i, j, k)``, the frame's field minus its
        iso value (positive inside, zero on the surface), over ``world_bounds`` grown by 5 %
        of its longest edge per side, ``resolution`` nodes along the longest edge."""
    def export(
        self,
        dir: PathLike,
        frames: int = 9,
        resolution: Optional[int] = None,
        format: str = "ply",
        timeout: Optional[float] = None,
    ) -> Dict[str, Any]:
        """Writes what ``isomorph morph --out DIR`` writes (``frame_NNN.ply``/``.obj``/``.stl``,
        or with ``format="usd"`` one USD stage ``morph.usda`` holding every frame as a time
        sample; ``contact_sheet.png``, ``preview.gif``, ``report.json``) and returns
        ``report.json`` as a dict."""

def morph(
    source: Input,
    target: Input,
    method: str = "level-set",
    resolution: Optional[int] = None,
    threads: Optional[int] = None,
    fit: bool = True,
    iso: Optional[float] = None,
    timeout: Optional[float] = None,
    **settings: Any,
) -> Morph:
    """Builds the morph of ``source`` into ``target`` with ``method``.

    ``resolution`` (8-1024): grid nodes along the longest edge for the grid methods
    (baseline, level-set, warp) and the default frame resolution (else the libraries'
    defaults and 64, like the CLI's ``--res``). ``threads``: worker threads (default all
    cores; results do not depend on it). ``fit``/``iso``: how files are read (see the
    package docs). ``timeout``: seconds after which the build is cancelled
    (:class:`Cancelled`). ``settings``: the method's keyword settings, see
    :func:`defaults`.
    """

def compare(
    source: Input,
    target: Input,
    methods: Optional[Sequence[str]] = None,
    resolution: Optional[int] = None,
    frames: int = 9,
    out: Optional[PathLike] = None,
    threads: Optional[int] = None,
    fit: bool = True,
    iso: Optional[float] = None,
    format: str = "ply",
    timeout: Optional[float] = None,
    **settings: Any,
) -> List[Dict[str, Any]]:
    """Runs ``methods`` (default: all) on the pair as ``isomorph compare`` does and returns
    the table: one dict per method (method, status ``"ok"``/``"skipped"``/``"failed"``,
    reason, converged, build_seconds, export_seconds, endpoint distances in voxels, genus,
    area, volume and components per frame, ...). With ``out`` it writes the same files as
    ``isomorph compare --out``: ``compare.png``, ``compare.json``, ``compare.md``,
    ``compare.html`` and one folder per method; without, nothing is kept."""

def defaults(method: str) -> Dict[str, Any]:
    """The keyword settings of ``method`` and their Rust defaults."""

def methods() -> List[str]:
    """The method names: baseline, level-set, rbf, warp, tspline, blobtree."""
