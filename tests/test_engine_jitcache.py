"""Numba's on-disk cache is never stale (``fruitimpact.engine.jitcache``).

Numba keys a cached function on its own file; a cached function that calls a jitted function of another file keeps
the callee it was compiled with (numba's "Notes on caching" name the limit). That is what a ``pip install`` over an
older fruitimpact does to every cross-file call: a CI machine whose site-packages held the caches of an earlier
commit fitted pulses with a 64-node table on a 48-node one and overflowed into NaN. The reference here is plain
Python: the value the source says, after the source changed.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import fruitimpact
from fruitimpact.engine import jitcache

CALLEE = """\
import numba as nb

from fruitimpact.engine.jitcache import CACHE

VALUE = {value}


@nb.njit(cache=CACHE)
def callee():
    return VALUE
"""

CALLER = """\
import numba as nb

from fruitimpact.engine._probe_callee import callee
from fruitimpact.engine.jitcache import CACHE


@nb.njit(cache=CACHE)
def caller():
    return callee() + 1.0
"""


def _run(root: Path) -> str:
    env = {**os.environ, "PYTHONPATH": str(root)}
    env.pop("NUMBA_CACHE_DIR", None)
    done = subprocess.run([sys.executable, "-c", "from fruitimpact.engine._probe_caller import caller; print(caller())"],
                          capture_output=True, text=True, env=env, cwd=root, timeout=300)
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


def test_a_cached_function_follows_a_change_of_the_function_it_calls_in_another_file(tmp_path):
    package = tmp_path / "fruitimpact"
    shutil.copytree(Path(fruitimpact.__file__).parent, package, ignore=shutil.ignore_patterns("__pycache__"))
    callee = package / "engine" / "_probe_callee.py"
    callee.write_text(CALLEE.format(value=1.0))
    (package / "engine" / "_probe_caller.py").write_text(CALLER)
    assert jitcache.CACHE  # numba's cache internals are those this module knows: caching is on
    assert _run(tmp_path) == "2.0"
    index = next((package / "engine" / "__pycache__").glob("_probe_caller.caller-*.nbi"))
    written = index.stat().st_mtime_ns
    assert _run(tmp_path) == "2.0"
    assert index.stat().st_mtime_ns == written  # nothing changed: the cache was used, not rewritten
    callee.write_text(CALLEE.format(value=5.0))  # the caller's own file is unchanged
    assert _run(tmp_path) == "6.0"  # numba's own stamp alone gives 2.0 here
    assert index.stat().st_mtime_ns != written
    (package / "cli" / "extra.py").write_text("# a file above the engine's layer\n")
    written = index.stat().st_mtime_ns
    assert _run(tmp_path) == "6.0"
    assert index.stat().st_mtime_ns == written  # the engine cannot import the CLI: its caches stay


def test_the_layers_are_those_of_the_import_linter_contract():
    """``jitcache.LAYERS`` must list the contract's layers from the bottom up to the highest that holds jitted
    code, or a change in a package a jitted function may read would not refresh its cache."""
    config = tomllib.loads((Path(__file__).parents[1] / "pyproject.toml").read_text())
    contract = next(c for c in config["tool"]["importlinter"]["contracts"] if c["type"] == "layers")
    bottom_up = [layer.replace(" ", "") for layer in reversed(contract["layers"])]
    assert tuple(bottom_up[:len(jitcache.LAYERS)]) == jitcache.LAYERS
    source = Path(fruitimpact.__file__).parent
    jitted = {path.relative_to(source).parts[0] for path in source.rglob("*.py") if "nb.njit" in path.read_text()}
    covered = {name for layer in jitcache.LAYERS for name in layer.split("|")}
    assert jitted <= covered, jitted - covered
    assert jitcache.packages_below("physics") == ("engine", "physics")
