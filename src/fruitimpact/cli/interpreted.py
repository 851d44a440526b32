"""One impact from the console without starting numba (issue 15 item 4: a warm ``fruitimpact simulate`` within
0.4 s).

Importing numba and starting its CPU target take about 0.7 s on two cores, ten times what one impact costs. For
``fruitimpact simulate`` the console script runs the engine's own functions — the same source, every line —
interpreted by Python: a stand-in ``numba`` module whose ``njit`` returns the function itself (and ``prange``
is ``range``, the only other name the engine uses) is installed before anything imports numba.  One impact then
takes about 0.2 ms interpreted (the compiled row takes 5 µs): nothing a person at a terminal sees.

Interpreted code is ~50x slower, which one Hunt–Crossley or plastic impact does not feel, but the adaptive
integrator of a stiff law would (Kuwabara–Kono: 5 s interpreted against 0.75 s compiled): an engine function
called after ``BUDGET`` seconds of interpretation stops the run the same way, and the command runs compiled.

Where interpretation and compilation could differ, they are not allowed to.  Compiled with
``error_model="numpy"``, an engine function returns inf or NaN where Python's ``math`` raises (a division by
zero, ``log(0)``, an overflow); every engine function is wrapped so that such an exception inside it stops the
run before anything is printed (``Recompile``, not a ``ValueError``: it must not pass for a refused input), and
the console re-runs the command compiled (``FRUITIMPACT_COMPILED=1``).  ``tests/test_cli.py`` checks the
interpreted and compiled commands print the same bytes over random impacts.
"""

from __future__ import annotations

import functools
import os
import sys
import time
import types

#: Set to 1 to run every command compiled (the re-run after a ``Recompile``, and a user's choice).
COMPILED_VARIABLE = "FRUITIMPACT_COMPILED"
#: Commands answered interpreted: one impact each (``--plot`` draws curves of a few hundred points: still
#: interpreted, in about 0.1 s).
INTERPRETED_COMMANDS = ("simulate",)


#: Seconds of interpretation (from the stand-in's install, imports included) after which the command is run
#: compiled instead: one impact takes ~0.15 s in all, numba's start-up alone 0.7 s.
BUDGET = 0.4
_deadline = [float("inf")]


class Recompile(BaseException):
    """An engine function met what compiled code turns into inf or NaN: the command must run compiled."""


def _guarded(function):
    @functools.wraps(function)
    def run(*args, **kwargs):
        if time.perf_counter() > _deadline[0]:  # only ever inside the engine: nothing has been printed
            raise Recompile(f"{function.__qualname__}: over {BUDGET} s interpreted")
        try:
            return function(*args, **kwargs)
        except (ArithmeticError, ValueError) as exc:  # the engine raises none itself: these are math's
            raise Recompile(f"{function.__qualname__}: {exc}") from exc

    run.py_func = function
    return run


def _njit(*args, **kwargs):
    if args and callable(args[0]) and len(args) == 1 and not kwargs:
        return _guarded(args[0])
    return _guarded


def wanted(command: str | None) -> bool:
    """Whether the console should answer ``command`` interpreted: one of ``INTERPRETED_COMMANDS``, numba not
    imported yet, and no ``FRUITIMPACT_COMPILED=1``."""
    return (command in INTERPRETED_COMMANDS and "numba" not in sys.modules
            and os.environ.get(COMPILED_VARIABLE, "") != "1")


def interpret_engine() -> None:
    """Install the stand-in ``numba`` (before any engine module is imported)."""
    stand_in = types.ModuleType("numba")
    stand_in.__doc__ = "fruitimpact's stand-in: the engine interpreted (fruitimpact.cli.interpreted)"
    stand_in.njit = _njit
    stand_in.prange = range
    sys.modules["numba"] = stand_in
    _deadline[0] = time.perf_counter() + BUDGET


def rerun_compiled(argv) -> None:
    """Replace this process by the same command, compiled (flushing nothing: nothing was printed yet)."""
    os.environ[COMPILED_VARIABLE] = "1"
    os.execv(sys.executable, [sys.executable, "-m", "fruitimpact", *argv])


__all__ = ["BUDGET", "COMPILED_VARIABLE", "INTERPRETED_COMMANDS", "Recompile", "interpret_engine", "rerun_compiled", "wanted"]
