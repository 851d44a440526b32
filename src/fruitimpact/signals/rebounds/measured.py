"""A contact judged against earlier contacts whose pulse was measured (or predicted): is it the rebound of one
of them (``judge``), whose rebound is due when (``rebounds_due``), and what pulse that rebound should be
(``expected_rebound``, ``hidden_rebound``)."""

from __future__ import annotations

import math
from dataclasses import replace

from fruitimpact.signals.rebounds.pulses import (AMBIGUOUS, NEW_FRUIT, TOLERANCES, PulseSummary, Verdict, _at,
                                                 flight_time, rebound_x)


def _speed_ratio(candidate: PulseSummary, parent: PulseSummary) -> float:
    """r solving I_j/I_p = r (1 + e(x_r))/(1 + e_p), x_r = ``rebound_x`` (a few fixed-point steps: the e term moves
    slowly)."""
    ratio = candidate.impulse / parent.impulse
    r = ratio
    for _ in range(8):
        previous = r
        r = ratio * (1.0 + parent.restitution) / (1.0 + _at("e", rebound_x(candidate.x, parent.x, r,
                                                                          candidate.damping_exponent)))
        if abs(r - previous) <= 1e-12 * r:  # e(x) moves slowly: each step gains ~2.5 digits, and the tests
            break  # compare r within a few per cent
    return r


def _hypothesis(candidate: PulseSummary, parent: PulseSummary) -> dict:
    """Deviations (in tolerances) of "candidate is parent's rebound", and what they compare."""
    tol = TOLERANCES
    r = _speed_ratio(candidate, parent)
    xr = rebound_x(candidate.x, parent.x, r, candidate.damping_exponent)
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
        / (z * math.sqrt(candidate.x_sd ** 2 + (xr / parent.x * parent.x_sd if parent.x > 0 else parent.x_sd) ** 2
                         + (tol["shape"] * xr) ** 2) + 1e-12),
    }
    if candidate.impulse / parent.impulse > 1.0 + z * r_sd:  # energy: a rebound carries I_p r (1 + e_j)/(1 + e_p)
        deviations["speed_ratio"] = math.inf  # ≤ I_p 2 e_p/(1 + e_p) < I_p, whatever e_p (no estimate of e needed)
    flight = candidate.onset - parent.separation
    evidence = {"parent": parent.sequence, **({"virtual_parent": True} if parent.virtual else {}),
                "flight_observed": flight, "flight_predicted": None,
                "peak_observed": candidate.peak_force, "peak_predicted": peak_pred, "speed_ratio": r,
                "restitution_parent": parent.restitution}
    if parent.velocity is not None and not parent.speed_read:
        predicted = flight_time(r * parent.velocity)
        evidence["flight_predicted"] = predicted
        deviations["flight"] = abs(math.log(flight / predicted)) / math.hypot(tol["flight"], r_sd) \
            if flight > 0 else math.inf
    elif not flight > 0:
        deviations["flight"] = math.inf
    evidence["deviations"] = {k: round(v, 3) if math.isfinite(v) else None for k, v in deviations.items()}
    evidence["score"] = max(deviations.values())
    return evidence


#: A lane whose first this many fruit have shown no rebound at all lands its fruit on something that stops them (a
#: pad, a brush, a cup): a rebound must then be clear, score ≤ 0.8 as on the feed's pitch (``judge``).  On a plate
#: every fruit rebounds (e ≈ 0.4–0.8), so a plate lane shows its first rebound within a fruit or two.
QUIET_LANE_FRUIT = 10


def _threshold(candidate: PulseSummary, last_fruit_onset: float | None, pitch: float | None,
               quiet_fruit: int = 0) -> tuple[float, str]:
    """The score a rebound must stay under, from the feed prior and the lane's own history (the package
    docstring; ``QUIET_LANE_FRUIT``)."""
    threshold, prior = 1.0, "none"
    if pitch is not None and last_fruit_onset is not None:
        cycles = (candidate.onset - last_fruit_onset) / pitch
        phase = abs(cycles - round(cycles)) if cycles >= 0.5 else math.inf
        if phase <= 0.15:
            threshold, prior = 0.8, f"on the feed's pitch ({cycles:.2f} pitches after the last fruit)"
        elif phase >= 0.3:
            threshold, prior = 1.25, f"off the feed's pitch ({cycles:.2f} pitches after the last fruit)"
        else:
            prior = f"{cycles:.2f} pitches after the last fruit"
    if quiet_fruit >= QUIET_LANE_FRUIT:
        quiet = f"the lane's {quiet_fruit} fruit have shown no rebound"
        threshold, prior = 0.8 * threshold, quiet if prior == "none" else f"{prior}; {quiet}"
    return threshold, prior


def judge(candidate: PulseSummary, earlier: list[PulseSummary], *, max_flight: float,
          last_fruit_onset: float | None = None, pitch: float | None = None, quiet_fruit: int = 0) -> Verdict:
    """Decide whether ``candidate`` is the rebound of one of the ``earlier`` contacts of its lane (most
    recent last; those whose separation is more than ``max_flight`` [s] before its onset, and those that
    already have their rebound, are not considered).  The best-scoring parent wins (the package docstring).
    ``quiet_fruit``: how many fruit the lane has shown without any rebound (``QUIET_LANE_FRUIT``)."""
    threshold, prior = _threshold(candidate, last_fruit_onset, pitch, quiet_fruit)
    parents = [p for p in reversed(earlier) if not p.rebound_taken and p.onset < candidate.onset
               and candidate.onset - p.separation <= max_flight]
    best = min((_hypothesis(candidate, p) for p in parents), key=lambda ev: ev["score"], default=None)
    if best is None or not best["score"] <= threshold:
        other = reassigned(candidate, earlier, threshold, max_flight) \
            or held_alternative(candidate, parents, earlier, threshold)
        if other is not None:
            other.evidence["feed_prior"] = prior
            return other
    if best is None:
        return NEW_FRUIT
    score = best["score"]
    _finish(best, threshold)
    best["feed_prior"] = prior
    rebound = score <= threshold
    ambiguous = AMBIGUOUS[0] * threshold < score <= AMBIGUOUS[1] * threshold
    if not rebound and not ambiguous:
        return NEW_FRUIT
    return Verdict(rebound, best["parent"] if rebound else None, ambiguous,
                   best["speed_ratio"] if rebound else None, best)


def _finish(evidence: dict, threshold: float) -> None:
    """The evidence of a verdict as reported: the threshold it was judged by, the score rounded (None if not
    finite)."""
    evidence["threshold"] = threshold
    evidence["score"] = round(evidence["score"], 3) if math.isfinite(evidence["score"]) else None


def reassigned(candidate: PulseSummary, earlier: list[PulseSummary], threshold: float,
               max_flight: float) -> Verdict | None:
    """``candidate`` as the rebound of a contact P whose rebound was already claimed by a contact C, when C is as
    well the rebound of another contact Q still free: a fruit's rebound and the bounce of an earlier rebound can
    land within a few ms of each other, and C, judged first, took the better-scoring of the two parents it fitted.
    Each contact rebounds once, so the pairing must explain both: candidate → P and C → Q, each within
    ``threshold`` (the same tests, ``_hypothesis``); of several, the one whose worse score is least.  Without
    such a pairing the candidate was judged against the free parents alone (``judge``); with it, it is P's
    rebound and C is re-read as Q's (its own line, already written, keeps the parent it was judged with: a
    rebound is not graded either way).  Only parents claimed through ``judge`` are re-read (``taken_by``)."""
    by_sequence = {p.sequence: p for p in earlier if not p.virtual}
    options = []
    for taken in earlier:
        claimant = by_sequence.get(taken.taken_by) if taken.rebound_taken and taken.taken_by is not None else None
        if claimant is None or not taken.onset < candidate.onset or candidate.onset - taken.separation > max_flight:
            continue
        mine = _hypothesis(candidate, taken)
        if not mine["score"] <= threshold:
            continue
        for other in earlier:
            if other is taken or other is claimant or other.rebound_taken or not other.onset < claimant.onset \
                    or claimant.onset - other.separation > max_flight:
                continue
            theirs = _hypothesis(replace(claimant, damping_exponent=candidate.damping_exponent), other)  # the range now
            if theirs["score"] <= threshold:
                options.append((max(mine["score"], theirs["score"]), mine, theirs, claimant))
    if not options:
        return None
    worst, mine, theirs, claimant = min(options, key=lambda option: option[0])
    _finish(mine, threshold)
    mine["reassigned"] = {"contact": claimant.sequence, "was_rebound_of": mine["parent"],
                          "rebound_of": theirs["parent"], "score": round(theirs["score"], 3),
                          "speed_ratio": theirs["speed_ratio"],
                          "deviations": theirs["deviations"]}
    ambiguous = AMBIGUOUS[0] * threshold < worst
    return Verdict(True, mine["parent"], ambiguous, mine["speed_ratio"], mine,
                   reassigned=(claimant.sequence, theirs["parent"]))


#: The least share of a contact's impulse a fruit must keep once a rebound held in it is taken out
#: (``held_alternative``): below it the contact was mostly that rebound, not a fruit with one.
HELD_FRUIT_SHARE = 0.4


def without_held(parent: PulseSummary) -> PulseSummary | None:
    """``parent``, a contact judged a new fruit while a rebound was due in it (``PulseSummary.held``), as the fruit
    alone: the held rebound's predicted impulse and peak (``hidden_rebound``) taken out.  Two pulses landing within
    a fraction of a millisecond add their impulses and, nearly, their peaks; the fruit's time to peak and shape
    are kept.  The sds grow by the prediction's own (``EXPECTED_RATIO_SD`` of r, which the impulse and peak follow
    to the first and 1.2th power).  None when the fruit would keep less than ``HELD_FRUIT_SHARE`` of the impulse."""
    if parent.held is None:
        return None
    impulse, peak, _ = parent.held
    fruit_impulse, fruit_peak = parent.impulse - impulse, parent.peak_force - peak
    if not (fruit_impulse >= HELD_FRUIT_SHARE * parent.impulse and fruit_peak > 0):
        return None
    impulse_sd = math.hypot(parent.impulse_sd * parent.impulse, EXPECTED_RATIO_SD * impulse) / fruit_impulse
    peak_sd = math.hypot(parent.peak_force_sd * parent.peak_force, 1.2 * EXPECTED_RATIO_SD * peak) / fruit_peak
    return replace(parent, impulse=fruit_impulse, peak_force=fruit_peak, impulse_sd=impulse_sd, peak_force_sd=peak_sd,
                   held=None)


def held_alternative(candidate: PulseSummary, parents: list[PulseSummary], earlier: list[PulseSummary],
                     threshold: float) -> Verdict | None:
    """``candidate`` as the rebound of a fruit that landed together with a rebound due in its contact, within a
    fraction of a millisecond (one pulse to a joint fit too, so the contact was read as one fruit, its impulse
    and peak those of both).  The fruit's own rebound then fails the tests against the contact as measured (its
    speed ratio, read from the impulses, comes out too low by the held share) but passes them against the fruit
    alone (``without_held``).  The physics bounds it as for any parent: r cannot exceed the fruit's e by more
    than the tolerance, so a lone fruit (whose due rebound landed elsewhere) is not claimed through this.  The
    verdict is said to be ambiguous; its evidence names the rebound held, whose parent (still free in
    ``earlier``: its rebound not seen elsewhere) the analysis then marks taken.  None when no such parent
    passes."""
    free = {p.sequence for p in earlier if not p.rebound_taken}
    options = []
    for parent in parents:
        if parent.virtual or parent.held is None or parent.held[2] not in free:  # its rebound seen elsewhere
            continue
        alone = without_held(parent)
        if alone is not None:
            evidence = _hypothesis(candidate, alone)
            # a hard bound, not only a tolerance: the fruit cannot come back faster than e V (+ 10 %: the spread
            # that the held rebound's prediction adds to r would otherwise let a light lively fruit through)
            if evidence["score"] <= threshold \
                    and evidence["speed_ratio"] <= (1.0 + TOLERANCES["speed_ratio_up"]) * alone.restitution:
                options.append((evidence, parent))
    if not options:
        return None
    best, parent = min(options, key=lambda option: option[0]["score"])
    impulse, peak, held_parent = parent.held
    _finish(best, threshold)
    best["held_rebound"] = {"rebound_of": held_parent, "impulse": impulse, "peak_force": peak,
                            "reason": f"contact #{parent.sequence} was read as one fruit while the rebound of "
                                      f"#{held_parent} was due in it and not seen elsewhere: judged as that "
                                      f"fruit alone"}
    return Verdict(True, best["parent"], True, best["speed_ratio"], best)


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
        flight = flight_time(parent.restitution * parent.velocity)
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
    the same fruit (m, K, c) at r V_p, so with x_r = r x_p (Hunt–Crossley's constant c: a prediction takes one
    law; a rebound measured later is judged under the line's range, ``pulses.rebound_x``)

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
        flight = flight_time(EXPECTED_RATIO * p.restitution * p.velocity)
        return abs(onset - (p.separation + flight)) / flight

    timed = [p for p in due if p.velocity is not None and p.velocity > 0 and p.restitution > 0]
    return min(timed, key=miss, default=None)


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
    impulse, e_r, _ = rebound_pulse(parent)
    de_dx = (_at("e", xr * 1.05) - _at("e", xr / 1.05)) / (xr * (1.05 - 1.0 / 1.05)) if xr > 0 else 0.0
    tc = parent.time_to_peak * r ** -0.2 * _at("tc", xr) / _at("tc", parent.x)
    return PulseSummary(sequence=sequence, onset=onset, separation=onset + math.exp(guess["log_duration"]),
                        peak_force=math.exp(guess["log_peak"]), time_to_peak=tc, impulse=impulse, x=xr,
                        restitution=e_r, peak_force_sd=guess["log_peak_sd"], time_to_peak_sd=guess["log_duration_sd"],
                        impulse_sd=math.hypot(EXPECTED_RATIO_SD, parent.impulse_sd), x_sd=guess["x_sd"],
                        restitution_sd=math.hypot(abs(de_dx) * guess["x_sd"], parent.restitution_sd),
                        velocity=r * parent.velocity if parent.velocity is not None else None, refined=True,
                        virtual=True, speed_read=parent.speed_read)


#: Least spread of the restitution of a lane's fruit and of a predicted rebound's (``rebounds_landed_together``).
LOT_RESTITUTION_SD = 0.02


def rebound_pulse(parent: PulseSummary) -> tuple[float, float, float]:
    """(impulse [N s], restitution, its sd) of ``parent``'s rebound: the same fruit at r V_p, r =
    ``EXPECTED_RATIO`` e_p ± ``EXPECTED_RATIO_SD`` (as ``hidden_rebound``)."""
    r = EXPECTED_RATIO * parent.restitution
    xr = r * parent.x
    e_r = _at("e", xr)
    de_dlnx = (_at("e", xr * 1.05) - _at("e", xr / 1.05)) / (2.0 * math.log(1.05))
    e_sd = math.hypot(abs(de_dlnx) * EXPECTED_RATIO_SD, parent.restitution_sd, LOT_RESTITUTION_SD)
    return parent.impulse * r * (1.0 + e_r) / (1.0 + parent.restitution), e_r, e_sd
