"""The line-audit page's numbers: a lot of fruit through the transfer points of a packing line, from the library
function ``fruitimpact line`` runs (``handling.line.audit_line``).

A request is a JSON object: ``points``, the line as the page's table holds it (a list of
``{"name", "drop_height", "surface", "fruit_on_fruit"}``, heights as typed, ``"30cm"``, or numbers in metres), the
lot (``fruit``, ``criterion``, ``mass``, ``diameter``, ``modulus``, ``failure_stress`` as numbers, values with units
or distributions such as ``"normal(180g, 20g)"``), ``rows``, ``seed``, ``spreads``, ``alternatives`` and,
optionally, ``what_if``: ``{"point": name, "surface": surface}``.  A name left out keeps its default: without
``points`` the example line (``examples/line.csv``), without ``fruit`` an apple, without ``rows``
:data:`PAGE_ROWS` fruit.  Unknown names are refused, as the CLI refuses an unknown option.

Each row of the table is read by ``read_point``, as ``read_line`` reads a row of a line CSV, with the library's
own checks (``parse_quantity``, ``_checked_point``): a refused cell gets the line the CLI prints for the same row of
``line.csv`` (``argument LINE: line.csv, line 3: drop_height: …``) and names the cell, ``["points", 1,
"drop_height"]``, for the page to show the line next to it.  The answer carries that ``line.csv`` and the
``fruitimpact line line.csv …`` command that reproduces the audit to the last digit (the same lot: same seed,
same rows).  Errors are the library's ``InputError``, worded by the server as the CLI words them.
"""

from __future__ import annotations

import math
import shlex

from fruitimpact.app.inputs import typed_value
from fruitimpact.handling.line import (DEFAULT_ALTERNATIVES, LINE_COLUMNS, MAX_LINE_FRUIT, MAX_POINTS,
                                      MEASURED_SURFACE_COLUMNS, TransferPoint, _distinct, read_point)
from fruitimpact.impact.outputs import json_safe
from fruitimpact.impact.quantities import option_of
from fruitimpact.impact.validation import InputError, read_count, usage_message

#: The file the page's line is saved as, and the name its command and its messages give it.
LINE_FILE = "line.csv"
#: The line the page opens on: ``examples/line.csv``'s transfer points, as its rows read.
DEFAULT_POINTS = (
    {"name": "bin tipper", "drop_height": "30cm", "surface": "rubber-belt", "fruit_on_fruit": False},
    {"name": "roller conveyor", "drop_height": "5cm", "surface": "pvc-belt", "fruit_on_fruit": False},
    {"name": "singulator", "drop_height": "10cm", "surface": "steel", "fruit_on_fruit": False},
    {"name": "accumulation table", "drop_height": "8cm", "surface": "foam-pad", "fruit_on_fruit": True},
    {"name": "packing into the carton", "drop_height": "15cm", "surface": "cardboard", "fruit_on_fruit": False},
)
#: The fruit the page opens on.
DEFAULT_FRUIT = "apple"
#: Fruit in the page's lot by default: the example line answers in about 0.3 s on a two-core machine (the CLI's
#: default, 10,000, takes 2-3 s there); the line's incidence is then known to ±4.4 points at worst (95 %).
PAGE_ROWS = 500
#: The largest lot the page computes (about 25 s for the example line on two cores); the CLI takes up to
#: ``MAX_LINE_FRUIT``, and the page's command runs any size.
MAX_PAGE_ROWS = 100_000
#: Inputs of the lot the page offers, by their names in ``quantities.INPUTS`` (the CLI's options).
LOT_INPUTS = ("fruit", "criterion", "mass", "diameter", "modulus", "failure_stress")
#: Every name a request may hold.
REQUEST_NAMES = ("points", *LOT_INPUTS, "rows", "seed", "spreads", "alternatives", "what_if")
#: Texts of a line CSV's ``fruit_on_fruit`` column (``read_line``'s).
#: z of a two-sided 95 % interval.
_Z95 = 1.959963984540054


def choices() -> dict:
    """What the page's controls offer: the fruits, the surfaces a transfer point may have (every surface
    ``_checked_point`` accepts, ``rigid`` included; "fruit on fruit" is the point's checkbox, not a surface), the
    surfaces a change may try (the library's own, as ``audit`` requires) and the criteria (``preset``: the fruit's
    own)."""
    from fruitimpact.impact.registries import SURFACE_CHOICES
    from fruitimpact.library import catalogue

    library = catalogue.surfaces()
    described = {"rigid": "a rigid plane (the founding paper's)",
                 **{name: entry.description for name, entry in library.items()}}
    return {
        "fruits": [{"name": name, "description": entry.description} for name, entry in catalogue.fruits().items()],
        "surfaces": [{"name": name, "description": described.get(name, "")} for name in SURFACE_CHOICES
                     if name != "fruit"],
        "alternatives": [name for name, entry in library.items() if entry.partner is None],
        "criteria": ["preset", "pressure", "shear", "energy"],
    }


def _cell_text(value) -> str | None:
    """A cell of the table as the text a line CSV would hold (``read_line`` strips every cell; a JSON number, in
    metres, written as Python reads it back); None for anything that is neither a text nor a number."""
    if isinstance(value, str):
        return value.strip()
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return repr(float(value)) if isinstance(value, float) else str(value)
    return None


def read_points(points) -> tuple[list[TransferPoint], list[dict]]:
    """The transfer points of the page's table, each row read by ``read_point`` as ``read_line`` reads a row of
    ``line.csv`` (names told apart by ``_distinct``), once its cells are texts (or the flag a bool), with the CLI's
    words for a refused cell; and the rows as the CSV holds them (texts), for ``line.csv`` and the page.

    ``InputError`` with ``argument`` ``["points", index, column]`` for a cell, ``"points"`` for the table."""
    if not isinstance(points, list) or not all(isinstance(row, dict) for row in points):
        raise InputError("points must be a list of transfer points, each an object with "
                         f"{', '.join(LINE_COLUMNS)}", "points")
    if not points:
        raise InputError(f"argument LINE: {LINE_FILE}: no transfer points below the header", "points")
    if len(points) > MAX_POINTS:
        raise InputError(f"argument LINE: {LINE_FILE}: {len(points)} transfer points; at most {MAX_POINTS}", "points")
    read, rows = [], []
    for index, row in enumerate(points):
        where = f"{LINE_FILE}, line {index + 2}"  # the header is line 1 (comment lines are not counted)

        def refused(message: str, column: str):
            return InputError(f"argument LINE: {message}", ["points", index, column])

        unknown = [key for key in row if key not in LINE_COLUMNS]
        if unknown:
            raise refused(f"{LINE_FILE}: unknown column(s) {', '.join(map(repr, unknown))} (columns: "
                          f"{', '.join(LINE_COLUMNS)})", unknown[0])
        cells = {}
        for column in LINE_COLUMNS[:3]:  # name, drop_height, surface: a missing cell is an empty one
            cells[column] = _cell_text(row.get(column, ""))
            if cells[column] is None:
                raise refused(f"{where}: {column} must be a number or a text; got {row[column]!r}", column)
        if "\n" in cells["name"] or "\r" in cells["name"]:  # one row of the CSV: a name on one line
            raise refused(f"{where}: name must be one line of text; got {cells['name']!r}", "name")
        measured = {}
        for column in MEASURED_SURFACE_COLUMNS:  # optional: absent, null (as the report writes it) or "" is blank
            measured[column] = _cell_text("" if row.get(column) is None else row[column])
            if measured[column] is None:
                raise refused(f"{where}: {column} must be a number or a text; got {row[column]!r}", column)
        flag = row.get("fruit_on_fruit", False)
        try:
            point = read_point({**cells, "fruit_on_fruit": flag, **measured}, where)
        except ValueError as error:  # "<where>: <column> must be …" or "<where>: <column>: …": that column's cell
            column = str(error)[len(where) + 2:].split(" ", 1)[0].rstrip(":")
            raise refused(str(error), column if column in LINE_COLUMNS else "name") from None
        read.append(point)
        rows.append({**cells, "fruit_on_fruit": point.fruit_on_fruit, **{k: v for k, v in measured.items() if v}})
    try:
        _distinct(read, LINE_FILE)
    except ValueError as error:
        names = [point.name for point in read]
        twice = next(i for i, name in enumerate(names) if name in names[:i])
        raise InputError(f"argument LINE: {error}", ["points", twice, "name"]) from None
    return read, rows


def _csv_field(text: str) -> str:
    """A CSV field: quoted when it holds a comma or a quote, or starts with ``#`` (``read_line`` would take the
    row for a comment)."""
    if any(mark in text for mark in ',"') or text.startswith("#"):
        return '"' + text.replace('"', '""') + '"'
    return text


def line_csv(rows: list[dict]) -> str:
    """The line CSV of the table's rows, as ``read_line`` reads it back (the page's ``line.csv``)."""
    measured = any(row.get(column) for row in rows for column in MEASURED_SURFACE_COLUMNS)
    columns = [column for column in LINE_COLUMNS if measured or column not in MEASURED_SURFACE_COLUMNS]
    lines = [",".join(columns)]
    for row in rows:
        fields = [_csv_field(row["name"]), _csv_field(row["drop_height"]), _csv_field(row["surface"]),
                  "true" if row["fruit_on_fruit"] else "false"]
        if measured:
            fields += [_csv_field(row.get(column, "")) for column in MEASURED_SURFACE_COLUMNS]
        lines.append(",".join(fields))
    return "\n".join(lines) + "\n"


def _lot_inputs(request: dict) -> dict:
    """The lot's inputs given (``LOT_INPUTS``), values as typed: an empty text is "not given", the fruit then
    :data:`DEFAULT_FRUIT`, and ``criterion`` ``preset`` is the fruit's own, as when it is not given."""
    inputs = {name: typed_value(name, request.get(name)) for name in LOT_INPUTS}
    inputs = {name: value for name, value in inputs.items() if value is not None}
    inputs.setdefault("fruit", DEFAULT_FRUIT)
    if inputs.get("criterion") == "preset":
        del inputs["criterion"]
    return inputs


def _alternatives(value) -> list[str]:
    """The surfaces tried in place of each point's (a list of names, or the CLI's comma-separated text; ``none``
    or an empty list: none); each name is checked by the library."""
    if value is None:
        return list(DEFAULT_ALTERNATIVES)
    if isinstance(value, str):
        text = value.strip()
        return [] if text.lower() in ("", "none") else [name.strip() for name in text.split(",")]
    if not isinstance(value, list) or not all(isinstance(name, str) for name in value):
        raise InputError(f"alternatives must be a list of library surface names; got {value!r}", "alternatives")
    return list(dict.fromkeys(name.strip() for name in value))


def _what_if(value, points: list[TransferPoint], surfaces: list[str]) -> dict | None:
    """The what-if asked for: one point's surface changed.  ``InputError`` naming ``["what_if", "point"]`` or
    ``["what_if", "surface"]`` for a point that is not on the line or lands on fruit (its surface is not met), or a
    surface that is not a library surface other than the point's own."""
    if value is None:
        return None
    if not isinstance(value, dict) or set(value) != {"point", "surface"}:
        raise InputError(f"what_if must be an object with point and surface; got {value!r}", "what_if")
    named = {point.name: point for point in points}
    point = named.get(value["point"]) if isinstance(value["point"], str) else None
    if point is None:
        raise InputError(f"what_if: point must be a transfer point of the line ({', '.join(map(repr, named))}); "
                         f"got {value['point']!r}", ["what_if", "point"])
    if point.fruit_on_fruit:
        raise InputError(f"what_if: transfer point {point.name!r} is fruit on fruit: the fruit lands on another "
                         f"fruit, not on its surface (untick fruit on fruit to change its surface)",
                         ["what_if", "point"])
    surface = value["surface"]
    if surface not in surfaces or surface == point.surface:
        raise InputError(f"what_if: surface must be a library surface other than {point.surface} "
                         f"({', '.join(s for s in surfaces if s != point.surface)}); got {surface!r}",
                         ["what_if", "surface"])
    return {"point": point.name, "surface": surface}


def command(inputs: dict, rows: int, seed, spreads: bool, alternatives: list[str]) -> str:
    """The ``fruitimpact line line.csv …`` command that audits the same line with the same lot."""
    words = ["fruitimpact", "line", LINE_FILE]
    for name in LOT_INPUTS:
        if name in inputs:
            words += [option_of(name), str(inputs[name])]
    words += ["-n", str(rows), "--seed", str(seed)]
    if not spreads:
        words.append("--no-spreads")
    if tuple(alternatives) != DEFAULT_ALTERNATIVES:
        words += ["--alternatives", ",".join(alternatives) or "none"]
    return " ".join(shlex.quote(word) for word in words)


def wilson_interval(share: float | None, count: int) -> list[float] | None:
    """The 95 % Wilson score interval of a share of ``count`` fruit (the sampling uncertainty of an incidence
    estimated on a lot of that size; it stays honest at 0 and 100 %, where the normal one shrinks to a point)."""
    if share is None or not count or not math.isfinite(share):
        return None
    z2 = _Z95 * _Z95
    centre = (share + z2 / (2 * count)) / (1 + z2 / count)
    half = _Z95 * math.sqrt(share * (1 - share) / count + z2 / (4 * count * count)) / (1 + z2 / count)
    return [max(0.0, centre - half), min(1.0, centre + half)]


def audit(request) -> dict:
    """Everything the line-audit page shows for one request (see the module's note); ``InputError`` for a bad
    input.

    The answer: ``report``, ``audit_line``'s report as strict JSON (NaN and infinity null; ``changes`` those of
    the request's ``alternatives``), ``worst_point``, ``incidence_interval`` (95 %, the lot's sampling
    uncertainty), ``request`` (the inputs as read: what the page shows), ``line_csv`` and ``command`` (the CLI run
    that reproduces the audit), ``what_if`` (or None) and ``choices`` (what the controls offer)."""
    from fruitimpact.handling.line import audit_line

    if not isinstance(request, dict):
        raise InputError("the request must be a JSON object of inputs", "request")
    for name in request:
        if name not in REQUEST_NAMES:
            raise InputError(f"unknown input {name!r} (inputs: {', '.join(REQUEST_NAMES)})", name)
    offered = choices()
    points, rows_shown = read_points(request.get("points", [dict(row) for row in DEFAULT_POINTS]))
    inputs = _lot_inputs(request)
    rows = request.get("rows", PAGE_ROWS)
    rows = read_count("rows", rows, 1, MAX_LINE_FRUIT)  # the CLI's words for what the CLI refuses too
    if rows > MAX_PAGE_ROWS:
        raise InputError(f"rows must be at most {MAX_PAGE_ROWS:,} on this page; got {rows:,} (the command line "
                         f"takes up to {MAX_LINE_FRUIT:,})", "rows")
    seed = request.get("seed", 0)
    spreads = request.get("spreads", True)  # checked by audit_line: True or False
    alternatives = _alternatives(request.get("alternatives"))
    what_if = _what_if(request.get("what_if"), points, offered["alternatives"])
    # The what-if is the library's own paired change: its surface is one more alternative of the same audit, so
    # the same fruit meet it (same lot, same seed), and audit() compares the line with and without the change over
    # the very same fruit; it is then taken out of the ranked changes, which stay those of the user's alternatives
    # (each change is computed on its own: the others are as a direct call with those alternatives gives them).
    tried = alternatives + ([what_if["surface"]] if what_if and what_if["surface"] not in alternatives else [])
    try:
        report = audit_line(points, rows=rows, seed=seed, criterion=inputs.get("criterion"), alternatives=tried,
                            spreads=spreads, **{k: v for k, v in inputs.items() if k != "criterion"})
    except InputError as error:
        raise _at_point(error, points) from None
    report = json_safe(report)  # NaN and inf as null, as the server's JSON writer writes them
    changes = report["changes"]
    report["changes"] = [change for change in changes if change["to"] in alternatives]
    seed_text = str(report["seed"])
    answer = {
        "report": report, "worst_point": report["worst_point"],
        "incidence_interval": wilson_interval(report["incidence"], report["fruit_computed"]),
        "request": {"points": rows_shown, **{name: inputs.get(name, "") for name in LOT_INPUTS},
                    "criterion": inputs.get("criterion", "preset"), "rows": rows, "seed": seed_text,
                    "spreads": spreads, "alternatives": alternatives},
        "line_csv": line_csv(rows_shown), "file": LINE_FILE,
        "command": command(inputs, rows, seed_text, spreads, alternatives),
        "what_if": None, "max_rows": MAX_PAGE_ROWS, "choices": offered,
    }
    if what_if:
        answer["what_if"] = _compared(what_if, changes, report, inputs, rows, seed_text, spreads)
    return answer


def _at_point(error: InputError, points: list[TransferPoint]) -> InputError:
    """A refusal ``audit_line`` words for one transfer point (``transfer point 'x': …``, a height or surface no
    fruit of the lot can take) named as that point's cell, with the CLI's line; any other as it is."""
    argument = error.argument
    if argument in ("drop_height", "surface", "velocity"):
        for index, point in enumerate(points):
            if str(error).startswith(f"transfer point {point.name!r}: "):
                column = "surface" if argument == "surface" else "drop_height"
                return InputError(usage_message(error), ["points", index, column])
    return error


def _compared(what_if: dict, changes: list[dict], report: dict, inputs: dict, rows: int, seed: str,
              spreads) -> dict:
    """The what-if's figures: the line before and after the change, over the same fruit, and what it saves."""
    point = next(p for p in report["points"] if p["name"] == what_if["point"])
    change = next((c for c in changes if c["point"] == what_if["point"] and c["to"] == what_if["surface"]), None)
    out = {"point": what_if["point"], "from": point["surface"], "to": what_if["surface"],
           "command": command(inputs, rows, seed, spreads, [what_if["surface"]])}
    if change is None:  # audit() drops a change no fruit of the lot could be computed with
        return {**out, "before": None, "after": None, "incidence_saved": None, "bruise_volume_saved": None,
                "fruit": 0, "message": f"no fruit of the lot could be computed on {what_if['surface']} at "
                                       f"{what_if['point']!r}"}
    if change["fruit"] == report["fruit_computed"]:  # the change compared over the line's own fruit: its figures
        before = {"incidence": report["incidence"], "mean_bruise_volume": report["mean_bruise_volume"]}
    else:  # over those of its fruit computable with the change too: the changed figure plus its saving
        before = {"incidence": _plus(change["incidence"], change["incidence_saved"]),
                  "mean_bruise_volume": _plus(change["mean_bruise_volume"], change["bruise_volume_saved"])}
    return {**out, "before": before,
            "after": {"incidence": change["incidence"], "mean_bruise_volume": change["mean_bruise_volume"]},
            "incidence_saved": change["incidence_saved"], "bruise_volume_saved": change["bruise_volume_saved"],
            "fruit": change["fruit"], "message": ""}


def _plus(value, saved):
    """The line's figure without the change: the changed figure plus its saving (None when either is unknown)."""
    return None if value is None or saved is None else value + saved


__all__ = ["DEFAULT_FRUIT", "DEFAULT_POINTS", "LINE_FILE", "LOT_INPUTS", "MAX_PAGE_ROWS", "PAGE_ROWS", "REQUEST_NAMES",
           "audit", "choices", "command", "line_csv", "read_points", "wilson_interval"]
