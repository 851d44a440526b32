"""Settings of the impact detector (``signals.detect``): what it tracks, its thresholds and windows, each value
checked at construction with a one-line ``ValueError`` naming it and its allowed range; and ``Analysis``, how its
contacts are analysed (``signals.analysis``).  Neither imports the detector or the fits (numba): a usage error is
answered without them."""

from __future__ import annotations

import itertools
import math
import numbers
from dataclasses import dataclass


from typing import TYPE_CHECKING

from fruitimpact.impact.units import parse_quantity
from fruitimpact.impact.validation import InputError, check_integer, check_number, is_boolean
from fruitimpact.physics.constants import STANDARD_GRAVITY

if TYPE_CHECKING:
    from fruitimpact.signals.analysis import LineAnalyzer
    from fruitimpact.signals.sort import FirmnessClasses

#: Most lanes (force channels) of one recording or stream: analyze, stream and the web app's pages.
MAX_LANES = 256

__all__ = ["HUM_AUTO", "MAX_LANES", "MIN_DISCHARGE_TIME", "Analysis", "DetectorSettings", "at_rate", "check_cutoff",
           "in_samples"]


#: ``DetectorSettings.hum_frequency`` that finds the mains frequency on the stream's first samples.
HUM_AUTO = "auto"
#: Shortest discharge time constant accepted [s]: a chain that discharges within 10 ms keeps little of a
#: contact of a few ms, and restoring it would amplify the noise as much as the force.
MIN_DISCHARGE_TIME = 0.01


@dataclass(frozen=True)
class DetectorSettings:
    """Settings of the impact detector (SI units; defaults suit fruit on a force plate at 10–50 kHz).

    Attributes
    ----------
    baseline_time_constant : float
        τ_b [s] of the baseline (zero/drift level and slope) estimate over quiet samples. Default 0.05.
    noise_time_constant : float
        [s] of the robust running noise σ over quiet samples. Default 0.5.
    warmup : float
        [s] learnt at the start (and after an overlong impact) before any onset; ≥ 16 samples. Default 0.05.
    k_on : float
        Onset threshold in σ (hysteresis high). Default 6.
    k_off : float
        Offset threshold in σ, 0 < k_off < k_on (hysteresis low). Default 3.
    threshold_floor : float
        Absolute floor [N] of the onset threshold (the offset floor is scaled by k_off/k_on); keeps a
        noise-free or quantised quiet signal (σ = 0) from triggering. Default 0.1 N.
    offset_hold : float
        [s] the signal must stay below the offset threshold to end an impact (≥ 1 sample). Default 0.5e-3.
    min_duration : float
        Shortest contact kept [s] (end − start + 1 samples, ≥ 1 sample). Default 0.5e-3.
    max_duration : float
        Longest contact [s]: longer ones are ended (``overlong``) and the baseline is re-learnt. Default 0.1.
    pre_trigger, post_trigger : float
        Margins [s] kept in the window before the onset and after the end. Default 2e-3 each.
    hum_frequency : float, "auto" or None
        Mains frequency [Hz] (50 or 60) of the hum to remove; ``"auto"``: found on the first ``warmup`` of the
        stream (50 or 60 Hz, where its amplitude is shown: ``signals.detect.find_mains_hum``), none when no lane
        shows one; None (default): no hum removal.
    hum_q : float
        Q of the hum notch (−3 dB bandwidth ≈ hum_frequency/Q; the canceller settles in ≈ Q/(π f) s).
        Default 10.
    hum_harmonics : tuple of int
        Harmonics of hum_frequency removed (ascending, at most 4), e.g. (1, 3). Default (1,).
    lowpass_cutoff : float or None
        −3 dB frequency [Hz] of the causal Butterworth low-pass; None (default): no low-pass.
    lowpass_order : int
        Order of the low-pass, 1–8. Default 4.
    clip_low, clip_high : float or None
        The acquisition's limits [N, raw sample units]: a sample at or beyond them during an impact
        flags it ``clipped``. Default None (not checked).
    discharge_time : float or None
        Discharge time constant τ [s] of a piezoelectric sensor chain (its data sheet's "time constant" or
        "discharge time constant"; the charge amplifier's "short" setting is ~0.1 s), ≥ ``MIN_DISCHARGE_TIME``:
        the detector restores the force the first-order high-pass took away (``signals.detect``, step 1b).
        None (default): measured on each lane's own contacts and restored where it shows; ``math.inf``: a
        sensor that holds a static force (a strain gauge), nothing measured or restored.
    """

    baseline_time_constant: float = 0.05
    noise_time_constant: float = 0.5
    warmup: float = 0.05
    k_on: float = 6.0
    k_off: float = 3.0
    threshold_floor: float = 0.1
    offset_hold: float = 0.5e-3
    min_duration: float = 0.5e-3
    max_duration: float = 0.1
    pre_trigger: float = 2e-3
    post_trigger: float = 2e-3
    hum_frequency: float | None = None
    hum_q: float = 10.0
    hum_harmonics: tuple = (1,)
    lowpass_cutoff: float | None = None
    lowpass_order: int = 4
    clip_low: float | None = None
    clip_high: float | None = None
    discharge_time: float | None = None

    def __post_init__(self):
        def number(name, low=None, high=None, low_open=True, high_open=True, optional=False):
            check_number(name, getattr(self, name), low=low, high=high, low_inclusive=not low_open,
                         high_inclusive=not high_open, optional=optional)

        for name in ("baseline_time_constant", "noise_time_constant", "warmup", "offset_hold", "min_duration",
                     "max_duration", "k_on"):
            number(name, 0)
        number("k_off", 0, self.k_on)
        for name in ("threshold_floor", "pre_trigger", "post_trigger"):
            number(name, 0, low_open=False)
        number("max_duration", self.min_duration, 60.0, high_open=False)
        if self.hum_frequency != HUM_AUTO:
            number("hum_frequency", 0, optional=True)
        number("hum_q", 0.5)
        number("lowpass_cutoff", 0, optional=True)
        number("clip_low", optional=True)
        number("clip_high", optional=True)
        if self.discharge_time != math.inf:  # inf: a sensor that never discharges
            number("discharge_time", MIN_DISCHARGE_TIME, low_open=False, optional=True)
        if self.clip_low is not None and self.clip_high is not None and not self.clip_low < self.clip_high:
            raise ValueError(f"clip_high must be > clip_low = {self.clip_low}; got {self.clip_high!r}")
        check_integer("lowpass_order", self.lowpass_order, 1, 8)
        harmonics = self.hum_harmonics
        if (not isinstance(harmonics, (tuple, list)) or not 1 <= len(harmonics) <= 4
                or any(isinstance(k, bool) or not isinstance(k, numbers.Integral) or not 1 <= k <= 16
                       for k in harmonics)
                or any(b <= a for a, b in itertools.pairwise(harmonics))):
            raise ValueError(f"hum_harmonics must be 1 to 4 ascending integers in [1, 16]; got {harmonics!r}")
        object.__setattr__(self, "hum_harmonics", tuple(int(k) for k in harmonics))


#: Highest sample rate accepted [Hz]: force plates on lines record at 1–100 kHz; 10 MHz leaves room for any
#: acquisition while refusing a rate whose buffers could not be held (1e12 Hz asked for terabytes).
MAX_RATE = 10e6


def check_rate(rate, argument: str = "rate") -> float | None:
    """A sample rate [Hz] (a number or a string with a unit, ``"20kHz"``) as a float in (0, ``MAX_RATE``]; None
    stays None.  ``InputError`` naming ``argument`` otherwise."""
    if rate is None:
        return None
    if isinstance(rate, str):
        try:
            rate = parse_quantity(rate, "frequency")
        except ValueError:
            raise InputError(f"{argument} must be a sample rate (a number of Hz, or with a unit: 20kHz); got "
                             f"{rate!r}", argument) from None
    if is_boolean(rate) or not isinstance(rate, numbers.Real):
        raise InputError(f"{argument} must be a number of samples per second [Hz] > 0; got {rate!r}", argument)
    rate = float(rate)
    if not math.isfinite(rate) or not 0.0 < rate <= MAX_RATE:
        raise InputError(f"{argument} must be a finite number of Hz in (0, {MAX_RATE:.0e}]; got {rate!r}", argument)
    return rate


def in_samples(name: str, seconds: float, rate: float, minimum: int) -> int:
    """``seconds`` [s] as a whole number of samples at ``rate`` [Hz], at least ``minimum``; ValueError otherwise."""
    count = round(seconds * rate)
    if count < minimum:
        raise ValueError(f"{name} must be at least {minimum} sample{'s' if minimum > 1 else ''} "
                         f"(>= {minimum / rate:g} s at {rate:g} Hz); got {seconds!r} s")
    return count


def at_rate(settings: DetectorSettings, rate: float) -> dict:
    """The detector's windows in samples at ``rate`` [Hz] (``offset_hold``, ``min_duration``, ``max_duration``,
    ``pre_trigger``, ``post_trigger``, ``warmup``) and its hum notch's gain, each checked against the rate: a
    window under its least samples, a hum harmonic at or above rate/2, a notch narrower than a quarter of the
    rate, a low-pass cutoff at or above rate/2.  ValueError (one line) otherwise.  Plain Python, so that an option
    the rate refuses is a usage error answered before the detector (numba) is loaded."""
    s = settings
    out = {"offset_hold": in_samples("offset_hold", s.offset_hold, rate, 1),
           "min_duration": in_samples("min_duration", s.min_duration, rate, 1),
           "max_duration": in_samples("max_duration", s.max_duration, rate, 1)}
    if out["max_duration"] <= out["min_duration"]:
        raise ValueError(f"max_duration must be longer than min_duration = {s.min_duration:g} s "
                         f"in samples at {rate:g} Hz; got {s.max_duration!r} s")
    out.update(pre_trigger=in_samples("pre_trigger", s.pre_trigger, rate, 0),
               post_trigger=in_samples("post_trigger", s.post_trigger, rate, 0),
               warmup=in_samples("warmup", s.warmup, rate, 16), hum_gain=0.0)
    if s.hum_frequency is not None and s.hum_frequency != HUM_AUTO:
        top = s.hum_frequency * s.hum_harmonics[-1]
        if not top < rate / 2:
            raise ValueError(f"hum_frequency × the highest harmonic must be below rate/2 = {rate / 2:g} Hz; "
                             f"got {s.hum_frequency:g} Hz × {s.hum_harmonics[-1]}")
        out["hum_gain"] = 2 * math.pi * s.hum_frequency / (s.hum_q * rate)
        if not out["hum_gain"] < 0.5:
            raise ValueError(f"hum_q must be > {4 * math.pi * s.hum_frequency / rate:g} at {rate:g} Hz "
                             f"(a notch narrower than a quarter of the sample rate); got {s.hum_q!r}")
    if s.lowpass_cutoff is not None:
        check_cutoff(s.lowpass_cutoff, rate)
    return out


def check_cutoff(cutoff: float, rate: float) -> None:
    """A low-pass cutoff [Hz] must lie in (0, rate/2): the Nyquist frequency of ``rate`` [Hz]; ValueError."""
    if not 0 < cutoff < rate / 2:
        raise ValueError(f"lowpass_cutoff must be in (0, rate/2) = (0, {rate / 2:g}) Hz; got {cutoff!r}")


#: Longest rebound flight considered when the impact speed is unknown [s] (V ≤ 1.5 m/s: drops ≤ 11 cm).
DEFAULT_MAX_FLIGHT = 0.3


@dataclass(frozen=True)
class Analysis:
    """How contacts are analysed.

    Parameters
    ----------
    rate : float
        Sample rate [Hz].
    fit : bool
        Fit the simulator's force law to every contact.
    velocity, mass : float, optional
        The fit's knowns (one of them with ``fit``): the line's impact velocity [m/s] (from the drop
        height) or the fruit mass [kg].  The velocity also predicts rebound flights.
    diameter, poisson : float, optional
        Both or neither: the modulus follows from k_c.
    classes : FirmnessClasses, optional
        Firmness classes of each new fruit.
    max_flight : float, optional
        Longest rebound flight considered [s]; 0 disables rebound detection.  Default: 1.25 × 2V/g +
        10 ms with a velocity (a fruit cannot come back faster than it came), else 0.3 s.
    pitch : float, optional
        The feed's time between fruit of a lane [s], when known: a prior for the rebound decision.
    """

    rate: float
    fit: bool = False
    velocity: float | None = None
    mass: float | None = None
    diameter: float | None = None
    poisson: float | None = None
    classes: FirmnessClasses | None = None
    max_flight: float | None = None
    pitch: float | None = None

    def __post_init__(self):
        if self.fit and (self.velocity is None) == (self.mass is None):
            raise InputError("the fit needs exactly one of the impact velocity (--velocity or --drop-height) and "
                             "the mass (--mass): one pulse determines three of k_c, c, m, V",
                             "mass" if self.mass is not None else "drop_height")  # the one to take out, or give
        if (self.diameter is None) != (self.poisson is None):
            raise ValueError("give both --diameter and --poisson (the modulus follows from k_c with both)")
        if self.classes is not None and self.classes.by in ("modulus", "stiffness") and not self.fit:
            raise ValueError(f"classes by {self.classes.by} need --fit")
        if self.classes is not None and self.classes.by == "modulus" and self.diameter is None:
            raise ValueError("classes by modulus need --diameter and --poisson")
        for name in ("max_flight", "pitch"):
            value = getattr(self, name)
            low = 0.0 if name == "max_flight" else 1e-3
            if value is not None and not (isinstance(value, (int, float)) and math.isfinite(value)
                                          and low <= value <= 60.0):
                raise ValueError(f"{name} must be a number of seconds in [{low:g}, 60]; got {value!r}")

    @property
    def flight_limit(self) -> float:
        """The longest rebound flight considered [s] (``max_flight`` or its default)."""
        if self.max_flight is not None:
            return self.max_flight
        if self.velocity is not None:
            return 1.25 * 2.0 * self.velocity / STANDARD_GRAVITY + 0.01
        return DEFAULT_MAX_FLIGHT

    def analyzer(self) -> LineAnalyzer:
        """A fresh analyser for one stream (its own lane histories)."""
        from fruitimpact.signals.analysis import LineAnalyzer  # the detector and the fits (numba) only now

        return LineAnalyzer(self)
