"""Comparing run folders: every file byte for byte, except the wall-clock
figures (summary.json's wall_seconds and stages, metrics.csv's last column)
and checkpoint.bin (which records them)."""

import json
from pathlib import Path

WALL_CLOCK_FILES = {"checkpoint.bin"}


def files(folder):
    folder = Path(folder)
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file())


def comparable(folder, name):
    path = Path(folder) / name
    if name == "summary.json":
        summary = json.loads(path.read_text())
        summary.pop("wall_seconds")
        summary.pop("stages")
        return summary
    if name == "metrics.csv":
        return [line.rsplit(",", 1)[0] for line in path.read_text().splitlines()]
    return path.read_bytes()


def assert_same_run(a, b):
    """The runs in folders ``a`` and ``b`` wrote the same files with the same
    content, wall-clock figures aside."""
    names = files(a)
    assert names == files(b)
    for name in names:
        if name in WALL_CLOCK_FILES:
            continue
        assert comparable(a, name) == comparable(b, name), name
