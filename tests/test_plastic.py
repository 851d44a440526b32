"""Tests of the elastic–plastic (Thornton) engine ``fruitimpact.engine.plastic`` and its batch path.

Every expected value here is computed independently of the engine:

* closed forms of Thornton's law (C. Thornton 1997; Thornton & Ning 1998, Powder Technol. 99:154,
  "TN98" eqs 9–44), written out again in this file from the force laws (not imported);
* SciPy's ``solve_ivp`` (DOP853, rtol 1e-12) of m δ'' = −F_T(δ)(1 + c δ'), with Thornton's
  loading/unloading history driven by F_T and an optional elastic-foundation (Winkler) layer in series
  (force found by root finding inside the right-hand side); plastic work ∮F_T dδ and viscous work
  ∫c F_T δ'² dt are integrated as states;
* ``engine.powerlaw.powerlaw_characteristics``, an independent exact method for F = K δ^1.5 (1 + c δ');
* the reference numbers of /work/shared/reference/damage-and-surfaces.md §a.2, §a.3, §e and §f (rounded
  there, so compared at their printed precision).

Known engine defects are pinned by ``xfail(strict=True)`` tests at the end (times near a kink of the
force law, and a tiny damping factor).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.special import beta as beta_function
from scipy.special import betainc

from fruitimpact.impact import evaluation as batch
from fruitimpact.engine.codes import CHARACTERISTIC_COLUMNS
from fruitimpact.engine.plastic import (
    PLASTIC_COLUMNS,
    crushing_characteristics,
    plastic_characteristics,
    yield_force,
    yield_pressure_of_force,
)
from fruitimpact.engine.powerlaw import powerlaw_characteristics

# ---------------------------------------------------------------------------------------------
# the example apple of the note (§a.2): d 75 mm, ρ 840 kg/m³, E 3 MPa, ν 0.3, p_y 0.3 MPa
# ---------------------------------------------------------------------------------------------
E, NU, D, RHO, P_Y = 3e6, 0.3, 0.075, 840.0, 0.3e6
R = D / 2.0
M = 4.0 / 3.0 * math.pi * R ** 3 * RHO  # a homogeneous sphere: the 1.5605 constant needs m = 4/3 π R³ ρ
ES = E / (1.0 - NU ** 2)  # E* of the fruit on a rigid flat (Johnson eq 4.22)
K = 4.0 / 3.0 * ES * math.sqrt(R)  # Hertz stiffness
INF = math.inf
EPS = np.finfo(float).eps
#: ∫_0^1 (1 − x^{5/2})^{−1/2} dx = (2/5) B(2/5, 1/2): the Hertz quarter-period factor (δ_max / V times it).
HERTZ_FACTOR = 0.4 * beta_function(0.4, 0.5)
#: Times (time to peak, to δ_max, contact duration) are Gauss–Legendre quadratures in the engine (24 nodes per
#: piece: measured ≤ 1e-10 where its substitutions make the integrands smooth; 5e-10 when it was tried with
#: 16); 1e-8 relative still catches a mis-substituted singular piece (such errors are ≥ 1e-7).
TIME_TOL = 1e-8
TIMES = ("time_to_peak", "time_to_max_deflection", "contact_duration")


def winkler_k_l(modulus, poisson, thickness, radius):
    """K_L = π k R, k = (1−ν)E/((1+ν)(1−2ν)h) (Simbody ElasticFoundationForce; written out here)."""
    return math.pi * (1.0 - poisson) * modulus / ((1.0 + poisson) * (1.0 - 2.0 * poisson) * thickness) * radius


def r_of(s):
    """r(s) = (s − ln(1+s))/s² (the first integral m v² r(c v) of m v' = −F(1 + c v)), written out here:
    a Taylor series Σ (−s)^k/(k+2) where the closed form cancels."""
    s = float(s)
    if abs(s) < 1e-2:
        return sum((-s) ** k / (k + 2.0) for k in range(12))
    return (s - math.log1p(s)) / (s * s)


def rebound_speed(m, c, energy):
    """w with m w² r(−c w) = energy: with z = −ln(1 − c w), c² energy/m = z + expm1(−z) (well conditioned
    as c w → 1, where the form in w is not), solved by brentq; c = 0: √(2 energy/m)."""
    if c == 0.0:
        return math.sqrt(2.0 * energy / m)
    q = c * c * energy / m
    z = brentq(lambda z: z + math.expm1(-z) - q, 0.0, q + 2.0 + math.sqrt(2.0 * q), xtol=1e-300, rtol=4 * EPS)
    return -math.expm1(-z) / c


def engine(velocity, c=0.0, p_y=P_Y, k_l=INF, h=INF, m=M, radius=R, e_star=ES):
    """One or more impacts through the engine: {column name: array} of both blocks."""
    stiffness = 4.0 / 3.0 * e_star * np.sqrt(radius)
    out, extra = plastic_characteristics(m, velocity, stiffness, radius, e_star, p_y, k_l, h, damping_factor=c)
    result = {name: out[:, j] for j, name in enumerate(CHARACTERISTIC_COLUMNS)}
    result.update({name: extra[:, j] for j, name in enumerate(PLASTIC_COLUMNS)})
    return result


def scales(ode, velocity, m=M):
    """What each ODE comparison is relative to: works to ½mV², δ_p to δ_max, e absolute (they vanish
    or are O(1) below yield), everything else to itself."""
    energy = 0.5 * m * velocity * velocity
    return {"plastic_work": energy, "viscous_work": energy, "permanent_deflection": ode["max_deflection"],
            "restitution": 1.0}


def rel(a, b):
    return np.abs(np.asarray(a, dtype=float) / np.asarray(b, dtype=float) - 1.0)


# ---------------------------------------------------------------------------------------------
# Thornton's closed forms (TN98), undamped, half-space, derived from the force laws
# ---------------------------------------------------------------------------------------------
def thornton_closed(m, V, e_star, radius, p_y):
    """Closed forms of an undamped Thornton impact (arrays in V)."""
    V = np.asarray(V, dtype=float)
    stiffness = 4.0 / 3.0 * e_star * math.sqrt(radius)
    # TN98 eq 10
    v_y = (math.pi / (2.0 * e_star)) ** 2 * math.sqrt(8.0 * math.pi * radius ** 3 / (15.0 * m)) * p_y ** 2.5
    f_y = math.pi ** 3 * p_y ** 3 * radius ** 2 / (6.0 * e_star ** 2)  # eq 16
    d_y = radius * (math.pi * p_y / (2.0 * e_star)) ** 2  # eq 14
    k_p = math.pi * p_y * radius  # eq 22, plastic stiffness
    x = v_y / V
    # eq 44, transcribed from the note
    e44 = math.sqrt(6.0 * math.sqrt(3.0) / 5.0) * np.sqrt(1.0 - x * x / 6.0) * \
        (x / (x + 2.0 * np.sqrt(6.0 / 5.0 - x * x / 5.0))) ** 0.25
    f_star = f_y * np.sqrt(6.0 / 5.0 * (V / v_y) ** 2 - 0.2)
    d_star = d_y + (f_star - f_y) / k_p  # eq 19
    a_star = np.sqrt(radius * d_star)  # a² = R α kept after yield
    r_p = 4.0 / 3.0 * e_star * a_star ** 3 / f_star  # PyGran's form of eqs 20/28: (4/3) E* a*³ / P*
    d_p = d_star - (f_star / (4.0 / 3.0 * e_star * np.sqrt(r_p))) ** (2.0 / 3.0)  # eq 29 at F = 0
    # rebound from the energy the Hertz unloading branch returns: ½ m w² = (2/5) F* (δ* − δ_p)
    e_energy = np.sqrt(0.8 * f_star * (d_star - d_p) / (m * V * V))
    w_p = 0.5 * m * V * V * (1.0 - e44 ** 2)
    # times: Hertz to δ_y (incomplete beta), harmonic plastic line to the turn, Hertz about δ_p back
    d_h = (5.0 * m * V * V / (4.0 * stiffness)) ** 0.4  # the elastic δ_max of the same impact
    t1 = d_h / V * HERTZ_FACTOR * betainc(0.4, 0.5, np.minimum((d_y / d_h) ** 2.5, 1.0))
    omega = math.sqrt(k_p / m)
    v_at_yield = np.sqrt(np.maximum(V * V - v_y * v_y, 0.0))
    t2 = np.arctan2(v_at_yield / omega, f_y / k_p) / omega
    t3 = (d_star - d_p) / (e44 * V) * HERTZ_FACTOR
    return {"v_y": v_y, "f_y": f_y, "d_y": d_y, "e44": e44, "e_energy": e_energy, "f_star": f_star,
            "d_star": d_star, "a_star": a_star, "r_p": r_p, "d_p": d_p, "w_p": w_p, "T": t1 + t2,
            "t_c": t1 + t2 + t3}


# ---------------------------------------------------------------------------------------------
# the reference integration: SciPy solve_ivp with Thornton's history (and a Winkler layer)
# ---------------------------------------------------------------------------------------------
def thornton_ode(m, V, e_star, radius, p_y, c, k_l=INF, h=INF, rtol=1e-12, crush=False):
    """Integrate m δ'' = −F_T(δ)(1 + c δ') from δ = 0, δ' = V to separation.

    Loading: Hertz to δ_y, then the plastic line; at the turn (δ' = 0) the unloading branch is Hertz with
    Thornton's R_p about δ_p; separation at F_T = 0.  With a layer, δ = δ_fruit(F) + δ_layer(F) is solved
    for F by ``brentq`` inside the right-hand side.  The integration restarts at every kink of F_T(δ)
    (yield, bottoming out) so that DOP853 only sees smooth pieces; the peak of F_T(1 + c δ') is located
    by an event on its time derivative, F_T'(δ) δ' − c F_T²/m (the sign of d/dt[F_T(1 + c δ')] when
    1 + c δ' > 0), and the peak of the centre pressure p_T (1 + c δ') likewise (half-space only).  ``crush``: the
    layer is a board whose flutes collapse at F_b = K_L h²: once the force passed F_b it stays at δ_L = h on
    unloading (it returns nothing) and the fruit alone unloads to separation at δ = δ_p + h."""
    stiffness = 4.0 / 3.0 * e_star * math.sqrt(radius)
    if p_y < INF:
        d_y = radius * (math.pi * p_y / (2.0 * e_star)) ** 2
        f_y = stiffness * d_y ** 1.5
        k_p = math.pi * p_y * radius
    else:
        d_y = f_y = k_p = INF
    layer = k_l < INF
    f_b = k_l * h * h if layer and h < INF else INF
    unloading = {}

    def d_layer(F):
        if not layer:
            return 0.0, 0.0
        if F <= f_b:
            return math.sqrt(F / k_l), (0.5 / math.sqrt(k_l * F) if F > 0.0 else INF)
        return h, 0.0

    def d_fruit_load(F):
        if F <= f_y:
            d = (F / stiffness) ** (2.0 / 3.0)
            return d, (2.0 / 3.0 * d / F if F > 0.0 else INF)
        return d_y + (F - f_y) / k_p, 1.0 / k_p

    def d_fruit_unload(F):
        d = (F / unloading["K"]) ** (2.0 / 3.0)
        return unloading["d_p"] + d, (2.0 / 3.0 * d / F if F > 0.0 else INF)

    def d_layer_unload(F):
        return (h, 0.0) if unloading.get("crushed") else d_layer(F)

    def force(delta, down):
        """(F_T, dF_T/dδ) on the loading (down False) or unloading branch."""
        if not layer:
            if down:
                x = max(delta - unloading["d_p"], 0.0)
                return unloading["K"] * x ** 1.5, 1.5 * unloading["K"] * math.sqrt(x)
            if delta <= d_y:
                x = max(delta, 0.0)
                return stiffness * x ** 1.5, 1.5 * stiffness * math.sqrt(x)
            return f_y + k_p * (delta - d_y), k_p
        fruit = d_fruit_unload if down else d_fruit_load
        board = d_layer_unload if down else d_layer

        def gap(F):
            return fruit(F)[0] + board(F)[0] - delta

        if gap(0.0) >= 0.0:
            return 0.0, 0.0
        lo, hi = 0.0, 1.0
        while gap(hi) < 0.0:
            lo, hi = hi, 4.0 * hi
        F = brentq(gap, lo, hi, xtol=1e-300, rtol=4.0 * EPS, maxiter=500)
        compliance = fruit(F)[1] + board(F)[1]
        return F, (1.0 / compliance if compliance > 0.0 else 0.0)

    def rhs(down):
        def f(t, y):
            F = force(y[0], down)[0]
            v = y[1]
            return [v, -F * (1.0 + c * v) / m, F * v, c * F * v * v]  # δ, δ', ∫F_T dδ, ∫c F_T δ'² dt
        return f

    def peak_event(t, y):
        F, slope = force(y[0], False)
        return slope * y[1] - c * F * F / m
    peak_event.direction = -1

    def pressure_event(t, y):  # d/dt[√δ (1 + c δ')] ∝ δ' − 2 c F_T δ / m on the Hertz piece
        return y[1] - 2.0 * c * force(y[0], False)[0] * y[0] / m
    pressure_event.direction = -1

    def turn(t, y):
        return y[1]
    turn.terminal, turn.direction = True, -1

    def stop_at(target, direction):
        def g(t, y):
            return y[0] - target
        g.terminal, g.direction = True, direction
        return g

    atol = [1e-18, 1e-16, 1e-20, 1e-20]
    kinks = sorted(d_fruit_load(F)[0] + d_layer(F)[0] for F in (f_y, f_b) if F < INF)
    t0, y0 = 0.0, np.array([0.0, V, 0.0, 0.0])
    forces, pressures = [], []

    def centre_pressure(y):  # half-space: Hertz p0 = (2E*/π)√(δ/R), capped at p_y (Thornton's truncated profile)
        return min(2.0 * e_star / math.pi * math.sqrt(max(y[0], 0.0) / radius), p_y) * (1.0 + c * y[1])

    for target in kinks + [INF]:
        events = [turn, peak_event, pressure_event] + ([stop_at(target, 1)] if target < INF else [])
        sol = solve_ivp(rhs(False), (t0, t0 + 10.0), y0, method="DOP853", rtol=rtol, atol=atol, events=events)
        assert sol.status == 1, sol.message
        for tt, yy in zip(sol.t_events[1], sol.y_events[1]):
            forces.append((force(yy[0], False)[0] * (1.0 + c * yy[1]), tt))
        if not layer and y0[0] < d_y:  # p_T (1 + c δ') peaks on the Hertz piece or at yield
            for tt, yy in zip(sol.t_events[2], sol.y_events[2]):
                pressures.append(centre_pressure(yy))
        t0, y0 = sol.t[-1], sol.y[:, -1].copy()
        forces.append((force(y0[0], False)[0] * (1.0 + c * y0[1]), t0))
        pressures.append(centre_pressure(y0))
        if sol.t_events[0].size:
            break
    T, d_max = t0, y0[0]
    y0[1] = 0.0
    f_star = force(d_max, False)[0]
    forces.append((f_star, T))
    if f_star > f_y:  # TN98 eqs 20/28 with a*² = R δ_fruit*
        a_star = math.sqrt(radius * (d_max - d_layer(f_star)[0]))
        r_p = 4.0 / 3.0 * e_star * a_star ** 3 / f_star
        unloading["K"] = 4.0 / 3.0 * e_star * math.sqrt(r_p)
        unloading["d_p"] = (d_max - d_layer(f_star)[0]) - (f_star / unloading["K"]) ** (2.0 / 3.0)
    else:
        unloading["K"], unloading["d_p"] = stiffness, 0.0
    unloading["crushed"] = crush and f_star > f_b
    if unloading["crushed"]:  # the board stays crushed: the fruit alone unloads, to δ_p over the board's h
        targets = [unloading["d_p"] + h]
    else:
        targets = ([d_fruit_unload(f_b)[0] + h] if f_b < f_star else []) + [unloading["d_p"]]
    for target in targets:
        sol = solve_ivp(rhs(True), (t0, t0 + 10.0), y0, method="DOP853", rtol=rtol, atol=atol,
                        events=[stop_at(target, -1)])
        assert sol.status == 1, sol.message
        t0, y0 = sol.t_events[0][0], sol.y_events[0][0].copy()
    peak, t_peak = max(forces)
    w = -y0[1]
    return {"restitution": w / V, "peak_force": peak, "time_to_peak": t_peak, "max_deflection": d_max,
            "time_to_max_deflection": T, "contact_duration": t0, "permanent_deflection": unloading["d_p"],
            "plastic_work": y0[2], "viscous_work": y0[3], "f_star": f_star, "max_pressure": max(pressures),
            "absorbed": 0.5 * m * (V * V - w * w)}


# =============================================================================================
# 1. sphere on a rigid flat, no damping: TN98's closed forms
# =============================================================================================
V_Y = (math.pi / (2.0 * ES)) ** 2 * math.sqrt(8.0 * math.pi * R ** 3 / (15.0 * M)) * P_Y ** 2.5
RATIOS = np.geomspace(1.01, 100.0, 41)


@pytest.fixture(scope="module")
def flat_batch():
    """The batch path (model hertz: undamped) at 41 log-spaced V/V_y in [1.01, 100], plus 0.9 V_y."""
    speeds = np.concatenate([RATIOS, [0.9]]) * V_Y
    frame = batch.evaluate({"mass": M, "diameter": D, "modulus": E, "poisson": NU, "velocity": speeds,
                            "yield_pressure": P_Y, "model": "hertz"})
    assert (frame["status"] == "ok").all(), frame["message"].unique()
    return speeds, frame


def test_flat_yield_velocity_and_constant(flat_batch):
    _, frame = flat_batch
    # TN98 eq 10 (written out above); the engine gets it from F_y, δ_y and its own work integral:
    # agreement to rounding, so 1e-10 relative leaves 5 orders for the operations' rounding.
    assert rel(frame["yield_velocity"], V_Y).max() < 1e-10
    # §a.2: V_y / √(p_y⁵/(E*⁴ρ)) = π²/√40 for m = 4/3 π R³ ρ (TN98 eq 11 rounds it to 1.56)
    constant = frame["yield_velocity"].to_numpy() / math.sqrt(P_Y ** 5 / (ES ** 4 * RHO))
    assert rel(constant, math.pi ** 2 / math.sqrt(40.0)).max() < 1e-10
    assert np.abs(constant - 1.5605).max() < 5e-5  # the note's 1.5605, printed to 4 decimals
    # §f's example apple, at its printed precision: V_y = 0.244216 m/s, F_y = 18.0536 N, δ_y = 0.7662 mm
    assert abs(frame["yield_velocity"].iloc[0] - 0.244216) <= 5e-7
    assert abs(yield_force(ES, R, P_Y) - 18.0536) <= 5e-5
    assert abs(R * (math.pi * P_Y / (2.0 * ES)) ** 2 * 1e3 - 0.7662) <= 5e-5


def test_flat_restitution_eq44(flat_batch):
    speeds, frame = flat_batch
    ref = thornton_closed(M, speeds[:-1], ES, R, P_Y)
    e = frame["restitution"].to_numpy()[:-1]
    # eq 44 is exact for the law (§f: ODE and closed form agree to 7e-12); 1e-8 absolute as asked,
    # measured 1e-15.
    assert np.abs(e - ref["e44"]).max() < 1e-8
    # eq 44 against the energy of the unloading branch, ½mw² = (2/5)F*(δ*−δ_p): two derivations
    assert np.abs(ref["e44"] - ref["e_energy"]).max() < 1e-13
    # the note's table (§a.3), printed to 5 decimals
    table = {1.01: 0.99998, 1.5: 0.97124, 2.0: 0.93063, 5.0: 0.77334, 10.0: 0.65856, 30.0: 0.50439, 100.0: 0.37430}
    got = engine(np.array(list(table)) * V_Y)["restitution"]
    assert np.abs(got - np.array(list(table.values()))).max() <= 5e-6


def test_flat_peaks_deflections_and_work(flat_batch):
    speeds, frame = flat_batch
    ref = thornton_closed(M, speeds[:-1], ES, R, P_Y)
    first = slice(0, -1)

    def column(name):
        return frame[name].to_numpy()[first]

    # closed forms of §a.3 (F*, α*, α_p from R_p, W_p = ½mV²(1−e²)): the engine solves W(F*) = ½mV² by
    # Newton to 1e-15, so 1e-8 relative (as asked) leaves a wide margin; measured ≤ 4e-14, and 1.5e-12
    # for W_p (the closed form's 1 − e² cancels near V_y).
    assert rel(column("peak_force"), ref["f_star"]).max() < 1e-8
    assert rel(column("max_deflection"), ref["d_star"]).max() < 1e-8
    assert rel(column("permanent_deflection"), ref["d_p"]).max() < 1e-8
    assert rel(column("plastic_work"), ref["w_p"]).max() < 1e-8
    assert rel(column("absorbed_energy"), ref["w_p"]).max() < 1e-8
    # undamped: no viscous work (rounding of absorbed − plastic only)
    assert np.abs(column("viscous_work")).max() < 1e-12 * 0.5 * M * speeds.max() ** 2
    # Thornton's truncated profile: the centre pressure is p_y once yielded; a* = √(R δ*)
    assert rel(column("max_pressure"), P_Y).max() < 1e-12
    assert rel(column("contact_radius"), ref["a_star"]).max() < 1e-8
    # the note's drop table (§e), g = 9.80665: e, F_max [N], δ_max/δ_p [mm], W_p/½mV², printed to 3–4
    # digits; compared to one unit of the last digit (its 1 m F_max 358.6 is 358.548 here: the note
    # rounds up by 0.052, not a half unit).
    table = {0.005: (0.988, 24.0, 0.94, 0.01, 0.024), 0.01: (0.946, 34.9, 1.24, 0.08, 0.106),
             0.02: (0.890, 50.1, 1.67, 0.23, 0.208), 0.05: (0.810, 79.8, 2.51, 0.64, 0.344),
             0.1: (0.750, 113.1, 3.46, 1.20, 0.438), 0.2: (0.692, 160.2, 4.79, 2.07, 0.521),
             0.5: (0.621, 253.5, 7.43, 3.97, 0.615), 1.0: (0.571, 358.6, 10.4, 6.27, 0.674)}
    V = np.sqrt(2.0 * 9.80665 * np.array(list(table)))
    got = engine(V)
    expected = np.array(list(table.values()))
    assert np.all(np.abs(got["restitution"] - expected[:, 0]) <= 1e-3)
    assert np.all(np.abs(got["peak_force"] - expected[:, 1]) <= 0.1)
    assert np.all(np.abs(got["max_deflection"] * 1e3 - expected[:, 2]) <= 0.01 + 0.09 * (expected[:, 2] >= 10))
    assert np.all(np.abs(got["permanent_deflection"] * 1e3 - expected[:, 3]) <= 0.01)
    assert np.all(np.abs(got["plastic_work"] / (0.5 * M * V * V) - expected[:, 4]) <= 1e-3)


def test_flat_below_yield_is_elastic(flat_batch):
    speeds, frame = flat_batch
    row = frame.iloc[-1]
    V = speeds[-1]
    assert abs(row["restitution"] - 1.0) < 1e-12  # asked: e = 1 to 1e-12
    assert row["permanent_deflection"] == 0.0 and row["plastic_work"] == 0.0
    # elastic Hertz in closed form: δ_max = (5mV²/4K)^{2/5}, F = K δ_max^{3/2},
    # T = (δ_max/V)(2/5)B(2/5, 1/2), t_c = 2T (Johnson §11.4); the quadrature reaches rounding: 1e-10.
    d_max = (5.0 * M * V * V / (4.0 * K)) ** 0.4
    assert rel(row["max_deflection"], d_max) < 1e-12
    assert rel(row["peak_force"], K * d_max ** 1.5) < 1e-12
    assert rel(row["time_to_max_deflection"], d_max / V * HERTZ_FACTOR) < TIME_TOL
    assert rel(row["contact_duration"], 2.0 * d_max / V * HERTZ_FACTOR) < TIME_TOL


def test_flat_times_closed_form():
    """Undamped times in closed form (Hertz incomplete beta + harmonic plastic line + Hertz unloading)
    for V/V_y in [1.5, 100] (V → V_y: the tests at the end)."""
    speeds = np.geomspace(1.5, 100.0, 25) * V_Y
    got = engine(speeds)
    ref = thornton_closed(M, speeds, ES, R, P_Y)
    # the closed forms are exact; the engine's Gauss rules: measured ≤ 3e-11 here (TIME_TOL above)
    assert rel(got["time_to_max_deflection"], ref["T"]).max() < TIME_TOL
    assert rel(got["time_to_peak"], ref["T"]).max() < TIME_TOL
    assert rel(got["contact_duration"], ref["t_c"]).max() < TIME_TOL
    # and the closed-form times agree with the ODE (checks the closed forms themselves)
    for V in speeds[[0, 12, 24]]:
        ode = thornton_ode(M, V, ES, R, P_Y, 0.0)
        assert rel(ode["time_to_max_deflection"], thornton_closed(M, V, ES, R, P_Y)["T"]) < 1e-10
        assert rel(ode["contact_duration"], thornton_closed(M, V, ES, R, P_Y)["t_c"]) < 1e-10


# =============================================================================================
# 2. two identical fruit
# =============================================================================================
def test_identical_fruit_yield_velocity_and_restitution():
    e_pair = E / (2.0 * (1.0 - NU ** 2))  # 1/E* = 2(1−ν²)/E for two identical bodies
    r_star, m_star = R / 2.0, M / 2.0
    # TN98 eq 10 with R*, m*, pair E*: V_y = √(π⁵/30) (p_y⁵ R*³/(E*⁴ m*))^{1/2} = 3.194 (…)^{1/2}; with
    # m = 4/3 π R³ ρ: (π²/√160)(p_y⁵/(E*_pair⁴ ρ))^{1/2} = 0.7803 (…)^{1/2}.  Derivation: R*³/m* =
    # (R³/8)/(2/3 π R³ ρ) = 3/(16 π ρ), and π⁵/30 · 3/(16π) = π⁴/160.
    v_y_general = math.sqrt(math.pi ** 5 / 30.0) * math.sqrt(P_Y ** 5 * r_star ** 3 / (e_pair ** 4 * m_star))
    v_y_pair = math.pi ** 2 / math.sqrt(160.0) * math.sqrt(P_Y ** 5 / (e_pair ** 4 * RHO))
    assert abs(v_y_general / v_y_pair - 1.0) < 1e-14
    assert abs(math.sqrt(math.pi ** 5 / 30.0) - 3.194) < 5e-4 and abs(math.pi ** 2 / math.sqrt(160.0) - 0.7803) < 5e-5
    ratios = np.geomspace(1.01, 100.0, 31)
    speeds = np.concatenate([ratios * v_y_pair, [0.5 * v_y_pair]])
    frame = batch.evaluate({"mass": M, "diameter": D, "modulus": E, "poisson": NU, "velocity": speeds,
                            "yield_pressure": P_Y, "surface": "fruit", "model": "hertz"})
    assert (frame["status"] == "ok").all(), frame["message"].unique()
    # the 0.7803 constant goes with the PAIR modulus: with the fruit's own E* = E/(1−ν²) (twice the pair's)
    # the same formula would be 4× smaller, and the flat's 1.5605 with the pair E* (PyGran's pitfall) 2×
    # larger.  1e-10 relative: rounding of the same operations.
    got = frame["yield_velocity"].to_numpy()
    assert rel(got, v_y_pair).max() < 1e-10
    assert rel(got, 2.0 * V_Y).max() < 1e-10  # twice the flat's for the same fruit
    assert rel(got, math.pi ** 2 / math.sqrt(160.0) * math.sqrt(P_Y ** 5 / (ES ** 4 * RHO))).min() > 1.0
    ref = thornton_closed(m_star, speeds[:-1], e_pair, r_star, P_Y)
    # e(V/V_y) follows eq 44 to 1e-8 (measured 1e-14); the rest with R*, m*, pair E*
    assert np.abs(frame["restitution"].to_numpy()[:-1] - ref["e44"]).max() < 1e-8
    assert rel(frame["peak_force"].to_numpy()[:-1], ref["f_star"]).max() < 1e-8
    assert rel(frame["max_deflection"].to_numpy()[:-1], ref["d_star"]).max() < 1e-8
    assert rel(frame["permanent_deflection"].to_numpy()[:-1], ref["d_p"]).max() < 1e-8
    assert rel(frame["plastic_work"].to_numpy()[:-1], ref["w_p"]).max() < 1e-8  # ½ m* V² (1 − e²)
    assert abs(frame["restitution"].iloc[-1] - 1.0) < 1e-12 and frame["plastic_work"].iloc[-1] == 0.0


# =============================================================================================
# 3. viscous damping: the engine against solve_ivp
# =============================================================================================
ODE_COLUMNS = ("restitution", "peak_force", "time_to_peak", "max_deflection", "time_to_max_deflection",
               "contact_duration", "permanent_deflection", "plastic_work", "viscous_work", "max_pressure")


@pytest.mark.parametrize("c", [0.3, 3.0])
@pytest.mark.parametrize("ratio", [0.5, 2.0, 4.0, 10.0, 30.0])
def test_damped_against_ode(c, ratio):
    """V/V_y away from the (damped) yield speed, 1.02 V_y at c = 0.3, 1.26 V_y at c = 3 (xfail test below)."""
    V = ratio * V_Y
    got = engine(V, c=c)
    ode = thornton_ode(M, V, ES, R, P_Y, c)
    energy = 0.5 * M * V * V
    # solve_ivp at rtol 1e-12 with restarts at the kinks reaches ~1e-12 (§f: 1e-11; changing rtol to
    # 1e-13 moves it by < 1e-12); the engine's forces, deflections and works are exact to rounding
    # (measured ≤ 2e-12): 1e-9; its times are quadratures: TIME_TOL (measured ≤ 2e-10).  Both tighter
    # than the asked 1e-7.
    # Works and δ_p are compared relative to ½mV² and δ_max (they vanish below yield).
    scale = scales(ode, V)
    for name in ODE_COLUMNS:
        error = abs(got[name][0] - ode[name]) / abs(scale.get(name, ode[name]))
        assert error < (TIME_TOL if name in TIMES else 1e-9), (name, error)
    # energy: W_p + W_v = ½mV²(1 − e²) with the ODE's e (independent of the engine's split), to 1e-8
    assert abs(got["plastic_work"][0] + got["viscous_work"][0] - ode["absorbed"]) < 1e-8 * energy
    # and the reference closes its own balance (its works are integrated states, not differences)
    assert abs(ode["plastic_work"] + ode["viscous_work"] - ode["absorbed"]) < 1e-10 * energy
    assert got["viscous_work"][0] > 0.0
    if ratio < 1.0:
        assert got["plastic_work"][0] == 0.0 and got["permanent_deflection"][0] == 0.0


def test_damped_note_value_through_batch():
    """§a.5 item 6 / §f: c = 0.3 s/m at V = 10 V_y: e = 0.4928, W_p = 0.198 J, W_v = 0.221 J (rounded
    there, so compared at half a unit of the last printed digit).  Through the batch: Hunt–Crossley with
    α = 0.2 s/m is c = 1.5 α = 0.3 s/m (the paper's eq 5)."""
    frame = batch.evaluate({"mass": M, "diameter": D, "modulus": E, "poisson": NU, "velocity": 10.0 * V_Y,
                            "yield_pressure": P_Y, "model": "hunt-crossley", "alpha": 0.2})
    row = frame.iloc[0]
    assert row["status"] == "ok", row["message"]
    assert abs(row["damping_factor"] - 0.3) < 1e-15
    assert abs(row["restitution"] - 0.4928) <= 5e-5
    assert abs(row["plastic_work"] - 0.198) <= 5e-4
    assert abs(row["viscous_work"] - 0.221) <= 5e-4
    ode = thornton_ode(M, 10.0 * V_Y, ES, R, P_Y, 0.3)
    assert abs(row["restitution"] - ode["restitution"]) < 1e-9
    assert abs(row["plastic_work"] - ode["plastic_work"]) < 1e-9 * ode["absorbed"]
    assert abs(row["viscous_work"] - ode["viscous_work"]) < 1e-9 * ode["absorbed"]


@pytest.mark.parametrize("c", [0.3, 3.0])
def test_damped_yield_velocity(c):
    """With damping the yield velocity is the impact speed whose largest F_T is F_y: by the loading first
    integral m V² r(cV) = ∫_0^{δ_y} F_T dδ = (2/5) F_y δ_y (independent derivation)."""
    V_yd = engine(1.0, c=c)["yield_velocity"][0]
    f_y = math.pi ** 3 * P_Y ** 3 * R ** 2 / (6.0 * ES ** 2)
    d_y = R * (math.pi * P_Y / (2.0 * ES)) ** 2
    assert abs(M * V_yd ** 2 * r_of(c * V_yd) / (0.4 * f_y * d_y) - 1.0) < 1e-12
    assert V_yd > V_Y  # damping takes energy on loading: a faster impact is needed to yield
    below, above = engine(np.array([0.999, 1.001]) * V_yd, c=c)["plastic_work"]
    assert below == 0.0 and above > 0.0
    ode = thornton_ode(M, V_yd, ES, R, P_Y, c)
    assert abs(ode["f_star"] / f_y - 1.0) < 1e-9  # the ODE turns at F_y at that speed


# =============================================================================================
# 4. elastic, no layer, damped: the plastic engine against the power-law engine
# =============================================================================================
def test_elastic_damped_equals_powerlaw():
    speeds = np.repeat([0.05, 1.0, 10.0], 9)
    cv = np.tile(np.geomspace(1e-2, 30.0, 9), 3)
    c = cv / speeds
    masses = np.repeat([0.05, M, 0.4], 9)
    got, _ = plastic_characteristics(masses, speeds, K, R, ES, INF, INF, INF, damping_factor=c)
    ref = powerlaw_characteristics(masses, K, c, speeds, R)
    # two exact methods (first integral + Gauss rules each): 1e-10 relative on all 12 columns, as asked.
    # Measured: 1e-14 on the columns that are not times; the times and firmnesses (F/t, F/t²) carry the
    # plastic engine's 24-node quadrature error, 1.6e-11 (time to peak) and 3.2e-11 (F/t²).  (With 16
    # nodes, tried during development, they were 3e-10 / 5e-10 and this test failed.)  Below c·V = 1e-2 the
    # time to peak degrades (xfail test below).
    error = np.abs(got / ref - 1.0)
    assert np.isfinite(got).all()
    assert error.max() < 1e-10, {CHARACTERISTIC_COLUMNS[j]: error[:, j].max() for j in range(12)}
    # undamped: the same, and e = 1
    got0, extra0 = plastic_characteristics(M, [0.1, 1.0, 5.0], K, R, ES)
    ref0 = powerlaw_characteristics(M, K, 0.0, [0.1, 1.0, 5.0], R)
    with np.errstate(divide="ignore", invalid="ignore"):  # absorbed energy: 0/0
        error0 = np.abs(got0 / ref0 - 1.0)
    assert np.delete(error0, CHARACTERISTIC_COLUMNS.index("absorbed_energy"), axis=1).max() < 1e-10
    assert np.abs(got0[:, 7]).max() < 1e-14 * 0.5 * M * 25.0  # absorbed: 0 up to rounding
    assert np.abs(got0[:, 6] - 1.0).max() < 1e-14 and (extra0[:, 2] == 0.0).all()


# =============================================================================================
# 5. a Winkler cushion layer in series
# =============================================================================================
RUBBER = (2.76e6, 0.45, 0.003)  # the library's rubber-belt (E, ν, h)
FOAM = (19200.0, 0.0, 0.0127)  # the library's foam-pad


def layer_work(F, stiffness, k_l, h):
    """W(F) = ∫ F dδ along elastic loading of Hertz + Winkler (capped at h) in series."""
    w = 0.4 * F ** (5.0 / 3.0) * stiffness ** (-2.0 / 3.0)  # Hertz: (2/5) F δ
    f_b = k_l * h * h
    if F <= f_b:
        return w + F ** 1.5 / (3.0 * math.sqrt(k_l))  # layer: F δ_L − ∫δ_L dF = (1/3) F δ_L
    return w + f_b * h / 3.0  # a bottomed layer stores no more


@pytest.mark.parametrize("pad,V,bottomed", [(RUBBER, 1.0, False), (RUBBER, 3.0, False), (FOAM, 0.5, False),
                                            (FOAM, 1.5, True), (FOAM, 2.0, True)])
def test_layer_elastic_undamped(pad, V, bottomed):
    k_l = winkler_k_l(*pad[:2], pad[2], R)
    h = pad[2]
    got = engine(V, p_y=INF, k_l=k_l, h=h)
    ode = thornton_ode(M, V, ES, R, INF, 0.0, k_l, h)
    # the largest force in closed form: W(F*) = ½mV² (independent of the ODE)
    f_star = brentq(lambda F: layer_work(F, K, k_l, h) - 0.5 * M * V * V, 0.0, 1e5, xtol=1e-300, rtol=4 * EPS)
    assert (f_star > k_l * h * h) == bottomed
    assert got["bottomed_out"][0] == (1.0 if bottomed else 0.0)
    assert abs(got["restitution"][0] - 1.0) < 1e-12
    assert got["plastic_work"][0] == 0.0 and got["permanent_deflection"][0] == 0.0
    assert rel(got["peak_force"][0], f_star) < 1e-12
    # ODE (brentq inside the RHS, restarts at bottoming): measured ≤ 4e-13 (F, δ) and ≤ 6e-11 (times)
    for name in ("peak_force", "max_deflection", "time_to_max_deflection", "contact_duration"):
        assert rel(got[name][0], ode[name]) < (TIME_TOL if name in TIMES else 1e-9), name
    assert abs(ode["restitution"] - 1.0) < 1e-10


def test_layer_through_batch_bottoms_out():
    """The library's foam pad (12.7 mm PU foam): an apple at 2 m/s crushes it (F* ≈ 177 N > K_L h² ≈ 29 N);
    the batch flags it and its numbers equal the ODE of the capped layer with the pad as used."""
    frame = batch.evaluate({"mass": M, "diameter": D, "modulus": E, "poisson": NU, "velocity": [2.0, 0.5],
                            "surface": "foam-pad", "model": "hertz"})
    assert (frame["status"] == "ok").all()
    for i, bottomed in enumerate((True, False)):
        row = frame.iloc[i]
        k_l = winkler_k_l(row["surface_modulus"], row["surface_poisson"], row["surface_thickness"], R)
        ode = thornton_ode(M, row["velocity"], ES, R, INF, 0.0, k_l, row["surface_thickness"])
        assert (ode["f_star"] > k_l * row["surface_thickness"] ** 2) == bottomed
        assert ("bottoms out" in row["warnings"]) == bottomed
        for name in ("peak_force", "max_deflection", "time_to_max_deflection", "contact_duration"):
            assert rel(row[name], ode[name]) < (TIME_TOL if name in TIMES else 1e-9), name


@pytest.mark.parametrize("pad,V", [(RUBBER, 2.0), (FOAM, 2.0)])
def test_layer_plastic_damped_against_ode(pad, V):
    """Everything at once: Thornton fruit + Winkler layer (the foam bottoms out) + c = 0.3 s/m.
    Cases with F_y/F* and F_b/F* ≳ 0.1 (see the xfail test for kinks far below the turn)."""
    k_l = winkler_k_l(*pad[:2], pad[2], R)
    got = engine(V, c=0.3, k_l=k_l, h=pad[2])
    ode = thornton_ode(M, V, ES, R, P_Y, 0.3, k_l, pad[2])
    scale = scales(ode, V)
    for name in ODE_COLUMNS[:-1]:  # the layered pressure is an approximation of the engine's own
        error = abs(got[name][0] - ode[name]) / abs(scale.get(name, ode[name]))
        assert error < (TIME_TOL if name in TIMES else 1e-9), (name, error)  # measured ≤ 1e-11 / 3e-10


# corrugated board that crushes (issue 14 item 3; the engine's ``crushes``): a board 4 mm thick, E = 1 MPa, ν = 0,
# its flutes collapsing at σ_c = 150 kPa, i.e. at the depth δ_c = σ_c/k (k = E/h), F_c = K_L δ_c² ≈ 11 N
BOARD = (1e6, 0.0, 0.004, 1.5e5)


def _board():
    k_l = winkler_k_l(*BOARD[:3], R)
    return k_l, BOARD[3] * math.pi * R / k_l


@pytest.mark.parametrize("c,p_y", [(0.0, INF), (0.3, INF), (3.0, INF), (0.3, P_Y)])
@pytest.mark.parametrize("over", [1.0 + 1e-6, 1.01, 1.5, 10.0])
def test_a_crushing_board_against_the_ode(c, p_y, over):
    """The engine's crushing board against ``thornton_ode`` with ``crush`` (SciPy DOP853 at rtol 1e-12 through the
    Winkler board, restarting at the crush, the fruit alone unloading from the turn): drops from just above the
    crush (``over`` × the speed that reaches F_c) to ten times it, undamped, damped (c = 0.3 and 3 s/m: the
    viscous work spent before the crush is what the earlier model, a rigid impact at V' = √(V² − 2W_c/m), left
    out; the physics audit of 2026-11-27 found its floor speed 41 % high at 1 cm) and plastic.  Tolerances as
    the other ODE comparisons here (TIME_TOL on times, 1e-9 on forces, deflections and works)."""
    k_l, depth = _board()
    f_c = k_l * depth * depth
    # the speed whose largest force is F_c: W(F_c) = E_in (``layer_work``, undamped), scaled up by the damping
    v_c = brentq(lambda v: engine(v, c=c, p_y=p_y, k_l=k_l, h=depth)["bottomed_out"][0] - 0.5, 1e-4, 5.0,
                 xtol=1e-15) if c > 0.0 or p_y < INF else math.sqrt(2.0 * layer_work(f_c, K, k_l, depth) / M)
    V = v_c * over
    stiffness = K
    out, extra = crushing_characteristics(M, V, stiffness, R, ES, p_y, k_l, depth, c)
    got = {name: out[0, j] for j, name in enumerate(CHARACTERISTIC_COLUMNS)}
    got.update({name: extra[0, j] for j, name in enumerate(PLASTIC_COLUMNS)})
    ode = thornton_ode(M, V, ES, R, p_y, c, k_l, depth, crush=True)
    assert got["bottomed_out"] == 1.0 and ode["f_star"] > f_c
    scale = scales(ode, V)
    for name in ODE_COLUMNS[:-1]:  # the pressure: below
        error = abs(got[name] - ode[name]) / abs(scale.get(name, ode[name]))
        assert error < (TIME_TOL if name in TIMES else 1e-9), (name, error)
    # the energy: the loop ∮F_T dδ (plastic work) holds the board's K_L δ_c³/3, lost in its collapsed flutes
    board_work = k_l * depth ** 3 / 3.0
    assert got["absorbed_energy"] == pytest.approx(ode["absorbed"], rel=1e-9)
    assert got["plastic_work"] + got["viscous_work"] == pytest.approx(got["absorbed_energy"], rel=1e-12)
    if p_y == INF:  # an elastic fruit: the loop is the board's work alone
        assert got["plastic_work"] == pytest.approx(board_work, rel=1e-9)
    if c == 0.0 and p_y == INF:  # energy alone: the rigid Hertz impact at V' (Johnson 1985 §11.4), its pressure
        v_left = math.sqrt(V * V - 2.0 * board_work / M)
        f_max = K * (5.0 * M * v_left ** 2 / (4.0 * K)) ** 0.6
        assert got["peak_force"] == pytest.approx(f_max, rel=1e-9)
        assert got["restitution"] == pytest.approx(v_left / V, rel=1e-9)
        # the crushed board spreads nothing: Hertz's p0 = (6 F E*² / (π³ R²))^(1/3) of the fruit on the floor
        assert got["max_pressure"] == pytest.approx((6 * f_max * ES ** 2 / (math.pi ** 3 * R * R)) ** (1 / 3), rel=1e-9)


def test_a_board_crushing_is_continuous_in_the_drop_height():
    """Across the drop height that first crushes the board the loading is the same (the board reaches F_c, then
    the fruit alone): the peak force and the largest deflection do not jump (they jumped by 18 % and −40 % with
    the earlier model, which restarted a rigid impact at V'); what changes is that the crushed board no longer
    springs back or spreads the load (restitution and pressure)."""
    k_l, depth = _board()
    v_c = brentq(lambda v: engine(v, c=0.3, p_y=INF, k_l=k_l, h=depth)["bottomed_out"][0] - 0.5, 1e-4, 5.0,
                 xtol=1e-15)
    below, above = (crushing_characteristics(M, v_c * f, K, R, ES, INF, k_l, depth, 0.3)[0][0]
                    for f in (1.0 - 1e-9, 1.0 + 1e-9))
    for name in ("peak_force", "max_deflection", "time_to_max_deflection"):
        j = CHARACTERISTIC_COLUMNS.index(name)
        assert above[j] == pytest.approx(below[j], rel=1e-6), name


# =============================================================================================
# 6. bioyield force F_pc read as Thornton's F_y
# =============================================================================================
@pytest.mark.parametrize("surface", ["rigid", "fruit"])
def test_bioyield_force_equals_yield_pressure(surface):
    f_pc = np.array([5.0, 18.0, 150.0])
    e_star = ES if surface == "rigid" else E / (2.0 * (1.0 - NU ** 2))
    radius = R if surface == "rigid" else R / 2.0
    m = M if surface == "rigid" else M / 2.0
    p_y = (6.0 * e_star ** 2 * f_pc / (math.pi ** 3 * radius ** 2)) ** (1.0 / 3.0)  # TN98 eq 16 inverted
    base = {"mass": M, "diameter": D, "modulus": E, "poisson": NU, "velocity": 1.0, "surface": surface,
            "model": "hunt-crossley", "alpha": 0.1}
    by_force = batch.evaluate({**base, "bioyield_force": f_pc})
    by_pressure = batch.evaluate({**base, "yield_pressure": p_y})
    assert (by_force["status"] == "ok").all() and (by_pressure["status"] == "ok").all()
    assert rel(by_force["yield_pressure"], p_y).max() < 1e-13
    assert by_force["plastic_work"].iloc[0] > 0.0 and by_force["plastic_work"].iloc[-1] == 0.0  # yielded, not
    names = list(CHARACTERISTIC_COLUMNS) + ["yield_velocity", "permanent_deflection", "plastic_work", "viscous_work"]
    for name in names:
        # the same p_y up to an ulp of the cube root ⇒ the same impact; measured ≤ 1.2e-11 (the time to
        # the damped peak, and firmness_c_star = F/t², carry the stationary-point root's 1e-14 × slope)
        a, b = by_force[name].to_numpy(), by_pressure[name].to_numpy()
        assert (np.abs(a - b) <= 1e-10 * np.abs(b)).all(), name
    # F_y = π³p_y³R²/(6E*²) (TN98 eq 16) is F_pc, and so is the Hertz force at which p0 = p_y
    assert rel(yield_force(e_star, radius, p_y), f_pc).max() < 1e-13
    assert rel(yield_force(e_star, radius, yield_pressure_of_force(e_star, radius, f_pc)), f_pc).max() < 1e-13
    # the undamped yield velocity from F_pc alone: ½ m* V_y² = (2/5) F_pc (F_pc/K)^{2/3}
    undamped = batch.evaluate({**base, "model": "hertz", "alpha": None, "bioyield_force": f_pc})
    stiffness = 4.0 / 3.0 * e_star * math.sqrt(radius)
    assert rel(undamped["yield_velocity"], np.sqrt(0.8 * f_pc * (f_pc / stiffness) ** (2.0 / 3.0) / m)).max() < 1e-12


# =============================================================================================
# 7. energy balance and first integrals over random inputs
# =============================================================================================
def first_integral_errors(m, V, c, e_star, radius, p_y, k_l, h, d_max, e, w_p):
    """Relative errors of (loading m V² r(cV) = W(F*), rebound speed from m w² r(−cw) = U(F*), W_p = W − U)
    for one impact, with F* from δ_max by root finding on δ(F) (Hertz/plastic fruit + capped layer)."""
    stiffness = 4.0 / 3.0 * e_star * math.sqrt(radius)
    d_y = radius * (math.pi * p_y / (2.0 * e_star)) ** 2 if p_y < INF else INF
    f_y = stiffness * d_y ** 1.5 if p_y < INF else INF
    k_p = math.pi * p_y * radius
    f_b = k_l * h * h if k_l < INF else INF

    def fruit(F):  # (δ_f, ∫_0^F δ_f dF) on loading
        if F <= f_y:
            d = (F / stiffness) ** (2.0 / 3.0)
            return d, 0.6 * F * d
        return d_y + (F - f_y) / k_p, 0.6 * f_y * d_y + d_y * (F - f_y) + 0.5 * (F - f_y) ** 2 / k_p

    def layer(F):  # (δ_L, ∫_0^F δ_L dF)
        if k_l == INF:
            return 0.0, 0.0
        if F <= f_b:
            d = math.sqrt(F / k_l)
            return d, 2.0 / 3.0 * F * d
        return h, 2.0 / 3.0 * f_b * h + h * (F - f_b)

    f_star = brentq(lambda F: fruit(F)[0] + layer(F)[0] - d_max, 0.0, 1e7, xtol=1e-300, rtol=4 * EPS)
    loaded = f_star * d_max - fruit(f_star)[1] - layer(f_star)[1]
    if f_star > f_y:  # TN98 eqs 20/28: R_p = (4/3) E* a*³ / F*, a*² = R δ_f*
        a_star = math.sqrt(radius * fruit(f_star)[0])
        k_u = 4.0 / 3.0 * e_star * math.sqrt(4.0 / 3.0 * e_star * a_star ** 3 / f_star)
    else:
        k_u = stiffness
    returned = 0.4 * f_star * (f_star / k_u) ** (2.0 / 3.0) + f_star * layer(f_star)[0] - layer(f_star)[1]
    return (m * V ** 2 * r_of(c * V) / loaded - 1.0,
            e * V / rebound_speed(m, c, returned) - 1.0,
            (w_p - (loaded - returned)) / (0.5 * m * V * V))


def test_energy_balance_random():
    rng = np.random.default_rng(20240607)
    n = 400
    modulus = 10 ** rng.uniform(6.0, 7.5, n)
    poisson = rng.uniform(0.2, 0.49, n)
    radius = 10 ** rng.uniform(-2.3, -1.3, n)
    mass = 4.0 / 3.0 * math.pi * radius ** 3 * rng.uniform(700.0, 1100.0, n)
    e_star = modulus / (1.0 - poisson ** 2)
    p_y = np.where(rng.random(n) < 0.2, INF, 10 ** rng.uniform(5.0, 6.0, n))
    V = 10 ** rng.uniform(-1.0, 1.0, n)
    # c·V in [1e-2, 100] (30 % undamped)
    c = np.where(rng.random(n) < 0.3, 0.0, 10 ** rng.uniform(-2.0, 2.0, n) / V)
    layered = rng.random(n) < 0.5
    h = np.where(layered, 10 ** rng.uniform(-3.0, -1.7, n), INF)
    k_l = np.where(layered, [winkler_k_l(10 ** rng.uniform(4, 7), rng.uniform(0, 0.45), hh, rr)
                             for hh, rr in zip(np.where(layered, h, 1.0), radius)], INF)
    stiffness = 4.0 / 3.0 * e_star * np.sqrt(radius)
    out, extra = plastic_characteristics(mass, V, stiffness, radius, e_star, p_y, k_l, h, damping_factor=c)
    col = {name: out[:, j] for j, name in enumerate(CHARACTERISTIC_COLUMNS)}
    col.update({name: extra[:, j] for j, name in enumerate(PLASTIC_COLUMNS)})
    energy = 0.5 * mass * V * V
    e = col["restitution"]
    w_p, w_v = col["plastic_work"], col["viscous_work"]
    assert np.isfinite(out).all() and np.isfinite(w_p).all()
    assert (e > 0.0).all()
    assert (e <= 1.0 + 4 * EPS).all()  # e = 1 up to rounding of √(2U/m)/V for elastic undamped rows
    assert (w_p >= 0.0).all()
    assert (w_v >= -1e-13 * energy).all()  # rounding of absorbed − plastic when both are ~0
    assert (np.abs(w_p + w_v - energy * (1.0 - e * e)) < 1e-9 * energy).all()
    undamped = c == 0.0
    assert (np.abs(w_v[undamped]) < 1e-12 * energy[undamped]).all()  # no damping, no viscous work
    elastic = ~np.isfinite(p_y)
    assert (w_p[elastic] == 0.0).all() and (col["permanent_deflection"][elastic] == 0.0).all()
    # the first integrals, written out here: loading m V² r(cV) = W(F*) at the turn, unloading
    # m w² r(−c w) = U(F*) (Thornton's unloading branch + the layer), W_p = W − U.  F* is found from the
    # engine's δ_max by root finding on δ(F) (Hertz/plastic fruit + capped layer in series).  1e-9
    # relative; measured 2e-14 (the rebound compared as a speed: U(w) is ill-conditioned as c w → 1).
    worst = 0.0
    for i in range(n):
        errors = first_integral_errors(mass[i], V[i], c[i], e_star[i], radius[i], p_y[i], k_l[i], h[i],
                                       col["max_deflection"][i], e[i], w_p[i])
        worst = max(worst, *map(abs, errors))
    assert worst < 1e-9, worst


# =============================================================================================
# times near the kinks of the force law (yield F_y, bottoming F_b), and known defects
# (strict xfail: these must fail until the engine is fixed; measured errors with src as of this writing)
# =============================================================================================
@pytest.mark.parametrize("ratio", [1.0 + 1e-8, 1.0001, 1.01])
def test_times_just_above_yield(ratio):
    """Undamped half-space just above V_y: the turn F* sits just above the kink F_y, so the Hertz piece
    [0, F_y] ends where v → 0.  Closed-form times (incomplete beta + harmonic + Hertz); measured ≤ 4.3e-10."""
    V = engine(1.0)["yield_velocity"][0] * ratio
    got = engine(V)
    ref = thornton_closed(M, V, ES, R, P_Y)
    assert rel(got["time_to_max_deflection"][0], ref["T"]) < TIME_TOL
    assert rel(got["contact_duration"][0], ref["t_c"]) < TIME_TOL


# (was an engine defect: v from energy − W(F) cancelled to 0 at the nodes next to the turn; the engine now
#  takes the first-order energy F δ'(F) (F* − F) there)
def test_times_at_yield_speed():
    V = engine(1.0)["yield_velocity"][0] * (1.0 + 1e-12)
    got = engine(V)
    ref = thornton_closed(M, V, ES, R, P_Y)
    assert rel(got["time_to_max_deflection"][0], ref["T"]) < TIME_TOL
    assert rel(got["contact_duration"][0], ref["t_c"]) < TIME_TOL


# (was an engine defect, issue 14 item 8: just above V_b the piece below F_b was integrated in s = √(F* − F)
#  with Gauss–Legendre over a range where 1/v changes on the scale √(F* − F_b): times off by 1.5e-6 at
#  V_b(1 + 1e-12), 4.1e-5 at 1.0001 V_b, 1.1e-6 at 1.001 V_b; such pieces are now cut geometrically in s)
@pytest.mark.parametrize("ratio", [1.0 + 1e-12, 1.0001, 1.001, 1.01, 1.05, 1.1])
def test_times_just_above_bottoming(ratio):
    """Elastic apple on the foam pad just above the speed at which it bottoms out, against the ODE (SciPy
    DOP853 at rtol 1e-12 with its events; TIME_TOL): measured ≤ 5e-11 at every ratio."""
    k_l = winkler_k_l(*FOAM[:2], FOAM[2], R)
    v_b = math.sqrt(2.0 * layer_work(k_l * FOAM[2] ** 2, K, k_l, FOAM[2]) / M)
    V = v_b * ratio
    got = engine(V, p_y=INF, k_l=k_l, h=FOAM[2])
    ode = thornton_ode(M, V, ES, R, INF, 0.0, k_l, FOAM[2])
    assert got["bottomed_out"][0] == 1.0
    assert rel(got["time_to_max_deflection"][0], ode["time_to_max_deflection"]) < TIME_TOL
    assert rel(got["contact_duration"][0], ode["contact_duration"]) < TIME_TOL


# (was an engine defect: a piece starting at a kink far below the turn lacked the F = 0 substitution; the
#  engine now splits such pieces and takes F = w^6 on their lower half)
@pytest.mark.parametrize("pad,V,p_y", [(FOAM, 8.0, INF), (RUBBER, 2.0, 0.1e6), (RUBBER, 0.5, 0.05e6)])
def test_times_kink_far_below_turn(pad, V, p_y):
    k_l = winkler_k_l(*pad[:2], pad[2], R)
    got = engine(V, p_y=p_y, k_l=k_l, h=pad[2])
    ode = thornton_ode(M, V, ES, R, p_y, 0.0, k_l, pad[2])
    assert rel(got["peak_force"][0], ode["peak_force"]) < 1e-9  # forces are right; the times are not
    for name in ("time_to_max_deflection", "contact_duration"):
        assert rel(got[name][0], ode[name]) < TIME_TOL, name


def test_damped_time_to_peak_near_yield():
    """c = 3 s/m: the damped yield speed is 1.26 V_y; at 1.3 V_y the peak of F_T(1 + cv) is at F_T = 0.90 F_y
    and the turn at 1.03 F_y, so the integral from 0 to the peak ends near the turn's singularity."""
    V = 1.3 * V_Y
    got = engine(V, c=3.0)
    ode = thornton_ode(M, V, ES, R, P_Y, 3.0)
    for name in ("time_to_peak", "time_to_max_deflection", "contact_duration"):
        assert rel(got[name][0], ode[name]) < TIME_TOL, name
    assert rel(got["peak_force"][0], ode["peak_force"]) < 1e-9


def test_tiny_damping_time_to_peak():
    cv = np.geomspace(1e-7, 1e-4, 13)
    got, _ = plastic_characteristics(M, 1.0, K, R, ES, INF, INF, INF, damping_factor=cv)
    ref = powerlaw_characteristics(M, K, cv, 1.0, R)
    assert np.isfinite(got).all()  # was −inf (v cancelled to 0 next to the turn) with status ok
    # the peak of F_T(1 + c v) sits within ~(cV)² F* of the turn.  Walked in the force (t ∝ √(F* − F) there)
    # locating it limited t_c to ~1e-7 relative at cV ~ 1e-6 (measured 2.4e-7); a half-space is now walked in
    # the speed (``engine.halfspace``), where the turn is regular: measured 1.4e-14.  The absorbed energy is a
    # difference of ½mV² and ½mw² with 1 − e ~ cV: 1.7e-9 at cV = 1e-7.
    assert np.abs(got[:, 1] / ref[:, 1] - 1.0).max() < 1e-12
    assert np.abs(got[:, [0, 2, 3, 6]] / ref[:, [0, 2, 3, 6]] - 1.0).max() < 1e-12


@pytest.mark.parametrize("p_y", [INF, P_Y])
def test_heavy_damping(p_y):
    """c·V = 30 … 100 (e = 1/(cV) to rounding: the rebound speed is 1/c up to exp(−1 − c²U/m)); the first
    engine version returned NaN there (its rebound start 1 − exp(−1 − q) rounded to 1)."""
    V = 3.0
    cv = np.array([30.0, 50.0, 100.0])
    got = engine(V, c=cv / V, p_y=p_y)
    assert all(np.isfinite(value).all() for name, value in got.items()
               if name not in ("yield_velocity", "yield_force") or p_y < INF)  # inf: elastic, by definition
    if p_y == INF:  # elastic: the power-law engine's exact values (measured 1e-15; times 1.5e-9)
        ref = powerlaw_characteristics(M, K, cv / V, V, R)
        for j, name in enumerate(CHARACTERISTIC_COLUMNS):
            tol = 2.0 * TIME_TOL if name in TIMES + ("firmness_c", "firmness_c_star") else 1e-10
            assert abs(got[name] / ref[:, j] - 1.0).max() < tol, name
    else:  # yielded at 3 m/s (F* > F_y): the ODE
        assert (got["plastic_work"] > 0.0).all()
        for i, c in enumerate(cv / V):
            ode = thornton_ode(M, V, ES, R, P_Y, c)
            for name in ODE_COLUMNS:
                scale = scales(ode, V).get(name, ode[name])
                assert abs(got[name][i] - ode[name]) / scale < (TIME_TOL if name in TIMES else 1e-9), name


# =============================================================================================
# the half-space walked in the speed (engine.halfspace) against the force walk (plastic._layered_impact)
# =============================================================================================
def test_speed_walk_equals_force_walk():
    """Two parametrisations of the same first integral: on a half-space ``plastic_row`` walks each branch in the
    speed (closed-form force of the work done; no inversions), the layered path in the force (an inversion of
    m v² r(c v) = E_in − W(F) at every node).  Over 3,000 random impacts (V/V_y 0.1 … 10⁴, c V 0 … 30,
    elastic rows among them) the peaks agree to rounding and the times to 2e-8: the force walk's own error
    next to a peak near the turn (c V < 1e-2; measured 5.7e-9, where the speed walk meets SciPy's DOP853 to
    1e-14, see the next test); the rest measured ≤ 4e-10."""
    import numba as nb
    from fruitimpact.engine import plastic as engine_module
    from fruitimpact.engine.quadrature import gauss_jacobi

    @nb.njit
    def both(mass, velocity, stiffness, radius, modulus, p_y, c, nodes, weights, force_walk, speed_walk, cw):
        for i in range(mass.size):
            p, energy, f_star = engine_module._setup(mass[i], velocity[i], stiffness[i], radius[i], modulus[i],
                                                     p_y[i], math.inf, math.inf, c[i], False)
            returned = engine_module.unload_energy(f_star, p)
            w = engine_module.rebound_speed_of_energy(mass[i], c[i], returned)
            cw[i] = c[i] * w
            force_walk[i, :] = engine_module._layered_impact(mass[i], c[i], energy, returned, p, f_star, p_y[i],
                                                             nodes, weights)
            row = np.empty(12)
            extra = np.empty(8)
            engine_module.plastic_row(mass[i], velocity[i], stiffness[i], radius[i], modulus[i], p_y[i], math.inf,
                                      math.inf, c[i], False, nodes, weights, row, extra)
            speed_walk[i, 0], speed_walk[i, 1], speed_walk[i, 2] = row[0], row[10], row[1]
            speed_walk[i, 3], speed_walk[i, 4] = row[4], row[2] - row[4]

    rng = np.random.default_rng(11)
    n = 3000
    mass = rng.uniform(0.05, 0.3, n)
    radius = rng.uniform(0.02, 0.045, n)
    modulus = rng.uniform(1e6, 8e6, n)
    stiffness = 4.0 / 3.0 * modulus * np.sqrt(radius)
    velocity = np.exp(rng.uniform(math.log(0.05), math.log(15.0), n))
    # p_y down to 1e3 Pa (V/V_y ~ 10⁴); beyond, the force walk's own times drift (3e-7 at p_y ~ 100 Pa, where the
    # speed walk meets DOP853 to 1e-11: test_speed_walk_against_ode)
    p_y = np.exp(rng.uniform(math.log(1e3), math.log(3e6), n))
    p_y[rng.random(n) < 0.1] = INF
    c = np.exp(rng.uniform(math.log(1e-3), math.log(30.0), n)) / velocity
    c[rng.random(n) < 0.15] = 0.0
    nodes, weights = (np.ascontiguousarray(a) for a in gauss_jacobi(24, 0.0, 0.0))
    force_walk, speed_walk, cw = np.empty((n, 5)), np.empty((n, 5)), np.empty(n)
    both(mass, velocity, stiffness, radius, modulus, p_y, c, nodes, weights, force_walk, speed_walk, cw)
    walked = cw < engine_module.HALFSPACE_DAMPING_LIMIT  # the rest take the force walk itself
    assert walked.mean() > 0.8
    error = np.abs(speed_walk[walked] / force_walk[walked] - 1.0)
    assert error[:, 0].max() < 1e-13  # peak force
    assert error[:, 1].max() < 1e-12  # peak pressure (its peak located to 1e-9 of V: the value to ~1e-18)
    assert error[:, 2:].max() < 2e-8, error[:, 2:].max(axis=0)  # time to peak, to δ_max, unloading
    # (the unloading time is read back as duration − time to δ_max: rounding)
    assert np.allclose(speed_walk[~walked], force_walk[~walked], rtol=1e-13, atol=0.0)


@pytest.mark.parametrize("V,c,p_y", [(1.0, 0.004, P_Y), (3.0, 0.002, 0.1e6), (0.3, 0.0, 0.05e6), (2.0, 1.5, 0.05e6),
                                     (1.0, 0.0, 300.0), (1.0, 0.5, 100.0), (15.0, 0.5, 1e4), (10.0, 1.0, 1e3)])
def test_speed_walk_against_ode(V, c, p_y):
    """The cases where the two walks differ most (a peak of F_T (1 + c v) next to the turn), and a fruit far
    beyond its yield speed (V/V_y up to 10⁵: the work to yield a 1e-16 sliver of the impact's, where the speed at
    yield and the plastic line's root v_b, as differences of two speeds, had cancelled to NaN or lost 4e-6; a
    review found them): the speed walk against SciPy's DOP853 at rtol 1e-12 (measured ≤ 1e-13 on the times)."""
    got = engine(V, c=c, p_y=p_y)
    ode = thornton_ode(M, V, ES, R, p_y, c)
    for name in ODE_COLUMNS:
        scale = scales(ode, V).get(name, ode[name])
        assert abs(got[name][0] - ode[name]) / scale < (1e-10 if name in TIMES else 1e-9), name


@pytest.mark.parametrize("c, over", [(3.0, 1.5), (20.0, 1.01), (20.0, 1.2), (20.0, 3.0)])
def test_a_crushing_board_s_damped_pressure_against_the_ode(c, over):
    """The largest centre pressure p_T (1 + c δ̇) on a crushing board, with damping, against SciPy: the loading
    integrated (DOP853, rtol 1e-11) with F_T(δ) found by brentq, and the documented pressure of each phase
    written out here: below F_c the fruit on the Winkler board, a² = R (δ_f + 2 δ_L), shape factor
    (1.5 δ_f + 4 δ_L)/(δ_f + 2 δ_L); beyond it the crushed board spreads nothing, p = 3 F_T/(2π R δ_f) (Hertz).
    With heavy damping the largest is below the crush: the engine's slope of the pressure straddled the jump at
    F_c and lost that peak (0.38 against 0.69 MPa at c = 20 s/m; found by a review).  Tolerance 1e-6: the
    engine locates a pressure peak to 1e-8 in F and the ODE's dense output is cubic between steps."""
    from scipy.integrate import solve_ivp

    k_l, depth = _board()
    f_c = k_l * depth * depth
    v_c = brentq(lambda v: engine(v, c=c, p_y=INF, k_l=k_l, h=depth)["bottomed_out"][0] - 0.5, 1e-4, 20.0,
                 xtol=1e-15)
    V = v_c * over
    got = crushing_characteristics(M, V, K, R, ES, INF, k_l, depth, c)[0][0, CHARACTERISTIC_COLUMNS.index(
        "max_pressure")]

    def parts(delta):  # (F_T, δ_f, δ_L) on loading: δ = (F/K)^(2/3) + √(F/K_L) below F_c, + h beyond
        if delta <= 0.0:
            return 0.0, 0.0, 0.0
        edge = (f_c / K) ** (2 / 3) + depth
        if delta >= edge:
            d_f = delta - depth
            return K * d_f ** 1.5, d_f, depth
        F = brentq(lambda F: (F / K) ** (2 / 3) + math.sqrt(F / k_l) - delta, 0.0, f_c, xtol=1e-300,
                   rtol=4 * EPS)
        return F, (F / K) ** (2 / 3), math.sqrt(F / k_l)

    def pressure(delta, rate):
        F, d_f, d_l = parts(delta)
        if F <= 0.0:
            return 0.0
        if F > f_c:
            p_t = 3.0 * F / (2.0 * math.pi * R * d_f)
        else:
            p_t = (1.5 * d_f + 4.0 * d_l) / (d_f + 2.0 * d_l) * F / (math.pi * R * (d_f + 2.0 * d_l))
        return p_t * (1.0 + c * rate)

    def turn(t, y):
        return y[1]
    turn.terminal, turn.direction = True, -1
    sol = solve_ivp(lambda t, y: [y[1], -parts(y[0])[0] * (1.0 + c * y[1]) / M], (0.0, 1.0), [0.0, V],
                    method="DOP853", rtol=1e-11, atol=[1e-16, 1e-14], events=turn, dense_output=True)
    times = np.linspace(0.0, sol.t[-1], 20001)
    states = sol.sol(times)
    scan = max(pressure(d, v) for d, v in zip(states[0], states[1]))
    # refine around the best sample: the dense output between its neighbours
    k = int(np.argmax([pressure(d, v) for d, v in zip(states[0], states[1])]))
    fine = np.linspace(times[max(k - 1, 0)], times[min(k + 1, times.size - 1)], 2001)
    scan = max(scan, max(pressure(*sol.sol(t)) for t in fine))
    assert got == pytest.approx(scan, rel=1e-6)
