"""Parameter sweeps ("wedges") of a scene as tasks on a Dask cluster.

A wedge is the cartesian product of a few scene settings, each named by its
path in the scene's dict (``"world.linear_damping"``,
``"materials.shape_memory_wire.form"``, ``"objects.0.mass"``). Every variant is
one task: it applies its settings to the scene's dict, validates it
(:meth:`Scene.from_dict`), runs it as ``opsim run`` does into a folder of its
own and returns one row of figures from its summary. The rows are gathered
into one table.

Nothing here imports Dask: :func:`sweep` takes any client with Dask's
``map`` / ``gather`` (``distributed.Client``), so the same code runs on a
``LocalCluster`` or on a cluster of many machines (README "Python": start
``dask scheduler`` on one machine and ``dask worker tcp://SCHEDULER:8786`` on
the others, each with this package installed and the output folder on a
shared file system). A variant gives the same frames wherever it runs: the
simulator is deterministic for any thread count and machine of the same
build.

Example::

    from distributed import Client, LocalCluster
    import oriented_particles as op
    from oriented_particles.sweep import sweep, table

    scene = op.Scene.load("scenes/cookbook/wire_bend_release.ron")
    with LocalCluster(n_workers=2, threads_per_worker=1) as cluster, Client(cluster) as client:
        rows = sweep(client, scene, {
            "materials.shape_memory_wire.form": [0.5, 1, 2, 4],
            "world.linear_damping": [0.1, 0.2, 0.3, 0.6],
        }, out="sweep-out")
    print(table(rows))
"""

import copy
import itertools
import os
import socket
from pathlib import Path
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence

from ._native import DivergenceError, Scene


def set_field(d: Dict[str, Any], path: str, value: Any) -> None:
    """Sets the field ``path`` (dot-separated keys, list indices as numbers)
    of the scene dict ``d`` to ``value``; the field's parent must exist.

    Raises ``KeyError`` naming the path when it does not.
    """
    keys = path.split(".")
    node: Any = d
    for depth, key in enumerate(keys[:-1]):
        try:
            node = node[int(key)] if isinstance(node, list) else node[key]
        except (KeyError, IndexError, ValueError):
            raise KeyError(
                f"{path}: the scene has no {'.'.join(keys[: depth + 1])}"
            ) from None
    last = keys[-1]
    if isinstance(node, list):
        node[int(last)] = value
    elif isinstance(node, dict):
        node[last] = value
    else:
        raise KeyError(f"{path}: {'.'.join(keys[:-1])} is not a dict or a list")


def wedge(axes: Mapping[str, Sequence[Any]]) -> List[Dict[str, Any]]:
    """The variants of a wedge: one dict of settings per combination of the
    values of ``axes`` (a field path to its values), the last axis varying
    fastest."""
    paths = list(axes)
    return [dict(zip(paths, values)) for values in itertools.product(*axes.values())]


def variant_name(settings: Mapping[str, Any]) -> str:
    """A file-safe folder name for a variant: ``form=0.5,linear_damping=0.1``
    (the last key of each path)."""
    parts = [f"{path.rsplit('.', 1)[-1]}={value}" for path, value in settings.items()]
    name = ",".join(parts)
    return "".join(c if c.isalnum() or c in "=,.-_" else "_" for c in name)


def run_variant(
    scene: Dict[str, Any],
    settings: Mapping[str, Any],
    out: str,
    *,
    origin: str = "<sweep>",
    base_dir: Optional[str] = None,
    expected_warnings: Sequence[str] = (),
    threads: int = 1,
    **run: Any,
) -> Dict[str, Any]:
    """One task of a sweep: the scene dict ``scene`` with ``settings``
    applied, run into ``out`` (``Scene.run``'s further arguments in
    ``run``). Returns its row: ``variant``, the settings, ``diverged``,
    ``frames``, ``steps``, ``wall_seconds``, per object
    ``<name>.rest_shape_error_max`` and ``<name>.rest_shape_error_final``,
    ``warnings`` (their count), ``host`` and ``out``.

    A variant that diverges is a row with ``diverged`` True (its summary
    says where); a variant that is not a valid scene raises ``ValueError``.
    """
    d = copy.deepcopy(scene)
    for path, value in settings.items():
        set_field(d, path, value)
    name = variant_name(settings)
    variant = Scene.from_dict(
        d,
        origin=f"{origin} [{name}]",
        base_dir=base_dir,
        expected_warnings=list(expected_warnings),
    )
    try:
        summary = variant.run(out=out, threads=threads, **run)
    except DivergenceError as e:
        summary = e.summary
    row: Dict[str, Any] = {"variant": name, **settings}
    row["diverged"] = summary["diverged"]
    row["frames"] = summary["frames"]
    row["steps"] = summary["steps"]
    for o in summary["objects"]:
        row[f"{o['name']}.rest_shape_error_max"] = o["rest_shape_error_max"]
        row[f"{o['name']}.rest_shape_error_final"] = o["rest_shape_error_final"]
    row["warnings"] = len(summary["warnings"])
    row["wall_seconds"] = summary["wall_seconds"]
    row["host"] = f"{socket.gethostname()}:{os.getpid()}"
    row["out"] = str(out)
    return row


def sweep(
    client: Any,
    scene: Scene,
    axes: Mapping[str, Sequence[Any]],
    out: "str | os.PathLike[str]",
    **run: Any,
) -> List[Dict[str, Any]]:
    """Runs every variant of the wedge ``axes`` of ``scene`` as one task on
    ``client`` (a ``distributed.Client``), each into ``out/<variant>``, and
    returns their rows (:func:`run_variant`) in wedge order.

    ``run`` holds ``Scene.run``'s arguments for every variant (``frames``,
    ``formats``, ``threads``: 1 by default, one task per worker thread).
    """
    out = Path(out)
    variants = wedge(axes)
    d = scene.to_dict()
    base_dir = str(scene.base_dir) if scene.base_dir is not None else None
    futures = [
        client.submit(
            run_variant,
            d,
            settings,
            str(out / variant_name(settings)),
            origin=scene.origin,
            base_dir=base_dir,
            expected_warnings=scene.expected_warnings,
            key=f"opsim-{scene.name}-{variant_name(settings)}",
            pure=False,
            **run,
        )
        for settings in variants
    ]
    return client.gather(futures)


def table(rows: Iterable[Mapping[str, Any]], columns: Optional[Sequence[str]] = None) -> str:
    """The rows as a Markdown table (numbers to 4 significant digits);
    ``columns`` chooses and orders them (default: every column but ``out``,
    in the first row's order)."""
    rows = list(rows)
    if not rows:
        return ""
    if columns is None:
        columns = [c for c in rows[0] if c != "out"]

    def cell(v: Any) -> str:
        if isinstance(v, float):
            return f"{v:.4g}"
        return str(v)

    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(cell(r.get(c, "")) for c in columns) + " |" for r in rows]
    return "\n".join(lines)
