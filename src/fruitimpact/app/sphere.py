"""The line-audit page's sphere log: an instrumented sphere's log, uploaded, audited as ``fruitimpact sphere``
audits it (``spheres.audit.sphere_audit``), in place of the typed table of transfer points.

The log, and optionally the sphere's calibration file, reach the server as the recording page's files do: uploads
(``POST /api/upload``, ``app.uploads``), named in the request by their ids (``log``, ``sphere_calibration``), each
stored under a name the server made and read after its checksum is verified.  The rest of a request is the sphere,
by the library's names (:data:`SPHERE_INPUTS`: ``sphere`` (a profile), ``sphere_mass``, ``sphere_diameter``,
``sphere_modulus``, ``sphere_poisson``, ``sphere_restitution``, ``logger_rate`` …, values as typed: ``"312g"``,
``"3kHz"``), and the lot the line page sends (``fruit``, ``criterion``, ``mass`` …, ``rows``, ``seed``,
``spreads``; read as ``app.line`` reads them, the same defaults).  Unknown names are refused.

The answer is ``sphere_audit``'s report as strict JSON, the stored files named as the user's files were (never the
server's own paths), with the skipped rows in the CLI's words and the ``fruitimpact sphere LOG …`` command that
gives the same report, the files by their names.  A refusal is the library's ``InputError``, worded by the server
as the CLI words it, about the control it names (``log``, ``sphere_calibration``, ``sphere_mass`` …).
"""

from __future__ import annotations

import shlex

from fruitimpact.app.inputs import typed_value
from fruitimpact.app.line import LOT_INPUTS, MAX_PAGE_ROWS, PAGE_ROWS, _lot_inputs
from fruitimpact.app.recording import refusal
from fruitimpact.handling.line import MAX_LINE_FRUIT
from fruitimpact.impact.outputs import json_safe
from fruitimpact.impact.quantities import option_of
from fruitimpact.impact.validation import COMMAND_ARGUMENTS, InputError, read_count

#: The sphere's inputs a request may give, in the order ``fruitimpact sphere`` lists its options (the values as
#: typed; ``sphere_audit`` reads them).  The page offers the profile, mass, diameter, modulus, Poisson's ratio,
#: restitution and logger rate; the others are the CLI's, for a script.
SPHERE_INPUTS = ("sphere", "sphere_mass", "sphere_diameter", "sphere_modulus", "sphere_poisson", "sphere_restitution",
                 "surface_poisson", "columns", "point_gap", "pass_gap", "uncertainty", "logger_rate", "target")
#: The uploads a request names by their ids: the log (required) and the sphere's calibration.
FILE_INPUTS = ("log", "sphere_calibration")
#: Every name a request may hold.
REQUEST_NAMES = (*FILE_INPUTS, *SPHERE_INPUTS, *LOT_INPUTS, "rows", "seed", "spreads")


def choices() -> dict:
    """What the page's sphere controls offer: the built-in device profiles (their mass and diameter) and the
    largest lot the page computes."""
    from fruitimpact.spheres.devices import DEVICES

    return {"devices": [{"name": name, "description": f"{device.description}: {device.mass * 1e3:.4g} g, "
                                                      f"{device.diameter * 1e3:.4g} mm",
                         "mass": device.mass, "diameter": device.diameter} for name, device in DEVICES.items()],
            "max_rows": MAX_PAGE_ROWS, "rows": PAGE_ROWS}


def _stored(uploads, request: dict, name: str):
    """The upload a request names as ``name`` (None when not given), with its verified path; a missing or changed
    upload refused about ``name``'s control."""
    upload_id = request.get(name)
    if upload_id is None or upload_id == "":
        return None, None
    try:
        upload = uploads.get(upload_id)
        return upload, upload.checked_path()
    except InputError as error:
        raise InputError(str(error), name) from None


def _named(value, names: dict):
    """``value`` (strict JSON) with every stored path in its texts replaced by the user's file name."""
    if isinstance(value, str):
        for path, name in names.items():
            value = value.replace(path, name)
        return value
    if isinstance(value, dict):
        return {key: _named(item, names) for key, item in value.items()}
    if isinstance(value, list):
        return [_named(item, names) for item in value]
    return value


def command(log: str, calibration: str | None, sphere: dict, lot: dict, rows: int, seed: str, spreads: bool) -> str:
    """The ``fruitimpact sphere LOG …`` command that gives the same report (the files by their names)."""
    words = ["fruitimpact", "sphere", log]
    given = {**sphere, **({"sphere_calibration": calibration} if calibration is not None else {})}
    for name in ("sphere", "sphere_mass", "sphere_diameter", "sphere_modulus", "sphere_poisson", "sphere_calibration",
                 *SPHERE_INPUTS[5:]):
        if name in given:
            words += [COMMAND_ARGUMENTS[name], str(given[name])]
    for name in LOT_INPUTS:
        if name in lot:
            words += [option_of(name), str(lot[name])]
    words += ["-n", str(rows), "--seed", seed]
    if not spreads:
        words.append("--no-spreads")
    return " ".join(shlex.quote(word) for word in words)


def audit(request, uploads) -> dict:
    """Everything the page shows for one sphere log (see the module's note); ``InputError`` for a bad input.

    The answer: ``report`` (``sphere_audit``'s, strict JSON, the files by the user's names), ``worst_point``,
    ``skipped`` (the skipped rows, one line each as the CLI prints them), ``file`` and ``calibration_file`` (the
    names), ``request`` (the inputs as read), ``command`` and ``max_rows``."""
    from fruitimpact.spheres.audit import sphere_audit
    from fruitimpact.spheres.log import skipped_lines

    if not isinstance(request, dict):
        raise InputError("the request must be a JSON object of inputs", "request")
    for name in request:
        if name not in REQUEST_NAMES:
            raise InputError(f"unknown input {name!r} (inputs: {', '.join(REQUEST_NAMES)})", name)
    sphere = {name: typed_value(name, request.get(name)) for name in SPHERE_INPUTS}
    sphere = {name: value for name, value in sphere.items() if value is not None}
    lot = _lot_inputs(request)
    rows = read_count("rows", request.get("rows", PAGE_ROWS), 1, MAX_LINE_FRUIT)  # the CLI's words, as on the line
    if rows > MAX_PAGE_ROWS:
        raise InputError(f"rows must be at most {MAX_PAGE_ROWS:,} on this page; got {rows:,} (the command line "
                         f"takes up to {MAX_LINE_FRUIT:,})", "rows")
    seed = request.get("seed", 0)
    spreads = request.get("spreads", True)  # checked by sphere_audit: True or False
    log, log_path = _stored(uploads, request, "log")
    if log is None:
        raise InputError("upload the sphere's log first (CSV: time, peak_acceleration, velocity_change[, duration]"
                         "[, point]; or a raw trace: time, acceleration)", "log")
    calibration, calibration_path = _stored(uploads, request, "sphere_calibration")
    names = {str(log_path): log.name}
    if calibration is not None:
        names[str(calibration_path)] = calibration.name
    try:
        report = sphere_audit(str(log_path), sphere_calibration=None if calibration is None else str(calibration_path),
                              rows=rows, seed=seed, spreads=spreads, **sphere, **lot)
    except ValueError as error:
        for path, name in names.items():  # the files by the names the user gave them
            error = refusal(error, path, name)
        raise error from None
    report = _named(json_safe(report), names)
    seed_text = str(report["seed"])
    return {
        "report": report, "worst_point": report["worst_point"],
        "skipped": skipped_lines(log.name, report["skipped"]),
        "file": log.name, "calibration_file": None if calibration is None else calibration.name,
        "request": {**sphere, **{name: lot.get(name, "") for name in LOT_INPUTS},
                    "criterion": lot.get("criterion", "preset"), "rows": rows, "seed": seed_text, "spreads": spreads},
        "command": command(log.name, None if calibration is None else calibration.name, sphere, lot, rows, seed_text,
                           spreads),
        "max_rows": MAX_PAGE_ROWS,
    }


__all__ = ["FILE_INPUTS", "REQUEST_NAMES", "SPHERE_INPUTS", "audit", "choices", "command"]
