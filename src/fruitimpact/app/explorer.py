"""The explorer page's numbers: one impact, its bounce sequence, the bruise verdict, the safe height and the risk
map, each from the library function the CLI runs (``simulate``, ``drop``, ``safe_height``, ``risk_map``).

A request is a JSON object of inputs named as the table of quantities names them (``fruit``, ``surface``,
``drop_height``, ``mass``…), values as the user typed them (``"30cm"``, ``"115g"``, numbers in SI); an empty
text is "not given".  Unknown names are refused, as the CLI refuses an unknown option.  Errors are the library's
``InputError``, which the server words as the CLI does (``impact.validation.usage_message``).
"""

from __future__ import annotations

import math
import shlex

from fruitimpact.app import inputs
from fruitimpact.impact.quantities import GROUP_DEFAULTS, INPUTS, OUTPUTS, option_of
from fruitimpact.impact.validation import InputError
from fruitimpact.physics.constants import STANDARD_GRAVITY

#: Inputs the explorer offers (a contract of its requests): the rest keep their defaults, as in
#: ``fruitimpact simulate`` without those options.
EXPLORER_INPUTS = ("fruit", "surface", "velocity", "drop_height", "model", "calibration", "criterion", "mass",
                   "diameter", "modulus", "poisson", "restitution", "failure_stress", "bruise_energy")
#: Characteristics shown, in this order (``quantities.OUTPUTS`` gives label, unit and scale).
SHOWN = ("peak_force", "time_to_peak", "contact_duration", "max_deflection", "restitution", "exit_velocity",
         "absorbed_energy", "firmness_c", "firmness_c_star", "max_pressure", "max_shear_stress", "contact_radius",
         "law_stiffness", "damping")
#: Samples of the curves sent to the page (the accurate solver's curves over [0, T]).
CURVE_POINTS = 401


def read_request(request) -> dict:
    """The inputs of an explorer request: names checked, empty texts dropped, values as typed."""
    return inputs.read_request(request, EXPLORER_INPUTS)


def command(inputs: dict, program: str = "simulate") -> str:
    """The ``fruitimpact`` command line that computes the same impact (the options the user set)."""
    words = ["fruitimpact", program]
    for name in EXPLORER_INPUTS:
        if name in inputs and not (program != "simulate" and name in ("velocity", "drop_height")):
            words += [option_of(name), str(inputs[name])]
    if program == "drop":  # the drop command takes the height only: the velocity's, V²/2g, when one was given
        words += [option_of("drop_height"), str(inputs["drop_height"]) if "drop_height" in inputs
                  else f"{_drop_height(inputs):.6g}"]
    return " ".join(shlex.quote(word) for word in words)


def _drop_height(inputs: dict) -> float:
    """The drop height [m] of the impact asked for (from the velocity when that was given)."""
    from fruitimpact.impact.validation import check_value

    if "drop_height" in inputs:
        return check_value("drop_height", inputs["drop_height"])
    velocity = check_value("velocity", inputs["velocity"]) if "velocity" in inputs else GROUP_DEFAULTS["velocity"]
    return velocity * velocity / (2.0 * STANDARD_GRAVITY)


def _number(value) -> float | None:
    """A JSON number (None for NaN or infinity)."""
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def _quantity(name: str, value) -> dict:
    quantity = OUTPUTS[name]
    si = _number(value)
    return {"name": name, "label": quantity.label, "unit": quantity.unit,
            "value": None if si is None else si * quantity.scale, "si": si}


def explore(request) -> dict:
    """Everything the explorer shows for one request (see the module's note); ``InputError`` for a bad input."""
    from fruitimpact.handling.drops import drop
    from fruitimpact.impact.simulation import simulate

    inputs = read_request(request)
    keywords = dict(inputs)
    fruit = keywords.pop("fruit", None)
    surface = keywords.pop("surface", None)
    result = simulate(fruit, surface=surface, curve_points=CURVE_POINTS, **keywords)
    flat = result.to_dict()
    flat["law_stiffness"] = result.law.stiffness
    out = {
        "status": result.status, "message": result.message, "warnings": list(result.warnings),
        "characteristics": [_quantity(name, flat.get(name)) for name in SHOWN],
        "law": {"stiffness_unit": flat["stiffness_unit"], "damping_unit": flat["damping_unit"]},
        "velocity": result.inputs.velocity,
        "drop_height": result.inputs.velocity ** 2 / (2.0 * STANDARD_GRAVITY),
        "names": {key: str(value) for key, value in result.names.items()},
        "command": command(inputs),
        "curves": None, "verdict": None, "safe_height": None, "drop": None,
    }
    if result.status != "failed":
        curves = result.curves
        out["curves"] = {"time": curves.time.tolist(), "deflection": curves.deflection.tolist(),
                         "force": curves.force.tolist()}
    criterion = result.names.get("criterion", "none")
    if criterion != "none":
        damage = result.damage
        out["verdict"] = {"criterion": criterion, "bruised": damage.get("bruised"),
                          "margin": _number(damage.get("bruise_margin")),
                          "volume": _number(damage.get("bruise_volume")),
                          "max_shear_stress": _number(damage.get("max_shear_stress"))}
        out["safe_height"] = _safe_height(inputs)
    out["drop"] = _bounces(drop, inputs)
    return out


def _without_impact(inputs: dict) -> dict:
    return {name: value for name, value in inputs.items() if name not in ("velocity", "drop_height")}


def _safe_height(inputs: dict) -> dict:
    from fruitimpact.handling.heights import safe_height

    try:
        found = safe_height(sensitivity=False, **_without_impact(inputs))
    except InputError as error:
        return {"error": str(error)}
    return {"height": _number(found["safe_height"]), "velocity": _number(found["safe_velocity"]),
            "status": found["status"], "message": found["message"], "command": command(inputs, "safe-height")}


def _bounces(drop, inputs: dict) -> dict:
    """The drop from the impact's height: each impact's time, speeds, peak force and verdict."""
    try:
        sequence = drop(_drop_height(inputs), **_without_impact(inputs))
    except InputError as error:  # a drop the library refuses (a free partner): said on the page
        return {"error": str(error)}
    impacts = [{key: (_number(impact[key]) if key != "bruised" else impact[key])
                for key in ("impact", "time", "velocity", "exit_velocity", "peak_force", "contact_duration",
                            "bruised", "bruise_volume")} for impact in sequence["impacts"]]
    return {"impacts": impacts, "status": sequence["status"], "message": sequence["message"],
            "warnings": list(sequence["warnings"]),
            "rest_time": _number(sequence.get("rest_time")), "bruised": sequence.get("bruised"),
            "bruise_volume": _number(sequence.get("bruise_volume")), "command": command(inputs, "drop")}


def risk(request) -> dict:
    """The risk map of the explorer's fruit: the share of a lot (the fruit's library spreads, ``MAP_FRUIT``
    fruit) bruised over drop height × library surface, the typical fruit's margin and its safe height on each
    surface (``handling.heights.risk_map``)."""
    from fruitimpact.handling.heights import risk_map

    inputs = _without_impact(read_request(request))
    inputs.pop("surface", None)
    if inputs.get("criterion", "none") == "none":  # risk_map would judge by its own default: say which
        raise InputError("criterion must be given for the risk map: pressure, shear or energy", "criterion")
    mapped = risk_map(by="surface", **inputs)
    return {"heights": [float(h) for h in mapped["heights"]], "columns": list(mapped["columns"]),
            "margins": [[_number(row["bruise_margin"]) for row in mapped["rows"] if row["surface"] == column]
                        for column in mapped["columns"]],
            "incidence": [[_number(row["incidence"]) for row in mapped["rows"] if row["surface"] == column]
                          for column in mapped["columns"]],
            "incidence_heights": {column: {share: _number(h) for share, h in shares.items()}
                                  for column, shares in mapped["incidence_heights"].items()},
            "lot": {"rows": mapped["lot"]["rows"], "spreads": list(mapped["lot"]["spreads"])},
            "safe_height": {key: _number(value) for key, value in mapped["safe_height"].items()},
            "warnings": list(mapped["warnings"])}


def options() -> dict:
    """What the page's controls offer: the libraries, the registries, and every input's default, unit and
    option, so that the page opens on ``fruitimpact simulate``'s default impact."""
    from fruitimpact.app.uploads import MAX_UPLOAD
    from fruitimpact.impact.registries import REGISTRIES
    from fruitimpact.library import catalogue

    controls = {}
    for name in EXPLORER_INPUTS:
        quantity = INPUTS[name]
        controls[name] = {"label": quantity.label, "option": option_of(name), "unit": quantity.si_unit,
                          "default": quantity.default, "doc": quantity.doc}  # inf is null in the JSON
    return {
        "fruits": [{"name": name, "description": entry.description} for name, entry in catalogue.fruits().items()],
        "surfaces": [{"name": "rigid", "description": "a rigid plane (the founding paper's)"}]
                    + [{"name": name, "description": entry.description}
                       for name, entry in catalogue.surfaces().items()],
        "models": list(REGISTRIES["model"]), "calibrations": list(REGISTRIES["calibration"]),
        "criteria": [name for name in REGISTRIES["criterion"] if name != "preset"],
        "controls": controls,
        "upload_limit": MAX_UPLOAD,  # the recording page's and the monitor's
    }


__all__ = ["CURVE_POINTS", "EXPLORER_INPUTS", "SHOWN", "command", "explore", "options", "read_request", "risk"]
