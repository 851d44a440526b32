"""One contact's report: its own samples, the raw indices, whether it is a new fruit or a rebound, and
with a fit the model's indices and parameters; a fruit's firmness class.

``Analysis`` holds what every contact of a recording or a stream is analysed with (the detector's
rate, the fit's knowns, the feed, the firmness classes); ``Analysis.analyzer()`` gives the state of one
stream (``LineAnalyzer``: the recent contacts of each lane, for the rebound decisions), so that
``fruitimpact analyze`` and ``fruitimpact stream`` produce the same JSON object for the same samples.

For each contact, in order, as soon as the detector emits it (nothing waits for a later contact):

1. **Its own samples.**  The window is cut after the previous contact of the lane ended and before the
   next one began (``DetectedImpact.previous_end`` / ``next_start``, less the rise the next contact
   had before it crossed the threshold): two fruit a few milliseconds apart are two contacts, each
   measured on its own samples.
2. **Raw indices** (``indices.impact_indices``).
3. **Overlap** (``signals.onepulse``).  A contact whose force falls and rises again beyond the noise and
   ``OVERLAP_FRACTION`` of its peak (``indices.second_pulse``), or that no single pulse fits as one fruit of
   its lane does (``split.MISFIT_LIMIT``, ``onepulse.LaneMisfits``), holds two fruit
   (or a fruit and a rebound): fitted as two pulses (``signals.split``), each becomes its own contact;
   when that fails, one report with status ``overlap``, no firmness, no fit, no class.
4. **Rebound or new fruit** (``signals.rebounds``): decided from the contacts before it, by the
   fruit's own physics (flight, speed ratio, peak, time to peak, shape), with the evidence when the
   decision is near its boundary.
5. **Fit** (optional): a new fruit at the line's velocity (or with the given mass), a rebound at its
   own speed r V_p.
6. **Class** (optional): for a new fruit only; a rebound is the same fruit, already graded, and its
   line carries ``rebound_of``.

Every report has ``status`` (``ok``, ``overlap``, ``truncated``, ``overlong``, ``clipped``, ``unfitted``
when a requested fit did not converge) and ``message``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np


from fruitimpact.signals.detect import DetectedImpact
from fruitimpact.signals.indices import impact_indices, second_pulse
from fruitimpact.signals.rebounds import (DAMPING_EXPONENT, HIDDEN_FRUIT_MIN, LANE_FRUIT_MIN, NEW_FRUIT,
                                         QUIET_LANE_FRUIT, PulseSummary, Verdict, claimed_parent, expected_rebound,
                                         from_indices, hidden_rebound, judge, judge_unmeasured, landed_with_rebound,
                                         landing_speed, lane_fruit, likeliest_hidden, median_of, rebound_of_a_rebound,
                                         rebounds_due, rebounds_landed_together, refine, robust_sd, shape_table,
                                         too_light_for_fruit, unmeasured_fruit)
from fruitimpact.signals.settings import Analysis  # also this module's public name (defined beside the detector's settings)
from fruitimpact.signals.reports import (FIRMNESS_KEYS, SUMMARY_KEYS, UNSPLIT, detector_status, is_finite_number,
                                        merge_fit, restated, shape_fit, without_firmness)
from fruitimpact.signals.onepulse import (SPLIT_GAIN, LaneMisfits, is_dip, may_split, misfit_limit, misfit_shown,
                                          single_misfit, split_gain)
from fruitimpact.signals.split import FITS, FITS_DUE, split_contact

#: At most this many earlier contacts whose rebound is due guide a joint fit (the latest first; their hypotheses
#: share the ``split.FITS`` fits; on a line of 10 fruit/s with two rebounds each, 1–3 are due at once).
MAX_DUE = 3
#: Largest relative standard error of the peak force of a split piece (the joint fit's, with the expected rebound's
#: priors): the issue's precision of a measured peak.  A fruit piece fixed less well makes the contact one overlap
#: (no firmness); a rebound piece fixed less well keeps its parent but is reported as an overlap.  The standard error
#: predicts the error: over the pieces of the line scenarios of tests/linegen.py it is 0.4 % at the median and 2.1 %
#: at p95, and their errors are of that size (0.4 %, 2.2 %); at 3 % the pieces' peaks were 1.5 % off at p95 (chain10,
#: noisy), at 1 % 0.9 %.  Two fruit 1.5–2 ms apart with no rebound due are fixed only to ±2–6 %.
PIECE_PRECISION = 0.01
#: Marks a piece of a split in which a third pulse was found but not told apart (``_split_further``).
HOLDS_TWO = "_holds_two"
#: Starts fitted when a piece of a split is tried as two pulses again (rare, and it delays the report).
FITS_AGAIN = 2
#: Measured new fruit kept per lane: they stand for a fruit hidden in an overlap (``rebounds.judge_unmeasured``).
LANE_FRUIT_KEPT = 15
#: An overlap that could not be split hides two fruit, not one, when what it carries beyond the rebound due in it
#: is at least this many times a fruit of the lane (each fruit m (1 + e) V: one fruit is 1 ± 0.15 of the lane's,
#: two 2 ± 0.2, so 1.75 lies 3.7 sd above one and 0.9 sd below two) and it lasts at least ``TWO_FRUIT_DURATION``
#: times a fruit's contact (two fruit landing apart).  Seen on tests/linegen.py's grades (seeds 9, 10, 18): a
#: fruit, a rebound and a second fruit 12 ms later in one 15-18 ms overlap, whose second fruit's rebound, with no
#: slot left for it, was graded as a new fruit.
TWO_FRUIT_IMPULSE, TWO_FRUIT_DURATION = 1.75, 1.5
#: A lane's impact speed read from its own rebounds when it is not given (``LineAnalyzer.line_speed``): each
#: clear first rebound of a new fruit flew 2 r V/g (r its speed ratio, measured from the two pulses), so
#: V = g · flight / (2 r).  It is used once ``SPEED_MIN_REBOUNDS`` of the lane's agree: their median, from the
#: lane's last ``SPEED_KEPT``, when its median absolute deviation is within ``SPEED_SPREAD`` of it (spin and an
#: off-axis bounce move one flight by ±10–20 %; rebounds that disagree more give no speed).  Per lane: lanes
#: may drop from different heights.
SPEED_MIN_REBOUNDS = 4
SPEED_KEPT = 15
SPEED_SPREAD = 0.15
#: The line's damping law read from its own rebounds (``LineAnalyzer.damping_exponent``): each clear rebound of a
#: measured contact at speed ratio r ≤ ``DAMPING_RATIO_MAX`` shows β = ln(x_r/x_p)/ln r (``rebounds.rebound_x``:
#: 1 when the damping c is the fruit's constant, 0 when the restitution is).  Once ``DAMPING_MIN_REBOUNDS`` have,
#: line-wide (a lot's property, not a lane's), its rebounds are judged within the median of the last
#: ``DAMPING_KEPT`` ± 3 standard errors of that median (robust sd/√n), at least ± ``DAMPING_HALF_WIDTH``: the range
#: is the lot's law, and one rebound's own scatter (its x measured to a few %, over ln r ≈ −0.5: a robust sd of
#: 0.25–0.3 in β on the lines of tests/linegen.py) is the shape test's tolerance.  Without it a fruit arriving just
#: before its predecessor's rebound, whose x lies between r x_p and x_p, passed for that rebound.
DAMPING_MIN_REBOUNDS = 4
DAMPING_KEPT = 15
DAMPING_HALF_WIDTH = 0.25
DAMPING_RATIO_MAX = 0.85


class LineAnalyzer:
    """The state of one stream's analysis: the recent contacts of each lane (``Analysis`` does the rest).
    ``reports(impact)`` must be called for the impacts of a lane in the order the detector emits them."""

    def __init__(self, analysis: Analysis):
        self.analysis = analysis
        self._history: dict[int, list[PulseSummary]] = {}
        #: per lane: (sequence, onset [s]) of the recent contacts taken for a fruit, the last one the feed prior's
        #: phase (``_last_fruit``); a contact found later to have been a rebound gives its place back
        self._fruit_onsets: dict[int, list[tuple[int, float]]] = {}
        #: per lane: (sequence, onset [s], end [s]) of recent contacts that could not be measured (overlaps)
        self._unmeasured: dict[int, list[tuple]] = {}
        #: per lane: the recent measured new fruit (the lot's typical pulse at the line's speed)
        self._fruit: dict[int, list[PulseSummary]] = {}
        #: per lane: the single-pulse misfit its recent contacts left (``onepulse.LaneMisfits``)
        self._misfits = LaneMisfits()
        #: per lane: the number of the next contact (a detected impact holds one to three contacts)
        self._sequence: dict[int, int] = {}
        #: per lane: fruit reported while the lane has shown no sign of a rebound; None once it has (``_quiet_fruit``)
        self._quiet: dict[int, int | None] = {}
        #: per lane: the impact speed [m/s] read from each clear first rebound of a new fruit (``line_speed``)
        self._speeds: dict[int, list[float]] = {}
        #: line-wide: β of each clear rebound of a measured contact (``damping_exponent``)
        self._exponents: list[float] = []
        #: (lane, sequence) of the overlaps whose hidden fruit's slot one contact has claimed without naming it its
        #: parent (``rebounds.judge_unmeasured``, ``new_fruit_excluded``): the next claim closes it
        self._claimed_once: set[tuple[int, int]] = set()
        _warm_up(analysis)  # tables built and compiled code loaded before the first fruit lands, not while it waits

    def reports(self, impact: DetectedImpact) -> list[dict]:
        """The dicts of the contacts in one detected impact, in time order (SI; ``public(report)`` is the
        JSON object): one, or two or three when fruit landing together were told apart (``signals.split``).
        Each names the τ of the sensor's discharge restored in its window (``discharge_time`` [s], None when
        none: ``signals.detect`` step 1b)."""
        reports = self._reports(impact)
        for report in reports:
            report["discharge_time"] = impact.discharge_time
        return reports

    def _reports(self, impact: DetectedImpact) -> list[dict]:
        analysis = self.analysis
        own = isolated(impact)
        report = impact_indices(own, analysis.rate)
        status, message = detector_status(impact)
        peak = report["peak_force"]
        second = second_pulse(own)
        shape = None
        learnt = math.nan  # the single pulse's misfit; the lane learns it when the contact is decided
        dip = is_dip(second, peak, impact.noise)
        if dip:
            status = "overlap"
            message = (f"two pulses in one contact: the force falls and rises again by {second:.3g} N "
                       f"({second / peak:.0%} of the peak): two fruit, or a fruit and a rebound; no firmness")
        elif status in ("ok", "clipped"):
            shape = shape_fit(own, analysis)
            misfit = single_misfit(shape.get("fit_residual", math.nan), impact.noise, peak)
            limit = misfit_limit(self._misfits.share(impact.lane))
            # what the lane learns: a converged fit of an unclipped contact (a clipped top is not the force law's)
            learnt = misfit if status == "ok" and shape.get("converged") else math.nan
            if misfit > limit and misfit_shown(misfit, peak, impact.noise, own.window.size):
                # converged or not: no single pulse fits
                status = "overlap"
                message = (f"not one pulse: the force law misses it by {misfit:.1%} of its peak beyond the noise "
                           f"(one fruit: at most {limit:.1%}): two fruit landing together; no firmness")
        parts = flags = None
        due = []
        if is_finite_number(report["start_time"]):
            onset = report["start_time"]
            # a contact holding several pulses may have no clean falling edge (its indices' duration NaN): then
            # the contact as detected, up to its last sample above the threshold, is where a rebound may be due
            end = onset + report["contact_duration"] if is_finite_number(report["contact_duration"]) \
                else (impact.end_index + 1) / analysis.rate
            due = rebounds_due(onset, end, self._history.get(impact.lane, []), max_flight=analysis.flight_limit)
        if status == "overlap" and not (impact.truncated or impact.overlong or impact.clipped):
            parts = self._split(own, due, FITS, dip=dip)
        elif status == "ok" and due and shape is not None and shape.get("converged") \
                and may_split(shape, impact.noise, model := self._misfits.model_variance(impact.lane, peak,
                                                                                          impact.noise)):
            parts = self._split(own, due, FITS_DUE, dip=False)
            gain = split_gain(shape, parts, impact.noise) if parts is not None else 0.0
            if gain < SPLIT_GAIN + model:
                parts = None  # one pulse fits as well, or no better than the lane's lone fruit: one fruit
            elif not any(flags := self._rebounds(parts, impact.noise)):
                # two pulses, but neither is the rebound that was due: landing within a fraction of a
                # millisecond, their onsets and amplitudes trade off; one contact, no firmness, is the honest report
                message = (f"two pulses in one contact ({gain:.2f} noise variances per sample better fitted as two) "
                           f"that could not be told apart: a fruit and the rebound of #{due[0].sequence} landing "
                           f"together; no firmness")
                status, parts = "overlap", None
        if parts is not None:
            flags = flags if flags is not None else self._rebounds(parts, impact.noise)  # judged once per split
            further = self._split_further(parts, flags, due)
            if further is not parts:
                parts, flags = further, self._rebounds(further, impact.noise)
            vague = _imprecise(parts, flags)
            if vague is not None:  # two pulses whose amplitudes the samples do not fix: no firmness either
                status, parts = "overlap", None
                message = (f"two pulses in one contact that could not be told apart: a piece's peak force is "
                           f"determined to ±{vague:.1%} only (at most ±{PIECE_PRECISION:.0%}); no firmness")
        if parts is not None:
            held = "two" if len(parts) == 2 else "three"
            # a third pulse found in one piece but not told apart: the joint fit gave the other pieces one pulse
            # too few, so a piece judged a new fruit has absorbed part of it (its peak 70 % high, seen on a fruit
            # and two rebounds within 4 ms): its firmness is not a measurement either
            short_by_one = any(fit.get(HOLDS_TWO) for _, fit in parts)
            reports = []
            for (piece, fit), rebound in zip(parts, flags):
                indices = impact_indices(piece, analysis.rate)
                if fit.get(HOLDS_TWO):  # a piece in which a third pulse was found but not told apart
                    indices.update({key: math.nan for key in FIRMNESS_KEYS})
                    reports.append(self._contact(piece, indices, fit, "overlap",
                                                 "a piece of a contact holding three pulses, in which two landed "
                                                 "together and could not be told apart; no firmness", piece=True))
                elif short_by_one and not rebound:
                    indices.update({key: math.nan for key in FIRMNESS_KEYS})
                    reports.append(self._contact(piece, indices, fit, "overlap",
                                                 "a piece of a contact holding three pulses, fitted beside the two "
                                                 "that could not be told apart as if they were one; no firmness",
                                                 piece=True))
                else:
                    reports.append(self._contact(piece, indices, fit, "ok", f"one of {held} fruit in one contact, "
                                                 "told apart by a joint fit of the pulses", piece=True))
                    spread = _relative_peak_error(fit)
                    if reports[-1]["rebound"] and not spread <= PIECE_PRECISION:
                        # a rebound is graded with its fruit, so the piece stays with its parent, but its amplitude
                        # traded off against the other pulse's: neither its peak nor its fit is a measurement
                        without_firmness(reports[-1], fit=True)
                        if "fit_converged" in reports[-1]:
                            reports[-1].update(fit_converged=False, fit_message="a joint fit of two pulses, whose "
                                               "amplitudes trade off: not a fit of this rebound alone")
                        reports[-1].update(status="overlap", message=(
                            f"a rebound landing on another fruit's contact, told apart by a joint fit of the pulses; "
                            f"its peak force is determined to ±{spread:.1%} only (at most ±{PIECE_PRECISION:.0%})"))
            self._misfits.seen(impact.lane, learnt)
            return reports
        self._misfits.seen(impact.lane, learnt)
        if status == "overlap":  # the indices of one pulse do not apply: the contact as detected
            without_firmness(report)
            inside = own.window[impact.start_index - own.window_start:impact.end_index + 1 - own.window_start]
            report.update(start_time=impact.start_index / analysis.rate,
                          time_to_peak=(impact.peak_index - impact.start_index) / analysis.rate,
                          contact_duration=(impact.end_index + 1 - impact.start_index) / analysis.rate,
                          impulse=float(np.sum(inside)) / analysis.rate)
        return [self._contact(own, report, shape, status, message, due)]

    def _split_further(self, parts, rebounds: list[bool], due: list[PulseSummary]):
        """The pieces of a split, one of them split again where it holds a third pulse: when more than one earlier
        contact's rebound is due (a fruit and two rebounds landing together), a piece that is no rebound itself
        (its samples less the other piece's pulse), that two pulses fit better by ``SPLIT_GAIN`` and that holds a
        rebound becomes two; one that two pulses fit better but holds none is marked ``HOLDS_TWO`` (reported as
        an overlap: never one fruit fitted through two).  ``rebounds``: which pieces are rebounds (``_rebounds``).
        Returns ``parts`` itself when nothing changed."""
        lane, noise = parts[0][0].lane, parts[0][0].noise
        highest = float(np.nanmax([fit["peak_force"] for _, fit in parts]))
        if len(due) < 2 or not may_split(parts[0][1], noise, self._misfits.model_variance(lane, highest, noise)):
            return parts  # the joint fit left only the noise (and what the lane's lone fruit leave)
        for k, ((piece, fit), rebound) in enumerate(zip(parts, rebounds)):
            if rebound:
                continue  # a rebound of its own: the third pulse is in the other piece
            again = self._split(piece, due, FITS_AGAIN, dip=False)
            if again is None or split_gain(fit, again, piece.noise) < SPLIT_GAIN + self._misfits.model_variance(
                    lane, fit["peak_force"], piece.noise):
                continue
            flags = self._rebounds(again, piece.noise)
            if not any(flags) or _imprecise(again, flags) is not None:
                return [*parts[:k], (piece, {**fit, HOLDS_TWO: True}), *parts[k + 1:]]
            return sorted([*parts[:k], *again, *parts[k + 1:]], key=lambda part: part[1]["start_time"])
        return parts

    def _not_a_fruit(self, lane: int, sequence: int) -> None:
        """Contact ``sequence`` of ``lane``, taken for a fruit, was a rebound (``rebound_of_a_rebound``): its grade
        stands, but the feed prior's last fruit is again the one before it (a rebound's onset is off the feed's
        pitch, and would move the phase every later contact is judged by)."""
        onsets = self._fruit_onsets.get(lane, [])
        onsets[:] = [entry for entry in onsets if entry[0] != sequence]  # a fruit landed since stays the last

    def _last_fruit(self, lane: int) -> float | None:
        """The onset [s] of ``lane``'s last contact taken for a fruit (the feed prior's phase), None before one."""
        onsets = self._fruit_onsets.get(lane)
        return onsets[-1][1] if onsets else None

    def _rebounds(self, parts, noise: float) -> list[bool]:
        """Which pieces of a split are judged rebounds of earlier contacts of their lane, as ``_contact`` will
        judge them: ``rebounds.judge`` on each piece's own indices and fit, in time order, with the feed prior and
        the last fruit's onset (an earlier piece judged a fruit is the last fruit for the next)."""
        lane = parts[0][0].lane
        history, last_fruit = self._history.get(lane, []), self._last_fruit(lane)
        flags = []
        for piece, fit in parts:
            summary = from_indices(impact_indices(piece, self.analysis.rate), -1, noise, None)
            rebound = summary is not None and judge(self._judged(refine(summary, fit)), history,
                                                    max_flight=self.analysis.flight_limit,
                                                    last_fruit_onset=last_fruit, pitch=self.analysis.pitch,
                                                    quiet_fruit=self._quiet_fruit(lane)).rebound
            if summary is not None and not rebound:
                last_fruit = summary.onset
            flags.append(rebound)
        return flags

    def _split(self, own: DetectedImpact, due: list[PulseSummary], fits: int = FITS, dip: bool = True):
        """Two (piece, fit) of a contact holding two pulses, or None (``signals.split``); ``due``: the earlier
        contacts whose rebound is due in this one (their expected pulses guide the joint fit)."""
        analysis = self.analysis
        time = (own.window_start + np.arange(own.window.size)) / analysis.rate
        typical = [fruit.restitution for fruit in self._fruit.get(own.lane, [])]
        parts = split_contact(time, own.window, own.noise, velocity=1.0 if analysis.mass is None else None,
                              mass=analysis.mass, diameter=analysis.diameter, poisson=analysis.poisson,
                              restitution=float(np.median(typical)) if len(typical) >= 3 else None,
                              expected=[expected_rebound(parent) for parent in due[:MAX_DUE]], fits=fits, dip=dip)
        if parts is None:
            return None
        (fit_a, force_a), (fit_b, force_b) = parts
        rate, ws = analysis.rate, own.window_start
        onset_b = min(max(math.ceil(fit_b["start_time"] * rate), own.start_index + 1), own.end_index)
        end_a = min(max(math.floor((fit_a["start_time"] + fit_a["contact_duration"]) * rate), own.start_index),
                    own.end_index)
        pieces = []
        for force, start, end, fit in ((force_a, own.start_index, end_a, fit_a),
                                       (force_b, onset_b, own.end_index, fit_b)):
            window = np.ascontiguousarray(force)
            window.setflags(write=False)
            inside = window[start - ws:end + 1 - ws]
            peak_index = start + int(np.argmax(inside)) if inside.size else start
            pieces.append((dataclasses.replace(own, window=window, start_index=start, end_index=end,
                                               peak_index=peak_index, peak_value=float(window[peak_index - ws])),
                           fit))
        return pieces

    def _contact(self, impact: DetectedImpact, report: dict, shape: dict | None, status: str, message: str,
                 due: list[PulseSummary] | tuple = (), piece: bool = False) -> dict:
        """The rest of a contact's report: the rebound decision, the fit restated, the class.  ``due``: the earlier
        contacts whose rebound was due in it (``rebounds_due``; none for a ``piece`` of a split, whose pulses the
        joint fit has already told apart).  In an overlap their rebounds are taken to have landed there
        (``rebounds.hidden_rebound``), so that each one's own rebound can be recognised; a single pulse judged a
        new fruit may be one and a due rebound, or the rebound of a fruit hidden in an earlier overlap
        (``_hidden_fruit_due``), landing together (``rebounds.landed_with_rebound``): then it is an overlap too,
        and each rebound it holds is seen there."""
        analysis = self.analysis
        sequence = self._sequence.get(impact.lane, 0)
        self._sequence[impact.lane] = sequence + 1
        report["sequence"] = sequence
        # what the rebound test knows of this contact (its impact speed is set once decided)
        summary = None
        if status in ("ok", "clipped"):
            summary = from_indices(report, sequence, impact.noise, None)
            if summary is None and shape is not None and shape.get("converged"):
                # an index the samples did not give (a weak rebound's falling edge lost in the noise): the fitted
                # pulse's own (without it the contact could not be judged at all, and was taken for a new fruit)
                summary = from_indices({**report, **{key: shape.get(key) for key in SUMMARY_KEYS}}, sequence,
                                       impact.noise, None)
            if summary is not None:
                summary = self._judged(refine(summary, shape))
        history = self._history.setdefault(impact.lane, [])
        verdict = None
        if summary is not None and analysis.flight_limit > 0:
            verdict = judge(summary, history, max_flight=analysis.flight_limit,
                            last_fruit_onset=self._last_fruit(impact.lane), pitch=analysis.pitch,
                            quiet_fruit=self._quiet_fruit(impact.lane))
        chosen, hidden_fruit, slot = verdict, False, None
        judged = verdict is not None and (verdict.rebound or verdict.ambiguous)
        if summary is not None and (not judged or verdict.ambiguous):
            # not clearly a measured (or predicted) contact's rebound: perhaps that of a fruit hidden in an overlap.
            # Where both hypotheses are near (a contact after an overlap that held a fruit and a rebound: the
            # rebound's own bounce, or the hidden fruit's), the closer one is kept
            hidden, slot = self._unmeasured_parent(impact.lane, summary)
            if (hidden.rebound or hidden.ambiguous) and (not judged or _score(hidden) < _score(verdict)):
                chosen, hidden_fruit = hidden, True
        rebound = chosen is not None and chosen.rebound
        together = together_parents = pair = pair_parents = may_carry = flagged = None
        hidden_due = self._hidden_fruit_due(impact.lane, summary) \
            if not rebound and status == "ok" and summary is not None and not piece else []
        if not rebound and status == "ok" and summary is not None and (due or hidden_due):
            lane_fruit = self._lane_fruit(impact.lane)
            landed = landed_with_rebound(summary, [*due, *hidden_due], lane_fruit)
            if landed is not None and landed[0]["ambiguous"]:
                may_carry = landed[0]  # a fruit, or a fruit and a rebound: decided below
            elif landed is not None:
                together, together_parents = landed
            found = rebounds_landed_together(summary, list(due), lane_fruit) if together is None and due else None
            pair, pair_parents = found if found is not None else (None, None)
        elif piece and not rebound and status == "ok" and summary is not None:
            # a piece of a split judged a new fruit may be two rebounds the joint fit took for one pulse (a fruit and
            # two rebounds 1-2 ms apart, fitted as two pulses: seen on tests/linegen.py's chain10 at seed 36); the
            # rebounds due in the piece itself, after the pieces before it have taken theirs
            piece_due = rebounds_due(summary.onset, summary.separation, history, max_flight=analysis.flight_limit)
            found = rebounds_landed_together(summary, piece_due, self._lane_fruit(impact.lane)) \
                if len(piece_due) >= 2 else None
            pair, pair_parents = found if found is not None else (None, None)
        orphan = None
        if not rebound and status == "ok" and summary is not None and together is None and pair is None:
            orphan = too_light_for_fruit(summary, self._lane_fruit(impact.lane))
        slow_parent = False
        if not rebound and status == "ok" and summary is not None and together is None and pair is None \
                and orphan is None and not piece and self._quiet_fruit(impact.lane) < QUIET_LANE_FRUIT:
            # perhaps the bounce of a rebound that was itself taken for a fruit (its parent hidden in an overlap)
            own = {fruit.sequence for fruit in self._fruit.get(impact.lane, [])}
            slow = rebound_of_a_rebound(summary, [p for p in reversed(history) if p.sequence in own],
                                        self._lane_fruit(impact.lane), self.line_speed(impact.lane),
                                        analysis.flight_limit)
            if slow.rebound:
                chosen, rebound, hidden_fruit, slow_parent = slow, True, False, True
                self._not_a_fruit(impact.lane, slow.parent)
        if orphan is not None:  # a rebound whose parent's pulse was not measured as it was: not graded
            if chosen is not None and chosen.evidence:  # a near miss of a known parent, kept as evidence
                orphan["nearest_parent"] = chosen.evidence
            rebound, chosen, hidden_fruit = True, None, False
            message = f"a rebound of a contact not measured as it was: {orphan['reason']}"
        if together is not None:  # one fruit fitted through two pulses would be a wrong grade: no firmness
            status, chosen, summary, hidden_fruit = "overlap", None, None, False
            held = "a rebound" if len(together["parents"]) == 1 else "two rebounds"
            message = f"a fruit and {held} landing together: {together['reason']}; no firmness"
            without_firmness(report)
        elif pair is not None:  # no fruit at all: two rebounds, each of its own parent
            status, chosen, summary, rebound, hidden_fruit = "overlap", None, None, True, False
            message = f"two rebounds landing together: {pair['reason']}; no firmness"
            without_firmness(report)
        elif may_carry is not None and not rebound and orphan is None \
                and not (chosen is not None and chosen.ambiguous) and self._quiet_fruit(impact.lane) < QUIET_LANE_FRUIT:
            # graded as the fruit it may be and flagged: said, not silently guessed (not on a lane whose fruit have
            # shown no rebound: a pad stops them, none is expected to land)
            chosen, hidden_fruit, flagged = None, False, may_carry
            message = f"perhaps a fruit and a rebound landing together: {flagged['reason']}"
        unjudged = None
        if summary is None and status in ("ok", "clipped") and due and not piece:
            # no pulse to judge (an index lost in the noise and no converged fit: a weak rebound at high noise) while
            # a rebound was due in it: "a new fruit" would be a guess, so it is said
            unjudged = {"judged": False, "due": [parent.sequence for parent in due],
                        "reason": f"the rebound of #{due[0].sequence} was due here, but the samples gave no pulse to "
                                  f"test against it (an index not found and no converged fit)"}
        speed = self.line_speed(impact.lane)
        read = analysis.velocity is None  # a speed read from the lane's rebounds: no flight is tested against it
        landing = math.nan  # the impact speed its own flight shows, for its next bounce (a hidden fruit's rebound)
        if orphan is not None:
            speed = None  # its speed is not measured: the fit leaves m and K unsplit
        elif rebound and hidden_fruit:  # a hidden fruit rebounds once
            # a rebound of it or of another unseen contact (``new_fruit_excluded``) leaves its slot open, once
            key = (impact.lane, chosen.parent)
            if chosen.evidence.get("new_fruit_excluded") and key not in self._claimed_once:
                self._claimed_once.add(key)
            else:  # the slot it was judged against (an overlap may hide two fruit: the other's stays)
                self._unmeasured[impact.lane].remove(slot)
            speed = None  # the hidden fruit's speed ratio is not measured: the fit leaves m and K unsplit
            landing = landing_speed(chosen.evidence["flight_observed"])
        elif rebound and slow_parent:  # its parent was a rebound taken for a fruit: no longer one of the lane's fruit
            index = claimed_parent(summary, history, chosen.parent)
            history[index] = history[index].taken()
            self._fruit[impact.lane] = [f for f in self._fruit[impact.lane] if f.sequence != chosen.parent]
            speed = None  # the parent's speed is read from this flight, not measured: the fit leaves m and K unsplit
            landing = chosen.evidence["landing_speed"]
        elif rebound and chosen is not None:
            if chosen.reassigned is not None:  # the parent's earlier claimant is re-read as another's rebound
                index = self._reassign(history, chosen)
            else:
                index = claimed_parent(summary, history, chosen.parent)
            parent = history[index]
            history[index] = parent.taken(by=sequence)
            if chosen.evidence.get("held_rebound") is not None:  # the rebound held in the parent's contact was seen
                self._held_seen(history, chosen.evidence["held_rebound"]["rebound_of"])
            self._read_speed(impact.lane, summary, parent, chosen)
            self._read_damping(summary, parent, chosen)
            speed = _rebound_speed(chosen.speed_ratio, parent)
            read = parent.speed_read
        unnamed = hidden_fruit and chosen.evidence.get("new_fruit_excluded")  # its parent is not known
        report.update(rebound=rebound, rebound_of=chosen.parent if chosen is not None and rebound and not unnamed else
                      pair["parents"][0] if pair is not None else None,
                      rebound_ambiguous=bool(chosen is not None and chosen.ambiguous or orphan is not None
                                             or flagged is not None or unjudged is not None),
                      rebound_evidence=chosen.evidence if chosen is not None
                      else together or pair or orphan or flagged or unjudged)
        if analysis.fit and shape is not None and status != "overlap":
            result = restated(shape, analysis, speed)
            merge_fit(report, result)
            if not result.get("converged") and status == "ok":
                status, message = "unfitted", f"the fit did not converge: {result.get('message', '')}"
            elif result.get(UNSPLIT):
                report["_fit"] = shape  # its curve (at V = 1 m/s, the same pulse) is still the one to draw
                message = message or result["message"]
            if speed is None and result.get("converged") and is_finite_number(result.get("velocity")):
                speed, read = result["velocity"], False  # the mass was given: the fit found the speed
        if summary is not None:
            # a hidden fruit's rebound: its flight from the overlap fixes the speed it landed at, so its own bounce
            # can be expected (``rebounds_due``) and its flight tested; the fit still leaves its m and K unsplit
            kept = summary.with_velocity(landing, False) if speed is None and is_finite_number(landing) \
                else summary.with_velocity(speed, read)
            if not rebound and status == "ok" and orphan is None and (due or hidden_due):
                # a new fruit while a rebound was due in it (a measured contact's, or a fruit's hidden in an earlier
                # overlap): that rebound may have landed with it, too close to tell apart, and then the fruit's own
                # rebound is judged against the fruit alone as well (``rebounds.held_alternative``)
                held = likeliest_hidden([*due, *hidden_due], report["start_time"])
                if held is not None:
                    pulse = hidden_rebound(held, sequence, report["start_time"])
                    kept = dataclasses.replace(kept, held=(pulse.impulse, pulse.peak_force, held.sequence))
            history.append(kept)
            # keep the contacts a later one could still be the rebound of
            recent = [s for s in history if summary.onset - s.separation <= analysis.flight_limit]
            history[:] = recent[-8:]
        if not rebound and status != "overlap":
            onsets = self._fruit_onsets.setdefault(impact.lane, [])
            onsets.append((sequence, report["start_time"]))
            del onsets[:-4]
        # the lane's tally: a rebound, a pulse holding rebounds, or a contact judged near a rebound (ambiguous) is
        # evidence that the lane's fruit come back; a fruit measured as one, that they may not
        if rebound or together is not None or pair is not None or (chosen is not None and chosen.ambiguous):
            self._quiet[impact.lane] = None
        elif status != "overlap" and self._quiet.get(impact.lane, 0) is not None:
            self._quiet[impact.lane] = self._quiet.get(impact.lane, 0) + 1
        if pair is not None:  # both rebounds are seen, and each may bounce again from here
            for parent in pair_parents:
                index = next((i for i, s in enumerate(history) if s is parent), None)
                if index is not None:
                    history[index] = parent.taken()
                history.append(hidden_rebound(parent, sequence, report["start_time"]))
        elif status == "overlap":
            span_end = report["start_time"] + report["contact_duration"]
            self._unmeasured.setdefault(impact.lane, []).append((sequence, report["start_time"], span_end))
            # the rebound due in it is taken out of its impulse; a piece's pieces before it may have taken theirs,
            # and a fruit landed with a rebound is one pulse (too short to be two fruit), so for those: none
            second = self._second_hidden_fruit(impact.lane, report, [] if piece or together is not None else due)
            if second is not None:  # the last of two hidden fruit ended with the overlap
                self._unmeasured[impact.lane].append((sequence, second, span_end))
            if together is not None:  # the rebounds it holds are seen here (once), their bounces expected from here
                for parent in together_parents:
                    if any(parent is hidden for hidden in hidden_due):  # a fruit hidden in an earlier overlap
                        self._unmeasured[impact.lane] = [u for u in self._unmeasured[impact.lane]
                                                         if u[0] != parent.sequence]
                    else:
                        index = next((i for i, s in enumerate(history) if s is parent), None)
                        if index is not None:
                            history[index] = parent.taken()
                    history.append(hidden_rebound(parent, sequence, report["start_time"]))
            else:
                likeliest = likeliest_hidden(list(due), report["start_time"])
                if likeliest is not None:  # at most one rebound hides in an overlap: the one due nearest its onset
                    history.append(hidden_rebound(likeliest, sequence, report["start_time"]))
        elif summary is not None and not rebound and summary.refined:
            self._fruit.setdefault(impact.lane, []).append(summary)
            del self._fruit[impact.lane][:-LANE_FRUIT_KEPT]
        if analysis.classes is not None:
            graded = not rebound and status not in ("overlap", "truncated")
            value = report.get(analysis.classes.by, math.nan)
            report["class"] = analysis.classes.classify([value if is_finite_number(value) else math.nan])[0] \
                if graded else None
            report["class_by"] = analysis.classes.by
        report["status"] = status
        report["message"] = message
        return report

    @staticmethod
    def _reassign(history: list[PulseSummary], verdict: Verdict) -> int:
        """Re-read the contact that had claimed ``verdict``'s parent as the rebound of the parent the pairing gave
        it (``rebounds.reassigned``): that parent is marked taken by it, and its impact speed is the new parent's
        r V (as for any rebound), so its own bounce is expected from there.  Returns the index of ``verdict``'s
        parent: the entry that contact had taken (two rebounds hidden in one overlap share its sequence), which
        the caller marks taken by the contact being judged."""
        claimant, parent = verdict.reassigned
        mine = next(i for i, s in enumerate(history) if s.sequence == claimant and not s.virtual)
        old = next(i for i, s in enumerate(history) if s.sequence == verdict.parent and s.taken_by == claimant)
        index = claimed_parent(history[mine], history, parent)
        new_parent = history[index]
        history[index] = new_parent.taken(by=claimant)
        history[mine] = history[mine].with_velocity(
            _rebound_speed(verdict.evidence["reassigned"]["speed_ratio"], new_parent), new_parent.speed_read)
        return old

    @staticmethod
    def _held_seen(history: list[PulseSummary], sequence: int) -> None:
        """Mark taken the contact whose rebound was held in a contact read as one fruit (``rebounds.held_alternative``
        judged a later contact that fruit's rebound): its rebound has been seen there."""
        index = next((i for i, s in enumerate(history) if s.sequence == sequence and not s.rebound_taken), None)
        if index is not None:
            history[index] = history[index].taken()

    def _quiet_fruit(self, lane: int) -> int:
        """How many fruit ``lane`` has reported without a single rebound (0 once it has shown one): a lane that
        stops its fruit (``rebounds.QUIET_LANE_FRUIT``)."""
        return self._quiet.get(lane, 0) or 0

    def reads_speed(self) -> bool:
        """Whether the impact speed is read from the rebounds: neither given nor found by each fit (the mass
        given)."""
        analysis = self.analysis
        return analysis.velocity is None and not (analysis.fit and analysis.mass is not None)

    def line_speed(self, lane: int) -> float | None:
        """The impact speed [m/s] of ``lane``'s fruit: the analysis's own (``velocity``, from the drop height), else
        the one the lane's rebounds show (``SPEED_MIN_REBOUNDS`` clear first rebounds of new fruit agreeing within
        ``SPEED_SPREAD``), else None; None too when the mass is given (then each fit finds its fruit's speed)."""
        if not self.reads_speed():
            return self.analysis.velocity
        speeds = np.asarray(self._speeds.get(lane, []))
        if speeds.size < SPEED_MIN_REBOUNDS:
            return None
        median = float(np.median(speeds))
        spread = float(np.median(np.abs(speeds - median)))
        return median if spread <= SPEED_SPREAD * median else None

    def _read_speed(self, lane: int, rebound: PulseSummary, parent: PulseSummary, verdict: Verdict) -> None:
        """Keep the impact speed that ``rebound``'s flight shows, V = g · flight / (2 r), when it is a clear first
        rebound (not ambiguous) of a measured new fruit of ``lane`` (``line_speed``).  Its flight was not tested
        against a speed read so (``PulseSummary.speed_read``), so a lane whose speed changes is read anew."""
        if not self.reads_speed() or verdict.ambiguous or parent.virtual or not verdict.speed_ratio:
            return
        if not any(fruit.sequence == parent.sequence for fruit in self._fruit.get(lane, [])):
            return  # a rebound's own bounce: its parent's speed is a guess
        flight = rebound.onset - parent.separation
        if flight > 0 and verdict.speed_ratio > 0:
            kept = self._speeds.setdefault(lane, [])
            kept.append(landing_speed(flight) / verdict.speed_ratio)
            del kept[:-SPEED_KEPT]

    def damping_exponent(self) -> tuple[float, float]:
        """The range of β (x_r = r^β x_p) the line's rebounds are judged with: ``rebounds.DAMPING_EXPONENT`` until
        ``DAMPING_MIN_REBOUNDS`` clear rebounds have shown the line's own, then the median of the last
        ``DAMPING_KEPT`` (held within ``DAMPING_EXPONENT``) ± max(3 robust sd/√n, ``DAMPING_HALF_WIDTH``)."""
        count = len(self._exponents)
        if count < DAMPING_MIN_REBOUNDS:
            return DAMPING_EXPONENT
        # the median held inside the laws' range, so the range is never narrower than the half-width on its side;
        # it is cut to the laws' range where a contact is judged (``rebounds.rebound_x``)
        median = min(max(median_of(self._exponents), DAMPING_EXPONENT[0]), DAMPING_EXPONENT[1])
        half = max(3.0 * robust_sd(self._exponents) / math.sqrt(count), DAMPING_HALF_WIDTH)
        return median - half, median + half

    def _judged(self, summary: PulseSummary) -> PulseSummary:
        """``summary`` with the range of β it is judged with as a rebound (``damping_exponent``)."""
        exponent = self.damping_exponent()
        return summary if exponent == summary.damping_exponent else \
            dataclasses.replace(summary, damping_exponent=exponent)

    def _read_damping(self, rebound: PulseSummary, parent: PulseSummary, verdict: Verdict) -> None:
        """Keep the β a clear rebound of a measured contact shows, ln(x_r/x_p)/ln r (``damping_exponent``)."""
        ratio = verdict.speed_ratio
        if verdict.ambiguous or parent.virtual or not ratio or not 0.0 < ratio <= DAMPING_RATIO_MAX \
                or not (rebound.refined and parent.refined and rebound.x > 0 and parent.x > 0):  # x of a shape fit
            return
        self._exponents.append(math.log(rebound.x / parent.x) / math.log(ratio))
        del self._exponents[:-DAMPING_KEPT]

    def _lane_fruit(self, lane: int) -> list[PulseSummary]:
        """The measured new fruit that stand for the next fruit of ``lane``: its own, or, until it has
        ``LANE_FRUIT_MIN``, those of every lane (one lot on one line, landing at the one speed the analysis is
        given: a lane just started, or one whose first fruit were hidden in overlaps, is judged by the line's)."""
        own = self._fruit.get(lane, [])
        if len(own) >= LANE_FRUIT_MIN or not any(other != lane for other in self._fruit):
            return own
        return [fruit for kept in self._fruit.values() for fruit in kept]

    def _hidden_fruit_due(self, lane: int, summary: PulseSummary) -> list[PulseSummary]:
        """The fruit hidden in the lane's recent overlaps whose rebound is due during ``summary``'s contact
        (``rebounds.unmeasured_fruit``: each the lane's typical fruit at the line's speed, landing at the overlap's
        onset); none without the line's speed or ``LANE_FRUIT_MIN`` measured fruit."""
        velocity = self.line_speed(lane)
        fruit = self._lane_fruit(lane)
        if velocity is None or len(fruit) < HIDDEN_FRUIT_MIN:
            return []
        hidden = [unmeasured_fruit(fruit, sequence, onset, velocity)
                  for sequence, onset, _ in self._unmeasured.get(lane, []) if onset < summary.onset]
        return rebounds_due(summary.onset, summary.separation, hidden, max_flight=self.analysis.flight_limit)

    def _unmeasured_parent(self, lane: int, summary: PulseSummary) -> tuple[Verdict, tuple | None]:
        """The verdict on a contact that no measured contact claims as its rebound: the rebound of a fruit hidden
        in an earlier overlap of the lane (``rebounds.judge_unmeasured``), or a new fruit; and the hidden fruit's
        slot (sequence, onset, end) it was judged against (None with no slot).  The caller removes that slot when it
        takes the verdict (a hidden fruit rebounds once)."""
        limit = self.analysis.flight_limit
        recent = [u for u in self._unmeasured.get(lane, []) if 0 < summary.onset - u[2] <= limit]
        self._unmeasured[lane] = [u for u in self._unmeasured.get(lane, []) if summary.onset - u[2] <= limit]
        fruit = self._lane_fruit(lane)
        judged = [(judge_unmeasured(summary, sequence, onset, fruit, self.line_speed(lane)), (sequence, onset, end))
                  for sequence, onset, end in reversed(recent)]
        return min(judged, key=lambda pair: pair[0].evidence["score"] if pair[0].evidence
                   and pair[0].evidence["score"] is not None else math.inf, default=(NEW_FRUIT, None))

    def _second_hidden_fruit(self, lane: int, report: dict, due: list[PulseSummary]) -> float | None:
        """The onset [s] of a second fruit hidden in an overlap that could not be split (``report``: the contact
        as detected, its impulse summed over it), or None: when it carries, beyond the rebound due in it (the
        likeliest of ``due``, as ``hidden_rebound`` predicts it), ``TWO_FRUIT_IMPULSE`` times the impulse of the
        lane's fruit (their median, with at least ``LANE_FRUIT_MIN`` of them) and lasts ``TWO_FRUIT_DURATION``
        times their contact.  The second fruit landed last, so its contact ends with the overlap's: it landed a
        fruit's contact duration before that."""
        fruit = self._lane_fruit(lane)
        impulse, duration = report.get("impulse"), report.get("contact_duration")
        if len(fruit) < LANE_FRUIT_MIN or not (is_finite_number(impulse) and is_finite_number(duration)):
            return None
        held = likeliest_hidden(list(due), report["start_time"])
        carried = impulse - (hidden_rebound(held, -1, report["start_time"]).impulse if held is not None else 0.0)
        lane = lane_fruit(fruit)
        if carried < TWO_FRUIT_IMPULSE * lane.impulse or duration < TWO_FRUIT_DURATION * lane.duration:
            return None
        return report["start_time"] + duration - lane.duration


#: Rate [Hz] of the warm-up's synthetic contacts.  What it prepares (the pulse tables, numba's compiled code) is
#: the same for every rate, and its cost grows with the rate (13 s at 10 MHz), so it runs once, at this rate.
WARM_RATE = 20_000.0
_WARM: list = []


def _rebound_speed(ratio: float, parent: PulseSummary) -> float | None:
    """The impact speed [m/s] of a rebound at speed ratio ``ratio`` of ``parent``: r V_p; None when the parent's
    speed is unknown or a guess (a predicted hidden rebound's), so that the fit leaves m and K unsplit."""
    return ratio * parent.velocity if parent.velocity is not None and not parent.virtual else None


def _warm_up(analysis: Analysis) -> None:
    """Build the pulse tables and load every compiled function a contact's report uses (~0.1–0.5 s once per
    process), by analysing a synthetic apple impact and a pair of them at ``WARM_RATE``: a stream's first fruit
    then costs what the others cost (without it the first report took 46–71 ms, benchmarks/latency.py)."""
    if _WARM:
        return
    analysis = dataclasses.replace(analysis, rate=WARM_RATE)
    from fruitimpact.engine.powerlaw import exact_x, powerlaw_characteristics, powerlaw_curves
    from fruitimpact.signals.fit import at_velocity, prepare

    prepare()
    shape_table()
    rate = analysis.rate
    mass, stiffness, velocity = 0.19, 1.2e6, 1.0
    c = float(exact_x(0.6)) / velocity
    duration = powerlaw_characteristics(mass, stiffness, c, velocity, 0.0375)[0][2]
    pre = max(8, round(2e-3 * rate))
    n = pre + round(2.5 * duration * rate) + pre
    t = (np.arange(n) - pre) / rate
    pulse = np.zeros(n)
    for shift in (0.0, 0.6 * duration):  # one pulse, then two in one contact
        inside = (t > shift) & (t < shift + duration)
        pulse[inside] += powerlaw_curves(mass, stiffness, c, velocity, t[inside] - shift)[2]
        window = pulse + 0.01 * np.sin(np.arange(n))  # a little "noise" so the fits have residuals
        window.setflags(write=False)
        peak = int(np.argmax(window))
        impact = DetectedImpact(lane=0, sequence=0, start_index=pre, end_index=n - pre, peak_index=peak,
                                peak_value=float(window[peak]), baseline=0.0, baseline_slope=0.0, noise=0.01,
                                previous_end=None, next_start=None, clipped=False, truncated=False, overlong=False,
                                window_start=0, window=window, emitted_at=n)
        impact_indices(impact, rate)
        second_pulse(impact)
        fit = shape_fit(impact, analysis)
        if fit.get("converged") and fit.get("velocity_stderr") == 0.0:
            at_velocity(fit, 1.0)
        split_contact(t, window, 0.01, velocity=1.0)
    _WARM.append(True)


def isolated(impact: DetectedImpact) -> DetectedImpact:
    """The impact with its window cut to its own samples: after the previous contact of the lane ended,
    and before the next one began less the rise that contact had before crossing the threshold (taken
    as 0.3 of this contact's own threshold-to-peak time, twice the rise of a Hertz pulse to 6 σ at
    1 % noise, (0.06)^(2/3) ≈ 0.15 of its time to peak, plus 2 samples)."""
    lo = impact.window_start
    hi = impact.window_end
    if impact.previous_end is not None:
        lo = max(lo, min(impact.previous_end + 1, impact.start_index))
    if impact.next_start is not None:
        guard = math.ceil(0.3 * max(impact.peak_index - impact.start_index, 0)) + 2
        hi = min(hi, max(impact.next_start - guard, impact.end_index + 1))
    if lo == impact.window_start and hi == impact.window_end:
        return impact
    window = impact.window[lo - impact.window_start:hi - impact.window_start]
    return dataclasses.replace(impact, window_start=lo, window=window)


def _imprecise(parts, rebounds) -> float | None:
    """The largest relative standard error of the peak force of a piece that is no rebound (``rebounds``: one flag
    per piece) when it exceeds ``PIECE_PRECISION``, else None: that fruit's amplitude is then not fixed by the
    samples (its rise overlaps the other's) and no firmness can be read from it.  A rebound piece does not make
    the contact an overlap (it is graded with its fruit): ``reports`` marks that piece alone."""
    worst = max((_relative_peak_error(fit) for (_, fit), rebound in zip(parts, rebounds) if not rebound),
                default=0.0)
    return worst if not worst <= PIECE_PRECISION else None


def _relative_peak_error(fit: dict) -> float:
    """The joint fit's relative standard error of a piece's peak force (inf when it has none)."""
    return fit.get("peak_force_stderr", math.inf) / fit["peak_force"] if fit.get("peak_force") else math.inf


def _score(verdict: Verdict) -> float:
    """A verdict's score (its distance from the hypothesis, in tolerances; inf when it has none)."""
    score = (verdict.evidence or {}).get("score")
    return float(score) if score is not None else math.inf


__all__ = ["Analysis", "LineAnalyzer", "isolated"]
