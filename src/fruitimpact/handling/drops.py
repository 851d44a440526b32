"""Drops: a fruit let fall from a height bounces on a surface until it rests.

Each impact is a full impact of ``impact.evaluation.evaluate`` at its own velocity.  The
rebound speed of one impact is the impact speed of the next, V_{n+1} = e_n V_n
(no drag), after a flight of 2 V_{n+1}/g.

Restitution across bounces (``bounces``, issue 14 item 6).  A fruit's damping
is a material property: by default (``"material"``) it is calibrated once, at
the first impact, to the restitution asked for (or the fruit's), and each
later impact keeps that damping factor c = λ/k (Hunt–Crossley's material
constant; on a flattened spot with the stiffness of the new radius), so e
follows the law at the lower speed: for the power law e is a function of
x = c V alone and rises as the fruit slows, as drop tests show (Hunt &
Crossley 1975: e = 1 − α V to first order; the founding paper's eq 6).
``"constant"`` recalibrates every impact to the same e (the rule before).

How repeated impacts on the same spot accumulate damage (the rule, stated in
every output and in docs/damage.md): the fruit lands on the same spot every
time.  A re-impact reloads the flattened spot as Hertz with its enlarged
radius R_p (TN98 eq 20) up to the same yield pressure p_y, and yields again
beyond it (issue 14 item 8): a later bounce can add plastic work, never a
pressure above p_y.  A crushable board (cardboard) stays crushed: once its flutes under the fruit
have collapsed, the later impacts land on the floor that carried the force beyond the crush (rigid, as
in the layer model), with no board work.  Before, each bounce met a fresh board and crushed it again (an
apple from 30 cm onto the library's cardboard: 2.1 mJ of crush work at each of its first 8 impacts).
Each impact that meets the bruise criterion adds
BS (W_f − W_th)₊ to the bruise volume.  Measured apple bruises keep growing over
3–5 repeated equal impacts before they stabilise (Komarnicki & Stopa 2013;
the pendulum studies of docs/damage.md): this rule does not reproduce that
growth; in a drop the later bounces carry much less energy, which limits the
difference.
"""

from __future__ import annotations

import math

import numpy as np

from fruitimpact.physics.constants import STANDARD_GRAVITY

#: Impacts followed at most.
MAX_IMPACTS = 50
#: The refusal of a drop onto a free partner.
FREE_PARTNER = ("a drop bounces on a fixed surface, not a free partner (surface fruit, partner_mass): simulate the "
                "fruit-on-fruit impact itself with --surface fruit")
#: The fruit is at rest once a rebound would rise less than this [m].
REST_HEIGHT = 1e-3
#: Accumulation rule, named in every output.
ACCUMULATION_RULE = ("same spot; later impacts reload the flattened spot (Hertz with its radius R_p) up to the "
                     "yield pressure p_y and yield again beyond it; once a board has crushed under the fruit, "
                     "later impacts land on its floor (rigid); each impact meeting the criterion adds "
                     "BS (W_f - W_th)+")

_IMPACT_FIELDS = ("velocity", "restitution", "exit_velocity", "peak_force", "time_to_peak", "contact_duration",
                  "max_deflection", "max_pressure", "max_shear_stress", "absorbed_energy", "plastic_work",
                  "viscous_work", "fruit_energy", "permanent_deflection", "bruise_margin", "bruised", "bruise_volume",
                  "bruise_depth", "bruise_width")


#: ``bounces``: how the restitution of the later impacts follows (module docstring).
BOUNCE_RULES = {"material": "damping calibrated at the first impact, kept: e follows the law as the fruit slows",
                "constant": "every impact calibrated to the same restitution"}


def drop(drop_height, *, max_impacts: int = MAX_IMPACTS, rest_height: float = REST_HEIGHT,
         bounces: str = "material", **inputs) -> dict:
    """The sequence of impacts of a fruit dropped from ``drop_height`` [m] onto a surface.

    Parameters
    ----------
    drop_height : float or str
        Height of the fall h > 0 [m] (or a string with a unit); V_1 = √(2 g h).
    max_impacts : int
        Impacts followed at most.
    rest_height : float
        The fruit rests once a rebound would rise less than this [m].
    bounces : str
        ``"material"`` (default: the damping calibrated at the first impact is kept, e rises as the fruit
        slows) or ``"constant"`` (every impact at the same e); ``BOUNCE_RULES``.
    **inputs
        Any input of ``quantities.INPUTS`` but the velocity (fruit, surface, model,
        plastic and bruise inputs), as for ``simulate``.

    Returns
    -------
    dict
        ``drop_height``, ``criterion``, ``accumulation_rule``, ``impacts`` (one dict per
        impact: ``velocity``, ``restitution``, ``peak_force``, ``plastic_work`` …, ``time``
        of the impact [s] after release), and the totals ``impact_count``,
        ``total_absorbed_energy``, ``total_plastic_work``, ``total_viscous_work``,
        ``bruised`` (any impact), ``bruise_volume`` (accumulated), ``rest_time``,
        ``status`` and ``message``, ``warnings``.

    Raises
    ------
    ValueError
        An input outside its range or unknown, ``velocity`` given (the drop sets it), ``bounces`` not one of
        ``BOUNCE_RULES``, ``max_impacts`` outside [1, 1000], a stress criterion for a fruit with no failure
        stress; the message names the argument.

    Examples
    --------
    >>> import fruitimpact as fi
    >>> report = fi.drop("30cm", fruit="apple", surface="steel")
    >>> [round(i["restitution"], 2) for i in report["impacts"][:3]]
    [0.55, 0.69, 0.77]

    References
    ----------
    Each impact is :func:`fruitimpact.simulate`'s (founding paper, "Theoretical aspects about simulating the
    reaction to impact of apples on rigid plane surfaces"); plastic reloading after C. Thornton, J. Appl. Mech.
    64 (1997) 383–386; bounce rule: docs/damage.md.
    """
    from fruitimpact.impact.validation import InputError, check_input_name, check_number, read_count

    if drop_height is None:
        raise InputError("drop_height must be given: the height the fruit falls from [m], e.g. 0.3 or \"30cm\"",
                         "drop_height")
    for name in ("velocity", "drop_height"):
        if inputs.get(name) is not None:
            raise InputError(f"{name} is set by the drop: give drop_height as the first argument", name)
    for name in inputs:
        check_input_name(name)
    if bounces not in BOUNCE_RULES:
        raise InputError(f"bounces must be one of {', '.join(BOUNCE_RULES)}; got {bounces!r}", "bounces")
    if bounces == "constant" and any(inputs.get(name) is not None for name in ("alpha", "damping")):
        raise InputError("bounces constant recalibrates every impact to one restitution: give restitution (with "
                         "alpha or damping the law sets e at each speed, which is bounces material)", "bounces")
    rest_height = check_number("rest_height", rest_height, low=0.0, low_inclusive=False, high=1.0,
                               high_inclusive=True)
    max_impacts = read_count("max_impacts", max_impacts, 1, 1000)
    from fruitimpact.library.catalogue import surfaces

    surface = inputs.get("surface").strip() if isinstance(inputs.get("surface"), str) else None
    partner = surface in surfaces() and surfaces()[surface].partner is not None
    if partner or inputs.get("partner_mass") is not None:
        raise InputError(FREE_PARTNER, "surface")  # every way to a free partner, before the engine
    # the engine only now: every argument above is answered without it
    from fruitimpact.impact.evaluation import evaluate_inputs
    from fruitimpact.impact.inputs import read_columns

    row = {name: value for name, value in inputs.items() if value is not None}
    row["drop_height"] = drop_height
    read, messages = read_columns({name: [value] for name, value in row.items()})
    first = evaluate_inputs(read, messages, detail=True)
    if first.status[0] == 3:  # invalid: the one-line refusal, naming the argument
        raise InputError(messages.text(0), messages.argument(0))
    if math.isfinite(first.columns["partner_mass"][0]):  # as the table resolved it (any spelling it accepts)
        raise InputError(FREE_PARTNER, "surface")
    height = float(first.columns["drop_height"][0])
    criterion = first.columns["criterion"][0]
    impacts = []
    warnings = list(first.warnings.row(0))
    status, message = "ok", "ok"
    time = math.sqrt(2.0 * height / STANDARD_GRAVITY)
    result, j = first, 0  # the impact's evaluation and its row there
    batch = None
    flattened = None
    crushed = False  # the board under the fruit has crushed: its spot stays so
    material_factor = float(first.columns["damping_factor"][0])
    if not math.isfinite(material_factor):
        material_factor = 0.0
    while True:
        columns = {name: (float(result.columns[name][j])) for name in _IMPACT_FIELDS}
        code = int(result.status[j])
        impact = {"impact": len(impacts) + 1, "time": time, **columns}
        impact["bruised"] = None if math.isnan(columns["bruised"]) else bool(columns["bruised"])
        impacts.append(impact)
        if code != 0:
            status = "failed" if code == 2 else "inaccurate"
            message = f"impact {len(impacts)}: {result.messages.text(j)}"
            break
        if result.plastic_block is not None and result.plastic[j] and columns["permanent_deflection"] > 0.0:
            flattened = float(result.plastic_block[j, -1])  # the spot as this impact left it: R_p
        crushed = crushed or _crushed_board(result, j)
        rebound = columns["exit_velocity"]
        if rebound * rebound / (2.0 * STANDARD_GRAVITY) < rest_height or len(impacts) >= max_impacts:
            if len(impacts) >= max_impacts and rebound * rebound / (2.0 * STANDARD_GRAVITY) >= rest_height:
                warnings.append(f"stopped after {max_impacts} impacts while the fruit still rebounds "
                                f"{rebound * rebound / (2.0 * STANDARD_GRAVITY) * 1e3:.3g} mm")
            break
        time += columns["contact_duration"] + 2.0 * rebound / STANDARD_GRAVITY
        velocity = rebound
        next_row = {**row, "velocity": velocity}
        next_row.pop("drop_height")
        if flattened is not None:
            # the same, flattened spot: Hertz with R_p (same E*), and the same limiting pressure p_y: a reload
            # whose Hertz pressure on R_p would pass p_y yields again (Thornton's elastic reload up to F* would
            # carry up to 1.5 p_y there, 3F* p_y/(2F* + F_y): more than the flesh's limit)
            next_row.pop("bioyield_force", None)
            next_row["yield_pressure"] = float(first.columns["yield_pressure"][0])
            next_row["stiffness"] = 4.0 / 3.0 * _contact_modulus(first) * math.sqrt(flattened)
            next_row["diameter"] = 2.0 * flattened
        if crushed:
            # the same spot of a crushed board: its flutes stay collapsed, so the fruit lands on the floor that
            # carried the force beyond the crush (rigid, as in the layer model), with none of the board's work
            for name in [name for name in next_row if name.startswith("surface")]:
                next_row.pop(name)
            next_row["surface"] = "rigid"
        if bounces == "material" and material_factor > 0.0:
            # the first impact's damping factor c = λ/k, a property of the flesh: λ = c k of this contact
            for name in ("restitution", "alpha", "damping"):
                next_row.pop(name, None)
            stiffness = next_row.get("stiffness", float(first.columns["law_stiffness"][0]))
            next_row["damping"] = material_factor * float(stiffness)
        if batch is None and flattened is None and len(impacts) == 1:
            batch = _bounces_at_once(first, next_row, bounces, material_factor, rest_height, max_impacts)
        if batch is not None and len(impacts) < batch.rows + 1 and \
                abs(float(batch.columns["velocity"][len(impacts) - 1]) - velocity) <= 1e-9 * velocity:
            result, j = batch, len(impacts) - 1  # predicted right: this impact was evaluated with the others
        else:
            batch = False if batch is not None else batch  # a prediction missed: the rest one by one, as always
            read, messages = read_columns({name: [value] for name, value in next_row.items()})
            result, j = evaluate_inputs(read, messages, detail=True), 0
            if result.status[0] == 3:
                status, message = "failed", f"impact {len(impacts) + 1}: {messages.text(0)}"
                break
        if result.status[j] == 3:
            status, message = "failed", f"impact {len(impacts) + 1}: {result.messages.text(j)}"
            break
        kinds = {text.split(":")[0] for text in warnings}
        for text in result.warnings.row(j):  # one warning of each kind (the first impact's figures)
            if text.split(":")[0] not in kinds and not text.startswith("diameter"):
                warnings.append(text)
    rest = impacts[-1]["time"] + impacts[-1]["contact_duration"]
    volumes = [i["bruise_volume"] for i in impacts]
    bruised = [i["bruised"] for i in impacts]
    return {
        "drop_height": height, "criterion": criterion, "accumulation_rule": ACCUMULATION_RULE,
        "bounces": bounces,
        "impacts": impacts, "impact_count": len(impacts),
        "total_absorbed_energy": float(sum(i["absorbed_energy"] for i in impacts)),
        "total_plastic_work": float(sum(i["plastic_work"] for i in impacts)),
        "total_viscous_work": float(sum(i["viscous_work"] for i in impacts)),
        "total_fruit_energy": float(sum(i["fruit_energy"] for i in impacts)),
        "energy_left": 0.5 * float(first.columns["mass"][0]) * impacts[-1]["exit_velocity"] ** 2,
        "bruised": None if criterion == "none" else any(bool(b) for b in bruised),
        # a bruised impact without a volume (no bruise susceptibility) leaves the total unknown, never 0
        "bruise_volume": None if criterion == "none" else
        (math.nan if any(b and math.isnan(v) for b, v in zip(bruised, volumes)) else float(np.nansum(volumes))),
        "rest_time": rest, "status": status, "message": message, "warnings": warnings,
    }


def _crushed_board(result, j: int) -> bool:
    """Whether row ``j`` of an evaluation crushed its board: a layer with a flat-crush strength that the pressure
    under the fruit reached (it bottomed out at the crush depth, ``impact.evaluation``)."""
    from fruitimpact.engine.plastic import PLASTIC_COLUMNS

    return result.plastic_block is not None and bool(result.plastic[j]) \
        and result.plastic_block[j, PLASTIC_COLUMNS.index("bottomed_out")] == 1.0 \
        and math.isfinite(float(result.columns["surface_crush_stress"][j]))


def _bounces_at_once(first, row: dict, bounces: str, factor: float, rest_height: float, max_impacts: int):
    """The later impacts of an elastic drop evaluated together in one table, or None where they cannot be
    predicted: their velocities follow from the law's own restitution without the impacts — for the power-law
    family e is a closed-form function of x = c V (``engine.powerlaw.exact_restitution``), with ``material``
    bounces c is the first impact's, with ``constant`` ones e is the first impact's.  The drop loop checks each
    predicted velocity against the rebound the previous impact really had (to 1e-9) and evaluates the rest one
    by one at the first miss, so this is a shortcut to the same numbers, never a second model.  Only without
    plastic or crushing contact (a flattened spot changes the next impact) and with every input a number."""
    from fruitimpact.engine.powerlaw import exact_restitution
    from fruitimpact.impact.evaluation import evaluate_inputs
    from fruitimpact.impact.inputs import read_columns
    from fruitimpact.physics.registry import get_law

    if (first.plastic is not None and first.plastic[0]) or not math.isfinite(float(first.columns["exit_velocity"][0])):
        return None
    law = get_law(str(first.columns["model"][0]))
    if bounces == "material" and (factor <= 0.0 or not law.force_family.first_integral):
        return None
    velocities, velocity = [], float(first.columns["exit_velocity"][0])
    e_first = float(first.columns["restitution"][0])
    while velocity * velocity / (2.0 * STANDARD_GRAVITY) >= rest_height * 0.999 and len(velocities) < max_impacts:
        velocities.append(velocity)  # one more predicted than the loop may need: the miss shows at the rest height
        e = float(exact_restitution(factor * velocity)) if bounces == "material" else e_first
        velocity *= e
    if len(velocities) < 2:
        return None
    table = {name: [value] * len(velocities) for name, value in row.items() if name != "velocity"}
    table["velocity"] = velocities
    read, messages = read_columns(table)
    return evaluate_inputs(read, messages, detail=True)


def _contact_modulus(evaluation) -> float:
    return float(evaluation.kernel_arguments["contact_modulus"][0])


__all__ = ["ACCUMULATION_RULE", "BOUNCE_RULES", "MAX_IMPACTS", "REST_HEIGHT", "drop"]
