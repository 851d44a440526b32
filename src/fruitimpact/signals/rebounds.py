"""Is a contact a new fruit or the rebound of an earlier one?  Decided by the fruit's own physics
(issue 13, item 1), never by "smaller and soon".

A fruit that leaves the plate at V₂ flies 2 V₂/g (no drag) and lands again as the *same* fruit: the
same mass m, contact stiffness K and Hunt–Crossley damping factor c (a material constant), at the lower
speed.  For the force law F = K δ^1.5 (1 + c δ̇) of the simulator every characteristic is a Hertz scale
times a function of x = c V alone (``engine.powerlaw``; δ_H = (1.25 m V²/K)^0.4, t_H = δ_H/V):

    F_max = K δ_H^1.5 · P(x)/1.25,   t_c = t_H · τ_c(x),   T = t_H · τ_T(x),   ∫F dt = m V (1 + e(x)),

with P, τ_c, τ_T, e the dimensionless peak, time to peak, duration and restitution of the exact engine
(m = V = 1, K = 1.25).  So if a contact j is the rebound of contact p at the speed ratio r = V_j/V_p:

    x_j = r x_p,
    F_j / F_p  = r^1.2  · P(r x_p)/P(x_p),
    t_cj/t_cp  = r^-0.2 · τ_c(r x_p)/τ_c(x_p),
    I_j / I_p  = r · (1 + e(r x_p))/(1 + e(x_p)),

none of which needs m, K or V.  The impulse ratio gives r (it does not depend on where the fruit lands on
itself); the peak force, the time to peak and the shape x must then agree with it, r must be the
restitution of p (r ≈ e_p: the fruit cannot come back faster, and spin or an off-axis bounce take a
little), and, when p's impact speed is known (the line's drop height, or a fitted velocity), the
observed flight from p's separation to j's onset must be the predicted 2 r V_p/g.

Each test gives a deviation in units of its tolerance; the score S of the hypothesis is the largest.
Tolerances (``TOLERANCES``), each drawn from what the physics leaves uncertain:

* flight: ±25 % (a spinning or off-axis fruit's flight is off by ±10–20 %; the estimate of r adds its
  own error in quadrature);
* speed ratio r against e_p: −25 % / +10 % (energy lost to spin and tangential motion lowers the
  vertical rebound speed, nothing raises it: a fruit cannot come back faster than it left; e_p itself
  is uncertain: 3 × its relative standard error is added in quadrature);
* peak force and time to peak: 3 × √(σ_meas² + 4 %²), the 4 % for a rebound landing on another spot
  of the fruit (local radius and modulus ±10 % move F_max and t_c by ~4 %: both go as K^±0.4);
* shape: x_j against r x_p within 3 × √(σ_j² + (r σ_p)² + (0.1 r x_p)²).

S ≤ 1: a rebound.  S > 1: a new fruit.  Near the boundary (``AMBIGUOUS`` band) the decision is kept but
flagged ambiguous, with the evidence (predicted and observed flight and peak).  A known feed
(``pitch``) is a prior: a contact on the pitch grid of the lane's last fruit needs S ≤ 0.8 to be a
rebound, one far off the grid S ≤ 1.25; without it the rule above alone decides.

The peak, time to peak and impulse are the raw indices (``from_indices``), the same with or without
``--fit``, so the decision is too; the fit then splits the Hertz scales at the rebound's speed r V_p.
The raw shape x is read from h = ∫F dt / (F_max t_c), which for the force law is (1 + e(x))/(P(x) τ_c(x)), a
function of x alone, increasing up to x ≈ 2.6 (e ≈ 0.35) and flat near its top, so the raw x is weak
for e ≈ 0.35–0.5 (its uncertainty is propagated).  So where a shape fit of the contact converged (the
simulator's pulse fitted to its own samples, e ± 0.01 at 1 % noise; ``analysis`` fits every contact,
with or without ``--fit``) its x, e and separation time replace the raw ones (``refine``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from fruitimpact.physics.constants import STANDARD_GRAVITY

__all__ = ["AMBIGUOUS", "LaneFruit", "PulseSummary", "TOLERANCES", "Verdict", "claimed_parent", "expected_rebound",
           "from_indices", "hidden_rebound", "judge", "judge_unmeasured", "landed_with_rebound", "lane_fruit",
           "likeliest_hidden", "rebounds_due", "rebounds_landed_together", "refine", "shape_table",
           "too_light_for_fruit", "unmeasured_fruit"]

#: Tolerances of the tests (module docstring): relative flight and speed ratio, the model part of the
#: peak and time-to-peak comparison, the model part of the shape comparison, and the z multiple.
TOLERANCES = {"flight": 0.25, "speed_ratio": 0.25, "speed_ratio_up": 0.10, "spot": 0.04, "shape": 0.10, "z": 3.0}
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

    def with_velocity(self, velocity: float | None) -> PulseSummary:
        return replace(self, velocity=velocity)

    def taken(self) -> PulseSummary:
        """The same contact, marked as already having its rebound (a contact rebounds once)."""
        return replace(self, rebound_taken=True)


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


NEW_FRUIT = Verdict(False, None, False, None, None)


def _speed_ratio(candidate: PulseSummary, parent: PulseSummary) -> float:
    """r solving I_j/I_p = r (1 + e(r x_p))/(1 + e_p) (a few fixed-point steps: the e term moves slowly)."""
    ratio = candidate.impulse / parent.impulse
    r = ratio
    for _ in range(8):
        r = ratio * (1.0 + parent.restitution) / (1.0 + _at("e", r * parent.x))
    return r


def _hypothesis(candidate: PulseSummary, parent: PulseSummary) -> dict:
    """Deviations (in tolerances) of "candidate is parent's rebound", and what they compare."""
    tol = TOLERANCES
    r = _speed_ratio(candidate, parent)
    xr = r * parent.x
    peak_pred = parent.peak_force * r ** 1.2 * _at("P", xr) / _at("P", parent.x)
    tc_pred = parent.time_to_peak * r ** -0.2 * _at("tc", xr) / _at("tc", parent.x)
    r_sd = math.hypot(candidate.impulse_sd, parent.impulse_sd)
    z = tol["z"]
    excess = math.log(r / parent.restitution)
    deviations = {
        "speed_ratio": abs(excess) / math.hypot(tol["speed_ratio_up" if excess > 0 else "speed_ratio"],
                                                z * parent.restitution_sd / parent.restitution, z * r_sd),
        "peak_force": abs(math.log(candidate.peak_force / peak_pred))
        / (z * math.sqrt(candidate.peak_force_sd ** 2 + parent.peak_force_sd ** 2 + (1.2 * r_sd) ** 2
                         + tol["spot"] ** 2)),
        "time_to_peak": abs(math.log(candidate.time_to_peak / tc_pred))
        / (z * math.sqrt(candidate.time_to_peak_sd ** 2 + parent.time_to_peak_sd ** 2 + tol["spot"] ** 2)),
        "shape": abs(candidate.x - xr)
        / (z * math.sqrt(candidate.x_sd ** 2 + (r * parent.x_sd) ** 2 + (tol["shape"] * xr) ** 2) + 1e-12),
    }
    flight = candidate.onset - parent.separation
    evidence = {"parent": parent.sequence, **({"virtual_parent": True} if parent.virtual else {}),
                "flight_observed": flight, "flight_predicted": None,
                "peak_observed": candidate.peak_force, "peak_predicted": peak_pred, "speed_ratio": r,
                "restitution_parent": parent.restitution}
    if parent.velocity is not None:
        predicted = 2.0 * r * parent.velocity / STANDARD_GRAVITY
        evidence["flight_predicted"] = predicted
        deviations["flight"] = abs(math.log(flight / predicted)) / math.hypot(tol["flight"], r_sd) \
            if flight > 0 else math.inf
    elif not flight > 0:
        deviations["flight"] = math.inf
    evidence["deviations"] = {k: round(v, 3) if math.isfinite(v) else None for k, v in deviations.items()}
    evidence["score"] = max(deviations.values())
    return evidence


def _threshold(candidate: PulseSummary, last_fruit_onset: float | None, pitch: float | None) -> tuple[float, str]:
    """The score a rebound must stay under, from the feed prior (module docstring)."""
    if pitch is None or last_fruit_onset is None:
        return 1.0, "none"
    cycles = (candidate.onset - last_fruit_onset) / pitch
    phase = abs(cycles - round(cycles)) if cycles >= 0.5 else math.inf
    if phase <= 0.15:
        return 0.8, f"on the feed's pitch ({cycles:.2f} pitches after the last fruit)"
    if phase >= 0.3:
        return 1.25, f"off the feed's pitch ({cycles:.2f} pitches after the last fruit)"
    return 1.0, f"{cycles:.2f} pitches after the last fruit"


def judge(candidate: PulseSummary, earlier: list[PulseSummary], *, max_flight: float,
          last_fruit_onset: float | None = None, pitch: float | None = None) -> Verdict:
    """Decide whether ``candidate`` is the rebound of one of the ``earlier`` contacts of its lane (most
    recent last; those whose separation is more than ``max_flight`` [s] before its onset, and those that
    already have their rebound, are not considered).  The best-scoring parent wins (module docstring)."""
    threshold, prior = _threshold(candidate, last_fruit_onset, pitch)
    parents = [p for p in reversed(earlier) if not p.rebound_taken and p.onset < candidate.onset
               and candidate.onset - p.separation <= max_flight]
    best = min((_hypothesis(candidate, p) for p in parents), key=lambda ev: ev["score"], default=None)
    if best is None:
        return NEW_FRUIT
    score = best["score"]
    best["threshold"] = threshold
    best["feed_prior"] = prior
    best["score"] = round(score, 3) if math.isfinite(score) else None
    rebound = score <= threshold
    ambiguous = AMBIGUOUS[0] * threshold < score <= AMBIGUOUS[1] * threshold
    if not rebound and not ambiguous:
        return NEW_FRUIT
    return Verdict(rebound, best["parent"] if rebound else None, ambiguous,
                   best["speed_ratio"] if rebound else None, best)


def claimed_parent(candidate: PulseSummary, earlier: list[PulseSummary], sequence: int) -> int:
    """The index in ``earlier`` of the contact whose rebound ``candidate`` was judged to be (``judge`` names it by
    its ``sequence``): of the entries with that sequence not yet rebounded, the one whose hypothesis scores best.
    Two rebounds hidden in one overlap (``hidden_rebound``) share the overlap's sequence, and the one the
    candidate matched must be the one marked taken."""
    named = [i for i, p in enumerate(earlier) if p.sequence == sequence and not p.rebound_taken]
    if len(named) <= 1:
        return named[0] if named else next(i for i, p in enumerate(earlier) if p.sequence == sequence)
    return min(named, key=lambda i: _hypothesis(candidate, earlier[i])["score"])


def rebounds_due(onset: float, end: float, earlier: list[PulseSummary], *, max_flight: float) -> list[PulseSummary]:
    """The earlier contacts whose rebound, not yet seen, is due to land during [onset, end] [s], latest first.

    Due: it left the plate at its separation with its measured restitution e_p at its known impact speed
    V_p, so it lands again after 2 r V_p/g with r within the speed-ratio tolerances of e_p (spin takes up to
    25 %, nothing adds more than 10 %) and the flight within its own ±25 % (``TOLERANCES``).  A contact in
    that window may hold the rebound and a new fruit landing within a millisecond or two of each other:
    one pulse to the eye, two to a joint fit (``analysis``)."""
    tol = TOLERANCES
    due = []
    for parent in reversed(earlier):
        if parent.rebound_taken or parent.velocity is None or not parent.refined or parent.onset >= onset:
            continue
        if onset - parent.separation > max_flight:
            continue
        flight = 2.0 * parent.restitution * parent.velocity / STANDARD_GRAVITY
        lo = parent.separation + flight * (1.0 - tol["speed_ratio"]) * (1.0 - tol["flight"])
        hi = parent.separation + flight * (1.0 + tol["speed_ratio_up"]) * (1.0 + tol["flight"])
        if lo <= end and onset <= hi:
            due.append(parent)
    return due


#: The speed ratio a rebound is expected at, as a share of its parent's restitution, and its relative sd: spin
#: and an off-axis bounce take 0–25 % of the exit speed and nothing adds more than 10 % (``TOLERANCES``), so
#: r = e_p (1 − 0.08) ± 10 % covers that range within 1.7 sd.
EXPECTED_RATIO, EXPECTED_RATIO_SD = 0.92, 0.10


def expected_rebound(parent: PulseSummary) -> dict:
    """The pulse that ``parent``'s rebound should be, as priors for a joint fit (``split.split_contact``):
    the same fruit (m, K, c) at r V_p, so with x_r = r x_p

        ln F_r = ln F_p + 1.2 ln r + ln P(x_r)/P(x_p),   ln T_r = ln T_p − 0.2 ln r + ln τ_T(x_r)/τ_T(x_p),

    at r = ``EXPECTED_RATIO`` e_p; each sd combines the spread of r (propagated through its derivative), the
    spot it lands on (``TOLERANCES["spot"]``) and the parent's own measurement.  Returns the keys
    ``log_peak``, ``log_duration``, ``x`` and their ``*_sd``."""
    tol = TOLERANCES
    duration = parent.separation - parent.onset

    def scales(r):
        xr = r * parent.x
        log_peak = math.log(parent.peak_force) + 1.2 * math.log(r) + math.log(_at("P", xr) / _at("P", parent.x))
        log_duration = math.log(duration) - 0.2 * math.log(r) + math.log(_at("T", xr) / _at("T", parent.x))
        return log_peak, log_duration, xr

    r = EXPECTED_RATIO * parent.restitution
    log_peak, log_duration, xr = scales(r)
    up, down = scales(r * (1 + EXPECTED_RATIO_SD)), scales(r * (1 - EXPECTED_RATIO_SD))
    spread = [abs(a - b) / 2.0 for a, b in zip(up, down)]
    return {"log_peak": log_peak, "log_duration": log_duration, "x": xr,
            "log_peak_sd": math.sqrt(spread[0] ** 2 + tol["spot"] ** 2 + parent.peak_force_sd ** 2),
            "log_duration_sd": math.sqrt(spread[1] ** 2 + tol["spot"] ** 2 + parent.time_to_peak_sd ** 2),
            "x_sd": math.sqrt(spread[2] ** 2 + (r * parent.x_sd) ** 2 + (tol["shape"] * xr) ** 2)}


def likeliest_hidden(due: list[PulseSummary], onset: float) -> PulseSummary | None:
    """Of the contacts whose rebound was due in an overlap starting at ``onset`` [s], the one whose rebound was
    predicted to land nearest it (in units of its flight): an overlap holds at most one hidden rebound."""
    def miss(p: PulseSummary) -> float:  # how far its predicted landing lies from the onset, in flights
        flight = 2.0 * EXPECTED_RATIO * p.restitution * p.velocity / STANDARD_GRAVITY
        return abs(onset - (p.separation + flight)) / flight

    timed = [p for p in due if p.velocity is not None and p.velocity > 0 and p.restitution > 0]
    return min(timed, key=miss, default=None)


def unmeasured_fruit(fruit: list[PulseSummary], sequence: int, onset: float, velocity: float) -> PulseSummary:
    """The summary of a fruit hidden in contact ``sequence``, an overlap starting at ``onset`` [s] (it held that
    fruit and another pulse and could not be measured): one of the lane's fruit at the line's speed ``velocity``
    [m/s], so its pulse is the median of the lane's measured ``fruit`` (at least ``LANE_FRUIT_MIN``) and its
    spreads theirs, floored at a lot's (as ``judge_unmeasured`` takes it; the peak's and the time to peak's from the
    lot's spreads of mass and stiffness through the Hertz scales).  Its rebound is then due like a measured
    fruit's (``rebounds_due``) and can be found landing with the next fruit (``landed_with_rebound``)."""
    lane = lane_fruit(fruit)

    def median_and_sd(values):
        logs = np.log(values)
        return float(np.exp(np.median(logs))), _robust_sd(logs)

    peak, peak_sd = median_and_sd([f.peak_force for f in fruit])
    tc, tc_sd = median_and_sd([f.time_to_peak for f in fruit])
    x, x_sd = median_and_sd([max(f.x, 1e-6) for f in fruit])
    duration = float(np.median([f.separation - f.onset for f in fruit]))
    # a lot's own spread, which three fruit cannot measure: Hertz, F_max ∝ m^0.6 K^0.4 and t_c ∝ m^0.4 K^-0.4
    # at one speed, with the mass spread of the impulse and the stiffness spread of a lot
    peak_floor = math.hypot(0.6 * LOT_IMPULSE_SD, 0.4 * LOT_STIFFNESS_SD)
    tc_floor = math.hypot(0.4 * LOT_IMPULSE_SD, 0.4 * LOT_STIFFNESS_SD)
    return PulseSummary(sequence=sequence, onset=onset, separation=onset + duration, peak_force=peak,
                        time_to_peak=tc, impulse=lane.impulse, x=x, restitution=lane.restitution,
                        peak_force_sd=max(peak_sd, peak_floor), time_to_peak_sd=max(tc_sd, tc_floor),
                        impulse_sd=max(lane.impulse_sd, LOT_IMPULSE_SD), x_sd=max(x_sd, TOLERANCES["shape"]) * x,
                        restitution_sd=max(lane.restitution_sd, LOT_RESTITUTION_SD), velocity=velocity,
                        refined=True, virtual=True)


def hidden_rebound(parent: PulseSummary, sequence: int, onset: float) -> PulseSummary:
    """The summary of ``parent``'s rebound when it landed inside a contact that could not be measured (contact
    ``sequence``, an overlap starting at ``onset`` [s], in which that rebound was due, ``rebounds_due``): the
    same fruit at r V_p, r = ``EXPECTED_RATIO`` e_p, its pulse the one ``expected_rebound`` predicts and its
    spreads those of the prediction.  Its own rebound, the fruit's next bounce at about r² V_p, is then judged
    like any other (``judge``): without it, that bounce had no parent and was taken for a new fruit (or for the
    rebound of the fruit hidden beside it, ``judge_unmeasured``)."""
    guess = expected_rebound(parent)
    r = EXPECTED_RATIO * parent.restitution
    xr = guess["x"]
    impulse, e_r, _ = _rebound_pulse(parent)
    de_dx = (_at("e", xr * 1.05) - _at("e", xr / 1.05)) / (xr * (1.05 - 1.0 / 1.05)) if xr > 0 else 0.0
    tc = parent.time_to_peak * r ** -0.2 * _at("tc", xr) / _at("tc", parent.x)
    return PulseSummary(sequence=sequence, onset=onset, separation=onset + math.exp(guess["log_duration"]),
                        peak_force=math.exp(guess["log_peak"]), time_to_peak=tc, impulse=impulse, x=xr,
                        restitution=e_r, peak_force_sd=guess["log_peak_sd"], time_to_peak_sd=guess["log_duration_sd"],
                        impulse_sd=math.hypot(EXPECTED_RATIO_SD, parent.impulse_sd), x_sd=guess["x_sd"],
                        restitution_sd=math.hypot(abs(de_dx) * guess["x_sd"], parent.restitution_sd),
                        velocity=r * parent.velocity if parent.velocity is not None else None, refined=True,
                        virtual=True)


#: The flight tolerance of ``TOLERANCES`` as a number of sd, and the 99 % point of χ² with 4 degrees of freedom
#: (``judge_unmeasured`` adds its four tests).
FLIGHT_TOLERANCE_SD, CHI2_4_99 = 2.0, 13.277
#: The 99 % point of χ² with 3 degrees of freedom (``too_light_for_fruit``: restitution, impulse, stiffness).
CHI2_3_99 = 11.345
#: Least spread (sd of ln) of the contact stiffness of a lane's fruit (``judge_unmeasured``): a lot's impact
#: modulus varies by 10–25 % (sd) and its local radius of curvature adds a few per cent.  Each measured fruit was
#: read on one spot of its own, so the lane's spread already holds the spot-to-spot part a rebound (landing on
#: another spot of the hidden fruit) adds.
LOT_STIFFNESS_SD = 0.10


def _log_stiffness(summary: PulseSummary, velocity: float) -> tuple[float, float]:
    """ln K [N/m^1.5] of the contact if it struck at ``velocity`` [m/s], and its sd: from the Hertz scales (module
    docstring) δ_H = V t_c/τ_c(x) and K = 1.25 F_max/(P(x) δ_H^1.5).  For one pulse K ∝ V^-1.5: a fruit at V read
    as a rebound at r V looks r^-1.5 (≈ 2.4 at r = 0.55; 0.9 in ln K) stiffer than it is, and a rebound read as a
    fruit at V as much softer: several times the spread of a lot."""
    x = summary.x
    log_k = math.log(1.25 * summary.peak_force / _at("P", x)) \
        - 1.5 * math.log(velocity * summary.time_to_peak / _at("tc", x))
    dx = max(summary.x_sd, 1e-3)
    lo, hi = max(x - dx, 0.0), x + dx
    slope = (math.log(_at("P", lo) / _at("P", hi)) + 1.5 * math.log(_at("tc", hi) / _at("tc", lo))) / (hi - lo)
    return log_k, math.sqrt(summary.peak_force_sd ** 2 + (1.5 * summary.time_to_peak_sd) ** 2 + (slope * dx) ** 2)
#: Fewest measured fruit of a lane before a contact can be judged the rebound of an unmeasured one, or a fruit and
#: a rebound (or two rebounds) landing together: their medians stand for the hidden or next fruit, and every test
#: floors their spreads at a lot's (``LOT_IMPULSE_SD``, ``LOT_RESTITUTION_SD``, ``LOT_STIFFNESS_SD``), which three
#: fruit cannot measure.  Was 5: on 48 line recordings of tests/linegen.py (six scenarios, seeds 1–8), 3 took
#: rebounds taken for fruit from 31 to 26 (the first fruit of a lane, before its fifth), fruit taken for rebounds
#: staying 0; 2 gave the same.
LANE_FRUIT_MIN = 3


def _robust_sd(values) -> float:
    values = np.asarray(values, dtype=float)
    return float(1.4826 * np.median(np.abs(values - np.median(values))))


@dataclass(frozen=True)
class LaneFruit:
    """What a lane's measured new fruit say of the next one: the median ``impulse`` [N s] and the robust sd of its
    logarithm, the median ``restitution`` and its robust sd (each caller floors the spreads as its test needs)."""

    impulse: float
    impulse_sd: float
    restitution: float
    restitution_sd: float


def lane_fruit(fruit: list[PulseSummary]) -> LaneFruit:
    """The ``LaneFruit`` of the measured ``fruit`` of a lane (``analysis`` keeps the last ``LANE_FRUIT_KEPT``)."""
    log_impulse = np.log([f.impulse for f in fruit])
    restitution = [f.restitution for f in fruit]
    return LaneFruit(float(np.exp(np.median(log_impulse))), _robust_sd(log_impulse), float(np.median(restitution)),
                     _robust_sd(restitution))


#: Least spread (sd of ln) of the impulse of a lane's fruit that ``landed_with_rebound`` assumes: fruit of one
#: lot differ in mass by 10–15 % (sd) and a lane's first few measured fruit understate that (5 fruit gave 5 %,
#: and a fruit 1.3 times their median then looked like a fruit and a rebound together).
LOT_IMPULSE_SD = 0.15


def landed_with_rebound(candidate: PulseSummary, due: list[PulseSummary],
                        fruit: list[PulseSummary]) -> tuple[dict, list[PulseSummary]] | None:
    """Is ``candidate``, one pulse judged no rebound, a new fruit and a due rebound that landed together?

    Two pulses starting within a fraction of a millisecond add up to one pulse that a single force law fits to
    the noise (no joint fit can part them), and its fit is one fruit of about the sum of their masses and
    stiffnesses: a wrong grade.  What betrays them is what they carry: the impulse m (1 + e) V of a fruit of the
    lane (the median and robust spread, at least ``LOT_IMPULSE_SD``, of its measured ``fruit``, at least
    ``LANE_FRUIT_MIN``) plus that of the rebound that was ``due`` (``rebounds_due``; a fruit hidden in an earlier
    overlap is due as the lane's typical fruit, ``unmeasured_fruit``): the same fruit as its parent at r V_p,
    r = ``EXPECTED_RATIO`` e_p, so I_p r (1 + e_r)/(1 + e_p) ± ``EXPECTED_RATIO_SD``.  They landed together when
    the impulse lies more than ``TOLERANCES["z"]`` sd above the lane's fruit (a fruit that heavy is improbable)
    and nearer, in sd, to a fruit and that rebound together.  The time the rebound was predicted to land is no
    evidence here: on a chain line the feed's pitch is about a rebound's flight, so due rebounds are predicted at
    new fruit's onsets, and on a pad they never land at all.  Returns (the evidence: the parent whose rebound it
    holds, both distances; the parents) or None."""
    if len(fruit) < LANE_FRUIT_MIN or not candidate.refined or not due:
        return None
    z = TOLERANCES["z"]
    lane = lane_fruit(fruit)
    impulse_lane, impulse_sd = lane.impulse, max(lane.impulse_sd, LOT_IMPULSE_SD)
    fruit_distance = math.log(candidate.impulse / impulse_lane) / math.hypot(impulse_sd, candidate.impulse_sd)
    if not fruit_distance > z:
        return None
    best = chosen_parents = None
    impulses = [(parent, _rebound_pulse(parent)[0]) for parent in due]
    # a fruit with one due rebound, or with two (a chain line's fruit, the last one's rebound and the one before's
    # second bounce can land within a millisecond)
    groups = [[one] for one in impulses] + [[a, b] for k, a in enumerate(impulses) for b in impulses[k + 1:]]
    for group in groups:
        rebound_impulse = sum(impulse for _, impulse in group)
        both = impulse_lane + rebound_impulse
        both_sd = math.hypot(impulse_lane * impulse_sd,
                             EXPECTED_RATIO_SD * math.sqrt(sum(impulse ** 2 for _, impulse in group))) / both
        distance = abs(math.log(candidate.impulse / both)) / math.hypot(both_sd, candidate.impulse_sd)
        if best is None or distance < best["together_distance"]:
            chosen_parents = [parent for parent, _ in group]
            best = {"landed_with_rebound_of": group[0][0].sequence,
                    "parents": [parent.sequence for parent in chosen_parents],
                    "impulse": candidate.impulse, "lane_fruit_impulse": impulse_lane,
                    "rebound_impulse_predicted": rebound_impulse, "lane_fruit": len(fruit),
                    "fruit_distance": round(fruit_distance, 3), "together_distance": distance}
    if not (best["together_distance"] < fruit_distance and best["together_distance"] <= z):
        return None
    best["together_distance"] = round(best["together_distance"], 3)
    held = " and ".join(f"#{sequence}" for sequence in best["parents"])
    those = "that rebound" if len(best["parents"]) == 1 else "those rebounds"
    best["reason"] = (f"one pulse carrying {candidate.impulse / impulse_lane:.2f} times the impulse of the lane's "
                      f"{len(fruit)} measured fruit ({fruit_distance:.1f} sd above them) where the rebound of "
                      f"{held} was due; a fruit and {those} "
                      f"together carry {(impulse_lane + best['rebound_impulse_predicted']) / impulse_lane:.2f} times "
                      f"({best['together_distance']:.1f} sd)")
    return best, chosen_parents


#: How many times farther (in sd) a new fruit must lie than a rebound of the lane's fruit for ``too_light_for_fruit``
#: to take a pulse for a rebound.  Measured on line recordings of tests/linegen.py: the rebounds it found (six
#: scenarios, seeds 1–8) lay 3.6–11 times nearer a rebound than a new fruit; light fruit of a lot spread 4 : 1 in
#: mass (80–320 g, chain7, chain10 and close at seeds 1–4) only 1.28–1.32 times, since a lot that wide spreads the
#: stiffness a rebound would be read at too.
ORPHAN_MARGIN = 2.0


def too_light_for_fruit(candidate: PulseSummary, fruit: list[PulseSummary]) -> dict | None:
    """Is ``candidate``, one pulse that no earlier contact claims as its rebound, a rebound all the same?

    Every fruit of a lane lands at the line's one speed V, so it carries the impulse m (1 + e) V of the lane's
    fruit (the median and robust spread, at least ``LOT_IMPULSE_SD``, of its measured ``fruit``, at least
    ``LANE_FRUIT_MIN``).  A pulse more than ``TOLERANCES["z"]`` sd below that is no likely fruit of the lot:
    with a 15 % spread, one below 0.64 of the lane's impulse.  Light fruit exist, though, so the pulse must also
    be what a rebound of one of the lane's fruit would be, on the three tests such a rebound and a new fruit share
    (``_as_lane_rebound``): its restitution (a rebound lands slower, at r V, so e(r x) is higher), its impulse
    (I_lane r (1 + e_r)/(1 + e)) and its contact stiffness read at r V (a light lively fruit read at the
    rebound's speed needs a fruit r^-1.5 times stiffer than the lot), the rebound fitting them within the 99 %
    point of χ² with three degrees of freedom and a new fruit ``ORPHAN_MARGIN`` times farther; as a first rebound (r =
    ``EXPECTED_RATIO`` e_lane) or a second (r times the same ratio at the first rebound's e).  Its parent is then a
    contact not measured as it was: a fruit and a rebound landing within a fraction of a millisecond read as one
    heavier fruit (``landed_with_rebound`` finds it only when the lane's spread of impulse allows), and their
    rebounds match no prediction.  First rebounds that carry more than 0.64 of the lane's impulse are never caught.
    Returns the evidence or None."""
    if len(fruit) < LANE_FRUIT_MIN or not candidate.refined:
        return None
    z = TOLERANCES["z"]
    lane = lane_fruit(fruit)
    impulse_sd = math.hypot(max(lane.impulse_sd, LOT_IMPULSE_SD), candidate.impulse_sd)
    distance = math.log(candidate.impulse / lane.impulse) / impulse_sd
    if not distance < -z:
        return None
    first = EXPECTED_RATIO * lane.restitution
    x_lane = float(np.exp(np.median(np.log([max(f.x, 1e-6) for f in fruit]))))
    second = first * EXPECTED_RATIO * _at("e", first * x_lane)
    # the line's speed cancels from the tests (``_as_lane_rebound``): 1 m/s stands for it, known or not
    tests = [(bounce, _as_lane_rebound(candidate, fruit, lane, 1.0, r)) for bounce, r in ((1, first), (2, second))]
    bounce, best = min(tests, key=lambda test: test[1]["rebound2"])
    if not (best["rebound2"] <= CHI2_3_99 and best["new_fruit2"] >= (ORPHAN_MARGIN ** 2) * best["rebound2"]):
        return None
    ratio = candidate.impulse / lane.impulse
    which = "first" if bounce == 1 else "second"
    return {"kind": "parent_not_measured", "bounce": bounce, "impulse": candidate.impulse,
            "lane_fruit_impulse": lane.impulse, "lane_fruit": len(fruit), "fruit_distance": round(distance, 3),
            "restitution": candidate.restitution, "lane_fruit_restitution": lane.restitution,
            "restitution_predicted": best["restitution_predicted"],
            "impulse_predicted": best["impulse_predicted"],
            "stiffness_at_rebound_speed_over_lane": best["stiffness_at_rebound_speed"] / best["lane_stiffness"],
            "rebound_distance": round(math.sqrt(best["rebound2"]), 3),
            "new_fruit_distance": round(math.sqrt(best["new_fruit2"]), 3), "score": None,
            "reason": (f"one pulse carrying {ratio:.2f} times the impulse of the lane's {len(fruit)} measured fruit "
                       f"({-distance:.1f} sd below them, at most {z:g}), nearer a {which} rebound of one of them "
                       f"than a new fruit in restitution ({candidate.restitution:.2f}; the lane's fruit "
                       f"{lane.restitution:.2f}, such a rebound {best['restitution_predicted']:.2f}), impulse and "
                       f"stiffness ({math.sqrt(best['rebound2']):.1f} against {math.sqrt(best['new_fruit2']):.1f} "
                       f"sd), and no earlier contact's predicted rebound")}


#: Least spread of the restitution of a lane's fruit and of a predicted rebound's (``rebounds_landed_together``).
LOT_RESTITUTION_SD = 0.02
#: Two due rebounds are taken to have landed together when the pulse lies within this distance (in sd, impulse and
#: restitution together) of what the two carry, and a new fruit of the lane lies ``PAIR_MARGIN`` times farther.
#: Chosen on 36 line recordings of tests/linegen.py (chain10, grades, close, lanes4, chain7, noisy at seeds 1–6):
#: the 4 contacts that were two rebounds lay at 0.93–1.17 sd from the pair and 1.9–3.1 times farther from a new
#: fruit; the nearest new fruit lay at 1.97 sd, two lone rebounds at 1.28 and 1.48.  Few cases: the margin is thin,
#: and a lively new fruit taken for two rebounds loses its grade (an overlap), where two rebounds taken for a
#: fruit are a fruit that never was, graded.
PAIR_DISTANCE_MAX, PAIR_MARGIN = 1.25, 1.5


def _rebound_pulse(parent: PulseSummary) -> tuple[float, float, float]:
    """(impulse [N s], restitution, its sd) of ``parent``'s rebound: the same fruit at r V_p, r =
    ``EXPECTED_RATIO`` e_p ± ``EXPECTED_RATIO_SD`` (as ``hidden_rebound``)."""
    r = EXPECTED_RATIO * parent.restitution
    xr = r * parent.x
    e_r = _at("e", xr)
    de_dlnx = (_at("e", xr * 1.05) - _at("e", xr / 1.05)) / (2.0 * math.log(1.05))
    e_sd = math.hypot(abs(de_dlnx) * EXPECTED_RATIO_SD, parent.restitution_sd, LOT_RESTITUTION_SD)
    return parent.impulse * r * (1.0 + e_r) / (1.0 + parent.restitution), e_r, e_sd


def rebounds_landed_together(candidate: PulseSummary, due: list[PulseSummary],
                             fruit: list[PulseSummary]) -> tuple[dict, list[PulseSummary]] | None:
    """Is ``candidate``, one pulse judged no rebound, the rebounds of two earlier contacts that landed together?

    On a chain-fed line one fruit's second bounce and the next fruit's first often land within a fraction of a
    millisecond: one pulse that a single force law fits, taken for a new fruit that never was, graded.  What it
    carries is the two rebounds': the impulse I_p r (1 + e_r)/(1 + e_p) of each (the same fruit at r V_p, r =
    ``EXPECTED_RATIO`` e_p ± ``EXPECTED_RATIO_SD``) added, and a rebound's restitution (a slower impact: livelier
    than the lane's fruit).  Of the pairs of ``due`` contacts (``rebounds_due``), the nearest in impulse and
    restitution (in sd) is taken when it lies within ``PAIR_DISTANCE_MAX`` and a new fruit of the lane (the
    medians and robust spreads of its measured ``fruit``, at least ``LANE_FRUIT_MIN``; spreads at least
    ``LOT_IMPULSE_SD`` and ``LOT_RESTITUTION_SD``) lies ``PAIR_MARGIN`` times farther.  Returns (the evidence:
    ``kind`` "two rebounds", ``parents`` (their sequences), both distances; the two parents themselves) or None."""
    if len(fruit) < LANE_FRUIT_MIN or not candidate.refined or len(due) < 2:
        return None
    lane = lane_fruit(fruit)
    impulse_lane, e_lane = lane.impulse, lane.restitution
    impulse_sd = math.hypot(max(lane.impulse_sd, LOT_IMPULSE_SD), candidate.impulse_sd)
    e_lane_sd = math.hypot(max(lane.restitution_sd, LOT_RESTITUTION_SD), candidate.restitution_sd)
    new_fruit = math.hypot(math.log(candidate.impulse / impulse_lane) / impulse_sd,
                           (candidate.restitution - e_lane) / e_lane_sd)
    pulses = [(parent, _rebound_pulse(parent)) for parent in due]
    best = None
    for i, (first, (i1, e1, s1)) in enumerate(pulses):
        for second, (i2, e2, s2) in pulses[i + 1:]:
            both = i1 + i2
            both_sd = math.hypot(EXPECTED_RATIO_SD * math.hypot(i1, i2) / both, candidate.impulse_sd)
            # the summed pulse's restitution leans to the larger pulse's: weighted by impulse (the weighting itself
            # uncertain by a quarter of their difference)
            e_pair = (i1 * e1 + i2 * e2) / both
            e_sd = math.hypot((i1 * s1 + i2 * s2) / both, abs(e1 - e2) / 4.0, candidate.restitution_sd)
            distance = math.hypot(math.log(candidate.impulse / both) / both_sd, (candidate.restitution - e_pair) / e_sd)
            if best is None or distance < best[0]:
                best = (distance, [first, second], both, e_pair)
    distance, pair, both, e_pair = best
    if not (distance <= PAIR_DISTANCE_MAX and new_fruit >= PAIR_MARGIN * distance):
        return None
    parents = [parent.sequence for parent in pair]
    return {"kind": "two rebounds", "parents": parents, "impulse": candidate.impulse, "impulse_predicted": both,
            "restitution": candidate.restitution, "restitution_predicted": e_pair, "pair_distance": round(distance, 3),
            "lane_fruit_impulse": impulse_lane, "lane_fruit_restitution": e_lane, "lane_fruit": len(fruit),
            "new_fruit_distance": round(new_fruit, 3),
            "reason": f"one pulse carrying the impulse and restitution of the rebounds of #{parents[0]} and "
                      f"#{parents[1]} together ({candidate.impulse / both:.2f} of their impulse, e "
                      f"{candidate.restitution:.2f} against {e_pair:.2f}: {distance:.1f} sd), where a new fruit of "
                      f"the lane lies {new_fruit:.1f} sd away (e {e_lane:.2f})"}, pair


def _as_lane_rebound(candidate: PulseSummary, fruit: list[PulseSummary], lane: LaneFruit, velocity: float,
                     r: float) -> dict:
    """The three tests a rebound of one of the lane's fruit and a new fruit of the lane share, for ``candidate``
    taken as that rebound at r V (r of the line's speed ``velocity`` [m/s]) or as a new fruit at V:

    * its restitution: e(r x_lane) for the rebound (a slower impact, so higher), the lane's e for a new fruit;
    * its impulse: I_lane r (1 + e_r)/(1 + e_lane) for the rebound, the lane's I for a new fruit;
    * its contact stiffness read from its pulse at the speed it struck (``_log_stiffness``: K ∝ V^-1.5 for one
      pulse): at r V the lane's K for a rebound, at V for a new fruit.  The line's speed cancels from both
      comparisons, so any ``velocity`` gives the same distances.

    Each within the lane's spreads (floored at a lot's: ``LOT_IMPULSE_SD``, ``LOT_RESTITUTION_SD``,
    ``LOT_STIFFNESS_SD``), r's (``EXPECTED_RATIO_SD`` and the lane's spread of e) and the candidate's own.
    Returns the deviations of the rebound (in tolerances, ``TOLERANCES["z"]`` sd), the squared distances in sd of
    both hypotheses (``rebound2``, ``new_fruit2``) and what they compare."""
    tol = TOLERANCES
    z = tol["z"]
    e_lane = lane.restitution
    log_x = np.log([max(f.x, 1e-6) for f in fruit])
    x_lane, x_sd = float(np.exp(np.median(log_x))), max(_robust_sd(log_x), tol["shape"])
    impulse_lane, impulse_sd = lane.impulse, max(lane.impulse_sd, LOT_IMPULSE_SD)
    r_sd = math.hypot(EXPECTED_RATIO_SD, lane.restitution_sd / e_lane)
    xr = r * x_lane
    e_pred = _at("e", xr)
    de_dlnx = (_at("e", xr * 1.05) - _at("e", xr / 1.05)) / (2.0 * math.log(1.05))
    e_sd = math.hypot(abs(de_dlnx) * math.hypot(x_sd, r_sd), candidate.restitution_sd)
    impulse_pred = impulse_lane * r * (1.0 + e_pred) / (1.0 + e_lane)
    log_k = [_log_stiffness(f, velocity)[0] for f in fruit]
    k_lane, k_sd = float(np.median(log_k)), max(_robust_sd(log_k), LOT_STIFFNESS_SD)
    k_rebound, k_meas = _log_stiffness(candidate, r * velocity)
    k_fruit = _log_stiffness(candidate, velocity)[0]  # the same pulse read as a fruit at the line's speed
    deviations = {
        "restitution": abs(candidate.restitution - e_pred) / (z * e_sd),
        "impulse": abs(math.log(candidate.impulse / impulse_pred))
        / (z * math.sqrt(impulse_sd ** 2 + r_sd ** 2 + candidate.impulse_sd ** 2)),
        "stiffness": abs(k_rebound - k_lane) / (z * math.sqrt(k_sd ** 2 + (1.5 * r_sd) ** 2 + k_meas ** 2)),
    }
    e_lane_sd = math.hypot(max(lane.restitution_sd, LOT_RESTITUTION_SD), candidate.restitution_sd)
    new_fruit2 = ((candidate.restitution - e_lane) / e_lane_sd) ** 2 + \
        (math.log(candidate.impulse / impulse_lane) / math.hypot(impulse_sd, candidate.impulse_sd)) ** 2 + \
        ((k_fruit - k_lane) / math.hypot(k_sd, k_meas)) ** 2
    rebound2 = sum((deviations[k] * z) ** 2 for k in ("restitution", "impulse", "stiffness"))
    return {"r": r, "r_sd": r_sd, "deviations": deviations, "rebound2": rebound2, "new_fruit2": new_fruit2,
            "restitution_predicted": e_pred, "impulse_predicted": impulse_pred,
            "stiffness_at_rebound_speed": math.exp(k_rebound), "lane_stiffness": math.exp(k_lane)}


def judge_unmeasured(candidate: PulseSummary, hidden: int, hidden_onset: float, fruit: list[PulseSummary],
                     velocity: float | None) -> Verdict:
    """Is ``candidate`` the rebound of a fruit hidden in an earlier contact that could not be measured (contact
    ``hidden``, landing at ``hidden_onset`` [s]: it held that fruit and another pulse landing together)?

    The hidden fruit has no pulse of its own, but it is one of the lane's fruit, landing at the line's speed
    V: its x, e, impulse and duration are those of the lane's measured fruit (``fruit``, at least
    ``LANE_FRUIT_MIN``), each within the lane's own spread (robust sd).  Its rebound is then the same fruit at
    r V, r = ``EXPECTED_RATIO`` e_lane, so (as for a measured parent, ``_hypothesis``)

    * it lands 2 r V/g after the hidden fruit left (its onset + the lane's duration), within the flight
      tolerance and the spread of r;
    * its restitution is e(r x_lane) (a rebound is slower, so higher), within the lane's spread of x and of r
      and the candidate's own sd;
    * its impulse is I_lane r (1 + e_r)/(1 + e_lane), within the lane's spread of impulse (the fruit's mass)
      and of r;
    * its contact stiffness, read from its pulse at the speed r V (``_log_stiffness``: K ∝ V^-1.5 for one
      pulse), is the lane's, within the lane's spread (at least ``LOT_STIFFNESS_SD``; it holds the spot-to-spot
      part) and 1.5 × that of r.  The impulse weighs the speed through the mass, this test
      through the modulus, which a lot spreads independently: a lively light fruit has a rebound's
      restitution and impulse, but at the rebound's speed its pulse would need a fruit far stiffer than the lot.

    Each deviation is reported in units of its tolerance (``TOLERANCES["z"]`` sd for the spreads, the flight's
    taken as ``FLIGHT_TOLERANCE_SD`` sd).  Each test alone is loose (the lot's spreads), so the evidence is
    added: the score is the distance in sd, √(Σ d²), over the 99 % point of χ² with four degrees of freedom
    (score ≤ 1: a rebound), with the ambiguous band of ``judge``.  The tests share r (a wrong r moves the flight,
    the impulse and the stiffness together), so that point is a scale chosen on the line recordings of
    tests/linegen.py, not a calibrated probability.  Without the line's speed or enough
    measured fruit: a new fruit, undecided (``NEW_FRUIT``)."""
    if velocity is None or len(fruit) < LANE_FRUIT_MIN or not candidate.refined:
        return NEW_FRUIT
    tol = TOLERANCES
    z = tol["z"]
    lane = lane_fruit(fruit)
    duration = float(np.median([f.separation - f.onset for f in fruit]))
    shared = _as_lane_rebound(candidate, fruit, lane, velocity, EXPECTED_RATIO * lane.restitution)
    r, r_sd = shared["r"], shared["r_sd"]
    flight_pred = 2.0 * r * velocity / STANDARD_GRAVITY
    flight = candidate.onset - (hidden_onset + duration)
    deviations = dict(shared["deviations"])
    deviations["flight"] = abs(math.log(flight / flight_pred)) / math.hypot(tol["flight"], r_sd) \
        if flight > 0 else math.inf
    # each test is loose (the lot's spreads), so their evidence is added: the distance in sd (the flight tolerance
    # taken as 2 sd) against the 99 % point of χ² with 4 degrees of freedom (a scale: the tests share r)
    sds = {"restitution": z, "impulse": z, "flight": FLIGHT_TOLERANCE_SD, "stiffness": z}
    distance2 = sum((deviations[k] * sds[k]) ** 2 for k in ("restitution", "impulse", "flight", "stiffness"))
    score = math.sqrt(distance2 / CHI2_4_99) if math.isfinite(distance2) else math.inf
    evidence = {"unmeasured_parent": hidden, "flight_observed": flight, "flight_predicted": flight_pred,
                "restitution": candidate.restitution, "restitution_predicted": shared["restitution_predicted"],
                "lane_restitution": lane.restitution, "impulse": candidate.impulse,
                "impulse_predicted": shared["impulse_predicted"], "lane_fruit": len(fruit),
                "stiffness_at_rebound_speed": shared["stiffness_at_rebound_speed"],
                "lane_stiffness": shared["lane_stiffness"],
                "deviations": {k: round(deviations[k], 3) if math.isfinite(deviations[k]) else None
                               for k in ("restitution", "impulse", "flight", "stiffness")},
                "score": round(score, 3) if math.isfinite(score) else None, "threshold": 1.0,
                "reason": f"contact #{hidden} held a fruit and another pulse landing together and could not be "
                          f"measured; its fruit's rebound, judged from the lane's {len(fruit)} measured fruit"}
    rebound = score <= 1.0
    ambiguous = AMBIGUOUS[0] < score <= AMBIGUOUS[1]
    # the other explanation: a new fruit of the lane at the line's speed (``_as_lane_rebound``): on the three tests
    # both hypotheses share the rebound must fit better than a new fruit does; otherwise the contact is a new
    # fruit, said to be ambiguous
    new_fruit2, rebound2 = shared["new_fruit2"], shared["rebound2"]
    evidence["new_fruit_distance"] = round(math.sqrt(new_fruit2), 3)
    evidence["rebound_distance"] = round(math.sqrt(rebound2), 3) if math.isfinite(rebound2) else None
    if rebound and not rebound2 < new_fruit2:
        rebound, ambiguous = False, True
        evidence["reason"] += "; but a new fruit of the lane fits its restitution, impulse and stiffness as well or better"
    if not rebound and not ambiguous:
        return NEW_FRUIT
    return Verdict(rebound, hidden if rebound else None, ambiguous, r if rebound else None, evidence)
