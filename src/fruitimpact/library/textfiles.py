"""The text tables users write by hand or export from a spreadsheet (a line, a sphere log, a table of drop tests,
a fruit file): read with one set of rules and one set of refusals.

A table is UTF-8 (an Excel export's byte-order mark is skipped), ``#`` starts a comment line, blank lines do
not count; each kept record keeps the number of its first line in the file, so a refusal can name it.  A quoted
field may hold line breaks (a spreadsheet cell with several lines): its record runs on to the line that closes
the quote, blank or ``#`` lines inside it included.
"""

from __future__ import annotations

import os


def table_lines(path, what: str = "", name: str | None = None) -> list[tuple[int, str]]:
    """The kept records of the text table at ``path``, each with the number of its first line (1 = the file's
    first line); a record is one line, or several where a quoted field holds line breaks.

    ``ValueError`` ("{what}cannot read {name}: …") for a path that is not a path, a folder, a file that cannot be
    opened or is not UTF-8 text; ``what`` prefixes the message (e.g. ``"points: "``), ``name`` says how the file
    is named in it (default: its path)."""
    if not isinstance(path, (str, os.PathLike)):  # an integer would be taken as a file descriptor, and closed
        raise ValueError(f"{what}expected the path of a CSV file; got {path!r}")
    shown = os.fspath(path) if name is None else name
    if os.path.isdir(path):
        raise ValueError(f"{what}cannot read {shown}: it is a folder, not a CSV file")
    try:
        with open(path, newline="", encoding="utf-8-sig") as handle:  # an Excel export starts with a BOM
            records = _records(enumerate(handle, start=1))
    except OSError as exc:
        raise ValueError(f"{what}cannot read {shown}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise ValueError(f"{what}cannot read {shown}: not a UTF-8 text file") from None
    if records and records[-1][1].count('"') % 2:
        # a stray quote would take every line after it into one field: rows lost without a word
        raise ValueError(f"{what}{shown}, line {records[-1][0]}: a quoted field opened there is never closed")
    return records


def _records(numbered) -> list[tuple[int, str]]:
    """Join the lines of a record whose quoted field runs over line breaks (an odd number of ``"`` so far: CSV
    doubles a quote inside a quoted field, so the parity says whether a quote is open); an unclosed quote at
    the end stays one record, with its odd count (``table_lines`` refuses it)."""
    records, pending, first = [], None, 0
    for number, line in numbered:
        if pending is not None:  # inside a quoted field: its lines are kept apart and joined once it closes
            pending.append(line)  # (joining as it grows was quadratic: a stray quote early in a 5,000,000-row
            if line.count('"') % 2:  # log re-read the rest of the file at every line)
                records.append((first, "".join(pending)))
                pending = None
            continue
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        if line.count('"') % 2:
            pending, first = [line], number
            continue
        records.append((number, line))
    if pending is not None:
        records.append((first, "".join(pending)))
    return records


#: The words a cell of a hand-written table may say yes or no with (case and surrounding blanks ignored).
YES_WORDS, NO_WORDS = frozenset({"true", "yes", "y", "1"}), frozenset({"false", "no", "n", "0"})


def yes_or_no(text: str, blank: bool | None = None) -> bool | None:
    """True or False for a yes/no word of ``YES_WORDS`` or ``NO_WORDS`` in ``text``; ``blank`` for an empty
    cell; None for anything else (the caller refuses it, naming its column)."""
    word = text.strip().lower()
    if not word:
        return blank
    return True if word in YES_WORDS else False if word in NO_WORDS else None


__all__ = ["NO_WORDS", "YES_WORDS", "table_lines", "yes_or_no"]
