"""An independent sorting-line recording generator, its truth, a scorecard and a grading check (issue 13).

Independence: this module does not import fruitimpact and shares no code with ``fruitimpact synth`` or the
project's engine.  The contact physics is integrated here with SciPy from its equations; the feed, the rebounds
and the sensor chain are modelled here from what real lines do.  Units are SI throughout, given in brackets.

Physics of one contact (Hunt–Crossley sphere on a rigid plate)
    E* = E / (1 − ν²),  R = d / 2,  K = (4/3) E* √R  [N/m^1.5]
    F = K δ^1.5 (1 + c δ̇),  δ ≥ 0,  F ≥ 0;   m δ̈ = −F,  δ(0) = 0,  δ̇(0) = V
    c [s/m] is a material constant of the fruit: the restitution e = V_out / V falls as c V grows (c V = 0.6 →
    e = 0.71, 1.0 → 0.59, 1.75 → 0.45), so a rebound at the lower speed e V has a higher restitution.  Integrated
    by ``solve_ivp`` (DOP853, rtol 1e-10) from δ = 0 with two events: the force maximum (dF/dt = 0) and the
    separation (δ back to 0).  ``damping_law`` (``DAMPING_LAWS``) may instead make the restitution the fruit's
    constant (c = χ(e₀)/V per contact: Lankarani–Nikravesh, Flores): a rebound is then as lively as its fruit.
    ``force_exponent`` n ≠ 1.5 gives the fruit a force law that is not Hertz's, F = K_n δ^n (1 + c δ̇), with K_n
    chosen for the same force at the fruit's undamped Hertz compression at the line's V (``contact``): a pulse
    that the analysis's Hertz law cannot fit exactly, as real fruit (not homogeneous spheres) give.
    The force is tabulated on a fine grid (8193 points over the contact) and
    interpolated at the recording's (oversampled) sample times, so onsets fall anywhere between samples.

Feed (per lane)
    A chain brings one fruit per pitch P = 1 / fruit_rate [s]; each fruit lands at its slot k P plus a uniform
    jitter of ±8 % of P (not accumulated: a chain).  A fraction ``close_fraction`` of fruit (round(fraction ×
    fruit per lane), at least one per lane when the fraction is not zero, at random places) are close arrivals:
    they land 2–20 ms after the END of the previous fruit's first contact on that lane (two fruit in one cup);
    the next fruit keeps its own slot.
    The first slot is ≥ 0.1 s after the recording starts (the detector warms up on ~50 ms of quiet signal).

Rebounds
    ``pad``: the pad catches the fruit, no rebound at all.  ``plate``: one or two rebounds (``rebounds`` = (min,
    max), drawn per fruit).  The fruit leaves vertically at its exit speed V_up = e V; its flight is 2 V_up / g
    times a uniform factor in [0.9, 1.1] (spin, off-axis bounce); it lands at V₂ = V_up (1 − s), s uniform in
    ``spin_loss`` (spin takes a few % of the speed); it lands on another spot of the fruit: K times a uniform
    factor in [0.95, 1.05]; same m and c.  A second rebound follows the first in the same way.  A rebound that
    lands on top of the next fruit's contact is kept (that happens on real lines): the truth lists, for every
    contact, the contacts of its lane it overlaps (``overlaps``).

Fruit (ranges chosen from the literature on apples and pears; each kind is a ``FruitKind``)
    * apple: m uniform 150–250 g, ρ = 800 kg/m³, d of the sphere of that mass and density times (1 + 3 % sd)
      for shape; E lognormal, median 3.5 MPa, sd of ln E 0.18, kept within 2.5–5 MPa; ν uniform 0.30–0.40;
      c lognormal, median 1.1 s/m, sd of ln c 0.25, kept within 0.65–1.75 s/m (e ≈ 0.45–0.70 from 5 cm).
    * pear: m uniform 150–250 g, ρ = 1000 kg/m³, shape spread 5 %; E lognormal, median 2.8 MPa, sd 0.18, within
      2–4 MPa; ν 0.30–0.40; c median 1.2 s/m, sd 0.25, within 0.65–1.85 s/m.
    * graded apple (``grades``): a sized lot, d = 75 mm with 3 % sd (the analysis is given one nominal diameter),
      m from ρ = 800 with 4 % sd, ν = 0.35, E lognormal median 3.3 MPa, sd of ln E 0.22, within 2–5.5 MPa.

Sensor chain (in the physical order)
    sum of the lane's contact forces on a grid ``oversample`` × finer than the rate → plate/transducer resonance
    H(s) = ωn² / (s² + 2 ζ ωn s + ωn²) (DC gain 1), discretised by the bilinear transform prewarped at ωn
    (derived in ``resonance_coefficients``) → optional piezo discharge, the first-order high-pass s/(s + 1/τ) of a
    charge amplifier or IEPE sensor (``discharge_time`` τ; ``discharge_coefficients``) → optional Butterworth
    anti-alias low-pass (``antialias_order`` at ``antialias_cutoff`` × the rate) → sampled at the rate (every
    ``oversample``-th point) → baseline
    offset + drift (linear + random walk, ~±``drift`` N over the recording) + mains hum (fundamental within
    ±0.02 Hz of 50/60 Hz, 3rd harmonic at 30 % of it; ``hum_level`` × the median primary peak) + white noise
    (σ = ``noise`` × the median primary peak) → optional ADC quantisation over ±``adc_range`` with clipping there
    (``adc_bits``) → float32 (the acquisition's word).  The order and the optional stages follow the impact-sensor
    background note's sensor chain (§3.1); its analysis (``_analysis``) is told the discharge time constant, as a
    user reads it from the sensor's data sheet.

Writers
    ``f32``: raw little-endian float32, lanes interleaved sample-major (analyze needs ``--rate R --lanes K``);
    lanes are named ``lane0``, ``lane1`` …  ``csv``: header ``time [s],lane0 [N],…`` (times with 12 decimals:
    the reader wants them uniform within 1e-6 of the interval), lanes ``lane0`` …  ``tdms``: one group ``line``,
    channels ``lane0`` … with wf_increment = 1/rate, wf_start_offset = 0, unit_string = "N"; lanes are named
    ``line/lane0`` …  ``npy``: samples × lanes float32, lanes ``lane0`` …  The truth is written beside the
    recording as ``NAME.truth.json``; its ``lanes`` list is the lane names as the reader reports them, and every
    contact's ``lane_name`` is the one reports carry in their ``lane`` key.

Scoring (``score``) and grading (``grade``): see their docstrings.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from scipy.signal import butter, lfilter, sosfilt

#: Standard gravity [m/s²].
G = 9.80665
#: Hertz impact: time to maximum compression = HERTZ_TIME × δ_m / V (Johnson, Contact Mechanics §11.4:
#: the contact lasts 2.9432 δ_m / V, symmetric about the maximum).
HERTZ_TIME = 1.4716
#: Points of the force table of one contact.
TABLE_POINTS = 8193
#: Extension written for each format.
EXTENSION = {"f32": ".f32", "csv": ".csv", "tdms": ".tdms", "npy": ".npy"}
#: TDMS group holding the lanes.
TDMS_GROUP = "line"
#: Class thresholds by modulus [Pa] and class names (softest first): issue 13 item 5.
THRESHOLDS = (2.8e6, 3.8e6)
CLASSES = ("soft", "medium", "firm")
#: The issue's goals for every scenario (item 6): name → (comparison, limit).
GOALS = {
    "recall": (">=", 1.0),
    "extra": ("<=", 0),
    "fruit_taken_for_rebounds": ("<=", 0),
    "rebounds_taken_for_fruit": ("<=", 0),
    "peak_force_p95": ("<=", 0.01),
    "time_to_peak_p95": ("<=", 0.02),
    "stiffness_median": ("<=", 0.02),
    "stiffness_p95": ("<=", 0.05),
    "restitution_p95": ("<=", 0.03),
}
#: Share of clearly classed fruit (true modulus ≥ 5 % from every threshold) that must get the right class.
GRADING_GOAL = 0.98


# ---------------------------------------------------------------------------------------------------------------
# One contact
# ---------------------------------------------------------------------------------------------------------------

def stiffness(modulus: float, poisson: float, diameter: float) -> float:
    """K = (4/3) E/(1 − ν²) √(d/2) [N/m^1.5] of a sphere of diameter d [m] on a rigid plate."""
    return 4.0 / 3.0 * modulus / (1.0 - poisson ** 2) * math.sqrt(diameter / 2.0)


def hertz_max_deflection(K: float, mass: float, velocity: float) -> float:
    """Undamped maximum compression δ_m = (5 m V² / (4 K))^0.4 [m]."""
    return (5.0 * mass * velocity ** 2 / (4.0 * K)) ** 0.4


@dataclass(frozen=True)
class Pulse:
    """One solved contact: its force table and characteristics (time from first touch [s])."""

    K: float                 # [N/m^1.5]
    mass: float              # [kg]
    damping: float           # c [s/m]
    velocity: float          # impact speed V [m/s]
    duration: float          # first touch → separation [s]
    time_to_peak: float      # first touch → F max [s]
    peak_force: float        # [N]
    exit_velocity: float     # V_out [m/s]
    max_deflection: float    # [m]
    table_t: np.ndarray = field(repr=False)   # [s]
    table_f: np.ndarray = field(repr=False)   # [N]

    @property
    def restitution(self) -> float:
        return self.exit_velocity / self.velocity

    def force(self, t: np.ndarray) -> np.ndarray:
        """Contact force [N] at times t [s] after first touch (0 outside the contact)."""
        return np.interp(t, self.table_t, self.table_f, left=0.0, right=0.0)


def contact(K: float, mass: float, damping: float, velocity: float, rtol: float = 1e-10, exponent: float = 1.5,
            reference_velocity: float | None = None) -> Pulse:
    """Integrate m δ̈ = −K_n δ^n (1 + c δ̇) from δ = 0, δ̇ = V to separation (``solve_ivp``, DOP853).

    n = ``exponent``: 1.5 is Hertz's sphere (K_n = K).  Another n is a fruit whose force law is not Hertz's (a
    turgid cell body's exponent lies between 1 and 2: Blahovec, Int. Agrophys. 10(2):89–95, 1996):
    K_n = K δ_r^(1.5 − n), the same force as Hertz's law at δ_r, the undamped Hertz compression at
    ``reference_velocity`` (default V; a rebound passes its fruit's first V, so the fruit keeps one force law).
    ``Pulse.K`` stays K."""
    n = exponent
    if not n >= 1.0:
        raise ValueError(f"exponent must be >= 1 (the force's slope at first touch); got {n!r}")
    reference = velocity if reference_velocity is None else reference_velocity
    if not reference > 0.0:
        raise ValueError(f"reference_velocity must be > 0; got {reference_velocity!r}")
    k_law = K * hertz_max_deflection(K, mass, reference) ** (1.5 - n)
    k_over_m = k_law / mass
    c = damping

    def force_of(d, v):
        d = np.maximum(d, 0.0)
        return np.maximum(k_law * d ** n * (1.0 + c * v), 0.0)

    def rhs(t, y):
        return [y[1], -float(force_of(y[0], y[1])) / mass]

    def separation(t, y):
        return y[0]

    separation.terminal = True
    separation.direction = -1

    def peak(t, y):  # dF/dt / K_n, positive while loading; zero at t = 0 (δ = 0), crossed downwards at the peak
        d = max(y[0], 0.0)
        v = y[1]
        acc = -k_over_m * d ** n * (1.0 + c * v)
        root = math.sqrt(d) if n == 1.5 else d ** (n - 1.0)  # Hertz's as it always was, to the last bit
        return n * root * v * (1.0 + c * v) + d ** n * c * acc

    peak.direction = -1
    # undamped compression: ½ m V² = K_n δ^(n+1)/(n+1)
    dm = ((n + 1.0) * mass * velocity ** 2 / (2.0 * k_law)) ** (1.0 / (n + 1.0))
    t_hertz = 2.0 * HERTZ_TIME * dm / velocity
    sol = solve_ivp(rhs, (0.0, 20.0 * t_hertz), [0.0, velocity], method="DOP853", rtol=rtol,
                    atol=[1e-12 * dm, 1e-12 * velocity], events=[separation, peak], dense_output=True)
    if sol.status != 1 or not len(sol.t_events[0]) or not len(sol.t_events[1]):
        raise RuntimeError(f"contact did not end: K={K}, m={mass}, c={c}, V={velocity}: {sol.message}")
    t_end = float(sol.t_events[0][0])
    t_peak = float(sol.t_events[1][0])
    d_peak, v_peak = sol.y_events[1][0]
    exit_velocity = -float(sol.y_events[0][0][1])
    t = np.linspace(0.0, t_end, TABLE_POINTS)
    t = np.unique(np.append(t, t_peak))
    y = sol.sol(t)
    f = force_of(y[0], y[1])
    f[0] = f[-1] = 0.0
    # maximum compression: δ̇ = 0, found on the table then refined by the dense output's root
    i = int(np.argmax(y[0]))
    d_max = float(np.max(sol.sol(np.linspace(t[max(i - 1, 0)], t[min(i + 1, t.size - 1)], 201))[0]))
    return Pulse(K=K, mass=mass, damping=c, velocity=velocity, duration=t_end, time_to_peak=t_peak,
                 peak_force=float(force_of(d_peak, v_peak)), exit_velocity=exit_velocity, max_deflection=d_max,
                 table_t=t, table_f=f)


# ---------------------------------------------------------------------------------------------------------------
# Scenarios
# ---------------------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class FruitKind:
    """A fruit population.  Masses [kg], density [kg/m³], moduli [Pa], damping c [s/m]."""

    name: str
    mass: tuple[float, float]             # uniform range [kg] (ignored when ``diameter`` is set)
    density: float                        # [kg/m³]
    shape_spread: float                   # relative sd of the contact diameter (shape) [-]
    modulus_median: float                 # [Pa]
    modulus_sigma: float                  # sd of ln E [-]
    modulus_range: tuple[float, float]    # [Pa], draws outside are redrawn
    poisson: tuple[float, float]          # uniform range [-]
    damping_median: float                 # c [s/m]
    damping_sigma: float                  # sd of ln c [-]
    damping_range: tuple[float, float]    # [s/m], draws outside are redrawn
    diameter: float | None = None         # nominal diameter of a sized lot [m]; mass then from ρ
    mass_spread: float = 0.04             # relative sd of the mass of a sized lot [-]


APPLE = FruitKind("apple", mass=(0.150, 0.250), density=800.0, shape_spread=0.03, modulus_median=3.5e6,
                  modulus_sigma=0.18, modulus_range=(2.5e6, 5.0e6), poisson=(0.30, 0.40), damping_median=1.1,
                  damping_sigma=0.25, damping_range=(0.65, 1.75))
PEAR = FruitKind("pear", mass=(0.150, 0.250), density=1000.0, shape_spread=0.05, modulus_median=2.8e6,
                 modulus_sigma=0.18, modulus_range=(2.0e6, 4.0e6), poisson=(0.30, 0.40), damping_median=1.2,
                 damping_sigma=0.25, damping_range=(0.65, 1.85))
GRADED_APPLE = FruitKind("apple", mass=(0.0, 0.0), density=800.0, shape_spread=0.03, modulus_median=3.3e6,
                         modulus_sigma=0.22, modulus_range=(2.0e6, 5.5e6), poisson=(0.35, 0.35),
                         damping_median=1.1, damping_sigma=0.25, damping_range=(0.65, 1.75), diameter=0.075)


@dataclass(frozen=True)
class Scenario:
    """One sorting line.  Times [s], rates [Hz], forces [N]; levels relative to the median primary peak."""

    name: str
    seed: int
    size: int                                   # fruit per lane at benchmark size
    lanes: int = 1
    rate: float = 20_000.0                      # sample rate [Hz]
    fmt: str = "f32"                            # f32, csv, tdms or npy
    fruit_rate: float = 7.0                     # fruit per second per lane [1/s]
    pitch_jitter: float = 0.08                  # uniform ± fraction of the pitch on each arrival
    close_fraction: float = 0.0                 # share of fruit landing 2–20 ms after the previous contact
                                                # (round(share × size) per lane, at least 1 when not 0)
    close_gap: tuple[float, float] = (0.002, 0.020)  # [s]
    surface: str = "plate"                      # plate (rebounds) or pad (no rebound)
    rebounds: tuple[int, int] = (1, 1)          # min, max rebounds per fruit on a plate
    flight_jitter: float = 0.10                 # uniform ± fraction of the flight 2 V_up / g
    spin_loss: tuple[float, float] = (0.0, 0.04)  # uniform fraction of V_up lost before the rebound lands
    spot_stiffness: float = 0.05                # uniform ± fraction of K where a rebound lands
    damping_law: str = "hunt-crossley"          # how c depends on the contact's speed (``DAMPING_LAWS``)
    force_exponent: float = 1.5                 # n of the fruit's force law K_n δ^n (1.5: Hertz; ``contact``)
    kinds: tuple[tuple[FruitKind, float], ...] = ((APPLE, 1.0),)  # kinds and their shares
    drop_height: float = 0.05                   # [m]
    noise: float = 0.01                         # white-noise σ / median primary peak
    hum_frequency: float = 50.0                 # [Hz]
    hum_level: float = 0.01                     # fundamental amplitude / median primary peak
    hum_third: float = 0.3                      # 3rd harmonic / fundamental
    drift: float = 1.0                          # drift over the recording [N]
    offset: float = 2.0                         # baseline offset, uniform ± [N]
    plate_frequency: float = 2500.0             # resonance [Hz]
    plate_damping: float = 0.05                 # ζ [-]
    discharge_time: float = 0.0                 # piezo chain's time constant τ [s] (first-order high-pass; 0: none)
    discharge_told: bool = True                 # the analysis is told τ (the data sheet) or must measure it
    antialias_order: int = 0                    # Butterworth anti-alias low-pass order (0: none)
    antialias_cutoff: float = 0.25              # its cut-off / the sample rate [-]
    adc_bits: int = 0                           # ADC word (0: none); quantised over ±adc_range, clipped there
    adc_range: float = 250.0                    # [N]
    oversample: int = 8                         # analogue grid / sample rate
    quiet: float = 0.15                         # quiet signal before the first slot [s]
    thresholds: tuple[float, ...] = THRESHOLDS  # class thresholds by modulus [Pa]
    classes: tuple[str, ...] = CLASSES
    grading: bool = False                       # analyse with --diameter/--poisson/--sort-by modulus
    quick_size: int = 20                        # fruit per lane for --quick and the tests

    @property
    def velocity(self) -> float:
        return math.sqrt(2.0 * G * self.drop_height)


SCENARIOS: dict[str, Scenario] = {s.name: s for s in [
    Scenario("chain7", seed=701, size=50, fmt="csv", fruit_rate=7.0, rebounds=(1, 1), drop_height=0.05,
             hum_level=0.008, plate_frequency=2500.0, plate_damping=0.06, quick_size=12),
    Scenario("chain10", seed=1002, size=40, fmt="f32", fruit_rate=10.0, rebounds=(1, 2), drop_height=0.04,
             hum_frequency=60.0, hum_level=0.01, plate_frequency=2800.0, plate_damping=0.05, quick_size=10),
    Scenario("pad", seed=303, size=80, fmt="tdms", fruit_rate=10.0, surface="pad", rebounds=(0, 0),
             drop_height=0.05, hum_level=0.006, plate_frequency=2200.0, plate_damping=0.08, quick_size=22),
    Scenario("close", seed=404, size=45, fmt="f32", fruit_rate=7.0, close_fraction=0.05, rebounds=(1, 1),
             drop_height=0.05, hum_level=0.01, plate_frequency=2600.0, plate_damping=0.05, quick_size=14),
    Scenario("noisy", seed=505, size=45, fmt="tdms", fruit_rate=7.0, rebounds=(1, 1), drop_height=0.05,
             hum_level=0.015, drift=1.0, offset=3.0, plate_frequency=2000.0, plate_damping=0.03, quick_size=12),
    Scenario("lanes4", seed=604, size=12, lanes=4, rate=25_000.0, fmt="f32", fruit_rate=7.0, rebounds=(1, 1),
             kinds=((APPLE, 0.5), (PEAR, 0.5)), drop_height=0.05, hum_level=0.01, plate_frequency=3000.0,
             plate_damping=0.1, quick_size=4),
    Scenario("pears3cm", seed=33, size=45, fmt="csv", fruit_rate=7.0, rebounds=(1, 1), kinds=((PEAR, 1.0),),
             drop_height=0.03, hum_level=0.012, plate_frequency=2400.0, plate_damping=0.04, quick_size=12),
    Scenario("grades", seed=1313, size=150, fmt="f32", fruit_rate=7.0, close_fraction=0.05, rebounds=(1, 2),
             kinds=((GRADED_APPLE, 1.0),), drop_height=0.05, hum_level=0.01, drift=1.0,
             plate_frequency=2500.0, plate_damping=0.04, grading=True, quick_size=80),
]}


# ---------------------------------------------------------------------------------------------------------------
# Generation
# ---------------------------------------------------------------------------------------------------------------

def _lognormal(rng, median: float, sigma: float, bounds: tuple[float, float]) -> float:
    """A lognormal draw (median, sd of ln) redrawn until within bounds."""
    for _ in range(1000):
        x = median * math.exp(sigma * rng.standard_normal())
        if bounds[0] <= x <= bounds[1]:
            return x
    raise RuntimeError("lognormal bounds too narrow")


#: How a contact's damping c [s/m] follows from the fruit and the contact's speed v [m/s] (``Scenario.damping_law``).
#: ``hunt-crossley``: c is the fruit's material constant, so a rebound (slower) has a higher restitution.  The two
#: others make the restitution a constant of the fruit, whatever the speed: e₀ is the Hunt–Crossley restitution of
#: that fruit at the line's speed V (the populations keep their range of e at V), and c = χ(e₀) / v with
#: ``lankarani-nikravesh`` χ = 3 (1 − e₀²) / 4 (Lankarani & Nikravesh 1990; derived for e₀ near 1, so its real
#: restitution is higher than e₀ for soft fruit) and ``flores`` χ = 8 (1 − e₀) / (5 e₀) (Flores et al. 2011).
DAMPING_LAWS = {
    "hunt-crossley": lambda fruit, v: fruit["damping"],
    "lankarani-nikravesh": lambda fruit, v: 3.0 * (1.0 - fruit["e0"] ** 2) / (4.0 * v),
    "flores": lambda fruit, v: 8.0 * (1.0 - fruit["e0"]) / (5.0 * fruit["e0"] * v),
}


def draw_fruit(rng, kind: FruitKind) -> dict:
    """One fruit of ``kind``: mass [kg], diameter [m], modulus [Pa], poisson, damping c [s/m], K [N/m^1.5]."""
    if kind.diameter is not None:
        diameter = kind.diameter * (1.0 + kind.shape_spread * rng.standard_normal())
        mass = kind.density * math.pi * diameter ** 3 / 6.0 * (1.0 + kind.mass_spread * rng.standard_normal())
    else:
        mass = rng.uniform(*kind.mass)
        diameter = (6.0 * mass / (math.pi * kind.density)) ** (1.0 / 3.0)
        diameter *= 1.0 + kind.shape_spread * rng.standard_normal()
    modulus = _lognormal(rng, kind.modulus_median, kind.modulus_sigma, kind.modulus_range)
    poisson = rng.uniform(*kind.poisson) if kind.poisson[1] > kind.poisson[0] else kind.poisson[0]
    damping = _lognormal(rng, kind.damping_median, kind.damping_sigma, kind.damping_range)
    return dict(kind=kind.name, mass=mass, diameter=diameter, modulus=modulus, poisson=poisson, damping=damping,
                stiffness=stiffness(modulus, poisson, diameter))


def classify(modulus: float, thresholds, classes) -> str:
    """The class of a true modulus [Pa]: classes[i] for thresholds[i-1] ≤ E < thresholds[i]."""
    return classes[int(np.searchsorted(np.asarray(thresholds), modulus, side="right"))]


def lane_names(fmt: str, lanes: int) -> list[str]:
    """The lane names a reader gives the lanes of a file written in ``fmt`` (reports' ``lane`` key)."""
    if fmt == "tdms":
        return [f"{TDMS_GROUP}/lane{i}" for i in range(lanes)]
    return [f"lane{i}" for i in range(lanes)]


def _contacts(scenario: Scenario, size: int, rng) -> tuple[list[dict], list[dict]]:
    """Every contact and fruit of the scenario (unsorted), each contact with its Pulse under ``pulse``."""
    names = lane_names(scenario.fmt, scenario.lanes)
    kinds = [k for k, _ in scenario.kinds]
    shares = np.array([w for _, w in scenario.kinds], float)
    shares /= shares.sum()
    pitch = 1.0 / scenario.fruit_rate
    V = scenario.velocity
    contacts: list[dict] = []
    fruits: list[dict] = []
    for lane in range(scenario.lanes):
        first_slot = scenario.quiet + scenario.pitch_jitter * pitch + rng.uniform(0.0, 0.5 * pitch)
        # close arrivals: round(close_fraction × size) fruit of the lane (at least one when the fraction is not
        # zero), at random places after the first
        n_close = max(1, round(scenario.close_fraction * size)) if scenario.close_fraction > 0 and size > 1 else 0
        close_ones = set(rng.choice(np.arange(1, size), size=n_close, replace=False).tolist()) if n_close else set()
        previous_end = None
        for k in range(size):
            fruit = draw_fruit(rng, kinds[int(rng.choice(len(kinds), p=shares))])
            fruit_id = len(fruits)
            close = k in close_ones
            if close:
                start = previous_end + rng.uniform(*scenario.close_gap)
            else:
                start = first_slot + k * pitch + rng.uniform(-1.0, 1.0) * scenario.pitch_jitter * pitch
                if previous_end is not None and start <= previous_end:  # cannot happen at these pitches
                    start = previous_end + scenario.close_gap[1]
            damping_of = DAMPING_LAWS[scenario.damping_law]
            law = dict(exponent=scenario.force_exponent, reference_velocity=V)
            if scenario.damping_law != "hunt-crossley":
                fruit["e0"] = contact(fruit["stiffness"], fruit["mass"], fruit["damping"], V, **law).restitution
            pulse = contact(fruit["stiffness"], fruit["mass"], damping_of(fruit, V), V, **law)
            primary = dict(lane=lane, lane_name=names[lane], fruit_id=fruit_id, kind=fruit["kind"], start_time=start,
                           pulse=pulse, is_rebound=False, parent=None, close_arrival=bool(close), flight_time=None,
                           modulus=fruit["modulus"], diameter=fruit["diameter"], poisson=fruit["poisson"])
            contacts.append(primary)
            previous_end = start + pulse.duration
            fruit.update(fruit_id=fruit_id, lane=lane, lane_name=names[lane], close_arrival=bool(close),
                         cls=classify(fruit["modulus"], scenario.thresholds, scenario.classes))
            fruits.append(fruit)
            n = 0 if scenario.surface == "pad" else int(rng.integers(scenario.rebounds[0], scenario.rebounds[1] + 1))
            parent = primary
            for _ in range(n):
                v_up = parent["pulse"].exit_velocity
                flight = 2.0 * v_up / G * (1.0 + rng.uniform(-1.0, 1.0) * scenario.flight_jitter)
                v2 = v_up * (1.0 - rng.uniform(*scenario.spin_loss))
                k2 = fruit["stiffness"] * (1.0 + rng.uniform(-1.0, 1.0) * scenario.spot_stiffness)
                p2 = contact(k2, fruit["mass"], damping_of(fruit, v2), v2, **law)
                rebound = dict(lane=lane, lane_name=names[lane], fruit_id=fruit_id, kind=fruit["kind"],
                               start_time=parent["start_time"] + parent["pulse"].duration + flight, pulse=p2,
                               is_rebound=True, parent=parent, close_arrival=False, flight_time=flight,
                               modulus=fruit["modulus"], diameter=fruit["diameter"], poisson=fruit["poisson"])
                contacts.append(rebound)
                parent = rebound
    return contacts, fruits


def resonance_coefficients(frequency: float, damping: float, rate: float) -> tuple[np.ndarray, np.ndarray]:
    """(b, a) of H(s) = ωn² / (s² + 2 ζ ωn s + ωn²) by the bilinear transform prewarped at ωn.

    s = κ (z − 1)/(z + 1) with κ = ωn / tan(ωn T / 2) (T = 1/rate) maps s = j ωn to z = e^{j ωn T}, so the
    resonance stays at ωn.  Multiplying numerator and denominator by (z + 1)² and dividing by z²:
    b = ωn² (1, 2, 1);  a = (κ² + 2ζωnκ + ωn², 2(ωn² − κ²), κ² − 2ζωnκ + ωn²), normalised by a₀.
    At z = 1 (DC) both sums are 4 ωn²: DC gain 1, so the impulse of every contact is kept.
    """
    wn = 2.0 * math.pi * frequency
    kappa = wn / math.tan(wn / (2.0 * rate))
    b = wn ** 2 * np.array([1.0, 2.0, 1.0])
    a = np.array([kappa ** 2 + 2 * damping * wn * kappa + wn ** 2, 2 * (wn ** 2 - kappa ** 2),
                  kappa ** 2 - 2 * damping * wn * kappa + wn ** 2])
    return b / a[0], a / a[0]


def discharge_coefficients(time_constant: float, rate: float) -> tuple[np.ndarray, np.ndarray]:
    """(b, a) of a piezo chain's discharge H(s) = s / (s + 1/τ), a first-order high-pass, by the bilinear
    transform: s = 2 rate (z − 1)/(z + 1) gives b = (1, −1)·g, a = (1, −(1 − q)/(1 + q)) with q = 1/(2 τ rate)
    and g = 1/(1 + q).  At DC (z = 1) b sums to 0: a static force decays with τ, and after a contact of impulse I the
    output undershoots by ≈ I/τ (``impact-sensors`` background note, sensor chain stage 3)."""
    q = 1.0 / (2.0 * time_constant * rate)
    return np.array([1.0, -1.0]) / (1.0 + q), np.array([1.0, -(1.0 - q) / (1.0 + q)])


def generate(scenario: Scenario | str, size: int | None = None, *, clean: bool = False):
    """(samples × lanes float32 recording [N], truth dict) of a scenario with ``size`` fruit per lane.

    ``clean`` leaves out offset, drift, hum and noise (the forces through the resonance only): for tests of the
    sensor chain."""
    if isinstance(scenario, str):
        scenario = SCENARIOS[scenario]
    size = scenario.size if size is None else size
    rng = np.random.default_rng(scenario.seed)
    contacts, fruits = _contacts(scenario, size, rng)
    contacts.sort(key=lambda c: (c["start_time"], c["lane"]))
    for i, c in enumerate(contacts):
        c["index"] = i
    ends = [c["start_time"] + c["pulse"].duration for c in contacts]
    duration = max(ends) + 0.15
    rate = scenario.rate
    n = int(math.ceil(duration * rate))
    fine = rate * scenario.oversample
    nf = n * scenario.oversample
    force = np.zeros((nf, scenario.lanes))
    for c, end in zip(contacts, ends):
        j0 = int(math.ceil(c["start_time"] * fine))
        j1 = int(math.floor(end * fine)) + 1
        j = np.arange(j0, j1)
        force[j, c["lane"]] += c["pulse"].force(j / fine - c["start_time"])
    b, a = resonance_coefficients(scenario.plate_frequency, scenario.plate_damping, fine)
    sensed = lfilter(b, a, force, axis=0)
    if scenario.discharge_time > 0.0:
        sensed = lfilter(*discharge_coefficients(scenario.discharge_time, fine), sensed, axis=0)
    if scenario.antialias_order > 0:
        sensed = sosfilt(butter(scenario.antialias_order, scenario.antialias_cutoff * rate, fs=fine, output="sos"),
                         sensed, axis=0)
    sensed = sensed[::scenario.oversample]
    t = np.arange(n) / rate
    peaks = [c["pulse"].peak_force for c in contacts if not c["is_rebound"]]
    typical = float(np.median(peaks))
    sensor = dict(typical_peak=typical, noise_sd=scenario.noise * typical, hum_amplitude=scenario.hum_level * typical,
                  offsets=[], drift_end=[], hum_frequency=None, hum_phase=None)
    if not clean:
        hum_f = scenario.hum_frequency + rng.uniform(-0.02, 0.02)
        phase = rng.uniform(0.0, 2 * math.pi)
        hum = sensor["hum_amplitude"] * (np.sin(2 * math.pi * hum_f * t + phase)
                                         + scenario.hum_third * np.sin(3 * (2 * math.pi * hum_f * t + phase) + 0.7))
        knots = np.arange(0.0, duration + 0.02, 0.01)
        for lane in range(scenario.lanes):
            offset = rng.uniform(-1.0, 1.0) * scenario.offset
            slope = rng.uniform(-1.0, 1.0) * scenario.drift / duration
            walk = np.cumsum(rng.standard_normal(knots.size))
            walk *= 0.5 * scenario.drift / math.sqrt(knots.size)
            baseline = offset + slope * t + np.interp(t, knots, walk)
            sensed[:, lane] += baseline + hum + sensor["noise_sd"] * rng.standard_normal(n)
            sensor["offsets"].append(offset)
            sensor["drift_end"].append(float(baseline[-1] - baseline[0]))
        sensor.update(hum_frequency=hum_f, hum_phase=phase)
    if scenario.adc_bits > 0:
        lsb = 2.0 * scenario.adc_range / 2 ** scenario.adc_bits
        sensed = np.clip(np.round(sensed / lsb) * lsb, -scenario.adc_range, scenario.adc_range - lsb)
    recording = sensed.astype(np.float32)
    index = {id(c): c["index"] for c in contacts}
    truth_contacts = []
    for c, end in zip(contacts, ends):
        p = c["pulse"]
        truth_contacts.append(dict(
            index=c["index"], lane=c["lane"], lane_name=c["lane_name"], fruit_id=c["fruit_id"], kind=c["kind"],
            start_time=c["start_time"], end_time=end, peak_force=p.peak_force, time_to_peak=p.time_to_peak,
            contact_duration=p.duration, stiffness=p.K, damping=p.damping, restitution=p.restitution,
            velocity=p.velocity, exit_velocity=p.exit_velocity, mass=p.mass, modulus=c["modulus"],
            diameter=c["diameter"], poisson=c["poisson"], max_deflection=p.max_deflection,
            impulse=p.mass * (p.velocity + p.exit_velocity), is_rebound=c["is_rebound"],
            rebound_of=None if c["parent"] is None else index[id(c["parent"])], flight_time=c["flight_time"],
            close_arrival=c["close_arrival"], overlaps=[],
            **{"class": fruits[c["fruit_id"]]["cls"]}))
    by_lane: dict[int, list[dict]] = {}
    for c in truth_contacts:
        by_lane.setdefault(c["lane"], []).append(c)
    for lane_contacts in by_lane.values():
        for i, c in enumerate(lane_contacts):
            for d in lane_contacts[i + 1:]:
                if d["start_time"] >= c["end_time"]:
                    continue
                c["overlaps"].append(d["index"])
                d["overlaps"].append(c["index"])
    for f in fruits:
        f["class"] = f.pop("cls")
        f["contacts"] = [c["index"] for c in truth_contacts if c["fruit_id"] == f["fruit_id"]]
    config = dataclasses.asdict(scenario)
    config["kinds"] = [dict(dataclasses.asdict(k), share=w) for k, w in scenario.kinds]
    truth = dict(scenario=scenario.name, size=size, rate=rate, samples=n, duration=n / rate, start_time=0.0,
                 format=scenario.fmt, lanes=lane_names(scenario.fmt, scenario.lanes), drop_height=scenario.drop_height,
                 velocity=scenario.velocity, thresholds=list(scenario.thresholds), classes=list(scenario.classes),
                 sensor=sensor, config=config, contacts=truth_contacts, fruit=fruits,
                 analysis=_analysis(scenario, fruits))
    return recording, truth


def _analysis(scenario: Scenario, fruits: list[dict]) -> dict:
    """What a user of the line knows and tells ``analyze``."""
    info = dict(format=scenario.fmt, rate=scenario.rate, lanes=scenario.lanes, drop_height=scenario.drop_height,
                hum=scenario.hum_frequency, grading=scenario.grading,
                discharge_time=(scenario.discharge_time or None) if scenario.discharge_told else None)
    if scenario.grading:
        kind = scenario.kinds[0][0]
        info.update(diameter=kind.diameter, poisson=kind.poisson[0], thresholds=list(scenario.thresholds),
                    classes=list(scenario.classes))
    return info


def analyze_options(truth: dict) -> list[str]:
    """The ``fruitimpact analyze FILE`` options for a recording written by ``write``: ``--json --fit`` with the
    drop height and the hum, ``--rate/--lanes`` for raw files, the grading options for a grading lot."""
    a = truth["analysis"]
    options = ["--json", "--fit", "--drop-height", f"{a['drop_height'] * 1000:g}mm", "--hum", f"{a['hum']:g}"]
    if a.get("discharge_time"):  # the sensor's data sheet gives it
        options += ["--discharge-time", f"{a['discharge_time']:g}s"]
    if a["format"] in ("f32", "npy"):
        options += ["--rate", f"{a['rate']:g}"]
    if a["format"] == "f32":
        options += ["--lanes", str(a["lanes"])]
    if a["grading"]:
        options += ["--diameter", f"{a['diameter'] * 1000:g}mm", "--poisson", f"{a['poisson']:g}",
                    "--sort-by", "modulus", "--thresholds", ",".join(f"{x:.10g}" for x in a["thresholds"]),
                    "--classes", ",".join(a["classes"])]
    return options


# ---------------------------------------------------------------------------------------------------------------
# Writers
# ---------------------------------------------------------------------------------------------------------------

def write_recording(path: Path, recording: np.ndarray, rate: float, fmt: str) -> None:
    """Write samples × lanes [N] as ``fmt`` (see the module docstring)."""
    path = Path(path)
    data = np.asarray(recording, np.float32)
    if fmt == "f32":
        data.astype("<f4").tofile(path)
    elif fmt == "npy":
        np.save(path, data)
    elif fmt == "csv":
        n, lanes = data.shape
        header = ",".join(["time [s]"] + [f"lane{i} [N]" for i in range(lanes)])
        table = np.column_stack([np.arange(n) / rate, data.astype(float)])
        np.savetxt(path, table, delimiter=",", header=header, comments="",
                   fmt=["%.12f"] + ["%.9g"] * lanes)
    elif fmt == "tdms":
        from nptdms import ChannelObject, TdmsWriter

        props = dict(wf_increment=1.0 / rate, wf_start_offset=0.0, unit_string="N")
        with TdmsWriter(str(path)) as writer:
            writer.write_segment([ChannelObject(TDMS_GROUP, f"lane{i}", data[:, i], properties=props)
                                  for i in range(data.shape[1])])
    else:
        raise ValueError(f"unknown format {fmt!r}")


def write(scenario: Scenario | str, directory: Path, size: int | None = None) -> tuple[Path, dict]:
    """Generate a scenario and write ``DIRECTORY/NAME.EXT`` and ``DIRECTORY/NAME.truth.json``; → (path, truth)."""
    if isinstance(scenario, str):
        scenario = SCENARIOS[scenario]
    recording, truth = generate(scenario, size)
    path = Path(directory) / f"{scenario.name}{EXTENSION[scenario.fmt]}"
    write_recording(path, recording, scenario.rate, scenario.fmt)
    path.with_name(f"{scenario.name}.truth.json").write_text(json.dumps(truth, indent=1))
    return path, truth


# ---------------------------------------------------------------------------------------------------------------
# Scoring
# ---------------------------------------------------------------------------------------------------------------

def _is_overlap(report: dict) -> bool:
    return report.get("status") == "overlap"


def match(reports: list[dict], truth: dict, window: float = 1e-3) -> dict:
    """Pair truth contacts with reports.

    Lanes: a report's ``lane`` is the lane name the reader gave (``lane0`` … for f32/npy/csv, ``line/lane0`` …
    for TDMS), the same as the truth's ``lanes[contact['lane']]`` (``contact['lane_name']``).  A truth contact
    is found by the report of its lane whose ``start_time`` is within ``window`` [s] of its own (pairs taken
    one-to-one, closest first).  A truth contact left over is also found when a report with status
    "overlap" of its lane covers its start (report start − window … start + contact_duration + window): one
    overlap report may stand for two contacts.  Returns {"pairs": [(truth, report)], "covered": [truth contacts
    found only by an overlap report], "missed": [...], "extra": [reports matching nothing]}.
    """
    contacts = truth["contacts"]
    candidates = []
    for ri, r in enumerate(reports):
        for c in contacts:
            if r.get("lane") == c["lane_name"] and abs(r["start_time"] - c["start_time"]) < window:
                candidates.append((abs(r["start_time"] - c["start_time"]), c["index"], ri))
    candidates.sort()
    by_truth: dict[int, int] = {}
    used: set[int] = set()
    for _, ci, ri in candidates:
        if ci in by_truth or ri in used:
            continue
        by_truth[ci] = ri
        used.add(ri)
    covered, missed = [], []
    for c in contacts:
        if c["index"] in by_truth:
            continue
        cover = [ri for ri, r in enumerate(reports) if _is_overlap(r) and r.get("lane") == c["lane_name"]
                 and r["start_time"] - window <= c["start_time"]
                 <= r["start_time"] + r.get("contact_duration", 0.0) + window]
        if cover:
            covered.append(c)
            used.update(cover)
        else:
            missed.append(c)
    pairs = [(contacts[ci], reports[ri]) for ci, ri in sorted(by_truth.items())]
    extra = [r for ri, r in enumerate(reports) if ri not in used]
    return dict(pairs=pairs, covered=covered, missed=missed, extra=extra)


def _p(values, q):
    values = [v for v in values if v is not None]
    return float(np.percentile(values, q)) if values else float("nan")


def _relative(report: dict, item: dict, key: str):
    value = report.get(key)
    if value is None or not np.isfinite(value):
        return math.inf  # a missing value (failed fit) counts as a failure, not as a skipped one
    return abs(value / item[key] - 1.0)


def score(reports: list[dict], truth: dict, window: float = 1e-3) -> dict:
    """The issue's scorecard of one analysed recording (reports: the JSON objects of ``analyze --json``).

    * ``recall``: share of truth contacts found (by a report within ``window`` of their start, or covered by an
      "overlap" report); ``extra``: reports that match no truth contact.
    * ``fruit_taken_for_rebounds``: truth primaries whose report says ``rebound: true``;
      ``rebounds_taken_for_fruit``: truth rebounds whose report says ``rebound: false`` (missing = false).
    * ``peak_force_p95`` and ``time_to_peak_p95``: 95th percentile of |report/truth − 1| over every paired
      contact (primaries and rebounds: model-free indices).
    * ``stiffness_median``, ``stiffness_p95`` (|ΔK|/K) and ``restitution_p95`` (|Δe|): over the fruit, i.e. the
      paired truth primaries, whatever the report says about them (a fruit taken for a rebound and fitted at e V
      counts with its error; the grade comes from this contact).  Rebounds are left out: their speed is e V
      less the spin loss the analysis cannot know.  A missing fitted value counts as an infinite error.
    * ``overlaps``: reports with ``status == "overlap"``; they are left out of the error statistics and of the
      misflag counts, and ``truth_overlaps`` says how many truth contacts overlap another (for comparison).
    * ``wrong_parent`` (information, not a goal): paired truth rebounds flagged as rebounds whose report's
      ``rebound_of`` (a ``sequence``) is not the report paired with the truth's parent; ``unknown_parent``
      (information): those whose report names no parent (``rebound_of`` null: a parent not measured as it was).
    Unknown report keys are ignored.
    """
    m = match(reports, truth, window)
    contacts = truth["contacts"]
    pairs = [(c, r) for c, r in m["pairs"] if not _is_overlap(r)]
    report_of = {c["index"]: r for c, r in m["pairs"]}
    found = len(m["pairs"]) + len(m["covered"])
    fruit_pairs = [(c, r) for c, r in pairs if not c["is_rebound"]]
    wrong_parent = unknown_parent = 0
    for c, r in pairs:
        if c["is_rebound"] and r.get("rebound") and "rebound_of" in r and r["rebound_of"] is None:
            unknown_parent += 1
        elif c["is_rebound"] and r.get("rebound") and "rebound_of" in r and "sequence" in r:
            parent = report_of.get(c["rebound_of"])
            if parent is None or parent.get("sequence") != r["rebound_of"]:
                wrong_parent += 1
    return dict(
        contacts=len(contacts),
        fruit=sum(not c["is_rebound"] for c in contacts),
        reports=len(reports),
        recall=found / len(contacts) if contacts else float("nan"),
        missed=len(m["missed"]),
        extra=len(m["extra"]),
        fruit_taken_for_rebounds=sum(1 for c, r in pairs if not c["is_rebound"] and r.get("rebound", False)),
        rebounds_taken_for_fruit=sum(1 for c, r in pairs if c["is_rebound"] and not r.get("rebound", False)),
        # of those, the ones the analysis said it could not decide (``rebound_ambiguous``): not silent
        rebounds_taken_for_fruit_flagged=sum(1 for c, r in pairs if c["is_rebound"] and not r.get("rebound", False)
                                             and r.get("rebound_ambiguous", False)),
        peak_force_p95=_p([_relative(r, c, "peak_force") for c, r in pairs], 95),
        time_to_peak_p95=_p([_relative(r, c, "time_to_peak") for c, r in pairs], 95),
        stiffness_median=_p([_relative(r, c, "stiffness") for c, r in fruit_pairs], 50),
        stiffness_p95=_p([_relative(r, c, "stiffness") for c, r in fruit_pairs], 95),
        restitution_p95=_p([abs(r["restitution"] - c["restitution"]) if r.get("restitution") is not None
                            else math.inf for c, r in fruit_pairs], 95),
        overlaps=sum(1 for r in reports if _is_overlap(r)),
        truth_overlaps=sum(1 for c in contacts if c["overlaps"]),
        wrong_parent=wrong_parent,
        unknown_parent=unknown_parent,
    )


def check(card: dict) -> dict[str, bool]:
    """Each goal of ``GOALS`` → met?  (NaN, e.g. no fruit paired, is not met.)"""
    result = {}
    for key, (op, limit) in GOALS.items():
        value = card[key]
        result[key] = bool(value >= limit) if op == ">=" else bool(value <= limit)
    return result


def grade(reports: list[dict], truth: dict, margin: float = 0.05, window: float = 1e-3) -> dict:
    """Grading of the fruit (issue 13 item 5), from reports carrying ``class``.

    Each fruit's grade is the ``class`` of the report paired with its first contact (a report without a class,
    e.g. an overlap, or a fruit not found, is ``None``: not graded, never right).  Returns the confusion matrix
    {true class: {reported class or "none": count}} over all fruit, and over the clear fruit (true modulus at
    least ``margin`` relative away from every threshold, first contact overlapping no other contact):
    ``clear``, ``clear_right``, ``clear_accuracy`` (goal ``GRADING_GOAL``), ``ungraded`` (fruit without a
    class) and ``overlapped`` (fruit whose first contact overlaps another one, e.g. the previous fruit's
    rebound: the sensor sees the sum of two forces, which issue 13 item 2 reports as "overlap" without a
    firmness, so they are left out of the accuracy; they stay in the confusion matrix)."""
    m = match(reports, truth, window)
    report_of = {c["index"]: r for c, r in m["pairs"]}
    classes = list(truth["classes"])
    thresholds = np.asarray(truth["thresholds"], float)
    confusion = {a: {b: 0 for b in classes + ["none"]} for a in classes}
    clear = right = ungraded = 0
    wrong = []
    contacts = truth["contacts"]
    overlapped = overlapped_clear = overlapped_right = overlapped_wrong = 0
    for f in truth["fruit"]:
        first = contacts[f["contacts"][0]]
        report = report_of.get(first["index"])
        got = report.get("class") if report is not None and not _is_overlap(report) else None
        ungraded += got is None
        confusion[f["class"]][got if got in classes else "none"] += 1
        if first["overlaps"]:
            overlapped += 1  # its force is summed with another contact's: not required to be gradable (item 2)
            if np.all(np.abs(f["modulus"] / thresholds - 1.0) >= margin):
                overlapped_clear += 1
                overlapped_right += got == f["class"]
                overlapped_wrong += got is not None and got != f["class"]
            continue
        if np.all(np.abs(f["modulus"] / thresholds - 1.0) >= margin):
            clear += 1
            if got == f["class"]:
                right += 1
            else:
                wrong.append(dict(fruit_id=f["fruit_id"], modulus=f["modulus"], truth=f["class"], got=got,
                                  reported_rebound=None if report is None else report.get("rebound")))
    return dict(fruit=len(truth["fruit"]), confusion=confusion, clear=clear, clear_right=right,
                clear_accuracy=right / clear if clear else float("nan"), ungraded=ungraded, overlapped=overlapped,
                overlapped_clear=overlapped_clear, overlapped_right=overlapped_right, overlapped_wrong=overlapped_wrong,
                wrong=wrong)


__all__ = ["APPLE", "CLASSES", "EXTENSION", "FruitKind", "G", "GOALS", "GRADED_APPLE", "GRADING_GOAL",
           "HERTZ_TIME", "PEAR", "Pulse", "SCENARIOS", "Scenario", "THRESHOLDS", "analyze_options", "check",
           "classify", "contact", "draw_fruit", "generate", "grade", "hertz_max_deflection", "lane_names",
           "match", "resonance_coefficients", "score", "stiffness", "write", "write_recording"]
