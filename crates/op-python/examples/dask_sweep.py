"""A parameter wedge of a cookbook scene on Dask distributed.

16 variants of the shape-memory wire of scenes/cookbook/wire_bend_release.ron
(form stiffness x linear damping), each a task that runs the scene into a
folder of its own and returns a row of its summary; the rows are gathered
into one table (printed, and written as OUT/table.md).

    python crates/op-python/examples/dask_sweep.py                      # a LocalCluster of 2 workers
    python crates/op-python/examples/dask_sweep.py tcp://host:8786      # an existing cluster

On several machines: `dask scheduler` on one, `dask worker tcp://host:8786
--nthreads 1` on each of the others (each with this package installed, `pip
install ./crates/op-python`, and the repository's scenes/ at the same path,
or the output folder `--out` on a shared file system), then give the
scheduler's address. A variant gives the same frames wherever it runs.
"""

import argparse
from pathlib import Path

import oriented_particles as op
from oriented_particles.sweep import sweep, table

REPO = Path(__file__).resolve().parents[3]

AXES = {
    "materials.shape_memory_wire.form": [0.5, 1.0, 2.0, 4.0],
    "world.linear_damping": [0.1, 0.2, 0.3, 0.6],
}

COLUMNS = [
    "variant",
    "diverged",
    "wire.rest_shape_error_max",
    "wire.rest_shape_error_final",
    "wall_seconds",
    "host",
]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scheduler", nargs="?", help="a Dask scheduler's address (default: a LocalCluster)")
    parser.add_argument("--out", default="sweep-out", help="output folder (one run folder per variant)")
    parser.add_argument("--workers", type=int, default=2, help="LocalCluster workers")
    parser.add_argument("--frames", type=int, default=None, help="frames per run (default: the scene's)")
    args = parser.parse_args(argv)

    from distributed import Client, LocalCluster

    scene = op.Scene.load(REPO / "scenes/cookbook/wire_bend_release.ron")
    run = {"formats": ["ply"], "frames": args.frames, "checkpoint_every": "off"}
    if args.scheduler:
        with Client(args.scheduler) as client:
            rows = sweep(client, scene, AXES, args.out, **run)
    else:
        with LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True) as cluster:
            with Client(cluster) as client:
                rows = sweep(client, scene, AXES, args.out, **run)
    text = table(rows, COLUMNS)
    Path(args.out).mkdir(parents=True, exist_ok=True)
    (Path(args.out) / "table.md").write_text(text + "\n")
    print(text)
    return rows


if __name__ == "__main__":
    main()
