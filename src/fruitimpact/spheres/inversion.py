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

Uncertainty.  Each reading has a relative standard uncertainty (2 % by default) and a logged duration also
the rounding to the logger's sample period Δt (uniform, Δt/√12).  Each is propagated by solving again at
the reading ± its uncertainty; the half-differences add in quadrature (first order, and exact for the
clipping at e = 1).  Intervals are 95 % (± 1.96 σ; in ln for V, h and E).

Honesty.  A surface whose compliance share s = 1 − E*/E*_s is not distinguishable from 0 at 95 % is rigid
to this sphere: its modulus is not reported (``NaN``, JSON null) but bounded from below.  A reading no
(V, E, e) reproduces is ``unreproduced`` with its residual: a pulse shorter than an elastic one
(Π above 0.5436 beyond the readings' uncertainty), an impact deader than e = 0.005, or a contact stiffer than
the sphere's own on a rigid plate.

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


def _solve_rigid(sphere: Sphere, peak, change, duration, u_q, u_pi, sample_period=0.0):
    """(e, V) of readings on a surface rigid to the sphere, where the contact is the sphere's own (K = K_s known):
    peak and ΔV then fix e by themselves, through q = a m^(2/5) K^(-2/5) ΔV^(-6/5) = f(e)/(1 + e)^(6/5), and the
    duration adds Π = ΔV/(a T) = Π(e).  e minimises the sum of both squared misfits in ln, each weighted by its
    readings' relative variance (``u_q``, ``u_pi``; arrays): the maximum-likelihood e under the readings' stated
    uncertainties.  A duration counted in samples of ``sample_period`` Δt is an interval, not a value: within
    ± Δt/2 of the reading its misfit is 0 (the uniform rounding error is not a Gaussian one: weighting it as
    Δt/√12 let the rounding of a short pulse, the same at every pass, bias e).  Found by a grid of 64 nodes in
    ln e, then golden-section steps in the bracketing cell."""
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

    nodes = np.linspace(table.log_e[0], 0.0, 64)
    values = np.stack([misfit(np.full(peak.shape, node)) for node in nodes])
    best = np.argmin(values, axis=0)
    low, high = nodes[np.maximum(best - 1, 0)], nodes[np.minimum(best + 1, nodes.size - 1)]
    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    for _ in range(40):  # golden section: the bracket shrinks to 0.618^40 of two cells, ~1e-9 in ln e
        a = high - ratio * (high - low)
        b = low + ratio * (high - low)
        left = misfit(a) <= misfit(b)
        high = np.where(left, b, high)
        low = np.where(left, low, a)
    e = np.exp(0.5 * (low + high))
    return e, change / (1.0 + e)


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
        Relative standard uncertainty of (a_max, ΔV, T) [-] (0.02).
    sample_period : float
        The logger's sample period Δt [s]: a logged duration is rounded to it (uncertainty Δt/√12).

    Returns
    -------
    Inversion
    """
    peak = np.atleast_1d(np.asarray(peak_acceleration, dtype=float))
    change = np.broadcast_to(np.asarray(velocity_change, dtype=float), peak.shape).astype(float)
    timed = np.zeros(peak.shape, bool) if duration is None else np.isfinite(
        np.broadcast_to(np.asarray(duration, dtype=float), peak.shape))
    span = np.where(timed, np.nan if duration is None else np.broadcast_to(np.asarray(duration, float), peak.shape),
                    np.nan)
    if not timed.all() and restitution is None:
        raise ValueError("restitution is needed for readings without a duration: peak acceleration and velocity "
                         "change alone fit a line of (drop height, restitution)")
    u_peak, u_change, u_duration = (uncertainty,) * 3 if np.isscalar(uncertainty) else uncertainty
    u_time = np.sqrt(u_duration ** 2 + (sample_period / np.where(timed, span, 1.0)) ** 2 / 12.0)
    given_e = np.full(peak.shape, np.nan) if restitution is None else \
        np.broadcast_to(np.asarray(restitution, float), peak.shape).astype(float)

    def solve(a, dv, t):
        e_t, v_t, c_t, pi = _solve(sphere, a, dv, np.where(timed, t, 1.0), None)
        e_g, v_g, c_g, _ = _solve(sphere, a, dv, None, np.where(timed, 1.0, given_e)) if not timed.all() \
            else (e_t, v_t, c_t, pi)
        return (np.where(timed, e_t, e_g), np.where(timed, v_t, v_g), np.where(timed, c_t, c_g),
                np.where(timed, pi, np.nan))

    e, velocity, contact, pi = solve(peak, change, span)
    share = 1.0 - contact / sphere.contact_modulus
    # first-order propagation: each reading moved by ± its uncertainty, the half-differences in quadrature
    spread = {name: np.zeros(peak.shape) for name in ("e", "lnv", "share")}
    for k, relative in enumerate((u_peak, u_change, u_time)):
        if k == 2 and not timed.any():
            continue
        ends = []
        for sign in (1.0, -1.0):
            moved = [peak, change, span]
            moved[k] = moved[k] * (1.0 + sign * relative)
            ends.append(solve(*moved))
        (e1, v1, c1, _), (e2, v2, c2, _) = ends
        spread["e"] += (0.5 * (e1 - e2)) ** 2
        spread["lnv"] += (0.5 * np.log(v1 / v2)) ** 2
        spread["share"] += (0.5 * ((1.0 - c1 / sphere.contact_modulus) - (1.0 - c2 / sphere.contact_modulus))) ** 2
    sd = {name: np.sqrt(value) for name, value in spread.items()}
    pi_sd = np.sqrt(u_peak ** 2 + u_change ** 2 + u_time ** 2)  # relative, of Π = ΔV/(a T)

    table = pulse_table()
    status = np.zeros(peak.shape, dtype=np.int8)
    residual = np.zeros(peak.shape)
    messages = [""] * peak.size
    elastic, dead = table.pi[-1], table.pi[0]
    for i in np.flatnonzero(timed & (pi > elastic)):
        excess = pi[i] / elastic - 1.0
        if excess <= Z95 * pi_sd[i]:
            messages[i] = (f"elastic within the readings' precision: ΔV/(a·T) = {pi[i]:.4f} exceeds the elastic "
                           f"Hertz pulse's {elastic:.4f} by {excess:.1%}, within their 95 % uncertainty "
                           f"{Z95 * pi_sd[i]:.1%}; e = 1 taken")
        else:
            status[i], residual[i] = UNREPRODUCED, excess
            messages[i] = (f"no impact reproduces this reading: the pulse is {excess:.1%} shorter than the elastic "
                           f"Hertz pulse of the same peak and ΔV (ΔV/(a·T) = {pi[i]:.4f} > {elastic:.4f}, beyond the "
                           f"readings' 95 % uncertainty {Z95 * pi_sd[i]:.1%}): a duration too short or a peak too low")
    for i in np.flatnonzero(timed & (pi < dead)):
        status[i], residual[i] = UNREPRODUCED, pi[i] / dead - 1.0
        messages[i] = (f"no impact reproduces this reading: ΔV/(a·T) = {pi[i]:.4g} is below that of any impact "
                       f"with e >= {E_MIN} ({dead:.4g}), by {-residual[i]:.1%}: a duration too long or a peak too "
                       f"high for a single impact")
    stiffer = (status == OK) & (share < -Z95 * sd["share"]) & (share < 0.0)
    for i in np.flatnonzero(stiffer):
        status[i], residual[i] = UNREPRODUCED, -share[i]
        messages[i] = (f"no impact reproduces this reading: it needs a contact {-share[i]:.1%} stiffer than the "
                       f"sphere's own on a rigid plate (E* = {contact[i] / 1e6:.4g} MPa > E*_s = "
                       f"{sphere.contact_modulus / 1e6:.4g} MPa, beyond the readings' 95 % uncertainty "
                       f"{Z95 * sd['share'][i]:.1%}): the sphere's stiffness ({sphere.stiffness_source}) or the "
                       f"reading is wrong")
    rigid = (status == OK) & (share < Z95 * sd["share"])
    # rigid to the sphere: the contact is the sphere's own, so peak and ΔV fix e without the duration, which is
    # the least precise reading (a few samples of a logger); e from both, weighted (``_solve_rigid``)
    refit = np.flatnonzero(rigid & timed)
    if refit.size:
        u_q = math.sqrt(u_peak ** 2 + (1.2 * u_change) ** 2)
        a_r, dv_r, t_r, ut_r = peak[refit], change[refit], span[refit], u_time[refit]
        u_pi = math.sqrt(u_peak ** 2 + u_change ** 2 + u_duration ** 2)  # the rounding is the interval's
        e[refit], velocity[refit] = _solve_rigid(sphere, a_r, dv_r, t_r, u_q, u_pi, sample_period)
        spread_e, spread_v = np.zeros(refit.size), np.zeros(refit.size)
        for k, relative in enumerate((u_peak, u_change, ut_r)):
            ends = []
            for sign in (1.0, -1.0):
                moved = [a_r, dv_r, t_r]
                moved[k] = moved[k] * (1.0 + sign * relative)
                ends.append(_solve_rigid(sphere, *moved, u_q, u_pi, sample_period))
            (e1, v1), (e2, v2) = ends
            spread_e += (0.5 * (e1 - e2)) ** 2
            spread_v += (0.5 * np.log(v1 / v2)) ** 2
        sd["e"][refit], sd["lnv"][refit] = np.sqrt(spread_e), np.sqrt(spread_v)
    compliance_factor = 1.0 - surface_poisson ** 2
    share_high = share + Z95 * sd["share"]
    share_low = share - Z95 * sd["share"]
    with np.errstate(divide="ignore", invalid="ignore"):
        modulus = np.where(rigid | (status != OK), np.nan, compliance_factor * contact / share)
        modulus_low = np.where(status == OK, compliance_factor * contact / share_high, np.nan)
        modulus_high = np.where(rigid | (status != OK), np.nan,
                                np.where(share_low > 0.0, compliance_factor * contact / share_low, np.inf))
    for i in np.flatnonzero(rigid):
        prefix = messages[i] + "; " if messages[i] else ""
        messages[i] = (f"{prefix}rigid to this sphere: the surface's share of the contact compliance, "
                       f"{share[i]:.1%} ± {Z95 * sd['share'][i]:.1%} (95 %), cannot be told from 0; its modulus "
                       f"is above {modulus_low[i] / 1e6:.4g} MPa (95 %) and is not reported")
    if not timed.all():
        for i in np.flatnonzero(~timed):
            messages[i] = (messages[i] + "; " if messages[i] else "") + \
                f"no duration: e = {given_e[i]:.3g} as given (--sphere-restitution), not measured"
    height = velocity ** 2 / (2.0 * STANDARD_GRAVITY)
    spread_v = np.exp(Z95 * sd["lnv"])
    bounds = {
        "velocity_low": velocity / spread_v, "velocity_high": velocity * spread_v,
        "drop_height_low": height / spread_v ** 2, "drop_height_high": height * spread_v ** 2,
        "restitution_low": np.clip(e - Z95 * sd["e"], 0.0, 1.0), "restitution_high": np.clip(e + Z95 * sd["e"], 0.0, 1.0),
        "surface_modulus_low": modulus_low, "surface_modulus_high": modulus_high,
    }
    bad = status != OK
    for name in ("velocity_low", "velocity_high", "drop_height_low", "drop_height_high", "restitution_low",
                 "restitution_high", "surface_modulus_low", "surface_modulus_high"):
        bounds[name] = np.where(bad, np.nan, bounds[name])
    return Inversion(np.where(bad, np.nan, velocity), np.where(bad, np.nan, height), np.where(bad, np.nan, e),
                     np.where(bad, np.nan, contact), modulus, rigid, np.where(bad, np.nan, share), residual, status,
                     messages, bounds)


__all__ = ["DEFAULT_UNCERTAINTY", "Inversion", "STATUS_NAMES", "SURFACE_POISSON", "invert"]
