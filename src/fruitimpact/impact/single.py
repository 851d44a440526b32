"""One impact without the table's bookkeeping: the per-call path of ``simulate()`` (issue 15 item 4).

``impact.evaluation`` validates, resolves, computes and judges whole tables: column checks, message books,
groups by model and method.  For one row that bookkeeping costs ~1 ms, 200 times the engine's own 5 µs, and
an optimiser, a notebook loop or the web explorer pays it on every call.  This module computes the rows that
need none of it, the common case, with the same formulas in scalar form, the same compiled row kernel of the
engine (``engine.powerlaw.powerlaw_single``, the row function of the table's kernel) and the same physical
check (``engine.checks``); every row outside that case goes to the table path, which is the reference:

* it covers only rows whose outcome is ``ok`` with no message and no warning: every input given inside its
  allowed *and* plausible range, no two alternatives given together, a power-law damping law
  (``ForceFamily.first_integral``), the ``accurate`` method, elastic contact on a half-space (no yield
  pressure, no layer, no free partner), criterion ``none``, a library fruit whose restitution is known or a
  restitution, α or λ given; and after computing, a physical impact inside Hertz's range;
* anything else, an input it cannot read, or a doubt, returns ``None``, and ``simulate`` takes the table
  path, which gives the one message, status and warnings of the CLI.

So there is one judgement: a row this path answers is one the table path answers ``ok`` with no warning, and
``tests/test_single.py`` checks over thousands of random rows, inside and outside this case, that both paths
give the same result to the last bit (the same row kernel, the same arithmetic).
"""

from __future__ import annotations

import math
import sys
from functools import lru_cache

import numpy as np

from fruitimpact.damage.bruise import hertz_max_shear
from fruitimpact.engine.checks import PHYSICAL, classify_row
from fruitimpact.engine.codes import CONTACT_RADIUS, MAX_PRESSURE
from fruitimpact.engine.powerlaw import CHARACTERISTIC_COLUMNS, exact_x, powerlaw_single, r_func, restitution_of_x
from fruitimpact.impact import presets
from fruitimpact.impact.evaluation import HERTZ_RANGE
from fruitimpact.impact.inputs import read_columns
from fruitimpact.impact.quantities import GROUP_DEFAULTS, INPUTS
from fruitimpact.impact.registries import REGISTRIES
from fruitimpact.impact.simulation import (Characteristics, ContactLaw, Fruit, ImpactInputs, ImpactResult,
                                           Surface, _unvalidated)
from fruitimpact.impact.solvers import SOLVERS
from fruitimpact.impact.validation import read_value
from fruitimpact.library.catalogue import is_fruit_file
from fruitimpact.physics import DAMPING_LAWS
from fruitimpact.physics.calibrate import damping_factor
from fruitimpact.physics.constants import STANDARD_GRAVITY

#: Numeric inputs this path reads; any other input given sends the row to the table path.
NUMERIC = frozenset(("velocity", "drop_height", "restitution", "alpha", "damping", "step", "mass", "diameter",
                     "modulus", "poisson", "stiffness", "surface_modulus", "surface_poisson", "surface_radius"))
#: Text inputs this path reads, with the values it covers (None: any value of the registry).
TEXT = {"model": None, "calibration": None, "method": ("accurate",), "criterion": ("none",)}
#: Damage inputs reported as used (``ImpactResult.damage_inputs``), as the table path names them.
_DAMAGE_INPUTS = ("yield_pressure", "surface_thickness", "partner_mass", "failure_stress", "bruise_susceptibility")
_DAMPED = ("restitution", "alpha", "damping")
#: The damage outputs of an elastic impact judged by no criterion (``impact.bruising.damage_columns``).
_NO_CRITERION = {"yield_velocity": math.inf, "permanent_deflection": 0.0, "plastic_work": 0.0, "viscous_work": None,
                 "fruit_energy": None, "max_shear_stress": None, "bruise_margin": math.nan, "bruised": None,
                 "bruise_volume": math.nan, "bruise_depth": math.nan, "bruise_width": math.nan}
_TOLERANCE = SOLVERS["accurate"].tolerance
#: The smallest normal double: a damping factor below it is reported by the table path (as calibrate's).
_TINY = sys.float_info.min
#: Most damping factors of distinct target restitutions kept (an optimiser may try many).
_CACHE_SIZE = 4096


@lru_cache(maxsize=64)
def _template(fruit: str, surface: str):
    """The library presets of one (fruit, surface) pair, resolved by the table path's own
    ``presets.resolve`` once: (numeric defaults by input name, default restitution or None when the fruit's
    entry has none, labels of the text outputs); None when the surface is not a half-space."""
    inputs, messages = read_columns({"fruit": [fruit], "surface": [surface]})
    if messages.flagged.any():
        return None
    resolved = presets.resolve(inputs, GROUP_DEFAULTS["restitution"])
    if int(resolved.surface_model[0]) != presets.HALF_SPACE or surface == "fruit":
        return None
    defaults = {name: (INPUTS[name].default if INPUTS[name].default is not None else math.nan)
                for name in INPUTS if INPUTS[name].numeric}
    for name, value in resolved.defaults.items():
        defaults[name] = float(value[0]) if getattr(value, "ndim", 0) else float(value)
    restitution = None if bool(resolved.missing["restitution"][0]) else float(resolved.restitution)
    names = {name: inputs.text[name][0] for name in ("fruit", "surface", "surface_model", "criterion")}
    return defaults, restitution, names


@lru_cache(maxsize=_CACHE_SIZE)
def _exact_x(restitution: float) -> float:
    """x = c V of the power-law family for restitution e (``engine.powerlaw.exact_x``, the table's own)."""
    return float(exact_x(restitution))


@lru_cache(maxsize=_CACHE_SIZE)
def _shear_ratio(poisson: float) -> float:
    """τ_max/p0 of Hertz's field at ν (``damage.bruise.hertz_max_shear``)."""
    return float(hertz_max_shear(poisson)[0])


def _number(name: str, value):
    """``value`` of input ``name`` as the table path reads it, or None when it must go there (unreadable,
    NaN, outside its allowed or plausible range: the table path says so)."""
    quantity = INPUTS[name]
    if type(value) is not float:
        try:
            value = read_value(name, value)
        except ValueError:
            return None
    if not quantity.allowed.contains(value):
        return None
    if quantity.plausible is not None and not quantity.plausible.contains(value):
        return None
    return value


def _read(fruit, surface, keywords: dict):
    """(fruit name, surface name, given numbers, text values) of a ``simulate`` call, or None."""
    given = {}
    fruit_name, surface_name = INPUTS["fruit"].default, INPUTS["surface"].default
    if isinstance(fruit, str):
        if is_fruit_file(fruit):
            return None  # a fruit file may change between calls: the table path reads it (the template is cached)
        fruit_name = fruit
    elif type(fruit) is Fruit:
        for name in ("mass", "diameter", "modulus", "poisson", "stiffness"):
            value = getattr(fruit, name)
            if value is not None:
                given[name] = value
    elif fruit is not None:
        return None
    if isinstance(surface, str):
        surface_name = surface
    elif type(surface) is Surface:
        if not (math.isinf(surface.thickness) and math.isinf(surface.crush_stress)):
            return None  # a cushion or a crushing board: the table path
        given.update(surface_modulus=surface.modulus, surface_poisson=surface.poisson,
                     surface_radius=surface.radius)
    elif surface is not None:
        return None
    text = {}
    for name, value in keywords.items():
        if name in TEXT:
            if not isinstance(value, str):
                return None
            allowed = TEXT[name]
            if allowed is not None and value not in allowed:
                return None
            text[name] = value
        elif value is None:
            continue
        elif name in NUMERIC:
            given[name] = value
        else:
            return None
    numbers = {}
    for name, value in given.items():
        number = _number(name, value)
        if number is None:
            return None
        numbers[name] = number
    if "velocity" in numbers and "drop_height" in numbers or sum(name in numbers for name in _DAMPED) > 1:
        return None
    return fruit_name, surface_name, numbers, text


def impact(fruit, surface, keywords: dict, curve_points: int):
    """The ``ImpactResult`` of one ``simulate`` call, or None when the row needs the table path (see the
    module's note).  ``keywords`` as ``simulate`` collects them; ``curve_points`` checked by the caller."""
    read = _read(fruit, surface, keywords)
    if read is None:
        return None
    fruit_name, surface_name, numbers, text = read
    for name, value in text.items():
        if value not in REGISTRIES[name]:
            return None
    template = _template(fruit_name, surface_name) if (fruit_name in REGISTRIES["fruit"]
                                                       and surface_name in REGISTRIES["surface"]) else None
    if template is None:
        return None
    defaults, library_restitution, names = template
    law = DAMPING_LAWS[text["model"]]
    family = law.force_family
    damped = [name for name in _DAMPED if name in numbers]
    if not family.first_integral or (law.undamped and damped) or ("alpha" in numbers and not family.alpha):
        return None
    if not damped and library_restitution is None:
        return None  # the table path warns that the default restitution is used
    used = {**defaults, **numbers}
    if not (math.isinf(used["yield_pressure"]) and math.isinf(used["partner_mass"])):
        return None
    mass = used["mass"]
    if "velocity" in numbers:
        velocity = numbers["velocity"]
    elif "drop_height" in numbers:
        velocity = math.sqrt(2.0 * STANDARD_GRAVITY * abs(numbers["drop_height"]))
    else:
        velocity = GROUP_DEFAULTS["velocity"]
    # physics.hertz's formulas, in the table's order of operations (the same bits)
    radius = 1.0 / (1.0 / (used["diameter"] / 2.0) + 1.0 / used["surface_radius"])
    modulus, poisson = used["modulus"], used["poisson"]
    fruit_modulus = 1.0 / ((1.0 - poisson * poisson) / modulus)  # on a rigid surface (its term is 0)
    surface_modulus, surface_poisson = used["surface_modulus"], used["surface_poisson"]
    pair_modulus = 1.0 / ((1.0 - poisson * poisson) / modulus
                          + (1.0 - surface_poisson * surface_poisson) / surface_modulus)
    contact_modulus = pair_modulus
    if "stiffness" in numbers:
        stiffness = numbers["stiffness"]
        contact_modulus = 0.75 * stiffness / math.sqrt(radius)
    else:
        stiffness = 4.0 / 3.0 * pair_modulus * math.sqrt(radius)
    target = numbers["restitution"] if "restitution" in numbers else math.nan if damped else library_restitution
    law_stiffness = float(law.linear_stiffness(mass, stiffness, velocity))
    if law.undamped:
        factor = 0.0
    elif "damping" in numbers:
        factor = numbers["damping"] / law_stiffness
    elif "alpha" in numbers:
        factor = 1.5 * numbers["alpha"]  # c = λ/k_c = 1.5 α (eq 5)
    else:
        if text["calibration"] == "exact" and not law.exact_by_construction:
            factor = _exact_x(target) / velocity
        else:
            factor = float(damping_factor(law, text["calibration"], target, mass, stiffness, velocity))
        if not (factor == 0.0 and target == 1.0 or _TINY <= abs(factor) < math.inf):
            return None  # not a normal number: the table path says what under- or overflowed
    if not (math.isfinite(law_stiffness) and law_stiffness > 0.0 and math.isfinite(factor)):
        return None
    out = powerlaw_single(mass, law_stiffness, 1.5, factor, velocity, radius)
    if classify_row(out, velocity, _TOLERANCE) != PHYSICAL:
        return None
    values = out.tolist()
    contact_radius = values[CONTACT_RADIUS]
    thickness = used["surface_thickness"]
    if contact_radius > HERTZ_RANGE * radius or (math.isfinite(thickness) and contact_radius > thickness):
        return None  # a warning the table path words
    characteristics = dict(zip(CHARACTERISTIC_COLUMNS, values))
    x = factor * velocity
    # the power through NumPy's array loop, as solvers.power_law_closed_forms takes it: its SIMD pow and the
    # scalar libm pow differ in the last bit for some arguments (NumPy 2.4 on AVX-512)
    base = 2.5 * mass * velocity ** 2 * r_func(x) / law_stiffness
    characteristics["max_deflection_closed_form"] = float(np.power(np.array([base]), 1.0 / 2.5)[0])
    characteristics["restitution_closed_form"] = restitution_of_x(x)
    absorbed = characteristics["absorbed_energy"]
    fruit_energy = absorbed * (1.0 if math.isinf(surface_modulus) else pair_modulus / fruit_modulus)
    peak_pressure = values[MAX_PRESSURE]
    shear = math.nan
    if math.isfinite(fruit_energy) and math.isfinite(peak_pressure) and 0.0 <= poisson <= 0.5:
        shear = _shear_ratio(poisson) * peak_pressure
    damage = dict(_NO_CRITERION, viscous_work=absorbed, fruit_energy=fruit_energy, max_shear_stress=shear)
    damage_inputs = {name: used[name] for name in _DAMAGE_INPUTS}
    damage_inputs["bruise_energy"] = 0.0  # no criterion: no threshold
    yield_pressure = used["yield_pressure"]
    inputs = _unvalidated(ImpactInputs, {
        "fruit": _unvalidated(Fruit, {"mass": mass, "diameter": used["diameter"], "modulus": modulus,
                                      "poisson": poisson, "stiffness": numbers.get("stiffness")}),
        "surface": _unvalidated(Surface, {"modulus": surface_modulus, "poisson": surface_poisson,
                                          "radius": used["surface_radius"], "thickness": thickness,
                                          "crush_stress": used["surface_crush_stress"]}),
        "velocity": velocity, "drop_height": numbers.get("drop_height"), "restitution": numbers.get("restitution"),
        "alpha": numbers.get("alpha"), "model": text["model"], "calibration": text["calibration"],
        "method": text["method"], "step": used["step"], "damping": numbers.get("damping"),
        "target_restitution": target if math.isfinite(target) else None})
    return _unvalidated(ImpactResult, {
        "inputs": inputs, "status": "ok", "message": "ok", "warnings": (), "curve_points": curve_points,
        "law": _unvalidated(ContactLaw, {"stiffness": law_stiffness, "damping_factor": factor, "exponent": 1.5,
                                         "family": law.family, "clamp": law.clamp}),
        "characteristics": _unvalidated(Characteristics, characteristics),
        "damage": damage, "names": dict(names), "damage_inputs": damage_inputs, "plastic": False,
        "plastic_arguments": {"mass": mass, "velocity": velocity, "stiffness": stiffness, "radius": radius,
                              "contact_modulus": contact_modulus, "yield_pressure": yield_pressure,
                              "layer_stiffness": math.inf, "thickness": math.inf, "damping_factor": factor,
                              "crushes": 0.0}})


__all__ = ["NUMERIC", "TEXT", "impact"]
