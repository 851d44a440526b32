"""What the rebound tests know of a contact (``PulseSummary``: its raw indices, refined by a shape fit) and of the
force law (the exact engine's dimensionless characteristics as functions of x = c V), and the ``Verdict``
they give (the package docstring states the tests)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from fruitimpact.physics.constants import STANDARD_GRAVITY


def flight_time(speed: float) -> float:
    """The time [s] a fruit leaving the plate at ``speed`` [m/s] spends in the air before it lands on it again:
    2 V/g (a ballistic flight between two points at one height, drag neglected; spin and an off-axis bounce change
    the path, not the vertical motion)."""
    return 2.0 * speed / STANDARD_GRAVITY


def landing_speed(flight: float) -> float:
    """The speed [m/s] at which a fruit lands again after ``flight`` [s] in the air, g · flight/2 (the inverse of
    ``flight_time``); NaN for a flight that is not > 0."""
    return STANDARD_GRAVITY * flight / 2.0 if math.isfinite(flight) and flight > 0 else math.nan


#: Tolerances of the tests (the package docstring): relative flight and speed ratio, the model part of the
#: peak and time-to-peak comparison, the model part of the shape comparison, and the z multiple.
TOLERANCES = {"flight": 0.25, "speed_ratio": 0.25, "speed_ratio_up": 0.10, "spot": 0.04, "shape": 0.10, "z": 3.0}
#: How a rebound's x = c V follows from its parent's: x_r = r^β x_p, β in this range.  β = 1 when the damping c is
#: a constant of the fruit (Hunt–Crossley: a slower impact is livelier); β = 0 when the restitution is
#: (Lankarani–Nikravesh, Flores: c ∝ 1/V).  Fruit lie between (an apple's e falls with the drop height, by
#: an amount that differs between studies), so a rebound is tested against the whole range.
DAMPING_EXPONENT = (0.0, 1.0)


def rebound_x(x: float, parent_x: float, ratio: float, exponent: tuple[float, float] = DAMPING_EXPONENT) -> float:
    """The x = c V of a rebound at speed ratio ``ratio`` of a parent of x ``parent_x``, nearest ``x`` (the rebound's
    own, measured) among those the damping laws allow: x_r = r^β x_p, β in ``exponent`` (``DAMPING_EXPONENT``, or
    the line's own range once its rebounds have shown it: ``PulseSummary.damping_exponent``)."""
    # within the laws' range whatever the line's range reaches (it is centred on the line's β)
    first, last = max(exponent[0], DAMPING_EXPONENT[0]), min(exponent[1], DAMPING_EXPONENT[1])
    low, high = sorted((ratio ** last * parent_x, ratio ** first * parent_x))
    return min(max(x, low), high)


#: Scores in this band around 1 mark the decision ambiguous (kept, with the evidence).
AMBIGUOUS = (0.8, 1.25)
#: Relative measurement uncertainties of the raw indices (indices.py: F_max sd ≈ 0.3 %, t_c ≈ 0.7 %,
#: impulse ≈ 0.25 % at 1 % noise; doubled for margin) used when the noise is not worse.
RAW_SD = {"peak_force": 0.006, "time_to_peak": 0.014, "impulse": 0.005}
_X_MAX = 10.0
_TABLE: list = []


def shape_table() -> dict:
    """The dimensionless characteristics of the force law against x = c V (built once, from the exact
    engine's batch path): ``x``, ``e``, ``P`` (peak), ``tc``, ``T`` and ``h`` = (1 + e)/(P τ_c)."""
    if not _TABLE:
        from fruitimpact.engine.codes import CONTACT_DURATION, PEAK_FORCE, RESTITUTION, TIME_TO_PEAK
        from fruitimpact.engine.powerlaw import powerlaw_characteristics

        x = np.expm1(np.linspace(0.0, math.log1p(_X_MAX), 801))
        one = np.ones_like(x)
        values = powerlaw_characteristics(one, 1.25 * one, x, one, one)
        e = values[:, RESTITUTION]
        peak, tc, duration = values[:, PEAK_FORCE], values[:, TIME_TO_PEAK], values[:, CONTACT_DURATION]
        _TABLE.append({"x": x, "e": e, "P": peak, "tc": tc, "T": duration, "h": (1.0 + e) / (peak * tc)})
    return _TABLE[0]


_LISTS: dict = {}


def _at(name: str, x: float) -> float:
    """``np.interp(x, table["x"], table[name])`` to the last bit, for one x: the rebound tests call it a few
    hundred times per contact, where NumPy's per-call overhead was ~12 % of a busy line's analysis.  The nodes
    are uniform in ln(1 + x), so the interval is found by arithmetic (then checked), and the value is NumPy's
    own formula slope × (x − x_j) + f_j."""
    if not _LISTS:
        table = shape_table()
        _LISTS.update({key: [float(v) for v in values] for key, values in table.items()})
        _LISTS["_scale"] = (len(_LISTS["x"]) - 1) / math.log1p(_X_MAX)
    xs, fs = _LISTS["x"], _LISTS[name]
    last = len(xs) - 1
    if not x >= xs[0]:  # below the table (and NaN: NumPy gives NaN for NaN, as the arithmetic below does)
        return fs[0] if x < xs[0] else x
    if x >= xs[last]:
        return fs[last]
    j = min(int(math.log1p(x) * _LISTS["_scale"]), last - 1)
    while j > 0 and xs[j] > x:
        j -= 1
    while xs[j + 1] <= x:
        j += 1
    slope = (fs[j + 1] - fs[j]) / (xs[j + 1] - xs[j])
    return slope * (x - xs[j]) + fs[j]


def _x_of_h(h: float) -> tuple[float, float]:
    """x from h on its increasing branch, and dx/dh there (inf on the flat top)."""
    table = shape_table()
    top = int(np.argmax(table["h"]))
    hs, xs = table["h"][:top + 1], table["x"][:top + 1]
    if h <= hs[0]:
        return 0.0, float((xs[1] - xs[0]) / (hs[1] - hs[0]))
    if h >= hs[-1]:
        return float(xs[-1]), math.inf
    k = int(np.searchsorted(hs, h))
    slope = (xs[k] - xs[k - 1]) / (hs[k] - hs[k - 1])
    return float(xs[k - 1] + (h - hs[k - 1]) * slope), float(slope)


@dataclass(frozen=True)
class PulseSummary:
    """What the rebound test knows of one contact (SI units; ``*_sd`` relative except ``x_sd``).

    onset [s] and separation [s] (onset + T) on the stream's clock; peak_force [N]; time_to_peak [s];
    impulse [N s]; x = c V and its absolute sd; restitution e and its sd; velocity [m/s] of the impact
    when known (the line's, a fitted one, or r V of the contact it rebounds from), else None."""

    sequence: int
    onset: float
    separation: float
    peak_force: float
    time_to_peak: float
    impulse: float
    x: float
    restitution: float
    peak_force_sd: float
    time_to_peak_sd: float
    impulse_sd: float
    x_sd: float
    restitution_sd: float
    velocity: float | None = None
    rebound_taken: bool = False
    refined: bool = False
    #: a rebound that landed inside an overlap, as predicted (``hidden_rebound``), not measured
    virtual: bool = False
    #: its velocity was read from the lane's own rebounds (``LineAnalyzer.line_speed``), not given or fitted: it
    #: predicts when a rebound is due, but a rebound's flight is not tested against it (a wrong reading would
    #: reject the very rebounds whose flights correct it)
    speed_read: bool = False
    #: the sequence of the contact judged its rebound (``judge``), which a later contact may show to have been the
    #: rebound of another (``measured.reassigned``)
    taken_by: int | None = None
    #: (impulse [N s], peak force [N], sequence of its parent) of a rebound that was due while this contact, judged
    #: a new fruit, lasted, and was not seen: it may have landed with it, too close for a joint fit to tell apart
    #: (``measured.held_alternative``)
    held: tuple[float, float, int] | None = None
    #: the range of β (x_r = r^β x_p, ``rebound_x``) this contact is judged with as a rebound: ``DAMPING_EXPONENT``
    #: until the line's own rebounds have shown where its fruit lie (``LineAnalyzer.damping_exponent``)
    damping_exponent: tuple[float, float] = DAMPING_EXPONENT

    def with_velocity(self, velocity: float | None, read: bool = False) -> PulseSummary:
        return replace(self, velocity=velocity, speed_read=bool(read and velocity is not None))

    def taken(self, by: int | None = None) -> PulseSummary:
        """The same contact, marked as already having its rebound (a contact rebounds once), by contact ``by``
        (its sequence) when that was judged against this one's pulse."""
        return replace(self, rebound_taken=True, taken_by=by)


def _finite(*values) -> bool:
    return all(isinstance(v, (int, float, np.floating)) and math.isfinite(float(v)) for v in values)


def from_indices(report: dict, sequence: int, noise: float, velocity: float | None) -> PulseSummary | None:
    """The summary of a contact from its raw indices (``indices.impact_indices``) and the noise sd [N];
    None when an index needed is missing (a truncated or too weak pulse)."""
    onset, peak, tc, impulse = (report.get(k) for k in ("start_time", "peak_force", "time_to_peak", "impulse"))
    if not _finite(onset, peak, tc, impulse) or not (peak > 0 and tc > 0 and impulse > 0):
        return None
    snr = noise / peak if noise > 0 else 0.0
    peak_sd = math.hypot(RAW_SD["peak_force"], 0.5 * snr)
    tc_sd = math.hypot(RAW_SD["time_to_peak"], 1.5 * snr)
    impulse_sd = math.hypot(RAW_SD["impulse"], 0.4 * snr)
    h = impulse / (peak * tc)
    x, slope = _x_of_h(h)
    h_sd = h * math.sqrt(peak_sd ** 2 + tc_sd ** 2 + impulse_sd ** 2)
    x_sd = min(abs(slope) * h_sd, _X_MAX)
    e = _at("e", x)
    e_sd = min(abs(_at("e", x + x_sd) - _at("e", max(x - x_sd, 0.0))) / 2.0, 1.0)
    duration = tc * _at("T", x) / _at("tc", x)
    return PulseSummary(sequence=sequence, onset=onset, separation=onset + duration, peak_force=peak,
                        time_to_peak=tc, impulse=impulse, x=x, restitution=e, peak_force_sd=peak_sd,
                        time_to_peak_sd=tc_sd, impulse_sd=impulse_sd, x_sd=x_sd, restitution_sd=e_sd,
                        velocity=velocity)


def refine(summary: PulseSummary, fit: dict) -> PulseSummary:
    """The summary with x, e and the separation time of a converged shape fit of the same contact (a
    ``fit.fit_impact`` result: its x = c V, restitution and contact times do not depend on the velocity
    or mass it was given); unchanged when the fit did not converge."""
    if not fit.get("converged") or not _finite(fit.get("restitution_stderr"), fit.get("damping_factor"),
                                               fit.get("velocity")):
        return summary
    x = float(fit["damping_factor"] * fit["velocity"])
    e, e_sd = float(fit["restitution"]), max(float(fit["restitution_stderr"]), 0.003)
    slope = abs(_at("e", x + 1e-3) - _at("e", max(x - 1e-3, 0.0))) / (x + 1e-3 - max(x - 1e-3, 0.0))
    x_sd = max(e_sd / slope if slope > 0 else 0.1 * x, 1e-3)
    return replace(summary, x=x, x_sd=x_sd, restitution=e, restitution_sd=e_sd,
                   separation=float(fit["start_time"] + fit["contact_duration"]), refined=True)


@dataclass(frozen=True)
class Verdict:
    """The decision on one contact: ``rebound`` of ``parent`` (its sequence) or a new fruit,
    ``ambiguous`` near the boundary, ``speed_ratio`` r = V_j/V_p when a rebound, and the ``evidence``
    (a JSON-able dict: parent, observed and predicted flight [s] and peak [N], r, e_p, each test's
    deviation in units of its tolerance, the score, the threshold used)."""

    rebound: bool
    parent: int | None
    ambiguous: bool
    speed_ratio: float | None
    evidence: dict | None
    #: (contact, its parent now) when this rebound's parent had been claimed by ``contact``, which is re-read as
    #: the rebound of another (``measured.reassigned``)
    reassigned: tuple[int, int] | None = None


NEW_FRUIT = Verdict(False, None, False, None, None)
