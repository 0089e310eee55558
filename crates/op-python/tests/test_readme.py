"""The README's Python example runs as written (from a folder that has
the repository's scenes/ as its own), and the package is documented and
typed: every public name has a docstring and a stub."""

import ast
import contextlib
import io
import os
import re

import oriented_particles as op
from conftest import REPO


def readme_example():
    text = (REPO / "README.md").read_text()
    section = text[text.index("\n## Python\n"):]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_the_readme_example_runs_as_written(tmp_path):
    (tmp_path / "scenes").symlink_to(REPO / "scenes")
    out = io.StringIO()
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        with contextlib.redirect_stdout(out):
            exec(compile(readme_example(), "README.md", "exec"), {})
    finally:
        os.chdir(cwd)
    printed = out.getvalue()
    assert '<dict>: objects[0] "wire".mass = -1: must be finite and > 0' in printed, printed
    assert (tmp_path / "out/wire_damped/summary.json").is_file()


def stubbed_names():
    stub = ast.parse((REPO / "crates/op-python/python/oriented_particles/_native.pyi").read_text())
    names = {}
    for node in stub.body:
        if isinstance(node, ast.ClassDef):
            names[node.name] = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
        elif isinstance(node, ast.FunctionDef):
            names[node.name] = set()
    return names


def test_every_public_name_has_a_docstring_and_a_stub():
    stubs = stubbed_names()
    assert op.__doc__
    for name in op.__all__:
        if name.startswith("__"):
            continue
        value = getattr(op, name)
        assert value.__doc__, name
        assert name in stubs, f"{name} is not in _native.pyi"
        if isinstance(value, type) and not issubclass(value, BaseException):
            for attr in dir(value):
                if attr.startswith("_"):
                    continue
                assert getattr(value, attr).__doc__, f"{name}.{attr}"
                assert attr in stubs[name], f"{name}.{attr} is not in _native.pyi"
    assert (REPO / "crates/op-python/python/oriented_particles/py.typed").is_file()


def test_the_stub_matches_the_module(tmp_path):
    """mypy's stubtest finds _native.pyi in agreement with the extension
    (every name, signature and class); skipped without mypy."""
    import subprocess
    import sys

    import pytest

    pytest.importorskip("mypy")
    # mypy's cache: .ci/run keeps one beside its environment.
    env = dict(os.environ)
    env.setdefault("MYPY_CACHE_DIR", str(tmp_path / "mypy-cache"))
    done = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "--ignore-disjoint-bases", "oriented_particles._native"],
        capture_output=True, text=True, env=env,
    )
    assert done.returncode == 0, done.stdout + done.stderr
