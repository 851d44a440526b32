"""A contact judged against the lane's measured fruit, which stand for a fruit that was not measured (hidden in an
overlap, or read together with a rebound) and for the next new fruit: the rebound of a hidden fruit
(``judge_unmeasured``), a fruit and a rebound or two rebounds landing together (``landed_with_rebound``,
``rebounds_landed_together``), a rebound whose parent was not measured as it was (``too_light_for_fruit``)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fruitimpact.signals.rebounds.measured import (EXPECTED_RATIO, EXPECTED_RATIO_SD, LOT_RESTITUTION_SD,
                                                     _hypothesis, rebound_pulse)
from fruitimpact.signals.rebounds.pulses import (AMBIGUOUS, NEW_FRUIT, TOLERANCES, PulseSummary, Verdict, _at,
                                                 flight_time, landing_speed)


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
        return float(np.exp(median_of(logs))), robust_sd(logs)

    peak, peak_sd = median_and_sd([f.peak_force for f in fruit])
    tc, tc_sd = median_and_sd([f.time_to_peak for f in fruit])
    x, x_sd = lane.x, lane.x_sd
    duration = lane.duration
    # a lot's own spread, which three fruit cannot measure: Hertz, F_max ∝ m^0.6 K^0.4 and t_c ∝ m^0.4 K^-0.4
    # at one speed, with the mass spread of the impulse and the stiffness spread of a lot
    peak_floor = math.hypot(0.6 * LOT_IMPULSE_SD, 0.4 * LOT_STIFFNESS_SD)
    tc_floor = math.hypot(0.4 * LOT_IMPULSE_SD, 0.4 * LOT_STIFFNESS_SD)
    return PulseSummary(sequence=sequence, onset=onset, separation=onset + duration, peak_force=peak,
                        time_to_peak=tc, impulse=lane.impulse, x=x, restitution=lane.restitution,
                        peak_force_sd=max(peak_sd, peak_floor), time_to_peak_sd=max(tc_sd, tc_floor),
                        impulse_sd=max(lane.impulse_sd, LOT_IMPULSE_SD), x_sd=max(x_sd, TOLERANCES["shape"]) * x,
                        restitution_sd=max(lane.restitution_sd, restitution_floor(len(fruit))), velocity=velocity,
                        refined=True, virtual=True)


#: The flight tolerance of ``TOLERANCES`` as a number of sd, and the 99 % point of χ² with 4 degrees of freedom
#: (``judge_unmeasured`` adds its four tests).
FLIGHT_TOLERANCE_SD, CHI2_4_99 = 2.0, 13.277
#: The 99 % point of χ² with 3 degrees of freedom (``too_light_for_fruit``: restitution, impulse, stiffness).
CHI2_3_99 = 11.345
#: How much better a rebound of a hidden fruit must explain a contact than a new fruit of the lane does before
#: ``judge_unmeasured`` takes it for one: the difference of their squared distances on the three tests they share
#: (restitution, impulse, stiffness), read as 2 ln B of a Bayes factor, at "strong" on Kass & Raftery's scale
#: (J. Am. Stat. Assoc. 90, 773, 1995: 2 ln B ≥ 6, odds 20 : 1).  Below it the contact is a new fruit, said to
#: be ambiguous.  On line recordings of tests/linegen.py (eight scenarios, seeds 1–8 with the drop height and 1–4
#: without) the rebounds it took lay 10.6 or more apart; a fruit of a lane of apples and pears, 2.0.
STRONG_EVIDENCE = 6.0
#: ``judge_unmeasured`` beyond its ambiguous band: a contact that no new fruit of the lane could have made (its
#: squared distance from one, on restitution, impulse and stiffness, at least the 99.9 % point of χ² with three
#: degrees of freedom) and that the hidden fruit's rebound explains by ``STRONG_EVIDENCE`` better is that rebound,
#: said to be ambiguous, up to this score.  The hidden fruit is the lane's median: a light fruit hidden in an
#: overlap, or one whose flight is off the lane's, rebounds off it by 1.3–1.5 (line recordings of tests/linegen.py:
#: chain7 at seed 26, its impulse 0.54 × the predicted rebound's, about 0.3 × the lane's fruit, after 3 measured
#: fruit, its flight 0.88 × the predicted; grades at seed 25, its flight 1.5 ×), where a new fruit lay 6.6–14.7 sd
#: from the lane.  Its flight must be one the fruit could fly (it left at most at e(V) V, below the e(r V) V of the
#: rebound's own pulse, plus the speed ratio's 10 %) and its impulse one no fruit of the lot carries
#: (``impulse_distance`` below −3 sd).  Such a rebound may also be the bounce of a rebound hidden beside the fruit
#: (chain10 at seed 7: three pulses in one overlap), so its parent is not named (``rebound_of`` null) and the
#: hidden fruit's slot stays open for one more contact (``analysis``).
HIDDEN_SCORE_MAX = 1.5
NEW_FRUIT_EXCLUDED = 16.27
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
#: Fewest measured fruit of a lane (or of the line, ``analysis``) before the rebound of a fruit hidden in an overlap
#: is judged (``judge_unmeasured``): a recording's first fruit are often hidden (a chain line's first rebounds land
#: on the next fruit), and one measured fruit already says what the lot lands like, within a lot's spreads
#: (the floors below), which stand in for the spreads the lane has not measured yet.
HIDDEN_FRUIT_MIN = 1
#: The spread (sd) of the restitution of a lot's fruit, assumed while a lane has measured fewer than
#: ``LANE_FRUIT_MIN`` (``restitution_floor``): the damping factor c varies by 20–30 % between fruit of one lot,
#: which moves e by ±0.05–0.07 at e ≈ 0.6 (split.RESTITUTION_SPREAD takes ±0.12 as the lot's range).
FEW_FRUIT_RESTITUTION_SD = 0.06


def restitution_floor(count: int) -> float:
    """The least sd of the restitution of a lane's fruit, measured from ``count`` of them: ``LOT_RESTITUTION_SD``
    once there are ``LANE_FRUIT_MIN``, a lot's own spread (``FEW_FRUIT_RESTITUTION_SD``) before."""
    return LOT_RESTITUTION_SD if count >= LANE_FRUIT_MIN else FEW_FRUIT_RESTITUTION_SD


def median_of(values) -> float:
    """``np.median`` of the few values a lane keeps (its fruit, or every lane's), to the bit, without NumPy's per-call
    overhead (~35 µs: the rebound tests take a dozen medians per contact, 15 % of a busy line's analysis).  NaN
    when empty or when any value is NaN, as NumPy."""
    ordered = sorted(float(v) for v in values)
    n = len(ordered)
    if n == 0 or any(v != v for v in ordered):
        return math.nan
    middle = n // 2
    return ordered[middle] if n % 2 else (ordered[middle - 1] + ordered[middle]) / 2.0


def robust_sd(values) -> float:
    values = [float(v) for v in values]
    center = median_of(values)
    return 1.4826 * median_of([abs(v - center) for v in values])


@dataclass(frozen=True)
class LaneFruit:
    """What a lane's measured new fruit say of the next one: the median ``impulse`` [N s] and the robust sd of its
    logarithm, the median ``restitution`` and its robust sd, the median shape ``x`` = c V and the robust sd of its
    logarithm (each caller floors the spreads as its test needs), and the median contact ``duration`` [s]."""

    impulse: float
    impulse_sd: float
    restitution: float
    restitution_sd: float
    x: float
    x_sd: float
    duration: float


def lane_fruit(fruit: list[PulseSummary]) -> LaneFruit:
    """The ``LaneFruit`` of the measured ``fruit`` of a lane (``analysis`` keeps the last ``LANE_FRUIT_KEPT``)."""
    log_impulse = np.log([f.impulse for f in fruit])
    restitution = [f.restitution for f in fruit]
    log_x = np.log([max(f.x, 1e-6) for f in fruit])
    return LaneFruit(float(np.exp(median_of(log_impulse))), robust_sd(log_impulse), float(median_of(restitution)),
                     robust_sd(restitution), float(np.exp(median_of(log_x))), robust_sd(log_x),
                     float(median_of([f.separation - f.onset for f in fruit])))


#: Least spread (sd of ln) of the impulse of a lane's fruit that ``landed_with_rebound`` assumes: fruit of one
#: lot differ in mass by 10–15 % (sd) and a lane's first few measured fruit understate that (5 fruit gave 5 %,
#: and a fruit 1.3 times their median then looked like a fruit and a rebound together).
LOT_IMPULSE_SD = 0.15
#: A pulse nearer (in sd) a fruit and a due rebound together than a fruit alone, more than this many sd above the
#: lane's fruit but not more than ``TOLERANCES["z"]``, may be either: it is graded as the fruit it may be, and
#: flagged with the evidence (``landed_with_rebound``; a fruit 2 sd heavier than its lane is 1 in 44).  On the
#: line scenarios of tests/linegen.py (seeds 1–32, 2,900 new fruit with a rebound due) 17 of the 22 fruit read
#: together with a rebound they did not part from lay beyond 2 sd, and 21 fruit landing alone (0.7 %).
LANDED_AMBIGUOUS_Z = 2.0


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
    and nearer, in sd, to a fruit and that rebound together; when it lies only ``LANDED_AMBIGUOUS_Z`` to
    ``TOLERANCES["z"]`` sd above, it may be either (evidence ``ambiguous``: graded as a fruit, and flagged).  The
    time the rebound was predicted to land is no evidence here: on a chain line the feed's pitch is about a
    rebound's flight, so due rebounds are predicted at new fruit's onsets, and on a pad they never land at all.
    Returns (the evidence: the parent whose rebound it holds, both distances, ``ambiguous``; the parents) or
    None."""
    if len(fruit) < LANE_FRUIT_MIN or not candidate.refined or not due:
        return None
    z = TOLERANCES["z"]
    lane = lane_fruit(fruit)
    impulse_lane, impulse_sd = lane.impulse, max(lane.impulse_sd, LOT_IMPULSE_SD)
    fruit_distance = math.log(candidate.impulse / impulse_lane) / math.hypot(impulse_sd, candidate.impulse_sd)
    if not fruit_distance > LANDED_AMBIGUOUS_Z:
        return None
    best = chosen_parents = None
    impulses = [(parent, rebound_pulse(parent)[0]) for parent in due]
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
    best["ambiguous"] = not fruit_distance > z
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


def impulse_distance(candidate: PulseSummary, lane: LaneFruit) -> float:
    """How many sd ``candidate``'s impulse lies from the lane's fruit (ln of the ratio over the lane's spread, at
    least ``LOT_IMPULSE_SD``, and the candidate's own): every fruit of a lane lands at the line's one speed, so
    carries the lane's m (1 + e) V within the lot's spread of mass; below −``TOLERANCES["z"]`` it is no likely
    fruit of the lot."""
    impulse_sd = math.hypot(max(lane.impulse_sd, LOT_IMPULSE_SD), candidate.impulse_sd)
    return math.log(candidate.impulse / lane.impulse) / impulse_sd


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
    distance = impulse_distance(candidate, lane)
    if not distance < -z:
        return None
    first = EXPECTED_RATIO * lane.restitution
    second = first * EXPECTED_RATIO * _at("e", first * lane.x)
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


#: Two due rebounds are taken to have landed together when the pulse lies within this distance (in sd, impulse and
#: restitution together) of what the two carry, and a new fruit of the lane lies ``PAIR_MARGIN`` times farther.
#: Chosen on 36 line recordings of tests/linegen.py (chain10, grades, close, lanes4, chain7, noisy at seeds 1–6):
#: the 4 contacts that were two rebounds lay at 0.93–1.17 sd from the pair and 1.9–3.1 times farther from a new
#: fruit; the nearest new fruit lay at 1.97 sd, two lone rebounds at 1.28 and 1.48.  Few cases: the margin is thin,
#: and a lively new fruit taken for two rebounds loses its grade (an overlap), where two rebounds taken for a
#: fruit are a fruit that never was, graded.
PAIR_DISTANCE_MAX, PAIR_MARGIN = 1.25, 1.5


def rebounds_landed_together(candidate: PulseSummary, due: list[PulseSummary],
                             fruit: list[PulseSummary]) -> tuple[dict, list[PulseSummary]] | None:
    """Is ``candidate``, one pulse judged no rebound, the rebounds of two earlier contacts that landed together?

    On a chain-fed line one fruit's second bounce and the next fruit's first often land within a fraction of a
    millisecond: one pulse that a single force law fits, taken for a new fruit that never was, graded.  What it
    carries is the two rebounds': the impulse I_p r (1 + e_r)/(1 + e_p) of each (the same fruit at r V_p, r =
    ``EXPECTED_RATIO`` e_p ± ``EXPECTED_RATIO_SD``) added, and a rebound's restitution (a slower impact: livelier
    than the lane's fruit).  Of the pairs of ``due`` contacts (``rebounds_due``), the nearest in impulse and
    restitution (in sd) is taken when it lies within ``PAIR_DISTANCE_MAX`` and a new fruit of the lane (the
    medians and robust spreads of its measured ``fruit``, at least one; spreads at least ``LOT_IMPULSE_SD`` and
    ``LOT_RESTITUTION_SD``, or ``FEW_FRUIT_RESTITUTION_SD`` before the lane has ``LANE_FRUIT_MIN``) lies
    ``PAIR_MARGIN`` times farther.  Returns (the evidence:
    ``kind`` "two rebounds", ``parents`` (their sequences), both distances; the two parents themselves) or None."""
    if not fruit or not candidate.refined or len(due) < 2:
        return None
    lane = lane_fruit(fruit)
    impulse_lane, e_lane = lane.impulse, lane.restitution
    impulse_sd = math.hypot(max(lane.impulse_sd, LOT_IMPULSE_SD), candidate.impulse_sd)
    # fewer than ``LANE_FRUIT_MIN`` fruit (a recording's first contacts) measure no spread of e: a lot's stands in
    e_lane_sd = math.hypot(max(lane.restitution_sd, restitution_floor(len(fruit))), candidate.restitution_sd)
    new_fruit = math.hypot(math.log(candidate.impulse / impulse_lane) / impulse_sd,
                           (candidate.restitution - e_lane) / e_lane_sd)
    pulses = [(parent, rebound_pulse(parent)) for parent in due]
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
    x_lane, x_sd = lane.x, max(lane.x_sd, tol["shape"])
    impulse_lane, impulse_sd = lane.impulse, max(lane.impulse_sd, LOT_IMPULSE_SD)
    r_sd = math.hypot(EXPECTED_RATIO_SD, lane.restitution_sd / e_lane)
    xr = r * x_lane
    e_pred = _at("e", xr)
    de_dlnx = (_at("e", xr * 1.05) - _at("e", xr / 1.05)) / (2.0 * math.log(1.05))
    e_sd = math.hypot(abs(de_dlnx) * math.hypot(x_sd, r_sd), candidate.restitution_sd)
    impulse_pred = impulse_lane * r * (1.0 + e_pred) / (1.0 + e_lane)
    log_k = [_log_stiffness(f, velocity)[0] for f in fruit]
    k_lane, k_sd = float(median_of(log_k)), max(robust_sd(log_k), LOT_STIFFNESS_SD)
    k_rebound, k_meas = _log_stiffness(candidate, r * velocity)
    k_fruit = _log_stiffness(candidate, velocity)[0]  # the same pulse read as a fruit at the line's speed
    deviations = {
        "restitution": abs(candidate.restitution - e_pred) / (z * e_sd),
        "impulse": abs(math.log(candidate.impulse / impulse_pred))
        / (z * math.sqrt(impulse_sd ** 2 + r_sd ** 2 + candidate.impulse_sd ** 2)),
        "stiffness": abs(k_rebound - k_lane) / (z * math.sqrt(k_sd ** 2 + (1.5 * r_sd) ** 2 + k_meas ** 2)),
    }
    e_lane_sd = math.hypot(max(lane.restitution_sd, restitution_floor(len(fruit))), candidate.restitution_sd)
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
    (score ≤ 1: a rebound; in the ambiguous band of ``judge`` above 1, a rebound only by ``STRONG_EVIDENCE`` over
    a new fruit).  The tests share r (a wrong r moves the flight,
    the impulse and the stiffness together), so that point is a scale chosen on the line recordings of
    tests/linegen.py, not a calibrated probability.  Without the line's speed or enough
    measured fruit: a new fruit, undecided (``NEW_FRUIT``)."""
    if velocity is None or len(fruit) < HIDDEN_FRUIT_MIN or not candidate.refined:
        return NEW_FRUIT
    tol = TOLERANCES
    z = tol["z"]
    lane = lane_fruit(fruit)
    duration = lane.duration
    shared = _as_lane_rebound(candidate, fruit, lane, velocity, EXPECTED_RATIO * lane.restitution)
    r, r_sd = shared["r"], shared["r_sd"]
    flight_pred = flight_time(r * velocity)
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
    ambiguous = AMBIGUOUS[0] < score <= AMBIGUOUS[1]
    # the other explanation: a new fruit of the lane at the line's speed (``_as_lane_rebound``): on the three tests
    # both hypotheses share the rebound must fit clearly better than a new fruit does (``STRONG_EVIDENCE``);
    # otherwise the contact is a new fruit, said to be ambiguous.  In the ambiguous band above 1 the score alone
    # (a scale, not a probability) cannot decide, and that comparison does: a contact 10.9 sd from any new fruit
    # of its lane and 3.9 sd from the hidden fruit's rebound (score 1.22) is that rebound, said to be ambiguous
    new_fruit2, rebound2 = shared["new_fruit2"], shared["rebound2"]
    strong = new_fruit2 - rebound2 >= STRONG_EVIDENCE
    # beyond the band, the hidden fruit (a lane's median standing for a fruit nobody measured) may simply be
    # further from the lane than its spread says; when no new fruit of the lane could have made the contact either
    # (``NEW_FRUIT_EXCLUDED``) and the rebound explains it strongly better, it is that rebound, said to be ambiguous
    # (its flight must still be one the fruit could fly: it left at most at e(V) V, below the e(r V) V its rebound
    # shows, since e falls with speed, plus the speed ratio's upward tolerance)
    possible = flight > 0 and landing_speed(flight) <= (1.0 + tol["speed_ratio_up"]) * candidate.restitution * velocity
    # and its impulse must be one no fruit of the lot carries (as ``too_light_for_fruit``): the other tests lean on
    # the lane's spreads of e and stiffness, which a few fruit understate (a 150 g apple of E 2.5 MPa and e 0.70
    # landing off its flight was excluded as a new fruit by them alone; found by a review)
    light = impulse_distance(candidate, lane) < -z
    excluded = AMBIGUOUS[1] < score <= HIDDEN_SCORE_MAX and new_fruit2 >= NEW_FRUIT_EXCLUDED and strong and possible \
        and light
    ambiguous = ambiguous or excluded
    rebound = score <= 1.0 or (ambiguous and strong)
    if excluded:  # a rebound, but perhaps of another unseen contact: the hidden fruit's own may still come
        evidence["new_fruit_excluded"] = True
    evidence["new_fruit_distance"] = round(math.sqrt(new_fruit2), 3)
    evidence["rebound_distance"] = round(math.sqrt(rebound2), 3) if math.isfinite(rebound2) else None
    if rebound and not strong:
        rebound, ambiguous = False, True
        evidence["reason"] += ("; but a new fruit of the lane fits its restitution, impulse and stiffness about as "
                               "well or better")
    if not rebound and not ambiguous:
        return NEW_FRUIT
    return Verdict(rebound, hidden if rebound else None, ambiguous, r if rebound else None, evidence)


#: The speed of a contact that was itself a rebound, as a share of the line's speed, read from its own rebound's
#: flight (``rebound_of_a_rebound``): a first bounce lands at r V with r = e less spin (0.35–0.8 for fruit of
#: e 0.45–0.85), a second at r² V (0.15–0.6).  A flight that says the parent moved at 0.85 V or more is a fruit's
#: own rebound landing late, which the flight tolerance already covers.
SLOW_PARENT_RATIO = (0.12, 0.85)


def rebound_of_a_rebound(candidate: PulseSummary, parents: list[PulseSummary], fruit: list[PulseSummary],
                         velocity: float | None, max_flight: float) -> Verdict:
    """Is ``candidate``, a contact no test claims, the rebound of one of ``parents`` (earlier contacts of its lane
    taken for new fruit at the line's speed ``velocity`` [m/s]) that was itself a rebound?

    A rebound of a fruit hidden in an overlap can pass for a new fruit (a heavy or lively fruit's rebound
    carries a typical fruit's impulse), and is then taken to have landed at the line's speed V.  Its own
    bounce fails the flight test against that speed (it lands after 2 r V_p/g with V_p the speed it really
    had, less than V) and is taken for a new fruit in turn: the mistake cascades.  The samples say more than
    that:

    * the candidate is the same fruit as the parent on every test that does not need the parent's speed
      (``measured._hypothesis``: speed ratio r from the impulse ratio against e_p, peak force, time to peak and
      shape x, each within its tolerance);
    * its flight measures the speed it landed at, u = g · flight/2 (ballistic), so the parent's own speed was
      V_p = u/r; as a share q = V_p/V of the line's speed it must be a rebound's (``SLOW_PARENT_RATIO``);
    * as a new fruit of the lane at V it is improbable: its restitution, impulse and contact stiffness read at V
      lie beyond the 99 % point of χ² with three degrees of freedom from the lane's measured ``fruit`` (at least
      ``LANE_FRUIT_MIN``; ``_as_lane_rebound``);
    * and the parent itself looks like what the flight says it was: a rebound of a lane fruit at q V explains its
      restitution, impulse and stiffness (read at q V) at least as well as a fruit of the lane at V does (the
      lane's other fruit, at least ``LANE_FRUIT_MIN``).  Without this a soft, light, lively new fruit landing
      after a fruit measured as the fruit it was passed the tests above (a lighter fruit mimics a rebound's pulse
      when it is also r^1.5 times softer: 0.6 of the mass and 0.5–0.7 of the stiffness, a lot's soft tail).

    Then the candidate is that parent's rebound, marked ambiguous, with the evidence (the parent's speed read
    from the flight; the parent's grade, already given, is not revised).  The nearest such parent on the tests
    is taken.  Otherwise ``NEW_FRUIT``."""
    if velocity is None or len(fruit) < LANE_FRUIT_MIN or not candidate.refined:
        return NEW_FRUIT
    lane = lane_fruit(fruit)
    as_fruit = _as_lane_rebound(candidate, fruit, lane, velocity, EXPECTED_RATIO * lane.restitution)["new_fruit2"]
    if not as_fruit >= CHI2_3_99:
        return NEW_FRUIT  # a plausible new fruit of the lane
    best = None
    for parent in parents:
        flight = candidate.onset - parent.separation
        if parent.rebound_taken or parent.velocity is None or not 0.0 < flight <= max_flight:
            continue
        evidence = _hypothesis(candidate, parent)
        shared_tests = [v for k, v in evidence["deviations"].items() if k != "flight"]
        if not shared_tests or any(v is None for v in shared_tests) or max(shared_tests) > 1.0:
            continue
        shared = max(shared_tests)
        r = evidence["speed_ratio"]
        landing = landing_speed(flight)
        share = landing / r / velocity
        if not SLOW_PARENT_RATIO[0] <= share <= SLOW_PARENT_RATIO[1]:
            continue
        # the parent itself must look like what the flight says it was: a rebound at share × V explains its
        # restitution, impulse and stiffness (read at that speed) at least as well as a fruit of the lane at V does.
        # A fruit that was measured as the fruit it is fails this (read at 0.6 V it needs a fruit 2.2 times stiffer
        # than the lot), so a soft, light, lively new fruit landing after it is not taken for its rebound
        others = [f for f in fruit if (f.sequence, f.onset) != (parent.sequence, parent.onset)]
        if len(others) < LANE_FRUIT_MIN:
            continue
        as_parent = _as_lane_rebound(parent, others, lane_fruit(others), velocity, share)
        if not as_parent["rebound2"] <= as_parent["new_fruit2"]:
            continue
        if best is None or shared < best[0]:
            best = (shared, parent, evidence, share, landing, as_parent)
    if best is None:
        return NEW_FRUIT
    shared, parent, evidence, share, landing, as_parent = best
    evidence.update(score=round(shared, 3), threshold=1.0, landing_speed=landing, parent_speed=share * velocity,
                    parent_speed_share=round(share, 3), new_fruit_distance=round(math.sqrt(as_fruit), 3),
                    parent_rebound_distance=round(math.sqrt(as_parent["rebound2"]), 3),
                    parent_fruit_distance=round(math.sqrt(as_parent["new_fruit2"]), 3),
                    kind="rebound_of_a_rebound",
                    reason=(f"the same fruit as #{parent.sequence} (speed ratio, peak force, time to peak and shape "
                            f"within {shared:.2f} of their tolerances) but landing {_flight_text(evidence)}: "
                            f"#{parent.sequence} moved at {share:.2f} of the line's speed, so it was itself a "
                            f"rebound (taken for a fruit, its grade given; as such a rebound it lies "
                            f"{math.sqrt(as_parent['rebound2']):.1f} sd from the lane's fruit, as a fruit "
                            f"{math.sqrt(as_parent['new_fruit2']):.1f}); as a new fruit this contact lies "
                            f"{math.sqrt(as_fruit):.1f} sd from the lane's fruit"))
    return Verdict(True, parent.sequence, True, evidence["speed_ratio"], evidence)


def _flight_text(evidence: dict) -> str:
    """"after 0.095 s, where a fruit at the line's speed would fly 0.139 s" (or the observed flight alone)."""
    observed, predicted = evidence.get("flight_observed"), evidence.get("flight_predicted")
    if predicted is None:
        return f"after {observed:.3g} s"
    return f"after {observed:.3g} s, where its rebound at the line's speed would fly {predicted:.3g} s"
