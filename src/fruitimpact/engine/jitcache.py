"""Numba's on-disk cache, keyed on everything a compiled function may have taken in.

Numba decides whether a cached machine code is still good from the source of the function's own file only
(``get_source_stamp``: the file's content hash in recent numba, its mtime and size in older ones). A compiled function
inlines the jitted functions it calls and freezes the module globals it reads, often from other files: change
``pulse.THETA_NODES`` and the cached least-squares fit of ``leastsquares.py``, unchanged, goes on evaluating the old
table. Numba's documentation names this limit ("Notes on caching": changes in functions of another file are not
detected). It bites every upgrade: ``pip install`` over an older fruitimpact leaves the old ``.nbi``/``.nbc`` files
in ``__pycache__``, and a fit then overflowed into NaN (seen on a CI machine whose site-packages held the caches of
an earlier commit).

So the stamp of a function of this package is numba's own stamp together with a hash of every file of the
packages its module may import: its own package and those below it in the import-linter layers contract
(``pyproject.toml``): ``engine`` < ``physics`` < ``damage | library`` < ``impact`` < ``handling | signals``.
Any change in those files makes numba compile anew and overwrite the stale entries; nothing is deleted by hand.
The locators register ahead of numba's own for this package's files only; other packages' caches are untouched.
If numba's cache internals are not what this module expects, ``CACHE`` is False: the functions compile in each
process (slower to start, never stale).
"""

from __future__ import annotations

import functools
import hashlib
import os

#: The packages a module of each package may import (its own and those below it in the layers contract).
LAYERS = ("engine", "physics", "damage|library", "impact", "handling|signals")

_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def packages_below(package: str) -> tuple[str, ...]:
    """The packages whose files a jitted function of ``package`` may depend on: its own layer and the ones below.
    A package outside the layers (none holds jitted code today) depends on all of them."""
    below: list[str] = []
    for layer in LAYERS:
        below.extend(layer.split("|"))
        if package in layer.split("|"):
            return tuple(below)
    return tuple(below)


@functools.lru_cache(maxsize=None)
def source_hash(package: str) -> bytes:
    """SHA-256 over the files (sources and data, not ``__pycache__``) of ``packages_below(package)``; read once
    per process (a few ms), as numba reads each stamp once, when a function is decorated."""
    digest = hashlib.sha256()
    for name in packages_below(package):
        for folder, subfolders, files in os.walk(os.path.join(_ROOT, name)):
            subfolders[:] = sorted(d for d in subfolders if d != "__pycache__")
            for file in sorted(files):
                path = os.path.join(folder, file)
                digest.update(os.path.relpath(path, _ROOT).encode())
                with open(path, "rb") as handle:
                    digest.update(hashlib.sha256(handle.read()).digest())
    return digest.digest()


def _package_of(py_file: str) -> str | None:
    """The top-level package of this project that holds ``py_file``, or None for another project's file."""
    relative = os.path.relpath(os.path.abspath(py_file), _ROOT)
    if relative.startswith(os.pardir) or os.sep not in relative:
        return None
    return relative.split(os.sep, 1)[0]


class _PackageStampMixin:
    """A numba cache locator for this package's files whose stamp adds the hash of the packages below."""

    @classmethod
    def from_function(cls, py_func, py_file):
        if _package_of(py_file) is None:
            return None
        return super().from_function(py_func, py_file)

    def get_source_stamp(self):
        return super().get_source_stamp(), source_hash(_package_of(self._py_file))


def _install() -> bool:
    """Put this package's locators ahead of numba's; True if done (or already done)."""
    try:
        from numba.core import caching

        # public names in recent numba, underscored in older ones
        impl, *bases = [getattr(caching, name, None) or getattr(caching, "_" + name) for name in
                        ("CacheImpl", "UserProvidedCacheLocator", "InTreeCacheLocator", "UserWideCacheLocator")]
        locators = impl._locator_classes
    except (ImportError, AttributeError):
        return False
    if any(issubclass(cls, _PackageStampMixin) for cls in locators):
        return True
    ours = [type("Fruitimpact" + base.__name__.lstrip("_"), (_PackageStampMixin, base), {}) for base in bases]
    impl._locator_classes = ours + list(locators)
    return True


#: The ``cache`` option of every ``numba.njit`` of this package.
CACHE = _install()
