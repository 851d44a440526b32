"""Refusing a run's inputs before it starts: what would refuse every row is a usage error, not a run of invalid
rows.  Both checks validate rows as :func:`fruitimpact.impact.evaluation.validate` does (no row computed, no
compiled engine loaded), so the refusal and the rows' own messages are the same words."""

from __future__ import annotations

import numpy as np

from fruitimpact.impact.evaluation import validate
from fruitimpact.impact.quantities import INPUTS
from fruitimpact.impact.validation import DEPENDENT_INPUTS, InputError


def refuse_constants(constants: dict, text: dict, given=()) -> None:
    """Refuse, before a run of many rows, a constant input out of its range or an input that the constants need
    and nobody gave (the energy criterion's threshold, a failure stress the fruit lacks): it would refuse every
    row.  One row of ``constants`` and ``text`` is validated as ``evaluation`` validates a row (not computed:
    the exact calibration's table limit is left to the rows); ``given`` names every input the rows will have
    (drawn or swept ones too).  ``InputError`` with that row's message."""
    if not constants and not text:
        return
    # the row validated, not computed: no compiled engine, so that a refusal after it (a missing output, another
    # job's parts) is answered at once too
    messages = validate({**{k: [v] for k, v in constants.items()}, **{k: [v] for k, v in text.items()}})
    message = messages.text(0)
    # the input a refusal names (its argument), else its first word: "plastic contact (--yield-pressure ...)"
    # is about yield_pressure
    name = messages.argument(0) or message.split(" ", 1)[0]
    # a dependent bound ("step must be at most 1/20 of the contact duration") may hold for the lot's other fruit;
    # any other refusal of such an input (alpha with a law that has none) holds for every row
    if not messages.flagged[0] or (name in DEPENDENT_INPUTS and message.startswith(f"{name} must be")):
        return
    if name in set(constants) | set(text) or (name in INPUTS and name not in set(given)):
        raise InputError(message, name)


def refuse_lot(columns, given, what: str) -> None:
    """Refuse, before a run, an input of the user's that every row of ``columns`` (a whole lot or grid, as it will
    be computed) is refused for: a step too coarse for rk4 for every fruit (which :func:`refuse_constants` leaves to
    the rows, since another fruit may meet it), a mass drawn from a range below zero.  Refused only when every row
    is refused, for one and the same input, and that input is in ``given`` (the inputs the user gave: constants,
    distributions, swept axes); ``InputError`` with the rows' message and ``what`` they are ("the lot's 500
    fruit")."""
    messages = validate(columns)
    rows = len(messages.codes)
    if rows == 0 or not messages.flagged.all() or len(np.unique(messages.codes)) != 1:
        return
    name = messages.argument(0)
    if name in set(given):
        raise InputError(f"{messages.text(0)}; every one of {what} is refused for it", name)


__all__ = ["refuse_constants", "refuse_lot"]
