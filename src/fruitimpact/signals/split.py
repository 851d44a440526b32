"""Two fruit in one contact, told apart (issue 13, item 2).

When a second fruit (or a rebound) lands on the plate while another is still in contact, forces on one plate
add and both contacts are the simulator's Hunt–Crossley pulse, so the contact is fitted as the sum of two,

    F(t) = F_A · H((t − t0_A)/T_A; x_A) + F_B · H((t − t0_B)/T_B; x_B),

with the tabulated shape H of one pulse (``signals.pulse``), eight parameters, by the same Levenberg–Marquardt
compiled for a sum of pulses (``leastsquares.fit_pulse_sum``).

Starts.  Two pulses a few milliseconds apart show no dip, so the fit is started from several places
(``signals.starts``: the landmarks of a dip, then the best pulse pairs of a grid, the best of each hypothesis
first) and ``fits`` of them are fitted.  With a rebound due, a fit that leaves only the noise (``GOOD_MISFIT``,
and a χ² within ``NOISE_CHI2_SD`` of the samples') and agrees with the rebound ends the search.  The fits run
one after the other on the calling thread: on two worker threads (the results taken in the starts' order, so
the same choice) a 2-core machine gained ~0.5 ms at the 1-lane p99 of benchmarks/latency.py when idle and lost
3-6 ms with another process busy on the second core (docs/performance.md).

Choice.  The first pulse's tail lies under the second, so several fits can leave the same residual (two fits
of one overlap: e 0.34 with 94.6 N, or e 0.71 with 99.9 N).  Physics chooses.  When an earlier fruit's rebound
is due in the contact, that rebound is the same fruit at its exit speed: its peak, duration and x are known
within the spread of the speed ratio and the spot it lands on (``rebounds.expected_rebound``).  They enter as
Gaussian priors on one pulse (extra rows of the least squares; the grid also holds pairs with that pulse
itself), and the least χ² of data and prior together wins.  Of fits whose χ² are alike (with a rebound due or
without), the one whose restitutions do not fall below the lane's fruit (a rebound lands slower, so its e is
higher).

Acceptance.  A separation is kept only when the sum leaves nothing but the noise (``MISFIT_LIMIT`` of the
larger peak beyond it, as for one pulse), both pulses lie in the window in order (the last may end a little
after a window cut before the next contact) and each is well above the noise; then each pulse is reported as
its own contact, its indices measured on the samples less the other pulse's model, its fit the corresponding
block of the joint fit (its standard errors from the joint covariance, so the other pulse's uncertainty is in
them).  Otherwise the contact stays one report with status ``overlap`` (``analysis``).
"""

from __future__ import annotations

import math

import numpy as np

from fruitimpact.engine.powerlaw import restitution_of_x
from fruitimpact.signals.fit import MIN_PEAK_SNR, RESULT_KEYS, named_result
from fruitimpact.signals.leastsquares import fit_pulse_sum
from fruitimpact.signals.pulse import X_MAX, PulseModel
from fruitimpact.signals.starts import joint_starts, landmarks

__all__ = ["MISFIT_LIMIT", "split_contact"]

#: A fit whose residual beyond the noise, √(rms² − σ²), exceeds this share of the peak is not one pulse (and
#: a joint fit of two, of the larger peak, not two).  One Hunt–Crossley contact leaves the noise plus a
#: structured part (plate ringing, hum left over) of at most 1.6 % of its peak over the line scenarios of
#: tests/linegen.py (2–3 kHz ringing, ζ 0.03–0.1, hum, drift) and 0.9 % in tests/test_signals_detect.py; two
#: fruit landing within a fraction of a time to peak leave 2–10 %.
MISFIT_LIMIT = 0.018
#: Starts fitted: a contact held for two pulses (a dip or a misfit), and one that one pulse fits but in which a
#: rebound is due (``FITS_DUE``: most contacts of a busy line; each fit costs 0.3–1.4 ms, hot).
FITS = 4
FITS_DUE = 4
#: A fit whose prior χ² (three parameters) is within this (the 95 % point of χ² with 3 degrees of freedom) agrees
#: with the expected rebound.
PLAUSIBLE_PRIOR_CHI2 = 7.81
#: Iterations of one joint fit: from these starts an accepted fit converges in ≤ 20 (90 %) and 52 at most (the
#: line scenarios); one still moving after 40 is a start in the wrong valley, and another start is tried.
SPLIT_ITERATIONS = 40
#: How far a pulse may end after the window [share of its duration]: the window is cut before the next
#: contact's rise, and a Hunt–Crossley pulse's last 15 % carry ~2 % of its impulse (its force ~(T − t)^1.5).
END_ALLOWANCE = 0.15
#: A separation that leaves at most this share of the peak beyond the noise and whose pulse agrees with the
#: expected rebound is taken at once (the rest of the starts are not fitted: latency); otherwise every start
#: is fitted and the choice below made.  Without a prior no fit is taken early: wrong local minima of two fruit
#: 1 ms apart leave as little (0.2–0.3 %).
GOOD_MISFIT = 0.004
#: ... and only when the samples' χ² is what the noise alone leaves: within this many sd (√(2n)) of the n samples.
#: A wrong valley can leave less than ``GOOD_MISFIT`` of a large peak (0.38 % of 104 N, χ² 326 for 268 samples,
#: 2.7 sd, where the right pair left χ² 269).
NOISE_CHI2_SD = 2.0
#: Separations whose χ² lie within this of the least are alike (3 sd of one parameter): the data cannot choose
#: between them, the lane's restitution does (``_implausibility``).
ALIKE_CHI2 = 9.0
#: A part's restitution may lie this far below the lane's fruit before it counts as implausible (the lot's
#: spread of e: c varies ±25 % between fruit, e by ±0.1 at e ≈ 0.6).
RESTITUTION_SPREAD = 0.12


class _TwoPulses:
    """F(t; θ_A) + F(t; θ_B) and its Jacobian (the fitted model, for residuals and the separated forces)."""

    def __init__(self, t: np.ndarray):
        self.first, self.second = PulseModel(t), PulseModel(t)

    def __call__(self, theta, jacobian: bool = False):
        if not jacobian:
            return self.first.pulse(theta[:4]).copy() + self.second.pulse(theta[4:])
        fa, ja = self.first.pulse(theta[:4], True)
        fb, jb = self.second.pulse(theta[4:], True)
        return fa + fb, np.hstack([ja, jb])


def split_contact(time, force, noise: float, *, velocity=None, mass=None, diameter=None, poisson=None,
                  restitution=None, expected=(), fits: int = FITS, dip: bool = True):
    """Fit two pulses to one contact (module docstring).

    ``time`` [s] and ``force`` [N] are the contact's window (baseline removed), ``noise`` the noise sd [N];
    ``velocity`` or ``mass`` and ``diameter``/``poisson`` as for ``fit.fit_impact`` (applied to both).
    ``restitution``: the lane's typical fruit restitution, when known, to choose between separations that fit
    alike; ``expected``: the pulses one of the two may be (``rebounds.expected_rebound`` of each earlier contact
    whose rebound is due), each as Gaussian priors on its peak, duration and x (module docstring); ``fits``: how
    many of the best starts are fitted; ``dip``: the force falls and rises again (the landmarks then give the
    first start; without a dip, landmarks found in the noise would only waste a fit).
    Returns ((result_A, separated force A), (result_B, separated force B)) in time order, each result a dict
    with the keys of ``fit.RESULT_KEYS``, or None when the contact is not separated."""
    t = np.asarray(time, dtype=float)
    y = np.asarray(force, dtype=float)
    if t.size < 24 or not noise > 0:
        return None
    t_ref = float(t[0])
    ts = t - t_ref
    model = _TwoPulses(ts)
    weights = np.full(ts.shape, 1.0 / noise)
    args = (velocity if mass is None else None, mass, diameter, poisson)
    found = []
    for theta, prior in joint_starts(ts, y, noise, landmarks(y) if dip else None, expected, fits):
        fit = _separated(model, ts, y, noise, weights, theta, prior)
        if fit is None:
            continue
        found.append(fit)
        prior_chi2 = prior.chi2(fit[2]) if prior is not None else math.inf
        if prior_chi2 <= PLAUSIBLE_PRIOR_CHI2 and fit[1] <= GOOD_MISFIT \
                and fit[0] - prior_chi2 <= ts.size + NOISE_CHI2_SD * math.sqrt(2.0 * ts.size):
            break  # it leaves only the noise and one pulse is the rebound that was due: taken (latency)
    if not found:
        return None
    # the least χ² (with a rebound due, the posterior: the data's χ² and the prior's); of fits alike in it, the one
    # whose restitutions are plausible for the lane (two fits of a fruit and a due rebound 3.5 ms later on a noisy
    # line: χ² 374.6 with the fruit at e 0.30, 377.3 with it at 0.57, the lane's fruit at 0.55)
    least = min(fit[0] for fit in found)
    alike = [fit for fit in found if fit[0] <= least + ALIKE_CHI2]
    best = min(alike, key=lambda fit: (_implausibility(fit[2], restitution), fit[0]))
    _, _, theta, covariance, rms, iterations = best
    try:
        return _parts(theta, covariance, args, t_ref, ts, rms, noise, iterations, model, y)
    except (OverflowError, ValueError, np.linalg.LinAlgError):  # a part beyond double precision: not separated
        return None


def _implausibility(theta, restitution) -> float:
    """How far the parts' restitutions fall below the lane's fruit (0 without a lane value): a fruit has the
    restitution of the lane's fruit and a rebound, landing slower, a higher one (x = c V is smaller), so a part
    far below it is the other pulse's tail traded for its amplitude."""
    if restitution is None:
        return 0.0
    return sum(max(0.0, restitution - RESTITUTION_SPREAD - restitution_of_x(float(x))) for x in theta[3::4])


def _separated(model, ts, y, noise, weights, theta, prior=None):
    """(χ², misfit, θ, covariance, rms, iterations) of the joint fit started at ``theta`` when it is accepted
    (module docstring), else None."""
    with np.errstate(all="ignore"):  # a trial step far out (a duration of e^700) is a failed separation
        theta, jac, _, iterations, converged, _ = fit_pulse_sum(
            ts, y, weights, theta, *((prior.index, prior.mean, prior.weight) if prior is not None else ()),
            max_iterations=SPLIT_ITERATIONS)
    if not np.all(np.isfinite(theta)):
        return None
    try:  # a degenerate pulse (a peak or duration beyond double precision) is a failed separation
        with np.errstate(all="ignore"):
            residual = model(theta) - y
            rms = float(np.sqrt(np.mean(residual ** 2)))
            peaks = math.exp(theta[1]), math.exp(theta[5])
            misfit = math.sqrt(max(rms ** 2 - noise ** 2, 0.0)) / max(peaks)
            durations = math.exp(theta[2]), math.exp(theta[6])
            # the window may end a little before the last pulse does (cut before the next contact's rise):
            # its last 15 % carries ~2 % of the impulse, so the fit still sees the whole pulse
            late = max(theta[0] + durations[0] - ts[-1], theta[4] + durations[1] - ts[-1], 0.0)
            if not (converged and misfit <= MISFIT_LIMIT and ts[0] <= theta[0] < theta[4]
                    and late <= END_ALLOWANCE * min(durations)
                    and min(peaks) > MIN_PEAK_SNR * noise and theta[3] < X_MAX and theta[7] < X_MAX):
                return None
            # the posterior: the samples and, with a rebound due, what physics expects of it (the fruit piece is
            # then determined given that the other pulse is that rebound; the rebound piece's own values are
            # drawn toward the expected ones within their spread, so its rebound test confirms consistency)
            covariance = np.linalg.inv(jac.T @ jac)
            chi2 = float(np.sum((residual / noise) ** 2)) + (prior.chi2(theta) if prior is not None else 0.0)
            return chi2, misfit, theta, covariance, rms, iterations
    except (OverflowError, ValueError, np.linalg.LinAlgError):
        return None


def _parts(theta, covariance, args, t_ref, ts, rms, noise, iterations, model, y):
    """The two results and separated forces of a joint fit (``split_contact``)."""
    out = []
    for k, (lo, hi) in enumerate(((0, 4), (4, 8))):
        part = theta[lo:hi]
        result = {name: math.nan for name in RESULT_KEYS}
        result.update(named_result(part, covariance[lo:hi, lo:hi], args, t_ref))
        inside = int(np.count_nonzero((ts > part[0]) & (ts < part[0] + math.exp(part[2]))))
        if not all(math.isfinite(result[name]) for name in ("peak_force", "contact_duration", "restitution")):
            raise ValueError("a part without a finite peak, duration or restitution")
        result.update(fit_residual=rms, fit_residual_relative=rms / result["peak_force"], noise=noise,
                      samples_in_contact=inside, converged=True, iterations=int(iterations),
                      message="converged; one of two pulses in one contact, fitted together")
        other = (model.second.pulse(theta[4:]) if k == 0 else model.first.pulse(theta[:4])).copy()
        out.append((result, y - other))
    return tuple(out)
