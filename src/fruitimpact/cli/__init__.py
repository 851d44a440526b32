"""Command-line interface: ``fruitimpact simulate | paper | models | batch | sweep | population``.

One module per group of commands (``simulate``, ``reference``, ``runs``); the
shared option handling and the one-line error live in ``common``.  Heavy
imports (matplotlib, pandas, scipy, pyarrow, dask) happen only in the
subcommands that need them.
"""

from __future__ import annotations

import argparse
import sys

from .common import PROG, UsageError, _attach_negative_values, _numba_without_blas, _Parser, dump_json
from .simulate import format_result_table

__all__ = ["PROG", "UsageError", "build_parser", "dump_json", "format_result_table", "main"]


def build_parser() -> argparse.ArgumentParser:
    from . import reference, runs, simulate

    parser = _Parser(prog=PROG, description="Simulate and measure fruit impacts on surfaces (SI units).")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    simulate.add_parser(sub)
    reference.add_parsers(sub)
    runs.add_parsers(sub)
    return parser


def main(argv=None) -> int:
    if argv is None:  # the console script; in-process callers keep numba's defaults
        _numba_without_blas()
    parser = build_parser()
    argv = _attach_negative_values(list(sys.argv[1:] if argv is None else argv))
    try:
        args = parser.parse_args(argv)
        if getattr(args, "func", None) is None:
            parser.print_help()
            return 2
        return args.func(args)
    except UsageError as exc:
        command = getattr(locals().get("args"), "command", None) or next(
            (token for token in argv if token in ("simulate", "paper", "models", "batch", "sweep", "population")), None)
        prefix = f"{PROG} {command}" if command else PROG
        print(f"{prefix}: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # e.g. piped into head
        return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
