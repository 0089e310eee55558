"""Shape-memory deformable objects from oriented particles, from Python.

The Rust simulator of this repository (``opsim``) as a Python package:

- :class:`Scene` -- a scene file or a dict of the same schema (docs/scenes.md),
  validated as ``opsim`` validates it; ``scene.run(out=...)`` writes exactly
  what ``opsim run`` writes and returns the summary as a dict;
- :class:`Simulation` -- ``scene.build()``: step a scene from Python and read or
  write its particles as numpy arrays, its skins and surfaces as meshes;
- :func:`fit` -- point-set interpolation, as ``opsim fit``;
- :class:`DivergenceError` -- a run that diverged (``opsim run``'s exit 3);
- :mod:`oriented_particles.sweep` -- parameter sweeps as Dask tasks.

Bad input raises ``ValueError`` with opsim's message (the field path, the value
and what is allowed). Steps run with the GIL released, on as many threads as
asked (the results do not depend on the count); Ctrl-C stops a run or an
``advance`` at the next frame and raises ``KeyboardInterrupt``.

Example::

    import oriented_particles as op

    scene = op.Scene.load("scenes/spiral.ron")
    summary = scene.run(out="out/spiral", formats=["obj", "ply"])
    sim = scene.build()
    sim.advance(1.0)
    xyz = sim.positions("spiral")          # (n, 3) float64
"""

from ._native import (
    DivergenceError,
    FitResult,
    Scene,
    Simulation,
    __version__,
    fit,
)

__all__ = [
    "DivergenceError",
    "FitResult",
    "Scene",
    "Simulation",
    "fit",
    "__version__",
]
