"""Fruit files (a fitted fruit, ``fruitimpact fit-damage --output``) in an evaluation: the warnings their values
get as the options they stand for would, and a failure stress used under another criterion than it was fitted
under.  Called by ``impact.evaluation``."""

from __future__ import annotations

from fruitimpact.library import catalogue as library
from fruitimpact.impact.inputs import InputColumns
from fruitimpact.impact.validation import MessageBook, WarningBook, fruit_file_warnings


def plausibility(inputs: InputColumns, resolved, warnings: WarningBook) -> None:
    """The plausibility warnings a fruit file's values get, as the options they stand for do (where the row does
    not give that input itself)."""
    labels = {label for label in inputs.text["fruit"].labels if library.is_fruit_file(label)}
    for label in sorted(labels):
        rows = resolved.fruit_of == label
        if not rows.any():
            continue  # refused by the text check
        for name, text in fruit_file_warnings(label):
            warnings.add(rows & ~inputs.given[name], text)


def fitted_stress_warnings(inputs: InputColumns, resolved, where, name: str, messages: MessageBook,
                            warnings: WarningBook) -> None:
    """A failure stress fitted by fit-damage under one criterion, used under another (``name``): one warning per
    fruit file, naming the file and both criteria (the stress at onset differs between criteria)."""
    files = sorted(label for label in inputs.text["fruit"].labels if library.is_fruit_file(label))
    if not files:
        return
    using = where & ~inputs.given["failure_stress"] & ~messages.flagged
    fruits = library.fruits()
    for label in files:
        fitted = library.fitted_criterion(fruits[label]) if label in fruits else None
        if fitted is not None and fitted != name:
            warnings.add(using & (resolved.fruit_of == label), library.fitted_criterion_message(label, fitted, name))


__all__ = ["fitted_stress_warnings", "plausibility"]
