"""Command-line interface: ``fruitimpact simulate | paper | models | batch | sweep | population``.

One module per group of commands (``simulate``, ``reference``, ``runs``); the
shared option handling and the one-line error live in ``common``.  This
module imports nothing but the standard library, so that a Ctrl-C at any
moment of the start-up is answered with one line (exit status 130), and
heavy imports (numba, pandas, matplotlib, pyarrow, dask) happen only in the
subcommands that need them.
"""

from __future__ import annotations

import importlib
import sys

PROG = "fruitimpact"
COMMANDS = ("simulate", "paper", "models", "batch", "sweep", "population", "drop", "safe-height", "line", "sphere",
            "fruits", "surfaces", "analyze", "classes", "stream", "synth", "serve", "fit-damage")


def build_parser():
    """The argparse parser of every command (built from the table of quantities)."""
    from fruitimpact.cli import app, damage, labtests, reference, runs, signals, simulate, sphere
    from fruitimpact.cli.common import _Parser

    parser = _Parser(prog=PROG, description="Simulate and measure fruit impacts on surfaces (SI units).")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    simulate.add_parser(sub)
    reference.add_parsers(sub)
    runs.add_parsers(sub)
    damage.add_parsers(sub)
    labtests.add_parsers(sub)
    sphere.add_parsers(sub)
    signals.add_parsers(sub)
    app.add_parsers(sub)
    return parser


def _command(argv) -> str | None:
    return next((token for token in argv if token in COMMANDS), None)


#: Set by the console script's SIGINT handler (``_note_interrupts``): a Ctrl-C arrived.
_SIGNALLED: list = []


def _note_interrupts() -> None:
    """Python's own answer to SIGINT (KeyboardInterrupt at the next bytecode), noted as it is raised.  A Ctrl-C
    that lands inside an import run by C code can come back as another error: NumPy's C extension imports
    ``datetime`` through ``PyCapsule_Import``, which replaces the KeyboardInterrupt by "ImportError:
    PyCapsule_Import could not import module "datetime"" (seen once in 24 SIGINTs 0.55–0.9 s into a start-up
    under load).  With the note, ``main`` answers such a failure as the interrupt it is."""
    import signal

    def interrupt(signum, frame):
        _SIGNALLED.append(signum)
        _deliver_interrupt(signum, frame)

    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:  # not when SIGINT is ignored (nohup, &)
        signal.signal(signal.SIGINT, interrupt)


#: The import system's own frames: a Ctrl-C is not raised inside them (``_deliver_interrupt``).
IMPORT_SYSTEM = ("<frozen importlib._bootstrap>", "<frozen importlib._bootstrap_external>")


def _deliver_interrupt(signum, frame) -> None:
    """Raise the KeyboardInterrupt of a Ctrl-C, unless the main thread is inside the import system's own code
    (``IMPORT_SYSTEM``): there it can escape the lock bookkeeping as a traceback printed before the one line
    (seen once in a fresh-clone CI run: raised in ``_lock_unlock_module``'s ``release``, 24 SIGINTs into
    `simulate`'s start-up under load) or leave a module's lock held.  It is then delivered again 5 ms later by a
    one-shot timer (SIGALRM, as ``_redeliver_interrupts_from_callbacks`` does), by then back in ordinary code."""
    import signal

    if frame is not None and frame.f_code.co_filename in IMPORT_SYSTEM and hasattr(signal, "setitimer"):
        signal.signal(signal.SIGALRM, _deliver_interrupt)
        signal.setitimer(signal.ITIMER_REAL, 0.005)
        return
    raise KeyboardInterrupt


#: Callbacks in which a Ctrl-C was swallowed.  numba's compiler then fails on its own (a cache that never
#: received its object: "RuntimeError: no compiled object yet"), before the interrupt is delivered again;
#: that failure is the interrupt's, and is answered as one.
_SWALLOWED: list = []


def _redeliver_interrupts_from_callbacks() -> None:
    """A Ctrl-C that lands inside a C callback (numba's LLVM object cache notifies Python through ctypes)
    cannot propagate: Python prints "Exception ignored ... Traceback ... KeyboardInterrupt" and goes on.
    Swallowing it would ignore the user; it is delivered again 5 ms later by a one-shot timer (SIGALRM,
    which nothing else here uses), by then back in Python code, where ``main`` answers it with its one
    line and exit status 130.  Raising it inside the hook itself would only be reported as ignored too."""
    import signal

    if not hasattr(signal, "SIGALRM"):  # Windows: no one-shot timer; Python's own report stands
        return
    default_hook = sys.unraisablehook

    def hook(unraisable):
        if isinstance(unraisable.exc_value, KeyboardInterrupt):
            _SWALLOWED.append(unraisable.object)
            signal.signal(signal.SIGALRM, _deliver_interrupt)
            signal.setitimer(signal.ITIMER_REAL, 0.005)
            return
        default_hook(unraisable)

    sys.unraisablehook = hook


def _cancel_redelivery() -> None:
    """A redelivery still pending when ``main`` ends would interrupt whoever called it: cancel it."""
    import signal

    if hasattr(signal, "setitimer"):
        signal.setitimer(signal.ITIMER_REAL, 0)


def _answering() -> None:
    """The console script is answering (its last line, its exit status): a second Ctrl-C, or one that lands just
    as the command ends, must not cut the answer into a traceback (it did, in 1 of 8 double Ctrl-Cs 0.1 s apart).
    Pending redeliveries are cancelled and further SIGINTs ignored; the process is ending anyway."""
    import signal

    _cancel_redelivery()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _forget_unhandled_interrupt()


def _quiet_after_interrupt() -> None:
    """The command was interrupted and has said so: what fails after, in finalizers run as the process ends, is
    the interrupt's doing and not reported.  A Ctrl-C inside llvmlite's start-up leaves a half-built object whose
    ``__del__`` then raises ("Exception ignored in ObjectRef.__del__ … AttributeError", seen once in 24 SIGINTs
    into `simulate` on a fresh clone), which Python prints as a traceback after the one line."""
    sys.unraisablehook = lambda unraisable: None


def _forget_unhandled_interrupt() -> None:
    """A Ctrl-C during numba's start-up could end the process by SIGINT after main had printed "interrupted" and
    returned 130: exit status -2 in 4 of 72 SIGINTs sent 0.60–0.85 s after the start (tests/test_cli.py saw it
    once).  CPython ends a process so when it noted a KeyboardInterrupt that escaped code run through ``PyRun_*``
    (its ``_Py_UnhandledKeyboardInterrupt``), and every ``PyRun_*`` call resets that note: one empty statement run
    that way, after SIGINT is ignored, gave 130 in 71 of 72 (and 0 once: the impact was done first)."""
    try:
        import ctypes

        ctypes.pythonapi.PyRun_SimpleString(b"pass")
    except (ImportError, AttributeError, OSError):  # not CPython: no such note either
        pass


def _defer_numpy() -> None:
    """Import NumPy when it is first used, not when a module names it (``importlib.util.LazyLoader``): the
    parser reads only the table of quantities and the registries' names, so ``--help`` and a usage error never
    load it (0.15 s of the 0.25 s allowed, issue 15 item 4); a command that computes loads it on its first
    call.  Nothing in the modules the parser imports touches NumPy at import (``tests/test_cli.py`` checks)."""
    import importlib.util

    if "numpy" in sys.modules:
        return
    spec = importlib.util.find_spec("numpy")
    if spec is None or spec.loader is None:
        return
    lazy = getattr(importlib.util, "_LazyModule", None)
    if lazy is None:  # another Python's internals: NumPy is imported as usual (slower, as correct)
        return

    class Deferred(lazy):
        # ``import numpy`` of a module already in sys.modules reads its __spec__ (is it initialising?):
        # answered without loading, so that only a real use of NumPy loads it
        def __getattribute__(self, name):
            if name in ("__spec__", "__name__"):
                return object.__getattribute__(self, "__dict__")[name]
            return super().__getattribute__(name)

    loader = importlib.util.LazyLoader(spec.loader)
    spec.loader = loader
    module = importlib.util.module_from_spec(spec)
    sys.modules["numpy"] = module
    loader.exec_module(module)
    module.__class__ = Deferred


def main(argv=None) -> int:
    """Run ``fruitimpact ARGV``; returns the exit status (0 ok, 1 a result not ok, 2 bad input,
    130 interrupted)."""
    console = argv is None  # the console script; in-process callers keep numba's defaults
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        if console:
            _note_interrupts()
            _defer_numpy()  # before the first module that names NumPy
        from fruitimpact.cli.common import UsageError, _attach_negative_values, _numba_without_blas

        interpreted = False
        if console:
            _redeliver_interrupts_from_callbacks()
            from fruitimpact.cli import interpreted as engine_mode

            interpreted = engine_mode.wanted(_command(argv))
            if interpreted:  # one impact: the engine's functions run by Python, numba never started
                engine_mode.interpret_engine()
            else:
                _numba_without_blas()
        parser = build_parser()
        argv = _attach_negative_values(argv)
        try:
            args = parser.parse_args(argv)
            if getattr(args, "func", None) is None:  # no command: a usage error like any other (one line, stderr)
                parser.error(f"argument COMMAND: a command is required, one of {', '.join(COMMANDS)} "
                             f"(fruitimpact --help describes them)")
            if not interpreted:
                return args.func(args)
            try:
                return args.func(args)
            except engine_mode.Recompile:  # a value compiled code reads as inf or NaN: the same command, compiled
                engine_mode.rerun_compiled(argv)
        except UsageError as exc:
            command = getattr(locals().get("args"), "command", None) or _command(argv)
            prefix = f"{PROG} {command}" if command else PROG
            print(f"{prefix}: error: {exc}", file=sys.stderr)
            return 2
    except KeyboardInterrupt:
        if console:
            _answering()  # first: neither a pending redelivery nor a second Ctrl-C may interrupt this answer
            _quiet_after_interrupt()
        command = _command(argv)
        print(f"{PROG}{' ' + command if command else ''}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # e.g. piped into head
        return 0
    except Exception:
        if not _SWALLOWED and not _SIGNALLED:
            raise
        if console:
            _answering()
            _quiet_after_interrupt()
        command = _command(argv)  # a failure caused by a Ctrl-C (swallowed in a C callback, or replaced in C code)
        print(f"{PROG}{' ' + command if command else ''}: interrupted", file=sys.stderr)
        return 130
    finally:
        if console:
            _answering()


_EXPORTS = {"UsageError": "common", "dump_json": "common", "format_result_table": "simulate"}


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'fruitimpact.cli' has no attribute {name!r}")
    return getattr(importlib.import_module(f".{module}", __name__), name)


__all__ = ["COMMANDS", "PROG", "UsageError", "build_parser", "dump_json", "format_result_table", "main"]


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
