"""Many impacts at once: a table of inputs in, a table of characteristics out.

``evaluate(table)`` takes rows named like ``fruitimpact simulate``'s options
(the inputs of ``quantities.INPUTS``: mass, diameter, modulus, poisson,
stiffness, velocity, drop_height, restitution, alpha, damping, the surface,
step, model, calibration, method; plain SI numbers or strings with units)
and returns, per row, the inputs as used, the contact law, every
characteristic, a ``status`` (``ok``, ``inaccurate``, ``failed``,
``invalid``), a ``message`` and ``warnings``.  A bad row never stops the
others.  ``simulate()`` is this function on one row: there is one validation
and one judgement (``impact.single`` answers the rows this path judges ok with
no warning, to the same bit, and hands it every other row).

The work is vectorised end to end: validation on whole columns, one call of
the compiled kernels per (model, method) group, messages as integer codes
(``validation.MessageBook``) turned into categorical columns only at the end.
"""

from __future__ import annotations

from dataclasses import dataclass

import math

import numpy as np

from fruitimpact.library import catalogue as library
from fruitimpact.physics import hertz as contact
from fruitimpact.physics.hertz import hertz_contact_duration
from fruitimpact.physics.constants import STANDARD_GRAVITY
from fruitimpact.engine.codes import CHARACTERISTIC_COLUMNS, CONTACT_RADIUS, N_CHARACTERISTICS, TIME_TO_PEAK
from fruitimpact.impact.inputs import InputColumns, read_columns
from fruitimpact.physics import DAMPING_LAWS
from fruitimpact.impact.registries import REGISTRIES
from fruitimpact.impact import presets
from fruitimpact.engine.plasticforms import PLASTIC_COLUMNS, winkler_stiffness, yield_pressure_of_force
from fruitimpact.impact.quantities import (ALLOWED_BOUNDS, ALTERNATIVES, DAMAGE_NAMES, GROUP_DEFAULTS, INPUTS, NUMERIC_DEFAULTS,
                         NUMERIC_INPUTS, PLAUSIBLE_BOUNDS, TEXT_INPUTS, inside)
from fruitimpact.impact.solvers import (RK4_FINE_STEP_REFUSAL, RK4_MAX_STEPS, RK4_MIN_STEPS_PER_CONTACT,
                                        RK4_STEP_REFUSAL, SOLVERS, max_rk4_step, power_law_closed_forms)
from fruitimpact.impact.status import FAILED, INVALID, STATUS_NAMES, UNDERFLOW_MESSAGE, judge
from fruitimpact.impact.labels import Labels
from fruitimpact.impact import fruitfiles
from fruitimpact.impact.bruising import check_damage_inputs, damage_columns, range_warnings
from fruitimpact.impact.validation import (DEPENDENT_INPUTS, MessageBook, WarningBook, choice_message, conflict_message,
                                           implausible_message, nan_message, range_message)

#: Inputs reported as used (the requested restitution is ``target_restitution``; the damping as used is
#: ``damping``, given or calibrated).
INPUT_OUTPUTS = tuple(name for name in NUMERIC_INPUTS if name not in ("restitution", "damping")) + TEXT_INPUTS
LAW_COLUMNS = ("target_restitution", "law_stiffness", "damping", "damping_factor")
OUTPUT_COLUMNS = INPUT_OUTPUTS + LAW_COLUMNS + CHARACTERISTIC_COLUMNS + DAMAGE_NAMES + ("status", "message", "warnings")
#: Contact radius / effective radius beyond which Hertz's theory is left: the paraboloid that
#: replaces the sphere in Hertz's solution is then more than (a/R)²/4 = 4 % off at the contact edge.
HERTZ_RANGE = 0.4


@dataclass
class Evaluation:
    """Everything ``evaluate`` found, as arrays: output ``columns`` by name (float arrays,
    and ``Labels`` for the text columns), ``status`` codes (``status.STATUS_NAMES``),
    ``messages`` and ``warnings`` books, and for the power-law rows the closed-form
    self-check (δ_max, e) when asked for."""

    rows: int
    columns: dict
    status: np.ndarray
    messages: MessageBook
    warnings: WarningBook
    closed_forms: np.ndarray | None = None
    block: np.ndarray | None = None  # the characteristics as the engine wrote them (rows × 12)
    plastic: np.ndarray | None = None  # rows computed by the plastic engine (yield pressure or a layer)
    kernel_arguments: dict | None = None  # those rows' arguments of engine.plastic (for their curves)
    plastic_block: np.ndarray | None = None  # engine.plastic.PLASTIC_COLUMNS of those rows (NaN elsewhere)

    def labels(self) -> dict[str, Labels]:
        """``status``, ``message`` and ``warnings`` as ``Labels`` (no message on a row: its status)."""
        messages = self.messages
        codes, categories = self.warnings.categories()
        return {"status": Labels(self.status.astype(np.int32), STATUS_NAMES),
                "message": Labels(messages.codes, ("ok",) + tuple(messages.texts[1:])),
                "warnings": Labels(codes, tuple(categories))}

    def _all(self) -> dict:
        return {**self.columns, **self.labels()}

    def frame(self):
        """A pandas DataFrame of ``OUTPUT_COLUMNS`` (text columns categorical; no copies)."""
        import pandas as pd

        data = {name: value.to_pandas() if isinstance(value, Labels) else value for name, value in self._all().items()}
        return pd.DataFrame({name: data[name] for name in OUTPUT_COLUMNS}, copy=False)

    def table(self, first_row: int | None = None):
        """A pyarrow Table of ``OUTPUT_COLUMNS`` (text columns dictionary-encoded; floats not
        copied), with a ``row`` column in front numbering the rows from ``first_row`` if given."""
        import pyarrow as pa

        data = self._all()
        arrays = [data[name].to_arrow() if isinstance(data[name], Labels) else pa.array(data[name])
                  for name in OUTPUT_COLUMNS]
        names = list(OUTPUT_COLUMNS)
        if first_row is not None:
            arrays.insert(0, pa.array(np.arange(first_row, first_row + self.rows, dtype=np.int64)))
            names.insert(0, "row")
        return pa.Table.from_arrays(arrays, names=names)

    def status_counts(self) -> dict[str, int]:
        """Rows per status name (only the statuses present)."""
        counts = np.bincount(self.status.astype(np.int64), minlength=len(STATUS_NAMES))
        return {name: int(count) for name, count in zip(STATUS_NAMES, counts) if count}


def _check_ranges(inputs: InputColumns, messages: MessageBook, detail: bool) -> None:
    if detail:  # one impact: the NaN refusals read from the cells get the value, as range refusals do
        for i in np.flatnonzero(messages.flagged):
            name = messages.argument(i)
            if isinstance(name, str) and name in inputs.values and np.isnan(inputs.values[name][i]) \
                    and messages.text(i) == nan_message(INPUTS[name]):
                messages.codes[i] = messages.code(f"{nan_message(INPUTS[name])}; got nan", name)
    which = inputs.given_inputs()
    bad = inputs.given_matrix[which] & ~inside(ALLOWED_BOUNDS, inputs.matrix, which)
    for row, j in enumerate(which):  # in table order: a row is refused for its first problem
        if not bad[row].any():
            continue
        name = NUMERIC_INPUTS[j]
        text = range_message(INPUTS[name])
        if detail:
            text += f"; got {float(inputs.matrix[j, 0])!r}"
        messages.set(bad[row] & ~messages.flagged, text, name)
    for group in ALTERNATIVES:
        count = np.sum([inputs.given[name] for name in group], axis=0)
        if np.any(count > 1):
            for i in np.flatnonzero(count > 1):
                named = [name for name in group if inputs.given[name][i]]
                messages.set_row(i, conflict_message(named), tuple(named))


def _check_text(inputs: InputColumns, messages: MessageBook) -> None:
    for name, registry in REGISTRIES.items():
        labels = inputs.text[name]
        for code, value in enumerate(labels.labels):
            if not (isinstance(value, str) and value in registry):
                messages.set(labels.codes == code, choice_message(name, value, registry), name)


def _resolve_preset_criterion(inputs: InputColumns, messages: MessageBook) -> None:
    """``criterion preset``: each row takes the criterion its fruit's library entry names (issue 14 item 5c);
    a fruit without one is refused, naming ``--criterion``."""
    criteria = inputs.text["criterion"]
    preset = criteria.mask("preset")
    if not preset.any():
        return
    fruits = library.fruits()
    labels = list(criteria.labels)
    codes = criteria.codes.copy()
    fruit_labels = inputs.text["fruit"]
    for code, name in enumerate(fruit_labels.labels):
        rows = preset & (fruit_labels.codes == code)
        if not rows.any():
            continue
        chosen = fruits[name].criterion if name in fruits else None
        if chosen is None:  # refused; the row keeps the "preset" it was given
            messages.set(rows & ~messages.flagged,
                         f"criterion preset: the {name} entry of the fruit library names no bruise criterion the "
                         f"literature supports: give --criterion pressure, shear or energy", "criterion")
            continue
        if chosen not in labels:
            labels.append(chosen)
        codes[rows] = labels.index(chosen)
    inputs.text["criterion"] = Labels(codes, tuple(labels))


def _plausibility(inputs: InputColumns, warnings: WarningBook, detail: bool) -> None:
    which = [j for j in inputs.given_inputs() if INPUTS[NUMERIC_INPUTS[j]].plausible is not None]
    if not which:
        return
    outside = inputs.given_matrix[which] & np.isfinite(inputs.matrix[which]) & \
        ~inside(PLAUSIBLE_BOUNDS, inputs.matrix, which)
    for row, j in enumerate(which):
        if outside[row].any():
            quantity = INPUTS[NUMERIC_INPUTS[j]]
            warnings.add(outside[row], implausible_message(quantity, inputs.matrix[j, 0] if detail else None))


#: Rows handed to a compiled kernel at once.  Python regains control between two slices, so a Ctrl-C
#: stops any run within about half a second, even at the slowest kernels' ~30,000 rows/s (damped
#: plastic contact), where one call on a 500,000-row chunk used to hold it for 16 s (issue 15 item 5).
KERNEL_SLICE = 16_384
#: Rows of a group above which power-law rows use the engine's table by default (as
#: ``engine.powerlaw.powerlaw_characteristics`` decides for one call).
TABLE_ROWS = 20_000


def in_slices(kernel, *args):
    """``kernel(*args)`` over slices of ``KERNEL_SLICE`` rows: every array argument whose first axis is the
    row count is cut, the others (law, flags) are passed whole; the results (an array or a tuple of arrays,
    one row per input row) are joined.  Rows are independent, so the result is the same as one call."""
    rows = next(a.shape[0] for a in args if isinstance(a, np.ndarray) and a.ndim >= 1)
    if rows <= KERNEL_SLICE:
        return kernel(*args)
    joined = None
    for start in range(0, rows, KERNEL_SLICE):
        stop = min(start + KERNEL_SLICE, rows)
        part = kernel(*(a[start:stop] if isinstance(a, np.ndarray) and a.ndim >= 1 and a.shape[0] == rows
                        else a for a in args))
        pieces = part if isinstance(part, tuple) else (part,)
        if joined is None:  # the whole result allocated once, each slice written in place (no list to join)
            joined = tuple(np.empty((rows, *piece.shape[1:]), dtype=piece.dtype) for piece in pieces)
        for whole, piece in zip(joined, pieces):
            whole[start:stop] = piece
    return joined if isinstance(part, tuple) else joined[0]


def evaluate_inputs(inputs: InputColumns, messages: MessageBook, *, tabulated: bool | None = None,
                    detail: bool = False, closed_forms: bool = False) -> Evaluation:
    """The core of ``evaluate``: validated, resolved and computed rows, all arrays.

    ``detail`` (one row, the single-impact API) puts the offending value in messages;
    ``closed_forms`` adds the power-law first-integral self-check."""
    # NaN and inf in refused rows propagate quietly: every row's outcome is judged explicitly
    with np.errstate(invalid="ignore", divide="ignore", over="ignore", under="ignore"):
        return _evaluate(inputs, messages, tabulated, detail, closed_forms)


def _evaluate(inputs: InputColumns, messages: MessageBook, tabulated, detail, closed_forms,
              validate_only: bool = False) -> Evaluation | MessageBook:
    rows = inputs.rows
    values, given = inputs.values, inputs.given
    given_any = {name: bool(given[name].any()) for name in ("alpha", "damping")}
    warnings = WarningBook(rows)
    _check_ranges(inputs, messages, detail)
    codes = {name: inputs.text[name].codes for name in REGISTRIES}
    uniques = {name: inputs.text[name].labels for name in REGISTRIES}
    _check_text(inputs, messages)
    _resolve_preset_criterion(inputs, messages)
    _plausibility(inputs, warnings, detail)

    # the inputs as used: each input's own row of the matrix, its default written where it was not given (in
    # place: a fresh column per input was 23 columns of new memory, the slowest part of a large table); the
    # checks above have read the given cells, and every later reader of ``values`` looks at given rows only
    used = {}
    for j, name in enumerate(NUMERIC_INPUTS):
        column = inputs.matrix[j]
        if not given[name].any():
            column.fill(NUMERIC_DEFAULTS[j, 0])
        elif not given[name].all():
            np.copyto(column, NUMERIC_DEFAULTS[j, 0], where=~inputs.given_matrix[j])
        used[name] = column
    resolved = presets.resolve(inputs, GROUP_DEFAULTS["restitution"])
    resolved.apply(used, given)
    fruitfiles.plausibility(inputs, resolved, warnings)
    velocity = np.where(given["velocity"], values["velocity"],
                        np.where(given["drop_height"], np.sqrt(2.0 * STANDARD_GRAVITY * np.abs(values["drop_height"])),
                                 GROUP_DEFAULTS["velocity"]))
    radius = contact.effective_radius(used["diameter"] / 2.0, used["surface_radius"])
    layer = resolved.surface_model == presets.LAYER
    any_layer = bool(layer.any())
    fruit_modulus = contact.effective_modulus(used["modulus"], used["poisson"])
    # on a layer the fruit's own contact is with the (rigid) substrate; the layer is a spring in series
    pair_modulus = contact.effective_modulus(used["modulus"], used["poisson"], used["surface_modulus"],
                                             used["surface_poisson"])
    contact_modulus = np.where(layer, fruit_modulus, pair_modulus) if any_layer else pair_modulus
    hertz = contact.hertz_stiffness(contact_modulus, radius)
    stiffness = np.where(given["stiffness"], values["stiffness"], hertz)
    if given["stiffness"].any():  # the modulus that goes with a given k_c (Thornton needs E*)
        contact_modulus = np.where(given["stiffness"], 0.75 * stiffness / np.sqrt(radius), contact_modulus)
    damped_given = given["alpha"] | given["damping"]
    target = np.where(given["restitution"], values["restitution"],
                      np.where(damped_given, np.nan, resolved.restitution))
    defaulted = resolved.missing["restitution"] & ~given["restitution"] & ~damped_given
    for fruit in sorted(set(resolved.fruit_of[defaulted])) if defaulted.any() else ():
        warnings.add(defaulted & (resolved.fruit_of == fruit),
                     f"restitution is not in the {fruit} entry of the fruit library: the default "
                     f"{GROUP_DEFAULTS['restitution']:g} (the founding paper's Jonathan apple at 1 m/s) is used; give "
                     f"--restitution")
    used["velocity"], used["stiffness"] = velocity, stiffness
    # a free partner (another fruit): the reduced mass moves at the approach speed
    mass = presets.effective_mass(used["mass"], used["partner_mass"])
    yield_pressure = np.where(given["bioyield_force"],
                              yield_pressure_of_force(contact_modulus, radius, used["bioyield_force"]),
                              used["yield_pressure"])
    thickness = np.where(layer, used["surface_thickness"], np.inf) if any_layer else np.full(rows, np.inf)
    layer_stiffness = np.where(layer, winkler_stiffness(used["surface_modulus"], used["surface_poisson"],
                                                        thickness, radius), np.inf) if any_layer \
        else np.full(rows, np.inf)
    plastic = np.isfinite(yield_pressure) | layer
    check_damage_inputs(inputs, resolved, layer, used, thickness, messages, warnings)
    # a board that crushes (issue 14 item 3): its flutes collapse where the pressure under the fruit, k δ_L at
    # the centre of the Winkler layer, reaches the flat-crush strength σ_c; the crushed board carries no more
    # and the fruit meets the floor, so the layer bottoms out at δ_L = σ_c/k (k = K_L/(π R)) instead of at h
    crush = used["surface_crush_stress"]
    crushing = layer & np.isfinite(crush) & (crush * math.pi * radius / layer_stiffness < thickness) \
        if any_layer else np.zeros(rows, dtype=bool)
    bottoming = np.where(crushing, crush * math.pi * radius / layer_stiffness, thickness) \
        if crushing.any() else thickness

    # rk4's refusals need only the impact's scales: made before the laws' calibration (compiled), so that a
    # refused step is a usage error answered without the engine
    step = used["step"]
    rk4 = np.zeros(rows, dtype=bool)
    for code, method in enumerate(uniques["method"]):
        if method == "rk4":
            rk4 |= codes["method"] == code
    if rk4.any() and plastic.any():
        messages.set(rk4 & plastic & ~messages.flagged,
                     "method rk4 integrates the paper's elastic laws only: plastic contact and cushion layers are "
                     "computed exactly (method accurate)", "method")
    if rk4.any():
        limit = max_rk4_step(mass, stiffness, velocity)
        finest = limit * RK4_MIN_STEPS_PER_CONTACT / RK4_MAX_STEPS

        def refuse(bad, text, detailed):  # ``detailed``: one impact's message, naming its own range
            bad = rk4 & ~messages.flagged & bad
            if bad.any():
                messages.set(bad, detailed() if detail else text, "step")

        refuse(~(step <= limit), RK4_STEP_REFUSAL,
               lambda: f"step must be in (0, {float(limit[0]):.3g}] s for this impact (at least "
                       f"{RK4_MIN_STEPS_PER_CONTACT} steps per contact); got {float(step[0])!r}")
        refuse(step < finest, RK4_FINE_STEP_REFUSAL,
               lambda: f"step must be in [{float(finest[0]):.3g}, {float(limit[0]):.3g}] s for this impact (at most "
                       f"{RK4_MAX_STEPS:,} steps per contact); got {float(step[0])!r}")

    law_stiffness = np.full(rows, np.nan)
    factor = np.full(rows, np.nan)
    model_codes = codes["model"]
    for code, model in enumerate(uniques["model"]):
        law = DAMPING_LAWS.get(model) if isinstance(model, str) else None
        if law is None:
            continue
        in_model = ~messages.flagged if len(uniques["model"]) == 1 else (model_codes == code) & ~messages.flagged
        family = law.force_family
        if not family.alpha and given_any["alpha"]:
            messages.set(in_model & given["alpha"],
                         f"alpha is Hunt–Crossley's damping parameter of the power-law laws; model {model} is "
                         f"{family.formula}: give restitution, or damping ({family.damping_symbol} "
                         f"[{family.damping_unit}])", "alpha")
            in_model &= ~messages.flagged
        if not family.pressure:
            criteria = inputs.text["criterion"]
            for code_c, name in enumerate(criteria.labels):
                if name in ("pressure", "shear"):
                    messages.set(in_model & (criteria.codes == code_c),
                                 f"criterion {name} compares the Hertz contact pressure with the failure stress; "
                                 f"model {model} is {family.formula}, a linear spring with no Hertz pressure: use "
                                 f"--criterion energy, or a law with a Hertz elastic part (hunt-crossley, tsuji, "
                                 f"kuwabara-kono, ...)", "criterion")
            in_model &= ~messages.flagged
        if not family.first_integral and plastic.any():
            messages.set(in_model & plastic,
                         f"plastic contact (--yield-pressure, --bioyield-force) and cushion layers are built on the "
                         f"power-law family F = F_T(δ)(1 + c δ̇); model {model} is {family.formula}: use hertz "
                         f"(pure Thornton) or a power-law damping law (hunt-crossley, ...)",
                         "yield_pressure" if not layer.any() else "surface_model")
            in_model &= ~messages.flagged
        idx, sel = _selection(in_model)
        if idx.size == 0:
            continue
        m, k, v = mass[sel], stiffness[sel], velocity[sel]
        k_law = np.asarray(law.linear_stiffness(m, k, v), dtype=float) * np.ones(idx.size)
        law_stiffness[sel] = k_law
        if law.undamped:
            factor[sel] = 0.0
            given_some = given["restitution"][sel] | damped_given[sel]
            warnings.add(_mask(idx[given_some], rows), f"model {model} is undamped (e = 1): the restitution, "
                                                       f"alpha or damping given is ignored")
            continue
        calibrate = np.ones(idx.size, dtype=bool)
        if given_any["damping"]:
            from_damping = given["damping"][sel]
            factor[idx[from_damping]] = values["damping"][idx[from_damping]] / k_law[from_damping]
            calibrate &= ~from_damping
        if given_any["alpha"]:
            from_alpha = given["alpha"][sel]
            factor[idx[from_alpha]] = 1.5 * values["alpha"][idx[from_alpha]]  # c = λ/k_c = 1.5 α (eq 5)
            calibrate &= ~from_alpha
        calibrations = codes["calibration"][sel]
        for cal_code, calibration in enumerate(uniques["calibration"]):
            sub = calibrate if len(uniques["calibration"]) == 1 else calibrate & (calibrations == cal_code)
            rows_sub, sub_sel = _selection(sub, idx, sel)
            if rows_sub.size == 0 or validate_only:
                continue
            # the compiled engine is loaded where a row is computed, not to validate one (a usage error in 0.25 s)
            from fruitimpact.physics.calibrate import TABLE_E_MIN
            from fruitimpact.physics.calibrate import damping_factor as calibrated_damping_factor

            factor[sub_sel] = calibrated_damping_factor(law, calibration, target[sub_sel], mass[sub_sel],
                                                        stiffness[sub_sel], velocity[sub_sel])
            if calibration == "exact" and not family.first_integral and not law.exact_by_construction:
                below = rows_sub[target[sub_sel] < TABLE_E_MIN]
                messages.set(_mask(below, rows), f"restitution must be >= {TABLE_E_MIN:g} for model {model} with "
                                                 f"calibration exact (its table of e against the damping stops "
                                                 f"there)", "restitution")

    if validate_only:  # every refusal the inputs alone decide (the exact calibration's table limit aside)
        return messages
    status = np.full(rows, INVALID, dtype=np.int8)
    out = None
    plastic_block = None
    valid = ~messages.flagged
    # inputs that are legal but whose law leaves double precision (Kelvin–Voigt at V_i = 1e-160 m/s): failed,
    # not computed; impacts whose own scales underflow are caught by the judge (T = 0)
    collapsed = valid & ~(np.isfinite(law_stiffness) & (law_stiffness > 0) & np.isfinite(factor))
    if collapsed.any():
        status[collapsed] = FAILED
        messages.set(collapsed, UNDERFLOW_MESSAGE)
        valid &= ~collapsed
    methods = max(len(uniques["method"]), 1)
    groups = codes["model"] * methods + codes["method"]
    keys = [0] if len(uniques["model"]) == 1 and methods == 1 else np.unique(groups[valid])
    for key in keys:
        model = uniques["model"][key // methods]
        solver = SOLVERS[uniques["method"][key % methods]]
        law = DAMPING_LAWS[model]
        idx, sel = _selection(valid if len(keys) == 1 else valid & (groups == key))
        if idx.size == 0:
            continue
        # the engine's table pays for its build above TABLE_ROWS rows: decided on the whole group, before
        # in_slices cuts it (a slice alone would never use it, and the numbers would depend on the cut)
        group_tabulated = tabulated if tabulated is not None else idx.size > TABLE_ROWS
        group_plastic = plastic[idx]
        if group_plastic.any():  # elastic-plastic or layered rows: the plastic engine
            elastic_rows = idx[~group_plastic]
            plastic_rows = idx[group_plastic]
            group = np.empty((idx.size, N_CHARACTERISTICS))
            if plastic_block is None:
                plastic_block = np.full((rows, len(PLASTIC_COLUMNS)), np.nan)
            group[group_plastic], plastic_block[plastic_rows] = in_slices(
                _plastic_engine, crushing[plastic_rows], mass[plastic_rows], velocity[plastic_rows],
                stiffness[plastic_rows], radius[plastic_rows],
                contact_modulus[plastic_rows], yield_pressure[plastic_rows], layer_stiffness[plastic_rows],
                bottoming[plastic_rows], factor[plastic_rows])
            if elastic_rows.size:
                group[~group_plastic] = in_slices(solver.batch, law, law_stiffness[elastic_rows],
                                                  factor[elastic_rows], mass[elastic_rows], velocity[elastic_rows],
                                                  radius[elastic_rows], step[elastic_rows],
                                                  tabulated if tabulated is not None else
                                                  elastic_rows.size > TABLE_ROWS)
            reference = None  # rk4 is refused for these rows
            sel = idx
        else:
            arguments = (law_stiffness[sel], factor[sel], mass[sel], velocity[sel], radius[sel], step[sel],
                         group_tabulated)
            group = in_slices(solver.batch, law, *arguments)
            reference = in_slices(SOLVERS["accurate"].batch, law, *arguments) if solver.checked else None
        judge(group, idx, status, messages, solver=solver, velocity=velocity, step=step, reference=reference,
              time_scale=lambda some: hertz_contact_duration(mass[some], stiffness[some], velocity[some]))
        if out is None and idx.size == rows:  # one group: its array is the output (no scatter)
            out = group
        else:
            if out is None:
                out = np.full((rows, N_CHARACTERISTICS), np.nan)
            out[sel] = group
    if out is None:
        out = np.full((rows, N_CHARACTERISTICS), np.nan)

    leaves_hertz = (status != INVALID) & (out[:, CONTACT_RADIUS] > HERTZ_RANGE * radius)
    if leaves_hertz.any():
        ratio = f" = {float(out[0, CONTACT_RADIUS] / radius[0]):.3g}" if detail else ""
        warnings.add(leaves_hertz, f"the contact radius leaves Hertz's range: a/R{ratio} > {HERTZ_RANGE:g} "
                                   f"(δ_max/R > {HERTZ_RANGE ** 2:g}), where the paraboloid that Hertz puts in "
                                   f"place of the fruit is more than 4 % off; treat the figures as an estimate")

    # a peak at first touch (Kelvin–Voigt's dashpot force b V above all the spring gives later): C = F_max/t_c
    # and C* are undefined, said rather than left as NaN without a word (docs/models.md)
    at_touch = (status != INVALID) & (out[:, TIME_TO_PEAK] == 0.0)
    if at_touch.any():
        warnings.add(at_touch, "firmness C = F_max/t_c and C* = F_max/t_c² are undefined: the peak force is at "
                               "first touch (t_c = 0), the dashpot's force b·V above any force the spring reaches "
                               "later (heavy damping)")
    done = status != INVALID
    range_warnings(warnings, out, plastic_block, layer, thickness, used["surface_thickness"], radius, done, detail,
                    crushing)
    # failed rows carry no damage figures (their characteristics are not an impact)
    damage = damage_columns(out, plastic_block, done & (status != FAILED), mass, velocity, used, inputs,
                             fruit_modulus, pair_modulus, layer, resolved)
    # the onset energy of a stress criterion, W_f (threshold/quantity)^5, is exact only for elastic contact on a
    # half-space at a fixed restitution (damage.assess); say where a volume rests on it otherwise
    estimated = (damage["bruised"] == 1.0) & (plastic | layer | damped_given) & np.isin(
        inputs.text["criterion"].codes, [k for k, label in enumerate(inputs.text["criterion"].labels)
                                         if label in ("pressure", "shear")])
    warnings.add(estimated, "bruise volume: the onset energy it counts from is the Hertz-scaling estimate "
                            "W_f (threshold/stress)^5, exact only for elastic contact on a half-space at a fixed "
                            "restitution (not with plastic contact, a cushion, or damping given by alpha or "
                            "damping): the volume may be off by tens of %; safe-height finds the exact onset")
    columns = {name: used[name] for name in NUMERIC_INPUTS if name in INPUT_OUTPUTS}
    columns["yield_pressure"] = yield_pressure
    columns["bruise_energy"] = damage.pop("bruise_energy")
    columns.update(damage)
    columns["drop_height"] = np.where(given["drop_height"], values["drop_height"], np.nan)
    columns["alpha"] = np.where(given["alpha"], values["alpha"], np.nan)
    for name in TEXT_INPUTS:
        columns[name] = inputs.text[name]
    columns["target_restitution"] = target
    columns["law_stiffness"] = law_stiffness
    columns["damping"] = factor * law_stiffness
    columns["damping_factor"] = factor
    for j, name in enumerate(CHARACTERISTIC_COLUMNS):
        columns[name] = out[:, j]
    closed = None
    if closed_forms:
        closed = np.full((rows, 2), np.nan)
        for code, model in enumerate(uniques["model"]):
            law = DAMPING_LAWS.get(model) if isinstance(model, str) else None
            idx = np.flatnonzero((model_codes == code) & (status != INVALID) & ~plastic)
            if law is not None and law.force_family.first_integral and idx.size:
                closed[idx, 0], closed[idx, 1] = power_law_closed_forms(law_stiffness[idx], factor[idx], mass[idx],
                                                                        velocity[idx])
    arguments = dict(mass=mass, velocity=velocity, stiffness=stiffness, radius=radius,
                     contact_modulus=contact_modulus, yield_pressure=yield_pressure, layer_stiffness=layer_stiffness,
                     thickness=bottoming, damping_factor=factor, crushes=crushing.astype(float))
    return Evaluation(rows, columns, status, messages, warnings, closed, out, plastic, arguments, plastic_block)


def _plastic_engine(crushing: np.ndarray, *columns):
    """The plastic engine of rows (``columns`` as for ``plastic_characteristics``), the rows on a board that
    crushes (``crushing``, one flag per row: sliced with the rows by ``in_slices``) by the crushing engine."""
    from fruitimpact.engine.plastic import crushing_characteristics, plastic_characteristics

    if crushing.all():
        return crushing_characteristics(*columns)
    if not crushing.any():
        return plastic_characteristics(*columns)
    out = np.empty((crushing.size, N_CHARACTERISTICS))
    extra = np.empty((crushing.size, len(PLASTIC_COLUMNS)))
    for mask, run in ((crushing, crushing_characteristics), (~crushing, plastic_characteristics)):
        out[mask], extra[mask] = run(*(np.asarray(c)[mask] for c in columns))
    return out, extra


def _selection(mask: np.ndarray, idx: np.ndarray | None = None, sel=None):
    """(row numbers, a selector) of the True entries of ``mask``: the selector is ``slice(None)``
    when that is every row, so that whole-table groups are views, not copies.  With ``idx``
    and ``sel``, ``mask`` is over the rows ``idx`` already selected by ``sel``."""
    if mask.all():
        return (np.arange(mask.size) if idx is None else idx), (slice(None) if sel is None else sel)
    positions = np.flatnonzero(mask)
    rows = positions if idx is None else idx[positions]
    return rows, rows


def _mask(index: np.ndarray, size: int) -> np.ndarray:
    mask = np.zeros(size, dtype=bool)
    mask[index] = True
    return mask


def evaluation(table, *, tabulated: bool | None = None, errors=None) -> Evaluation:
    """``evaluate`` without the DataFrame: the ``Evaluation`` (arrays, codes), for callers that
    write Arrow tables or summarise columns (``runs``).  Same parameters as ``evaluate``."""
    rows = None
    messages = None
    if errors is not None:
        errors = list(errors)
        rows = len(errors)
        messages = MessageBook(rows)
        for i, text in enumerate(errors):
            if text:
                messages.set_row(i, str(text))
    inputs, messages = read_columns(table, messages, rows)
    result = evaluate_inputs(inputs, messages, tabulated=tabulated)
    if errors is not None:
        unread = np.array([bool(text) for text in errors], dtype=bool)
        if unread.any():  # a row the reader refused was never read: no input of it was "used"
            for name in NUMERIC_INPUTS:
                if name in result.columns:
                    result.columns[name] = np.where(unread, np.nan, result.columns[name])
    return result


def validate(table) -> MessageBook:
    """The refusals ``evaluate`` would give each row of ``table`` (as its ``messages``), without computing a row:
    every check the inputs alone decide, with no compiled engine loaded (the exact calibration's table limit is
    left to the computation)."""
    inputs, messages = read_columns(table)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore", under="ignore"):
        return _evaluate(inputs, messages, None, False, False, validate_only=True)


def evaluate(table, *, tabulated: bool | None = None, errors=None) -> "pandas.DataFrame":  # noqa: F821
    """Characteristics of every row of ``table``.

    Parameters
    ----------
    table : pandas.DataFrame, mapping of column → values, or pyarrow.Table
        Columns named like the inputs of ``quantities.INPUTS`` (``-`` may stand for
        ``_``); an unknown column is refused (``ValueError``) before any work.  Cells
        are numbers [SI] or strings with units; None, pd.NA, an Arrow null or an empty
        string means "not given" (the default); NaN is invalid.
    tabulated : bool or None
        Passed to ``engine.powerlaw.powerlaw_characteristics``: True makes power-law rows
        independent of how a run is split into chunks (the table agrees with the exact
        kernel to ~1e-13; by default it is used for groups of more than 20000 rows).
    errors : sequence of str, optional
        A message per row ("" or None: none); rows with one are invalid with it and
        their cells are not read (a file reader's verdict, e.g. a ragged CSV row).

    Returns
    -------
    pandas.DataFrame
        ``OUTPUT_COLUMNS``: the inputs as used (SI), ``target_restitution``, the contact
        law (``law_stiffness`` [N/m^1.5, N/m for Kelvin–Voigt], ``damping``,
        ``damping_factor``), the characteristics, and categorical ``status``
        (ok, inaccurate, failed, invalid), ``message`` and ``warnings``.

    Raises
    ------
    ValueError
        An unknown or misspelt column, a column of the wrong length; a bad value in a row makes that row
        ``invalid`` with its message instead (a batch never dies on one bad row).

    Examples
    --------
    >>> import fruitimpact as fi
    >>> table = fi.evaluate({"drop_height": ["2cm", "10cm", "-1"], "fruit": "apple"})
    >>> table["status"].tolist()
    ['ok', 'ok', 'invalid']

    References
    ----------
    As :func:`fruitimpact.simulate`, row by row.
    """
    return evaluation(table, tabulated=tabulated, errors=errors).frame()


def curves(table, times=None, points: int = 201):
    """Curves of every ok row of ``table``, each from its own solver (``--method``):
    a dict with ``row`` (the row numbers), ``time`` [s], ``deflection`` [m], ``rate``
    [m/s] and ``force`` [N], each of shape (rows, points).  ``times`` [s] is a common
    grid (points,) or one grid per row (rows, points); by default each row gets
    ``points`` samples over its own [0, T]."""
    inputs, messages = read_columns(table)
    result = evaluate_inputs(inputs, messages)
    rows = np.flatnonzero(result.status == 0)
    columns = {name: array[rows] if isinstance(array, Labels) else np.asarray(array)[rows]
               for name, array in result.columns.items()}
    if times is None:
        grid = np.linspace(0.0, 1.0, int(points))[None, :] * columns["contact_duration"][:, None]
    else:
        grid = np.broadcast_to(np.asarray(times, dtype=float), (len(rows), np.shape(times)[-1])).copy()
    deflection, rate, force = np.empty(grid.shape), np.empty(grid.shape), np.empty(grid.shape)
    models, methods = columns["model"], columns["method"]
    keys = models.codes.astype(np.int64) * len(methods.labels) + methods.codes
    for key in np.unique(keys):
        idx = np.flatnonzero(keys == key)
        law = DAMPING_LAWS[models.labels[key // len(methods.labels)]]
        solver = SOLVERS[methods.labels[key % len(methods.labels)]]
        deflection[idx], rate[idx], force[idx] = solver.curves(
            law, columns["law_stiffness"][idx], columns["damping_factor"][idx], columns["mass"][idx],
            columns["velocity"][idx], columns["step"][idx], grid[idx])
    return dict(row=rows, time=grid, deflection=deflection, rate=rate, force=force)


__all__ = ["DEPENDENT_INPUTS", "Evaluation", "HERTZ_RANGE", "LAW_COLUMNS", "OUTPUT_COLUMNS", "REGISTRIES",
           "curves", "evaluate", "evaluate_inputs", "evaluation",
           "validate"]
