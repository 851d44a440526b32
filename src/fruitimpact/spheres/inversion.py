"""A sphere's reading → the impact that made it: velocity, equivalent drop, restitution, surface modulus.

The sphere's impact on a flat surface is a Hunt–Crossley impact of its mass m and radius R on the Hertz
contact of its own stiffness in series with the surface's (``spheres.pulse``, ``spheres.devices``).  A
reading is the peak acceleration a_max = F_max/m, the velocity change ΔV = (1 + e) V and, where the
device logs it, the contact duration T.  Three readings fix the three unknowns:

1. e from Π = ΔV/(a_max T), which depends on e alone (``spheres.pulse``); without T, e is the user's
   (``restitution``): (a_max, ΔV) alone leave a line of (V, E, e), e.g. 92 g and 1.58 m/s fit a 5 cm drop
   at e = 0.6 and a 7.5 cm drop at e = 0.3 (docs/tasks/sphere.md);
2. V = ΔV/(1 + e) and the equivalent drop height h = V²/(2 g), mass-independent, so it carries over to the
   fruit;
3. the Hertz stiffness K from a_max (``stiffness_from_peak``), E* = 3K/(4√R) and the surface's compliance
   (1 − ν_w²)/E_w = 1/E* − 1/E*_s, with ν_w = 0.3 unless given.

Which solution.  Three readings, three unknowns: where the exact solution is physical (e in (0, 1], a surface
no stiffer than rigid) it is the answer, so clean readings give back the impact exactly.  Where noise makes it
unphysical — a contact stiffer than the sphere's own on a rigid plate, or a pulse slightly shorter than an
elastic one — the answer is the most likely physical one on the boundary: the surface rigid (the contact is the
sphere's own, so peak and ΔV fix e by themselves, and the duration adds what it can, as an interval of ± half a
logger sample) or e = 1 (``_solve_rigid``).  This constrained maximum likelihood matters on stiff surfaces, where
half the noisy readings fall on the wrong side of "rigid".

Uncertainty.  Each reading has a relative standard uncertainty (2 % by default), a logged duration also the
rounding to the logger's sample period Δt, taken as a bound (± Δt/2: it is the same at every pass of a short
pulse, not a random error).  The 95 % interval of e is that of Π = ΔV/(a_max T) (± 1.96 σ and ± Δt/2) mapped
through the monotone e(Π), clipped at e = 1 — or, on the rigid boundary, the profile-likelihood interval of the
refit (Δ(−2 ln L) ≤ 3.84); V and h combine it with ΔV's own.  The surface's compliance C = 1/E* − 1/E*_s is
propagated to first order (each reading moved by ± its uncertainty, the half-differences in quadrature) with
the uncertainty of the sphere's own E*_s (a calibration's), and E_w = (1 − ν_w²)/C.

Honesty.  A surface whose compliance cannot be told from 0 at 95 % (C < 1.96 σ_C) is rigid to this sphere: its
modulus is not reported (``NaN``, JSON null) but bounded from below.  A reading no (V, E, e) reproduces is
``unreproduced`` with its residual: a pulse shorter than an elastic one (Π above 0.5436 beyond the readings'
uncertainty), an impact deader than e = 0.005, or a contact stiffer than the sphere's own on a rigid plate
beyond the readings' uncertainty.

References: Hunt & Crossley 1975, J. Appl. Mech. 42:440; Johnson 1985, Contact Mechanics, eqs 4.22–4.23;
the founding paper, "Theoretical aspects about simulating the reaction to impact of apples on rigid plane
surfaces", eqs 5–9.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fruitimpact.physics.constants import STANDARD_GRAVITY
from fruitimpact.spheres.devices import Sphere
from fruitimpact.spheres.pulse import E_MIN, pulse_table, stiffness_from_peak

#: Relative standard uncertainty of each reading by default (peak, ΔV, duration): a device's stated error is
#: ~0.5–5 % of reading (Smart Berry 0.53 % of span; BIRD ΔV < 5 %), see docs/tasks/sphere.md.
DEFAULT_UNCERTAINTY = 0.02
#: Coverage factor of the intervals (95 %, normal).
Z95 = 1.96
#: Poisson ratio of the surface unless given (a half-space of a polymer or metal).
SURFACE_POISSON = 0.3
#: Status codes of a reading.
OK, UNREPRODUCED = 0, 1
STATUS_NAMES = ("ok", "unreproduced")


@dataclass(frozen=True)
class Inversion:
    """Per reading (arrays): the impact that reproduces it, with 95 % intervals, its status and message.

    ``velocity`` [m/s], ``drop_height`` [m], ``restitution`` [-], ``contact_modulus`` E* [Pa],
    ``surface_modulus`` E_w [Pa] (NaN: rigid to this sphere, or not reproduced), ``rigid`` (bool),
    ``surface_share`` s [-], ``residual`` (the relative misfit of the reading the model could not meet; 0 when
    reproduced), ``status`` (codes of ``STATUS_NAMES``), ``message`` (list of str), and ``X_low``/``X_high``
    for velocity, drop_height, restitution and surface_modulus."""

    velocity: np.ndarray
    drop_height: np.ndarray
    restitution: np.ndarray
    contact_modulus: np.ndarray
    surface_modulus: np.ndarray
    rigid: np.ndarray
    surface_share: np.ndarray
    residual: np.ndarray
    status: np.ndarray
    message: list
    bounds: dict

    def row(self, i: int) -> dict:
        """Reading ``i`` as a dict (NaN where unknown)."""
        out = {name: float(getattr(self, name)[i]) for name in
               ("velocity", "drop_height", "restitution", "contact_modulus", "surface_modulus", "surface_share",
                "residual")}
        out.update({name: float(values[i]) for name, values in self.bounds.items()})
        out.update(rigid=bool(self.rigid[i]), status=STATUS_NAMES[int(self.status[i])], message=self.message[i])
        return out


def _solve(sphere: Sphere, peak, change, duration, restitution):
    """(e, V, E*, Π) of each reading, e clipped to [E_MIN, 1] (the caller judges the clipping)."""
    table = pulse_table()
    if restitution is None:
        pi = change / (peak * duration)
        e = table.restitution(np.clip(pi, table.pi[0], table.pi[-1]))
    else:
        pi = np.full_like(peak, np.nan)
        e = np.broadcast_to(np.asarray(restitution, dtype=float), peak.shape).copy()
    velocity = change / (1.0 + e)
    stiffness = stiffness_from_peak(e, sphere.mass, velocity, sphere.mass * peak)
    contact = 0.75 * stiffness / math.sqrt(sphere.radius)
    return e, velocity, contact, pi


def _rigid_misfit(sphere: Sphere, peak, change, duration, u_q, u_pi, sample_period):
    """−2 ln L of readings on a surface rigid to the sphere, as a function of ln e (broadcast against the readings):
    the contact is the sphere's own (K = K_s), so q = a m^(2/5) K^(-2/5) ΔV^(-6/5) = f(e)/(1 + e)^(6/5) (peak and
    ΔV) and Π = ΔV/(a T) = Π(e) (the duration) each give e; each misfit in ln is weighted by its readings' relative
    variance (``u_q``, ``u_pi``).  A duration counted in samples of ``sample_period`` Δt is an interval: within
    ± Δt/2 of the reading its misfit is 0."""
    table = pulse_table()
    stiffness = 4.0 / 3.0 * sphere.contact_modulus * math.sqrt(sphere.radius)
    log_q = np.log(peak * sphere.mass ** 0.4 * stiffness ** -0.4 * change ** -1.2)
    log_pi = np.log(change / (peak * duration))
    half = 0.5 * sample_period / duration

    def misfit(log_e):
        e = np.exp(log_e)
        model_q = np.log(table.force(e)) - 1.2 * np.log1p(e)
        timing = np.maximum(np.abs(log_pi - np.log(table.group(e))) - half, 0.0)  # ln T_model/T = ln Π/Π(e)
        return ((log_q - model_q) / u_q) ** 2 + (timing / u_pi) ** 2

    return misfit


#: Nodes in ln e of the profile-likelihood interval of the rigid refit (every 5th of the pulse table's).
_PROFILE_STRIDE = 5
#: Readings per block of that profile (nodes × readings floats at a time).
_PROFILE_BLOCK = 2048


def _solve_rigid(sphere: Sphere, peak, change, duration, u_q, u_pi, sample_period):
    """(e, e_low, e_high) of readings on a surface rigid to the sphere: the e of least misfit (``_rigid_misfit``),
    found on the table's nodes in ln e and refined by golden-section steps in the bracketing cells, and its
    95 % profile-likelihood interval {e : misfit − min ≤ 3.84}."""
    table = pulse_table()
    nodes = table.log_e[::_PROFILE_STRIDE]
    e = np.empty(peak.shape)
    low_e, high_e = np.empty(peak.shape), np.empty(peak.shape)
    for start in range(0, peak.size, _PROFILE_BLOCK):
        part = slice(start, start + _PROFILE_BLOCK)
        misfit = _rigid_misfit(sphere, peak[part], change[part], duration[part], u_q, u_pi, sample_period)
        values = misfit(nodes[:, None])  # nodes × readings
        best = np.argmin(values, axis=0)
        low = nodes[np.maximum(best - 1, 0)]
        high = nodes[np.minimum(best + 1, nodes.size - 1)]
        ratio = (math.sqrt(5.0) - 1.0) / 2.0
        for _ in range(40):  # golden section: the bracket shrinks to 0.618^40 of two cells, ~1e-10 in ln e
            a = high - ratio * (high - low)
            b = low + ratio * (high - low)
            left = misfit(a) <= misfit(b)
            high = np.where(left, b, high)
            low = np.where(left, low, a)
        log_e = 0.5 * (low + high)
        e[part] = np.exp(log_e)
        inside = values - misfit(log_e)[None, :] <= Z95 ** 2
        first = np.argmax(inside, axis=0)
        last = nodes.size - 1 - np.argmax(inside[::-1], axis=0)
        # the interval's ends between nodes: one node outward (a conservative grid of 0.7 % in e)
        low_e[part] = np.exp(np.minimum(nodes[np.maximum(first - 1, 0)], log_e))
        high_e[part] = np.exp(np.maximum(nodes[np.minimum(last + 1, nodes.size - 1)], log_e))
    return e, low_e, high_e


def invert(sphere: Sphere, peak_acceleration, velocity_change, duration=None, *, restitution=None,
           surface_poisson: float = SURFACE_POISSON, uncertainty=DEFAULT_UNCERTAINTY,
           sample_period: float = 0.0) -> Inversion:
    """Invert readings of ``sphere``: the impact velocity, equivalent drop, restitution and surface modulus.

    Parameters
    ----------
    sphere : Sphere
    peak_acceleration : array_like
        a_max [m/s²] (a reading in g times 9.80665).
    velocity_change : array_like
        ΔV = V_in + V_out [m/s].
    duration : array_like, optional
        Contact duration T [s]; NaN where a reading has none.  Without it ``restitution`` is needed.
    restitution : float or array_like, optional
        e of the impacts, for readings without a duration (the user's; a duration, where given, wins).
    surface_poisson : float
        ν_w of the surface [-] (0.3).
    uncertainty : float or (float, float, float)
        Relative standard uncertainty of (a_max, ΔV, T) [-] (0.02), each > 0.
    sample_period : float
        The logger's sample period Δt [s]: a logged duration is rounded to it (± Δt/2).

    Returns
    -------
    Inversion
    """
    table = pulse_table()
    peak = np.atleast_1d(np.asarray(peak_acceleration, dtype=float))
    change = np.broadcast_to(np.asarray(velocity_change, dtype=float), peak.shape).astype(float)
    span = np.full(peak.shape, np.nan) if duration is None else \
        np.broadcast_to(np.asarray(duration, dtype=float), peak.shape).astype(float)
    timed = np.isfinite(span)
    if not timed.all() and restitution is None:
        raise ValueError("restitution is needed for readings without a duration: peak acceleration and velocity "
                         "change alone fit a line of (drop height, restitution)")
    u_peak, u_change, u_duration = (uncertainty,) * 3 if np.isscalar(uncertainty) else uncertainty
    if not min(u_peak, u_change, u_duration) > 0.0:
        raise ValueError(f"uncertainty must be > 0 (a reading is never exact); got {uncertainty!r}")
    given_e = np.full(peak.shape, np.nan) if restitution is None else \
        np.broadcast_to(np.asarray(restitution, float), peak.shape).astype(float)
    u_sphere = sphere.contact_modulus_sd

    def solve(a, dv, t):
        e_t, v_t, c_t, pi = _solve(sphere, a, dv, np.where(timed, t, 1.0), None)
        if timed.all():
            return e_t, v_t, c_t, pi
        e_g, v_g, c_g, _ = _solve(sphere, a, dv, None, np.where(timed, 1.0, given_e))
        return (np.where(timed, e_t, e_g), np.where(timed, v_t, v_g), np.where(timed, c_t, c_g),
                np.where(timed, pi, np.nan))

    # the exact solution, and its surface compliance C = 1/E* − 1/E*_s with C's first-order uncertainty
    e, velocity, contact, pi = solve(peak, change, span)
    compliance = 1.0 / contact - 1.0 / sphere.contact_modulus
    spread = np.zeros(peak.shape)
    for k, relative in enumerate((u_peak, u_change, u_duration)):
        if k == 2 and not timed.any():
            continue
        ends = []
        for sign in (1.0, -1.0):
            moved = [peak, change, span]
            moved[k] = moved[k] * (1.0 + sign * relative)
            ends.append(1.0 / solve(*moved)[2])
        spread += (0.5 * (ends[0] - ends[1])) ** 2
    sd_compliance = np.sqrt(spread + (u_sphere / sphere.contact_modulus) ** 2)
    # the duration's rounding to the logger's samples is a bound, the same at every pass: its range is added
    # to the 95 % half-width, not in quadrature (``rounding``: C's half-range over T ± Δt/2)
    rounding = np.zeros(peak.shape)
    if sample_period > 0.0 and timed.any():
        longer = 1.0 / solve(peak, change, span + 0.5 * sample_period)[2]
        shorter = 1.0 / solve(peak, change, np.maximum(span - 0.5 * sample_period, 0.5 * span))[2]
        rounding = np.where(timed, 0.5 * np.abs(longer - shorter), 0.0)
    margin = Z95 * sd_compliance + rounding  # C's 95 % half-width

    status = np.zeros(peak.shape, dtype=np.int8)
    residual = np.zeros(peak.shape)
    messages = [""] * peak.size
    sigma_pi = math.sqrt(u_peak ** 2 + u_change ** 2 + u_duration ** 2)  # relative, of Π = ΔV/(a T)
    half = np.where(timed, 0.5 * sample_period / np.where(timed, span, 1.0), 0.0)  # the rounding, relative
    elastic, dead = table.pi[-1], table.pi[0]
    allowed = np.exp(Z95 * sigma_pi) / np.maximum(1.0 - half, 1e-9) - 1.0  # Π's 95 % excess over the elastic
    excess = pi / elastic - 1.0
    for i in np.flatnonzero(timed & (excess > allowed)):
        status[i], residual[i] = UNREPRODUCED, excess[i]
        messages[i] = (f"no impact reproduces this reading: the pulse is {excess[i]:.1%} shorter than the elastic "
                       f"Hertz pulse of the same peak and ΔV (ΔV/(a·T) = {pi[i]:.4f} > {elastic:.4f}, beyond the "
                       f"readings' 95 % uncertainty {allowed[i]:.1%}): a duration too short or a peak too low")
    for i in np.flatnonzero(timed & (pi < dead * np.exp(-Z95 * sigma_pi) * (1.0 - half))):
        status[i], residual[i] = UNREPRODUCED, pi[i] / dead - 1.0
        messages[i] = (f"no impact reproduces this reading: ΔV/(a·T) = {pi[i]:.4g} is below that of any impact "
                       f"with e >= {E_MIN} ({dead:.4g}), by {-residual[i]:.1%}: a duration too long or a peak too "
                       f"high for a single impact")
    stiffer = (status == OK) & (compliance < -margin)
    for i in np.flatnonzero(stiffer):
        share = compliance[i] * contact[i]
        status[i], residual[i] = UNREPRODUCED, -share
        messages[i] = (f"no impact reproduces this reading: it needs a contact {-share:.1%} stiffer than the "
                       f"sphere's own on a rigid plate (E* = {contact[i] / 1e6:.4g} MPa > E*_s = "
                       f"{sphere.contact_modulus / 1e6:.4g} MPa, beyond the readings' 95 % uncertainty): the "
                       f"sphere's stiffness ({sphere.stiffness_source}) or the reading is wrong")
    ok = status == OK
    rigid = ok & (compliance < margin)

    # e and its 95 % interval: from Π where the exact solution is physical, on the boundary where it is not
    pi_low = pi * np.exp(-Z95 * sigma_pi) / (1.0 + half)
    pi_high = pi * np.exp(Z95 * sigma_pi) / np.maximum(1.0 - half, 1e-9)
    e_low = np.where(timed, table.restitution(np.clip(pi_low, dead, elastic)), given_e)
    e_high = np.where(timed, table.restitution(np.clip(pi_high, dead, elastic)), given_e)
    boundary = np.flatnonzero(ok & timed & ((compliance < 0.0) | (pi > elastic)))
    if boundary.size:
        u_q = math.sqrt(u_peak ** 2 + (1.2 * u_change) ** 2)
        u_pi = math.sqrt(u_peak ** 2 + u_change ** 2 + u_duration ** 2)
        refit, refit_low, refit_high = _solve_rigid(sphere, peak[boundary], change[boundary], span[boundary], u_q,
                                                    u_pi, sample_period)
        soft = compliance[boundary] >= 0.0  # a pulse just beyond the elastic one on a measurable surface: e = 1
        e[boundary] = np.where(soft, 1.0, refit)
        e_low[boundary] = np.where(soft, e_low[boundary], refit_low)
        e_high[boundary] = np.where(soft, 1.0, refit_high)
        velocity[boundary] = change[boundary] / (1.0 + e[boundary])
        for i, was_soft in zip(boundary, soft):
            messages[i] = ("elastic within the readings' precision: e = 1 taken" if was_soft else
                           f"the exact solution is unphysical (a contact {-compliance[i] * contact[i]:.1%} stiffer "
                           f"than the sphere's own, within the readings' uncertainty): solved as rigid, e from "
                           f"peak and ΔV with the duration as an interval")
        contact[boundary] = np.where(soft, contact[boundary], sphere.contact_modulus)
        compliance[boundary] = np.where(soft, compliance[boundary], 0.0)

    compliance_factor = 1.0 - surface_poisson ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        modulus = np.where(rigid | ~ok, np.nan, compliance_factor / compliance)
        compliance_high = np.maximum(compliance, 0.0) + margin
        compliance_low = compliance - margin
        modulus_low = np.where(ok, compliance_factor / compliance_high, np.nan)
        modulus_high = np.where(rigid | ~ok, np.nan,
                                np.where(compliance_low > 0.0, compliance_factor / compliance_low, np.inf))
    for i in np.flatnonzero(rigid):
        prefix = messages[i] + "; " if messages[i] else ""
        messages[i] = (f"{prefix}rigid to this sphere: the surface's share of the contact compliance, "
                       f"{max(compliance[i], 0.0) * contact[i]:.1%} ± {margin[i] * contact[i]:.1%} "
                       f"(95 %), cannot be told from 0; its modulus is above {modulus_low[i] / 1e6:.4g} MPa (95 %) "
                       f"and is not reported")
    for i in np.flatnonzero(~timed):
        messages[i] = (messages[i] + "; " if messages[i] else "") + \
            f"no duration: e = {given_e[i]:.3g} as given (--sphere-restitution), not measured"
    height = velocity ** 2 / (2.0 * STANDARD_GRAVITY)
    # ln V = ln ΔV − ln(1 + e): e's interval (asymmetric, clipped at 1) and ΔV's own, in quadrature
    spread_change = Z95 * u_change
    lnv_low = np.log(velocity) - np.hypot(np.log1p(e_high) - np.log1p(e), spread_change)
    lnv_high = np.log(velocity) + np.hypot(np.log1p(e) - np.log1p(e_low), spread_change)
    bounds = {
        "velocity_low": np.exp(lnv_low), "velocity_high": np.exp(lnv_high),
        "drop_height_low": np.exp(2.0 * lnv_low) / (2.0 * STANDARD_GRAVITY),
        "drop_height_high": np.exp(2.0 * lnv_high) / (2.0 * STANDARD_GRAVITY),
        "restitution_low": e_low, "restitution_high": e_high,
        "surface_modulus_low": modulus_low, "surface_modulus_high": modulus_high,
    }
    bad = ~ok
    bounds = {name: np.where(bad, np.nan, values) for name, values in bounds.items()}
    return Inversion(np.where(bad, np.nan, velocity), np.where(bad, np.nan, height), np.where(bad, np.nan, e),
                     np.where(bad, np.nan, contact), modulus, rigid, np.where(bad, np.nan, compliance * contact),
                     residual, status, messages, bounds)


__all__ = ["DEFAULT_UNCERTAINTY", "Inversion", "STATUS_NAMES", "SURFACE_POISSON", "invert"]
