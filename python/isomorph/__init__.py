"""isomorph: implicit and volumetric 3D shape metamorphosis, from Rust.

Five published morphing methods (and a naive baseline) behind one call::

    import isomorph
    m = isomorph.morph("sphere", "torus", method="level-set", resolution=48)
    vertices, faces = m.frame_mesh(0.5)        # float32 [n, 3], int64 [m, 3]
    volume = m.frame_volume(0.5)               # isomorph.Volume, values [k, j, i]
    m.report["converged"], m.export("out/sphere-torus")
    rows = isomorph.compare("sphere", "torus", methods=["baseline", "rbf"])

Inputs (``source``, ``target``):

- a built-in shape name (``"sphere"``, ``"torus"``, ``"ball"``, ``"c-shape"``,
  ``"mug"``, ``"chain"``, ``"cube"``, ``"holed-cube"``, ``"bunny"``), a mesh file
  (``.obj``, ``.ply``, ``.stl``), a ``.npy`` volume or a BlobTree scene
  (``.ron``/``.json``; for ``method="blobtree"`` also the built-in scene names),
  as ``str`` or ``os.PathLike``. Files are fitted into the built-in shapes' box
  (centred, longest side 0.9) unless ``fit=False``; ``iso`` is the surface level
  of volume files (as the CLI's ``--keep-scale`` and ``--iso``);
- a mesh: a ``(vertices, faces)`` tuple (float ``[n, 3]``, integer ``[m, 3]``)
  or any object with ``.vertices`` and ``.faces`` (a ``trimesh.Trimesh``),
  used in its own coordinates;
- a volume: an :class:`isomorph.Volume`, or a dict or object with ``values``
  (3D, ``[k, j, i]``), ``origin``, ``spacing`` and optionally ``iso``, used in
  its own coordinates.

Settings are keyword arguments with the Rust libraries' defaults
(``isomorph.defaults(method)`` lists them); an unknown setting, one of
another method or a bad value raises :class:`SettingError` (a ``ValueError``)
naming it. Rust errors become :class:`MorphError` (bad inputs
:class:`InputError`, also a ``ValueError``) with the Rust message.

Long calls run without the GIL; Ctrl-C cancels them through the morph
contract's cancellation and raises ``KeyboardInterrupt``; ``timeout=`` seconds
cancels them the same way and raises :class:`Cancelled`.
"""

from ._errors import Cancelled, InputError, MorphError, SettingError
from ._volume import Volume
from ._native import Morph, __version__, compare, defaults, methods, morph

__all__ = [
    "Cancelled",
    "InputError",
    "Morph",
    "MorphError",
    "SettingError",
    "Volume",
    "__version__",
    "compare",
    "defaults",
    "methods",
    "morph",
]
