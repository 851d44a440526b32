"""Text columns as integer codes and a short list of labels (a categorical).

A million rows of ``model = "chen"``, ``status = "ok"`` or one message cost
a million small integers and one string, not a million strings: evaluation
keeps text this way and converts only at the boundary, to a pandas
Categorical or an Arrow dictionary array (both keep the codes), or to plain
strings for one row.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Labels:
    """``codes`` (an integer array) into ``labels`` (distinct strings)."""

    codes: np.ndarray
    labels: tuple

    @classmethod
    def constant(cls, label, rows: int) -> "Labels":
        return cls(np.zeros(rows, dtype=np.int32), (label,))

    def __len__(self) -> int:
        return self.codes.shape[0]

    def __getitem__(self, index):
        """A row's label, or the ``Labels`` of a selection of rows."""
        if np.ndim(index) == 0 and not isinstance(index, slice):
            return self.labels[int(self.codes[index])]
        return Labels(self.codes[index], self.labels)

    def to_numpy(self) -> np.ndarray:
        """An object array of the labels."""
        return np.asarray(self.labels, dtype=object)[self.codes] if len(self.labels) else \
            np.empty(len(self), dtype=object)

    def mask(self, label) -> np.ndarray:
        """Rows whose label is ``label``."""
        if label not in self.labels:
            return np.zeros(len(self), dtype=bool)
        return self.codes == self.labels.index(label)

    def to_pandas(self):
        """A pandas Categorical with these codes (labels made unique if repeated)."""
        import pandas as pd

        return pd.Categorical.from_codes(self.codes, categories=_unique(self.labels))

    def to_arrow(self):
        """An Arrow dictionary array (string values) with these codes."""
        import pyarrow as pa

        return pa.DictionaryArray.from_arrays(pa.array(self.codes.astype(np.int32)),
                                              pa.array(list(self.labels), type=pa.string()))


def _unique(labels) -> list[str]:
    """Categories must be unique: a repeated label gets invisible padding (zero-width spaces).  A label that is not
    text (a number or NaN in a text column: its row is refused) is shown as the user wrote it, ``str`` of it."""
    seen: dict[str, int] = {}
    out = []
    for label in labels:
        label = label if isinstance(label, str) else str(label)
        count = seen.get(label, 0)
        seen[label] = count + 1
        out.append(label + "\u200b" * count)
    return out


def factorize(values: np.ndarray) -> Labels:
    """``Labels`` of an object array, by hashing (a million equal strings cost little)."""
    if values.size > 64:
        import pandas as pd

        codes, uniques = pd.factorize(values, use_na_sentinel=False)
        return Labels(codes.astype(np.int32), tuple(uniques))
    index: dict = {}
    codes = np.empty(values.size, dtype=np.int32)
    order = []
    for i, value in enumerate(values):
        key = (type(value), repr(value)) if isinstance(value, float) else (type(value), value)
        code = index.get(key)
        if code is None:
            code = index[key] = len(order)
            order.append(value)
        codes[i] = code
    return Labels(codes, tuple(order))


__all__ = ["Labels", "factorize"]
