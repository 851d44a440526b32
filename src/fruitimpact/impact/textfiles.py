"""The text tables users write by hand or export from a spreadsheet (a line, a sphere log, a table of drop tests):
read with one set of rules and one set of refusals.

A table is UTF-8 (an Excel export's byte-order mark is skipped), ``#`` starts a comment line, blank lines do
not count; each kept line keeps its line number in the file, so a refusal can name it.
"""

from __future__ import annotations

import os


def table_lines(path, what: str = "") -> list[tuple[int, str]]:
    """The kept lines of the text table at ``path``, each with its line number (1 = the file's first line).

    ``ValueError`` ("{what}cannot read {path}: …") for a path that is not a path, a folder, a file that cannot be
    opened or is not UTF-8 text; ``what`` prefixes the message (e.g. ``"points: "``)."""
    if not isinstance(path, (str, os.PathLike)):  # an integer would be taken as a file descriptor, and closed
        raise ValueError(f"{what}expected the path of a CSV file; got {path!r}")
    if os.path.isdir(path):
        raise ValueError(f"{what}cannot read {path}: it is a folder, not a CSV file")
    try:
        with open(path, newline="", encoding="utf-8-sig") as handle:  # an Excel export starts with a BOM
            return [(number, line) for number, line in enumerate(handle, start=1)
                    if line.strip() and not line.lstrip().startswith("#")]
    except OSError as exc:
        raise ValueError(f"{what}cannot read {path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise ValueError(f"{what}cannot read {path}: not a UTF-8 text file") from None


__all__ = ["table_lines"]
