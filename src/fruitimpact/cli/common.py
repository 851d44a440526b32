"""Shared pieces of the command line: the one-line error, option parsing with
units, JSON output, and the impact options every command shares.

Bad input is answered with one line on stderr naming the argument and its
allowed range, exit status 2, never a traceback.
"""

from __future__ import annotations

import argparse
import math
import re
import sys

from fruitimpact.impact.quantities import INPUTS
from fruitimpact.impact.outputs import dump_json  # noqa: F401  (the commands import it from here)
from fruitimpact.impact.units import parse_quantity
from fruitimpact.impact.validation import check_choice, check_value, usage_message

from fruitimpact.cli import PROG  # noqa: E402,F401  (defined by the package first; the commands import it from here)


class UsageError(Exception):
    """Bad command-line input: printed as one line, exit status 2."""


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs):
        # "--mas 0.1" is a misspelt option, not --mass: refused, never completed to a neighbour
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)

    def error(self, message):  # one line, no usage block
        raise UsageError(message)


def _help(quantity) -> str:
    unit = f" [{quantity.si_unit}]" if quantity.si_unit else ""
    return f"{quantity.doc}{unit}"


#: The arguments through which a command reads a file of the user's (positional files, a fruit file, a sphere's
#: calibration): no output may be written over one of them.
INPUT_FILE_ARGS = (("file", "FILE"), ("log", "LOG"), ("line", "LINE"), ("tests", "TESTS"), ("fruit", "--fruit"),
                   ("sphere_calibration", "--sphere-calibration"))


def check_outputs(*outputs, args=None) -> None:
    """Each ``(option, path, formats)`` whose path is given: a file that can be written, of one of ``formats``
    (``impact.outputs.check_output``), and not one of the files the command reads (``args``'
    ``INPUT_FILE_ARGS``: a figure written over the log it was drawn from loses the user's data), before any work;
    a figure (``FIGURE_FORMATS``) also needs matplotlib."""
    import importlib.util
    import os

    from fruitimpact.impact.outputs import FIGURE_FORMATS, check_output

    inputs = [(name, getattr(args, dest)) for dest, name in INPUT_FILE_ARGS
              if isinstance(getattr(args, dest, None), str) and os.path.isfile(getattr(args, dest))]
    for option, path, formats in outputs:
        if path is None:
            continue
        for name, read in inputs:
            if os.path.exists(path) and os.path.samefile(path, read):
                raise UsageError(f"argument {option}: {path!r} is the file {name} the command reads: write to "
                                 f"another file")
        _library_call(check_output, path, option, formats)
        if formats is FIGURE_FORMATS and importlib.util.find_spec("matplotlib") is None:
            raise UsageError(f"argument {option}: figures need matplotlib: pip install 'fruitimpact[plot]'")


def read_option_count(option: str, value, low: int, high: int | None = None) -> int:
    """An integer option (``--port``, ``--lanes``, ``--count`` …) read by ``impact.validation.read_count``:
    ``UsageError`` naming the option and its range otherwise (``str.isdigit`` took ``²`` for a digit)."""
    from fruitimpact.impact.validation import read_count

    try:
        return read_count(option.split("/")[-1].lstrip("-").replace("-", "_"), value, low, high)
    except ValueError as exc:
        raise UsageError(f"argument {option}: {exc}") from None


def _library_call(func, *args, **kwargs):
    """Run a library call, turning its ValueError into the CLI's one-line error."""
    try:
        return func(*args, **kwargs)
    except ValueError as exc:
        raise UsageError(usage_message(exc)) from None


def _add_impact_options(parser: argparse.ArgumentParser) -> None:
    from fruitimpact.impact.registries import REGISTRIES

    group = parser.add_argument_group("fruit and impact (plain numbers are SI; units accepted)")
    for quantity in INPUTS.values():
        if not quantity.option:
            continue
        if quantity.numeric:
            group.add_argument(quantity.option, metavar="VALUE", help=_help(quantity), type=_checked(quantity.name))
        else:
            registry = REGISTRIES[quantity.choices]
            choices = "{" + ",".join(registry) + "}"
            group.add_argument(quantity.option, metavar=choices, help=f"{quantity.doc} (default {quantity.default})",
                               type=_checked(quantity.name, registry))


def _checked(name: str, registry=None):
    """An argparse ``type`` that checks an impact option with the library's own check (``check_value`` or
    ``check_choice``, the same message) while parsing, so that a usage error is answered before any work or
    numba start-up (issue 15 item 4).  It returns the text as typed: the library reads it again."""
    def check(text: str) -> str:
        try:
            check_value(name, text) if registry is None else check_choice(name, text, registry)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
        return text

    check.__name__ = name  # argparse names the type in some of its own messages
    return check


def _simulate_kwargs(args) -> dict:
    """``simulate()`` keywords from the given options, as typed (the library reads the units):
    every input by its name, ``fruit`` and ``surface`` as library names."""
    return {name: getattr(args, name) for name in INPUTS if getattr(args, name, None) is not None}


def _float_list(option: str, text: str, low: float, high: float, high_inclusive: bool) -> list[float]:
    """"0.3,0.5,0.7" → floats, each in (low, high) or (low, high]."""
    values = []
    for item in text.split(","):
        try:
            value = float(parse_quantity(item, "velocity" if option == "--velocities" else "dimensionless"))
        except ValueError as exc:
            raise UsageError(f"argument {option}: {exc}") from None
        if not (math.isfinite(value) and low < value and (value <= high if high_inclusive else value < high)):
            bracket = "]" if high_inclusive else ")"
            raise UsageError(f"argument {option}: each value must be in ({low:g}, {high:g}{bracket}; got {item!r}")
        values.append(value)
    return values



class _Ordered(argparse.Action):
    """Store the value and remember the order in which the options were given (sweep axes)."""

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, values)
        namespace.order = [d for d in (getattr(namespace, "order", None) or []) if d != self.dest] + [self.dest]


_NEGATIVE = re.compile(r"^-(\d|\.\d|inf|nan)", re.IGNORECASE)


def _attach_negative_values(argv: list[str]) -> list[str]:
    """Let "--drop-height -3cm" reach our range check instead of argparse's
    "expected one argument": glue a value that starts with "-<digit>" to its option."""
    glued = []
    i = 0
    while i < len(argv):
        token = argv[i]
        if (token.startswith("--") and "=" not in token and i + 1 < len(argv)
                and _NEGATIVE.match(argv[i + 1])):
            glued.append(f"{token}={argv[i + 1]}")
            i += 2
            continue
        glued.append(token)
        i += 1
    return glued


def _numba_without_blas() -> None:
    """Start numba's CPU target, when numba is first imported, without letting it import SciPy's BLAS.

    On its first compiled call numba imports ``scipy.linalg.cython_blas`` (about
    0.2 s) only to offer ``np.dot`` inside compiled code, which the engine never
    uses.  In the CLI's own process we refuse that import while the target
    initialises; library users (who may want numba's np.dot) are not affected.
    Nothing happens until a command imports numba, so ``--help`` and usage errors
    (checked before any work) never start it (issue 15 item 4)."""
    if "numba" in sys.modules:
        _start_numba_target()
    elif not any(isinstance(finder, _AfterNumbaImport) for finder in sys.meta_path):
        sys.meta_path.insert(0, _AfterNumbaImport())


def _start_numba_target() -> None:
    if "scipy.linalg.cython_blas" in sys.modules:
        return
    sys.modules["scipy.linalg.cython_blas"] = None  # makes the import raise ImportError
    try:
        from numba.core.registry import cpu_target

        cpu_target.target_context.refresh()
    finally:
        del sys.modules["scipy.linalg.cython_blas"]


class _AfterNumbaImport:
    """A one-shot import hook: once ``import numba`` has run, start its target (``_start_numba_target``)."""

    def find_spec(self, name, path=None, target=None):
        if name != "numba":
            return None
        import importlib.machinery

        spec = importlib.machinery.PathFinder.find_spec(name, path)
        if spec is None or spec.loader is None:
            return spec
        run_module = spec.loader.exec_module

        def exec_module(module):
            if self in sys.meta_path:  # once: a probe (find_spec alone) does not use the hook up
                sys.meta_path.remove(self)
            run_module(module)
            try:
                _start_numba_target()
            except Exception:  # an optimisation only: numba starts its target itself on first use
                pass

        spec.loader.exec_module = exec_module
        return spec


# --------------------------------------------------------------------------------------------- lots
def add_spread_option(parser) -> None:
    """``--no-spreads``: every member at the fruit's central values (identical fruit)."""
    parser.add_argument("--no-spreads", action="store_true",
                        help="identical fruit: do not draw mass, size, modulus, failure stress, susceptibility "
                             "and (with --criterion energy) threshold energy from the fruit's library spreads (by "
                             "default a lot varies; giving an option fixes it)")


def print_spreads(command: str, lines) -> None:
    """The spreads a lot was drawn from, on stderr (the results stay on stdout)."""
    print(f"{PROG} {command}: the lot varies as (give an option to fix it, --no-spreads for identical fruit):",
          file=sys.stderr)
    for line in lines:
        print(f"  {line}", file=sys.stderr)
