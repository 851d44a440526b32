"""A force recording: one or several lanes of force samples on one uniform time grid.

``Recording`` is what the readers (``signals.read``) return and the synthetic
sensor (``signals.synth``) produces: SI units throughout (force [N], time [s],
rate [Hz]).  It is immutable: the lanes are read-only float64 arrays behind a
read-only mapping.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from fruitimpact.impact.validation import InputError, is_boolean


def _finite_number(name: str, value, *, positive: bool = False) -> float:
    if is_boolean(value) or not isinstance(value, numbers.Real):
        raise InputError(f"{name} must be a number; got {value!r}", name)
    value = float(value)
    if not math.isfinite(value) or (positive and value <= 0.0):
        raise InputError(f"{name} must be a finite number{' > 0' if positive else ''}; got {value!r}", name)
    return value


@dataclass(frozen=True, eq=False)
class Recording:
    """Force samples of one or several lanes, sampled together at ``rate``.

    Parameters
    ----------
    rate : float
        Sample rate [Hz], finite and > 0.
    lanes : mapping of str → 1-D array
        Force [N] of each lane (float64 after construction; every lane the same
        length, at least one sample, every sample finite).  Stored as read-only
        copies behind a read-only mapping, in the order given.
    start_time : float
        Time of the first sample [s] (default 0).
    clip_low, clip_high : float or None
        The ADC's limits [N] when known: samples equal to a limit were clipped
        there.  None when unknown (most files do not say).
    source : str
        Where the samples came from (a file path, ``"synthetic"``), for messages.

    Equality is identity (arrays do not compare as one truth value).
    """

    rate: float
    lanes: Mapping[str, np.ndarray]
    start_time: float = 0.0
    clip_low: float | None = None
    clip_high: float | None = None
    source: str = field(default="")

    def __post_init__(self):
        object.__setattr__(self, "rate", _finite_number("rate", self.rate, positive=True))
        object.__setattr__(self, "start_time", _finite_number("start_time", self.start_time))
        for name in ("clip_low", "clip_high"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, _finite_number(name, value))
        if self.clip_low is not None and self.clip_high is not None and not self.clip_low < self.clip_high:
            raise InputError(f"clip_low must be below clip_high; got {self.clip_low!r} and {self.clip_high!r}",
                             "clip_low")
        if not isinstance(self.source, str):
            raise InputError(f"source must be a string; got {self.source!r}", "source")
        if not isinstance(self.lanes, Mapping) or not self.lanes:
            raise InputError("lanes must be a non-empty mapping of lane name -> force samples [N]", "lanes")
        lanes = {}
        length = None
        for name, values in self.lanes.items():
            if not isinstance(name, str) or not name:
                raise InputError(f"lanes: every lane name must be a non-empty string; got {name!r}", "lanes")
            try:
                array = np.array(values, dtype=np.float64)  # a copy: the caller's array stays theirs
            except (TypeError, ValueError):
                raise InputError(f"lanes: lane {name!r} is not an array of numbers", "lanes") from None
            if array.ndim != 1:
                raise InputError(f"lanes: lane {name!r} must be 1-D; got shape {array.shape}", "lanes")
            if length is None:
                length = array.size
            elif array.size != length:
                raise InputError(f"lanes: every lane must have the same length; lane {name!r} has {array.size} "
                                 f"samples, the first lane {length}", "lanes")
            bad = np.flatnonzero(~np.isfinite(array))
            if bad.size:
                raise InputError(f"lanes: sample {bad[0]} of lane {name!r} is {float(array[bad[0]])!r}; "
                                 f"samples must be finite", "lanes")
            array.setflags(write=False)
            lanes[name] = array
        if length == 0:
            raise InputError("lanes: the lanes hold no samples", "lanes")
        object.__setattr__(self, "lanes", MappingProxyType(lanes))

    @property
    def samples(self) -> int:
        """Number of samples per lane."""
        return next(iter(self.lanes.values())).size

    @property
    def duration(self) -> float:
        """Time covered [s]: ``samples / rate`` (each sample stands for one interval 1/rate)."""
        return self.samples / self.rate

    @property
    def lane_names(self) -> tuple[str, ...]:
        """The lane names, in order."""
        return tuple(self.lanes)

    def time(self) -> np.ndarray:
        """Sample times [s]: ``start_time + arange(samples) / rate``."""
        return self.start_time + np.arange(self.samples) / self.rate

    def __repr__(self) -> str:
        return (f"Recording(rate={self.rate!r}, lanes={list(self.lanes)!r}, samples={self.samples}, "
                f"start_time={self.start_time!r}, clip_low={self.clip_low!r}, clip_high={self.clip_high!r}, "
                f"source={self.source!r})")


__all__ = ["Recording"]
