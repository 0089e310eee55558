"""Type stubs of the extension module ``oriented_particles._native``.

Kept by hand beside the Rust sources (crates/op-python/src); the tests check
that every public name of the module is stubbed here.
"""

import os
import pathlib
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union, final

import numpy as np
import numpy.typing as npt

__all__ = ["Scene", "Simulation", "FitResult", "fit", "DivergenceError", "__version__"]

__version__: str

_Path = Union[str, "os.PathLike[str]"]
_Floats = npt.NDArray[np.float64]
_Ints = npt.NDArray[np.int64]
_ArrayLike = npt.ArrayLike

class DivergenceError(RuntimeError):
    """The simulation diverged (``opsim run``'s exit code 3).

    The message is opsim's: it names the step, the time and the particle.
    ``summary`` holds the run's summary (summary.json as a dict) for
    ``Scene.run``, None for a ``Simulation`` stepped from Python.
    """

    summary: Optional[Dict[str, Any]]

@final
class Scene:
    """A validated scene: what to simulate, for how long, what to write.

    Immutable: edit its dict (``to_dict``) and make a new one (``from_dict``).
    """

    @staticmethod
    def load(
        path: _Path, *, no_work_limits: bool = False, max_particle_steps: Optional[float] = None
    ) -> "Scene":
        """Reads and validates a scene file (.ron or .json) as ``opsim run`` does.

        Raises ``ValueError`` with opsim's message for a bad scene, ``OSError``
        when the file cannot be read.
        """
    @staticmethod
    def from_dict(
        d: Dict[str, Any],
        *,
        origin: Optional[str] = None,
        base_dir: Optional[_Path] = None,
        expected_warnings: Optional[Sequence[str]] = None,
        no_work_limits: bool = False,
        max_particle_steps: Optional[float] = None,
    ) -> "Scene":
        """Makes a scene from a dict of the scene schema, validated as a file is.

        Raises ``ValueError`` naming the field path, the value and what is
        allowed.
        """
    def to_dict(self) -> Dict[str, Any]:
        """The scene as a dict (the JSON form of a scene file, defaults filled in)."""
    @property
    def name(self) -> str:
        """The scene's name (the default output folder ``opsim-out/<name>``)."""
    @property
    def origin(self) -> str:
        """Where the scene came from, in messages."""
    @property
    def source(self) -> Optional[pathlib.Path]:
        """The scene file, or None for a scene made from a dict."""
    @property
    def base_dir(self) -> Optional[pathlib.Path]:
        """Where relative points files are found (None: the working directory)."""
    @property
    def expected_warnings(self) -> List[str]:
        """The warnings the scene expects (``// expect-warning:`` header lines)."""
    @property
    def object_names(self) -> List[str]:
        """The names of the scene's objects, in scene order."""
    def stable_step(self) -> Dict[str, Any]:
        """The estimated edge of stability of ``world.dt`` (``opsim check``).

        Keys: ``dt_max``, ``recommended``, ``omega_squared``, ``object``.
        """
    def build(self, *, threads: Optional[int] = None) -> "Simulation":
        """Builds the scene into a simulation at frame 0 (settle phase run)."""
    def run(
        self,
        out: Optional[_Path] = None,
        *,
        formats: Optional[Sequence[str]] = None,
        threads: Optional[int] = None,
        progress: Union[None, bool, Callable[[int, int], Any]] = None,
        frames: Optional[int] = None,
        allow_breakup: bool = False,
        allow_unstable_step: bool = False,
        checkpoint_every: Union[None, int, str] = None,
        resume: bool = False,
    ) -> Dict[str, Any]:
        """Runs the scene as ``opsim run`` and returns the summary as a dict.

        Writes exactly what ``opsim run`` writes into ``out`` (default
        ``opsim-out/<name>``). Raises ``DivergenceError`` (with ``summary``)
        when the run diverged, ``ValueError`` for a step beyond the edge of
        stability, ``OSError`` for an output it cannot write,
        ``KeyboardInterrupt`` on Ctrl-C (after writing the summary and a
        checkpoint).
        """
    def __eq__(self, value: object, /) -> bool: ...
    def __reduce__(self) -> Tuple[Any, ...]: ...

@final
class Simulation:
    """A scene built into a world, stepped from Python (``Scene.build()``).

    Arrays are per object, in the object's particle order, float64, in scene
    coordinates (z-up).
    """

    @property
    def time(self) -> float:
        """Scene time (0 at frame 0; frame k at k / frame_rate)."""
    @property
    def steps(self) -> int:
        """Steps taken, the settle phase's included."""
    @property
    def dt(self) -> float:
        """The time step (``world.dt``)."""
    @property
    def frame_rate(self) -> float:
        """Frames per unit of scene time."""
    @property
    def duration(self) -> float:
        """The scene's duration (after the settle phase)."""
    @property
    def object_names(self) -> List[str]:
        """The object names, in scene order."""
    def advance(self, t: float) -> None:
        """Advances to scene time ``t`` through every frame time on the way."""
    def step(self) -> None:
        """Advances by one step of ``world.dt``."""
    def ids(self, name: str) -> List[int]:
        """The particle ids of object ``name``, one per row of its arrays."""
    def positions(self, name: str) -> _Floats:
        """Positions, shape (n, 3)."""
    def orientations(self, name: str) -> _Floats:
        """Orientations as unit quaternions (w, x, y, z), shape (n, 4)."""
    def normals(self, name: str) -> _Floats:
        """Unit normals, shape (n, 3)."""
    def velocities(self, name: str) -> _Floats:
        """Velocities, shape (n, 3)."""
    def set_positions(self, name: str, positions: _ArrayLike) -> None:
        """Moves the object's particles, shape (n, 3)."""
    def set_velocities(self, name: str, velocities: _ArrayLike) -> None:
        """Sets the object's velocities, shape (n, 3)."""
    def add_force(
        self,
        name: str,
        force: _ArrayLike,
        *,
        torque: Optional[_ArrayLike] = None,
        particles: Optional[Sequence[int]] = None,
    ) -> None:
        """Adds a force (and torque) to each particle, for the next step only."""
    def add_forces(self, name: str, forces: _ArrayLike) -> None:
        """Adds one force per particle, shape (n, 3), for the next step only."""
    def skin_mesh(self, name: str) -> Tuple[_Floats, _Ints]:
        """The object's implicit skin as ``(vertices, faces)``."""
    def surface_mesh(self, name: str) -> Tuple[_Floats, _Ints]:
        """The triangulation of the object's particles as ``(vertices, faces)``."""
    def stage_seconds(self) -> Dict[str, float]:
        """Seconds spent per stage so far."""
    def energies(self) -> Dict[str, float]:
        """``kinetic``, ``potential``, ``total``, ``oscillation``, ``max_speed`` now."""

@final
class FitResult:
    """The result of :func:`fit`: the mesh and the figures ``opsim fit`` prints."""

    @property
    def vertices(self) -> _Floats:
        """Mesh vertices, (m, 3), in the samples' coordinates."""
    @property
    def normals(self) -> _Floats:
        """Unit vertex normals, (m, 3)."""
    @property
    def faces(self) -> _Ints:
        """Triangles as vertex indices, (k, 3)."""
    @property
    def figures(self) -> Dict[str, Any]:
        """What ``opsim fit`` prints, as a dict."""
    def write_obj(self, path: _Path) -> None:
        """Writes the mesh as ``opsim fit --out`` does."""

def fit(
    points: Union[_Path, _ArrayLike],
    spacing: Optional[float] = None,
    open: Optional[bool] = None,
    *,
    normals: Optional[_ArrayLike] = None,
    relax: float = 0.0,
    approximate: Optional[bool] = None,
) -> FitResult:
    """Fits a surface of oriented particles to a point set, as ``opsim fit``."""
