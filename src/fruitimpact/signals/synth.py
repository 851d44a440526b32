"""A synthetic impact force sensor: recordings with a known truth, for testing analysis code.

Fruit fall onto a force plate.  Each impact's contact force F(t) is the
project's exact Hunt–Crossley solution (``impact.evaluation.evaluate`` for the
characteristics, ``engine.powerlaw.powerlaw_curves`` for the curve, evaluated at
t − t_onset on the sample grid, so onsets fall anywhere between samples).  The
sensor chain is applied in the physical order (impact-sensors.md §3.1):

1. the true contact force, summed over the impacts of a lane;
2. the plate/transducer resonance, a unit-DC-gain 2nd-order system
   y'' + 2ζω y' + ω² y = ω² F (``plate_frequency``, ``plate_damping``);
3. a causal 4th-order Butterworth anti-alias low-pass (``antialias_cutoff``);
4. sampling at ``rate``; then a baseline offset and linear drift, mains hum and
   white noise are added, and the ADC clips at ``clip_low``/``clip_high`` and
   quantises (``adc_bits``).

Stages 2 and 3 are analogue: they are simulated on a grid ``oversample`` times
finer than the output, each 2nd-order section (the resonance, the two sections
of the Butterworth) discretised exactly for a piecewise-linear input
(first-order hold, ``scipy.signal.cont2discrete``), then sampled.  Without them
the force is evaluated directly at the sample times.  SciPy is needed only for
those two stages and is imported when they are used.

Rebounds: after a contact the fruit leaves at its exit speed V₂ = e V₁ and lands
again after the flight time 2 V₂/g (no drag), on the same lane, with the same
material: the Hunt–Crossley damping factor c is a material constant, so the
rebound has the same c (given as α = c/1.5) at the lower speed, and a higher
restitution.  A second rebound follows the first in the same way.

``synthesize`` returns the ``Recording`` and its truth (a JSON-able dict);
``write_recording`` writes recordings in every format ``signals.read`` reads;
``write_truth`` writes the truth beside it.
"""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from fruitimpact.physics.constants import STANDARD_GRAVITY
from fruitimpact.impact.units import parse_quantity
from fruitimpact.impact.validation import InputError, check_integer, check_number
from fruitimpact.signals.read import _column, recording_format
from fruitimpact.signals.recording import Recording
from fruitimpact.signals.settings import check_rate

#: Number of output samples simulated at once on the analogue grid (bounds the memory of long recordings).
_CHUNK = 1 << 16
#: Exact force values per contact behind the interpolant of the analogue grid (``_splines``).
_NODES = 129
#: Quiet time kept after the last contact when no ``duration`` is given [s] (plus the plate's ring-down).
TAIL = 0.02


#: The dimension of each setting that may be given as a string with units (``"115g"``, ``"20kHz"``), as the
#: CLI reads them (``impact.units``).
_DIMENSIONS = {"mass": "mass", "diameter": "length", "modulus": "modulus", "poisson": "dimensionless",
               "velocity": "velocity", "drop_height": "length", "restitution": "dimensionless", "alpha": "alpha",
               "time": "time", "interval": "time", "jitter": "time", "start": "time", "rate": "frequency",
               "hum_frequency": "frequency", "plate_frequency": "frequency", "antialias_cutoff": "frequency",
               "noise_sd": "force", "hum_amplitude": "force", "clip_low": "force", "clip_high": "force",
               "noise": "dimensionless", "modulus_spread": "dimensionless", "mass_spread": "dimensionless",
               "plate_damping": "dimensionless"}


#: Largest lognormal spread (sd of ln E, ln m) of a synthetic population: a factor e² per sd.
MAX_LOG_SPREAD = 2.0


def _number(owner: str, name: str, value, **bounds):
    """``validation.check_number`` with the settings object's name in the message; a string is read with its
    unit first (``_DIMENSIONS``)."""
    if isinstance(value, str) and name in _DIMENSIONS:
        try:
            value = parse_quantity(value, _DIMENSIONS[name])
        except ValueError as exc:
            raise InputError(f"{owner}.{name}: {exc}", name) from None
    return check_number(name, value, owner=owner, **bounds)


def _integer(owner: str, name: str, value, low: int, high: int | None = None) -> int:
    return check_integer(name, value, low, high, owner=owner)


def _seed(owner: str, value):
    if value is None:
        return None
    return _integer(owner, "seed", value, 0)


# --------------------------------------------------------------------------- the sensor

@dataclass(frozen=True)
class SensorModel:
    """The force sensor and its acquisition chain (SI units).

    Parameters
    ----------
    rate : float
        Sample rate [Hz] in (0, 10 MHz] (default 20 kHz; ``signals.settings.check_rate``).
    noise_sd : float
        Standard deviation of the white noise [N] (default 0: none).
    noise : float
        The white noise instead as a fraction of the typical peak force: the
        median ``peak_force`` of the given (not rebound) impacts, in [0, 1].  At most one
        of ``noise_sd`` and ``noise`` may be non-zero.
    drift : float
        Linear baseline drift [N/s], from t = 0 (default 0).
    drift_offset : float
        Baseline offset [N] at t = 0 (default 0).
    hum_amplitude : float
        Mains hum amplitude [N] (default 0: none); its phase is drawn from ``seed``.
    hum_frequency : float
        Mains hum frequency [Hz] (default 50), below rate/2 when there is hum.
    adc_bits : int
        0 (default): no quantisation; else the samples are rounded to steps of
        (clip_high − clip_low)/2^adc_bits from clip_low (both limits are
        levels), which needs both limits.
    clip_low, clip_high : float or None
        The ADC's limits [N]: samples beyond are set to the limit.  None: no limit.
    plate_frequency : float
        Natural frequency f_n of the plate/transducer resonance [Hz] (default 0:
        none), below rate·oversample/20.
    plate_damping : float or None
        Damping ratio ζ > 0 of the resonance; required with ``plate_frequency``.
    antialias_cutoff : float
        −3 dB cut-off of the 4th-order Butterworth anti-alias filter [Hz]
        (default 0: none), below rate/2.
    oversample : int
        The analogue stages run on a grid ``oversample`` times finer than
        ``rate`` (default 16); unused without them.
    seed : int or None
        Seed of the noise and the hum phase (None: fresh entropy, recorded in
        the truth so that the run can be repeated).
    """

    rate: float = 20000.0
    noise_sd: float = 0.0
    noise: float = 0.0
    drift: float = 0.0
    drift_offset: float = 0.0
    hum_amplitude: float = 0.0
    hum_frequency: float = 50.0
    adc_bits: int = 0
    clip_low: float | None = None
    clip_high: float | None = None
    plate_frequency: float = 0.0
    plate_damping: float | None = None
    antialias_cutoff: float = 0.0
    oversample: int = 16
    seed: int | None = None

    def __post_init__(self):
        o = "SensorModel"
        rate = check_rate(self.rate, "rate")  # the one check of a sample rate (signals.settings)
        values = {
            "rate": rate,
            "noise_sd": _number(o, "noise_sd", self.noise_sd, low=0.0),
            "noise": _number(o, "noise", self.noise, low=0.0, high=1.0, high_inclusive=True),
            "drift": _number(o, "drift", self.drift),
            "drift_offset": _number(o, "drift_offset", self.drift_offset),
            "hum_amplitude": _number(o, "hum_amplitude", self.hum_amplitude, low=0.0),
            "hum_frequency": _number(o, "hum_frequency", self.hum_frequency, low=0.0, low_inclusive=False,
                                     high=rate / 2 if self.hum_amplitude else None),
            "adc_bits": _integer(o, "adc_bits", self.adc_bits, 0, 32),
            "clip_low": _number(o, "clip_low", self.clip_low, optional=True),
            "clip_high": _number(o, "clip_high", self.clip_high, optional=True),
            "oversample": _integer(o, "oversample", self.oversample, 1),
            "antialias_cutoff": _number(o, "antialias_cutoff", self.antialias_cutoff, low=0.0, high=rate / 2),
            "seed": _seed(o, self.seed),
        }
        values["plate_frequency"] = _number(o, "plate_frequency", self.plate_frequency, low=0.0,
                                            high=rate * values["oversample"] / 20)
        values["plate_damping"] = _number(o, "plate_damping", self.plate_damping, low=0.0, low_inclusive=False,
                                          optional=True)
        for name, value in values.items():
            object.__setattr__(self, name, value)
        if self.noise_sd > 0 and self.noise > 0:
            raise InputError("SensorModel: give noise_sd [N] or noise (a fraction of the typical peak force), "
                             "not both", "noise")
        if self.clip_low is not None and self.clip_high is not None and not self.clip_low < self.clip_high:
            raise InputError(f"SensorModel.clip_low must be below clip_high; got {self.clip_low!r} and "
                             f"{self.clip_high!r}", "clip_low")
        if self.adc_bits and (self.clip_low is None or self.clip_high is None):
            raise InputError("SensorModel.adc_bits needs both clip_low and clip_high (the ADC's range [N])",
                             "adc_bits")
        if self.plate_frequency > 0 and self.plate_damping is None:
            raise InputError("SensorModel.plate_damping (the damping ratio ζ > 0) is required with "
                             "plate_frequency", "plate_damping")

    @property
    def analogue(self) -> bool:
        """Whether an analogue stage (resonance, anti-alias filter) is modelled."""
        return self.plate_frequency > 0 or self.antialias_cutoff > 0

    @property
    def quantisation_step(self) -> float | None:
        """The ADC step (clip_high − clip_low)/2^adc_bits [N], or None without quantisation."""
        if not self.adc_bits:
            return None
        return (self.clip_high - self.clip_low) / 2.0 ** self.adc_bits


def _sections(sensor: SensorModel) -> list[tuple[float, float]]:
    """(ω [rad/s], ζ) of the analogue 2nd-order unit-DC-gain sections: the plate resonance and
    the two sections of the 4th-order Butterworth (Q = 1/(2 cos(π/8)), 1/(2 cos(3π/8)))."""
    sections = []
    if sensor.plate_frequency > 0:
        sections.append((2 * math.pi * sensor.plate_frequency, sensor.plate_damping))
    if sensor.antialias_cutoff > 0:
        omega = 2 * math.pi * sensor.antialias_cutoff
        sections += [(omega, math.cos(math.pi / 8)), (omega, math.cos(3 * math.pi / 8))]
    return sections


def _analogue_sos(sensor: SensorModel, fine_rate: float) -> np.ndarray:
    """Second-order sections of y'' + 2ζω y' + ω² y = ω² u per section, each discretised
    exactly for an input linear between the samples of the fine grid (first-order hold)."""
    from scipy import signal

    rows = []
    for omega, zeta in _sections(sensor):
        a = np.array([[0.0, 1.0], [-omega * omega, -2.0 * zeta * omega]])
        b = np.array([[0.0], [omega * omega]])
        c = np.array([[1.0, 0.0]])
        d = np.array([[0.0]])
        ad, bd, cd, dd, _ = signal.cont2discrete((a, b, c, d), 1.0 / fine_rate, method="foh")
        num, den = signal.ss2tf(ad, bd, cd, dd)
        num = np.ravel(num)
        rows.append(np.concatenate([num / den[0], den / den[0]]))
    return np.array(rows)


# --------------------------------------------------------------------------- impacts and populations

@dataclass(frozen=True)
class Impact:
    """One fruit hitting the plate (SI units).

    Parameters
    ----------
    time : float
        True first touch [s] from the start of the recording, >= 0.
    mass, diameter, modulus, poisson : float
        The fruit: mass [kg], diameter at the contact [m], flesh modulus E [Pa],
        Poisson's ratio [-] (checked by ``impact.evaluation.evaluate``).
    velocity, drop_height : float
        Impact speed [m/s] or drop height [m] (V = √(2 g h)): exactly one.
    restitution, alpha : float
        Restitution e the Hunt–Crossley damping is calibrated to (exactly), or
        Hunt–Crossley's α [s/m] (c = 1.5 α): exactly one.
    lane : int
        Lane index (lane ``lane<k>`` of the recording), default 0.
    rebounds : int
        Rebounds to simulate after this impact: 0 (default), 1 or 2.
    label : str
        Firmness class of the fruit (``class`` in the truth), default "".
    """

    time: float
    mass: float
    diameter: float
    modulus: float
    poisson: float
    velocity: float | None = None
    drop_height: float | None = None
    restitution: float | None = None
    alpha: float | None = None
    lane: int = 0
    rebounds: int = 0
    label: str = ""

    def __post_init__(self):
        o = "Impact"
        object.__setattr__(self, "time", _number(o, "time", self.time, low=0.0))
        for name in ("mass", "diameter", "modulus", "poisson"):
            object.__setattr__(self, name, _number(o, name, getattr(self, name)))
        for name in ("velocity", "drop_height", "restitution", "alpha"):
            object.__setattr__(self, name, _number(o, name, getattr(self, name), optional=True))
        if (self.velocity is None) == (self.drop_height is None):
            raise InputError("Impact: give exactly one of velocity [m/s] and drop_height [m]", "velocity")
        if (self.restitution is None) == (self.alpha is None):
            raise InputError("Impact: give exactly one of restitution and alpha [s/m]", "restitution")
        object.__setattr__(self, "lane", _integer(o, "lane", self.lane, 0))
        object.__setattr__(self, "rebounds", _integer(o, "rebounds", self.rebounds, 0, 2))
        if not isinstance(self.label, str):
            raise InputError(f"Impact.label must be a string; got {self.label!r}", "label")


@dataclass(frozen=True)
class Population:
    """Fruit arriving on a line: ``count`` per lane, one per slot of ``interval`` seconds.

    Fruit k of a lane first touches the plate at start + (k + ½)·interval + u,
    u uniform in [−jitter, jitter] (jitter ≤ interval/2: neighbours may touch,
    never swap).  Its modulus is lognormal around the median ``modulus`` (σ of
    ln E = ``modulus_spread``), its mass lognormal around ``mass`` (σ of ln m =
    ``mass_spread``) with the diameter scaled as (m/mass)^(1/3) (same density
    and shape); Poisson's ratio, speed (or drop height) and restitution (or α)
    are the same for all.  The firmness class is the first of ``classes``
    (label, upper bound of E [Pa]; increasing bounds, the last infinite) whose
    bound exceeds the fruit's modulus.

    ``impacts()`` draws them (reproducibly with ``seed``), lane by lane.
    """

    count: int
    interval: float
    mass: float
    diameter: float
    modulus: float
    poisson: float
    classes: Sequence[tuple[str, float]] | Mapping[str, float]
    velocity: float | None = None
    drop_height: float | None = None
    restitution: float | None = None
    alpha: float | None = None
    modulus_spread: float = 0.0
    mass_spread: float = 0.0
    jitter: float = 0.0
    start: float = 0.0
    rebounds: int = 0
    lanes: int = 1
    seed: int | None = None

    def __post_init__(self):
        o = "Population"
        object.__setattr__(self, "count", _integer(o, "count", self.count, 1))
        object.__setattr__(self, "interval", _number(o, "interval", self.interval, low=0.0, low_inclusive=False))
        for name in ("mass", "diameter", "modulus"):
            object.__setattr__(self, name, _number(o, name, getattr(self, name), low=0.0, low_inclusive=False))
        object.__setattr__(self, "poisson", _number(o, "poisson", self.poisson))
        for name in ("modulus_spread", "mass_spread"):  # beyond 2 (a factor e² per sd) the draws overflow to inf
            object.__setattr__(self, name, _number(o, name, getattr(self, name), low=0.0, high=MAX_LOG_SPREAD,
                                                   high_inclusive=True))
        object.__setattr__(self, "start", _number(o, "start", self.start, low=0.0))
        object.__setattr__(self, "jitter", _number(o, "jitter", self.jitter, low=0.0, high=self.interval / 2,
                                                   high_inclusive=True))
        object.__setattr__(self, "rebounds", _integer(o, "rebounds", self.rebounds, 0, 2))
        object.__setattr__(self, "lanes", _integer(o, "lanes", self.lanes, 1))
        object.__setattr__(self, "seed", _seed(o, self.seed))
        classes = list(self.classes.items()) if isinstance(self.classes, Mapping) else list(self.classes)
        checked = []
        for item in classes:
            if not (isinstance(item, (tuple, list)) and len(item) == 2 and isinstance(item[0], str) and item[0]):
                raise InputError(f"Population.classes must be (label, upper bound of E [Pa]) pairs; got {item!r}",
                                 "classes")
            bound = item[1]
            if isinstance(bound, (bool, np.bool_)) or not isinstance(bound, (int, float, np.integer, np.floating)) \
                    or math.isnan(bound):
                raise InputError(f"Population.classes: the bound of {item[0]!r} must be a number [Pa]; got {bound!r}",
                                 "classes")
            checked.append((item[0], float(bound)))
        bounds = [bound for _, bound in checked]
        if not checked or bounds[-1] != math.inf or any(b >= c for b, c in itertools.pairwise(bounds)):
            raise InputError("Population.classes must list (label, upper bound of E [Pa]) with increasing bounds, "
                             "the last one inf (e.g. (('soft', 2.5e6), ('medium', 4.5e6), ('firm', inf)))", "classes")
        object.__setattr__(self, "classes", tuple(checked))
        # the fruit's own checks (speed or height, restitution or alpha) before any draw
        Impact(time=0.0, mass=self.mass, diameter=self.diameter, modulus=self.modulus, poisson=self.poisson,
               velocity=self.velocity, drop_height=self.drop_height, restitution=self.restitution, alpha=self.alpha)

    def classify(self, modulus: float) -> str:
        """The firmness class of a fruit of modulus E [Pa]."""
        return next(label for label, bound in self.classes if modulus < bound)

    def impacts(self) -> list[Impact]:
        """The drawn impacts, lane by lane, in time order within each lane."""
        rng = np.random.default_rng(self.seed)
        out = []
        for lane in range(self.lanes):
            modulus = self.modulus * np.exp(self.modulus_spread * rng.standard_normal(self.count))
            mass = self.mass * np.exp(self.mass_spread * rng.standard_normal(self.count))
            shift = rng.uniform(-self.jitter, self.jitter, self.count)
            for k in range(self.count):
                out.append(Impact(time=self.start + (k + 0.5) * self.interval + float(shift[k]), mass=float(mass[k]),
                                  diameter=self.diameter * float(mass[k] / self.mass) ** (1.0 / 3.0),
                                  modulus=float(modulus[k]), poisson=self.poisson, velocity=self.velocity,
                                  drop_height=self.drop_height, restitution=self.restitution, alpha=self.alpha,
                                  lane=lane, rebounds=self.rebounds, label=self.classify(float(modulus[k]))))
        return out


# --------------------------------------------------------------------------- synthesis

@dataclass
class _Contact:
    lane: int
    start: float
    row: dict
    rebound: bool
    of: int | None
    input_index: int | None
    label: str
    rebounds_left: int
    extra: dict = field(default_factory=dict)


def _evaluate(rows: list[dict], names: list[str]) -> list[dict]:
    """Characteristics of every row (Hunt–Crossley, exact calibration, accurate solver);
    a row that is not ok is refused naming it."""
    from fruitimpact.impact.evaluation import evaluate

    keys = ("mass", "diameter", "modulus", "poisson", "velocity", "drop_height", "restitution", "alpha")
    table = {key: [row.get(key) for row in rows] for key in keys}
    table.update(model=["hunt-crossley"] * len(rows), calibration=["exact"] * len(rows),
                 method=["accurate"] * len(rows))
    frame = evaluate(table)
    out = []
    for i, record in enumerate(frame.to_dict("records")):
        if record["status"] != "ok":
            raise InputError(f"{names[i]}: {record['message']}", "impacts")
        out.append(record)
    return out


def synthesize(sensor: SensorModel, impacts, *, lanes: int = 1, duration: float | None = None):
    """A synthetic recording of ``impacts`` through ``sensor``, and its truth.

    Parameters
    ----------
    sensor : SensorModel
        The sensor the force passes through (noise, drift, hum, ADC, clipping, plate, filter).
    impacts : sequence of Impact, or Population
        The impacts (a Population gives its ``impacts()``).  May be empty (a recording of the disturbances alone; ``duration`` is
        then required).  Each impact's lane must be below ``lanes``.
    lanes : int
        Lanes of the recording, named ``lane0`` … (default 1).
    duration : float, optional
        Length of the recording [s] (samples = ⌈duration·rate⌉).  Default: to the
        end of the last contact (rebounds included) plus ``TAIL`` = 20 ms, plus
        five time constants 1/(ζ ω) of the plate when it is modelled.  Every
        given impact must start before it; rebounds landing after it are left out.

    Returns
    -------
    (Recording, dict)
        The recording (start time 0, the sensor's clip limits, source
        ``"synthetic"``) and the truth: ``rate``, ``samples``, ``duration``,
        ``lanes``, ``clip_low``, ``clip_high``, ``sensor`` (the settings, the
        noise sd used, the quantisation step, the analogue grid's rate, the hum
        phase, the seed entropy) and ``impacts``, in time order, each with
        ``lane`` (name), ``lane_index``, ``start_time`` (true first touch [s]),
        ``end_time`` (separation [s]), ``peak_force`` [N], ``time_to_peak`` [s],
        ``contact_duration`` [s], ``firmness_c`` [N/s], ``firmness_c_star``
        [N/s²], ``impulse`` (∫F dt = m (1 + e) V [N·s]), ``rebound``, ``of`` (the
        index in the truth's ``impacts`` of the contact it rebounds from, else
        None), ``flight_time`` (2 V₂/g before a rebound [s], else None),
        ``input_index`` (the index in the given impacts, None for rebounds),
        ``velocity``, ``exit_velocity`` [m/s], ``mass``, ``diameter``,
        ``modulus``, ``poisson``, ``stiffness`` (k_c [N/m^1.5]),
        ``damping_factor`` (c [s/m]), ``restitution``, ``max_deflection`` [m],
        ``class`` and ``complete`` (the contact ends inside the recording).
        All values are of the true contact force, not of the sensor's output.
    """
    if not isinstance(sensor, SensorModel):
        raise InputError(f"sensor must be a SensorModel; got {type(sensor).__name__}", "sensor")
    if isinstance(impacts, Population):
        impacts = impacts.impacts()
    if isinstance(impacts, (str, bytes, Impact)) or not isinstance(impacts, Sequence):
        raise InputError("impacts must be a sequence of Impact or a Population", "impacts")
    for i, impact in enumerate(impacts):
        if not isinstance(impact, Impact):
            raise InputError(f"impacts[{i}] must be an Impact; got {type(impact).__name__}", "impacts")
    lanes = _integer("", "lanes", lanes, 1)
    duration = _number("", "duration", duration, low=0.0, low_inclusive=False, optional=True)
    for i, impact in enumerate(impacts):
        if impact.lane >= lanes:
            raise InputError(f"impacts[{i}] is on lane {impact.lane} but the recording has lanes={lanes} "
                             f"(give lanes={impact.lane + 1} or more)", "lanes")
        if duration is not None and impact.time >= duration:
            raise InputError(f"impacts[{i}] starts at {impact.time:g} s, not before duration={duration:g} s",
                             "duration")
    if duration is None and not impacts:
        raise InputError("duration is required when there are no impacts", "duration")
    if sensor.noise > 0 and not impacts:
        raise InputError("SensorModel.noise is relative to the typical peak force, and there are no impacts; "
                         "give noise_sd [N]", "noise")
    # the contacts: the given impacts, then their rebounds, generation by generation
    rows = [{"mass": p.mass, "diameter": p.diameter, "modulus": p.modulus, "poisson": p.poisson,
             "velocity": p.velocity, "drop_height": p.drop_height, "restitution": p.restitution, "alpha": p.alpha}
            for p in impacts]
    results = _evaluate(rows, [f"impacts[{i}]" for i in range(len(impacts))]) if impacts else []
    contacts = [_Contact(lane=p.lane, start=p.time, row=r, rebound=False, of=None, input_index=i, label=p.label,
                         rebounds_left=p.rebounds) for i, (p, r) in enumerate(zip(impacts, results))]
    parents = [k for k, c in enumerate(contacts) if c.rebounds_left > 0]
    while parents:
        # the same fruit and material (c = 1.5 α), landing at its exit speed V₂ = e V₁
        rows = [{"mass": contacts[k].row["mass"], "diameter": contacts[k].row["diameter"],
                 "modulus": contacts[k].row["modulus"], "poisson": contacts[k].row["poisson"],
                 "velocity": contacts[k].row["exit_velocity"], "alpha": contacts[k].row["damping_factor"] / 1.5}
                for k in parents]
        names = [f"the rebound of impacts[{contacts[k].input_index}]" if not contacts[k].rebound else
                 f"a rebound of impacts[{_root(contacts, k).input_index}]" for k in parents]
        results = _evaluate(rows, names)
        new = []
        for k, r in zip(parents, results):
            parent = contacts[k]
            flight = 2.0 * parent.row["exit_velocity"] / STANDARD_GRAVITY
            start = parent.start + parent.row["contact_duration"] + flight
            if duration is not None and start >= duration:
                continue
            contacts.append(_Contact(lane=parent.lane, start=start, row=r, rebound=True, of=k, input_index=None,
                                     label=parent.label, rebounds_left=parent.rebounds_left - 1,
                                     extra={"flight_time": flight}))
            if parent.rebounds_left > 1:
                new.append(len(contacts) - 1)
        parents = new
    rate = sensor.rate
    if duration is None:
        tail = TAIL
        if sensor.plate_frequency > 0:
            tail += 5.0 / (sensor.plate_damping * 2 * math.pi * sensor.plate_frequency)
        duration = max(c.start + c.row["contact_duration"] for c in contacts) + tail
    samples = max(1, math.ceil(duration * rate * (1.0 - 1e-12)))
    primary_peaks = [c.row["peak_force"] for c in contacts if not c.rebound]
    noise_sd = sensor.noise_sd if sensor.noise == 0 else sensor.noise * float(np.median(primary_peaks))
    sequence = np.random.SeedSequence(sensor.seed)
    rng = np.random.default_rng(sequence)
    hum_phase = float(rng.uniform(0.0, 2 * math.pi)) if sensor.hum_amplitude > 0 else 0.0
    oversample = sensor.oversample if sensor.analogue else 1
    sos = _analogue_sos(sensor, rate * oversample) if sensor.analogue else None
    splines = _splines(contacts) if sensor.analogue and contacts else None
    t = np.arange(samples) / rate
    disturbance = sensor.drift_offset + sensor.drift * t
    if sensor.hum_amplitude > 0:
        disturbance = disturbance + sensor.hum_amplitude * np.sin(2 * math.pi * sensor.hum_frequency * t + hum_phase)
    names = [f"lane{k}" for k in range(lanes)]
    data = {}
    for lane in range(lanes):
        mine = [k for k, c in enumerate(contacts) if c.lane == lane]
        force = _force([contacts[k] for k in mine], samples, rate, oversample, sos,
                       [splines[k] for k in mine] if splines else None)
        values = force + disturbance
        if noise_sd > 0:
            values = values + rng.normal(0.0, noise_sd, samples)
        data[names[lane]] = _adc(values, sensor)
    recording = Recording(rate=rate, lanes=data, start_time=0.0, clip_low=sensor.clip_low,
                          clip_high=sensor.clip_high, source="synthetic")
    truth = _truth(sensor, recording, contacts, names, noise_sd, hum_phase, rate * oversample, sequence.entropy)
    return recording, truth


def _root(contacts, k):
    while contacts[k].of is not None:
        k = contacts[k].of
    return contacts[k]


def _curve(row: dict, times: np.ndarray) -> np.ndarray:
    """The exact contact force [N] of one impact at ``times`` [s] after its first touch."""
    from fruitimpact.engine.powerlaw import powerlaw_curves

    return powerlaw_curves(row["mass"], row["law_stiffness"], row["damping_factor"], row["velocity"], times)[2]


def _splines(contacts) -> list:
    """Per contact, a cubic Hermite interpolant of its force through ``_NODES`` exact values and
    exact slopes at Chebyshev–Lobatto times over [0, T] (dense at the ends, where F ~ t^1.5):
    the analogue grid has ~16 points per output sample, too many to evaluate exactly.  Its error
    is ~1e-6 of the peak force (below 1e-4 N for an apple of 90 N)."""
    from scipy.interpolate import CubicHermiteSpline

    from fruitimpact.engine.powerlaw import powerlaw_curves_batch

    rows = [c.row for c in contacts]
    mass, stiffness, damping, velocity, duration = (np.array([r[key] for r in rows]) for key in
                                                    ("mass", "law_stiffness", "damping_factor", "velocity",
                                                     "contact_duration"))
    nodes = 0.5 * (1.0 - np.cos(np.pi * np.linspace(0.0, 1.0, _NODES)))
    times = nodes[None, :] * duration[:, None]
    deflection, rate, force = powerlaw_curves_batch(mass, stiffness, damping, velocity, times)
    # dF/dt of F = K δ^1.5 (1 + c δ̇), with δ̈ = −F/m
    slope = stiffness[:, None] * (1.5 * np.sqrt(deflection) * rate * (1.0 + damping[:, None] * rate)
                                  - damping[:, None] * deflection ** 1.5 * force / mass[:, None])
    return [CubicHermiteSpline(times[i], force[i], slope[i], extrapolate=False) for i in range(len(rows))]


def _force(contacts, samples: int, rate: float, oversample: int, sos, splines) -> np.ndarray:
    """The true force of ``contacts`` through the analogue stages, at the sample times."""
    out = np.zeros(samples)
    if sos is None:
        for c in contacts:
            first = max(0, math.ceil(c.start * rate))
            last = min(samples - 1, math.floor((c.start + c.row["contact_duration"]) * rate))
            if last >= first:
                j = np.arange(first, last + 1)
                out[first:last + 1] += _curve(c.row, j / rate - c.start)
        return out
    from scipy import signal

    fine_rate = rate * oversample
    state = np.zeros((sos.shape[0], 2))
    for begin in range(0, samples, _CHUNK):
        end = min(samples, begin + _CHUNK)
        f0, f1 = begin * oversample, end * oversample  # the fine samples of this chunk's output samples
        fine = np.zeros(f1 - f0)
        for c, spline in zip(contacts, splines):
            first = max(f0, math.ceil(c.start * fine_rate))
            last = min(f1 - 1, math.floor((c.start + c.row["contact_duration"]) * fine_rate))
            if last >= first:
                tau = np.clip(np.arange(first, last + 1) / fine_rate - c.start, 0.0, c.row["contact_duration"])
                fine[first - f0:last + 1 - f0] += spline(tau)
        filtered, state = signal.sosfilt(sos, fine, zi=state)
        out[begin:end] = filtered[::oversample]
    return out


def _adc(values: np.ndarray, sensor: SensorModel) -> np.ndarray:
    low, high = sensor.clip_low, sensor.clip_high
    if low is not None or high is not None:
        values = np.clip(values, -np.inf if low is None else low, np.inf if high is None else high)
    if sensor.adc_bits:
        levels = 2 ** sensor.adc_bits
        step = (high - low) / levels
        code = np.rint((values - low) / step)
        values = np.where(code >= levels, high, low + code * step)
    return values


def _truth(sensor, recording, contacts, names, noise_sd, hum_phase, fine_rate, entropy) -> dict:
    order = sorted(range(len(contacts)), key=lambda k: (contacts[k].start, contacts[k].lane))
    position = {k: i for i, k in enumerate(order)}
    end_of_recording = recording.duration
    impacts = []
    for k in order:
        c = contacts[k]
        r = c.row
        end = c.start + r["contact_duration"]
        record = dict(
            lane=names[c.lane], lane_index=c.lane, start_time=c.start, end_time=end,
            peak_force=r["peak_force"], time_to_peak=r["time_to_peak"], contact_duration=r["contact_duration"],
            firmness_c=r["firmness_c"], firmness_c_star=r["firmness_c_star"],
            impulse=r["mass"] * (1.0 + r["restitution"]) * r["velocity"],
            rebound=c.rebound, of=None if c.of is None else position[c.of], input_index=c.input_index,
            velocity=r["velocity"], exit_velocity=r["exit_velocity"], mass=r["mass"], diameter=r["diameter"],
            modulus=r["modulus"], poisson=r["poisson"], stiffness=r["law_stiffness"],
            damping_factor=r["damping_factor"], restitution=r["restitution"], max_deflection=r["max_deflection"],
            **{"class": c.label}, complete=bool(end <= end_of_recording),
            flight_time=c.extra.get("flight_time"))
        impacts.append({key: (float(value) if isinstance(value, (float, np.floating)) else value)
                        for key, value in record.items()})
    settings = asdict(sensor)
    settings.update(noise_sd_used=float(noise_sd), quantisation_step=sensor.quantisation_step,
                    analogue_rate=float(fine_rate) if sensor.analogue else None, hum_phase=hum_phase,
                    seed_entropy=str(entropy))
    return {"rate": recording.rate, "samples": recording.samples, "duration": recording.duration,
            "start_time": recording.start_time, "lanes": list(names), "clip_low": recording.clip_low,
            "clip_high": recording.clip_high, "sensor": settings, "impacts": impacts}


# --------------------------------------------------------------------------- writing

def _check_lane_names(recording: Recording, kind: str) -> None:
    for name in recording.lane_names:
        if kind == "csv":
            readable = (name == name.strip() and not any(ch in name for ch in ',"\r\n')
                        and not name.lstrip().startswith("#"))
            if readable:
                try:
                    readable = _column("", f"{name} [N]", 0) == (name, False, 1.0)
                except ValueError:
                    readable = False
            if not readable:
                raise InputError(f"lane name {name!r} cannot be written to a CSV header that reads back as itself "
                                 f"(no commas, quotes, line breaks, surrounding blanks, time names or units)",
                                 "recording")


def write_recording(recording: Recording, path, format: str | None = None) -> Path:
    """Write ``recording`` to ``path`` (atomically: a temporary file beside it, then renamed).

    Formats (from the extension, or ``format``; ``signals.read.FORMATS``):

    * ``csv``: header ``time [s],<lane> [N],...``, then one row per sample, the
      time start_time + n/rate and the forces as shortest round-trip decimals;
    * ``npy``: float64, 1-D for one lane, else samples × lanes (names and
      rate are not stored: they read back as ``lane<k>`` with ``rate=``);
    * ``f32``: raw little-endian float32, lanes interleaved sample by sample
      (read back with ``rate=`` and ``lanes=``);
    * ``tdms``: group ``fruitimpact``, one channel per lane with
      ``wf_increment`` = 1/rate, ``wf_start_offset`` = start_time,
      ``wf_samples``, ``unit_string`` = ``N`` and, when known, ``clip_low`` and
      ``clip_high`` (reads back as lanes ``fruitimpact/<lane>``; needs nptdms).

    Returns the path.  ``ValueError`` (one line) for an unsupported format, a
    path that cannot be written, a lane name CSV cannot carry, or forces
    beyond float32 for ``f32``.
    """
    from fruitimpact.impact.outputs import atomic_write, check_output

    if not isinstance(recording, Recording):
        raise InputError(f"recording must be a Recording; got {type(recording).__name__}", "recording")
    kind = recording_format(path, format)
    path = check_output(path, "path")
    _check_lane_names(recording, kind)
    matrix = np.column_stack([recording.lanes[name] for name in recording.lane_names])
    if kind == "f32" and np.abs(matrix).max() > np.finfo(np.float32).max:
        raise InputError("recording: forces beyond the float32 range cannot be written as .f32", "recording")
    if kind == "tdms":
        try:
            import nptdms  # noqa: F401
        except ImportError:
            raise InputError("writing TDMS needs the nptdms package (pip install nptdms)", "format") from None

    def write(tmp: Path):
        if kind == "csv":
            _write_csv(tmp, recording, matrix)
        elif kind == "npy":
            with open(tmp, "wb") as handle:
                np.save(handle, matrix[:, 0] if matrix.shape[1] == 1 else matrix)
        elif kind == "f32":
            with open(tmp, "wb") as handle:
                handle.write(np.ascontiguousarray(matrix, dtype="<f4").tobytes())
        else:
            _write_tdms(tmp, recording)

    return atomic_write(path, write, "path")


def _write_csv(tmp: Path, recording: Recording, matrix: np.ndarray) -> None:
    import pyarrow as pa
    import pyarrow.csv as pacsv

    columns = {"time": pa.array(recording.time())}
    for k in range(matrix.shape[1]):
        columns[f"c{k}"] = pa.array(matrix[:, k])
    header = ",".join(["time [s]"] + [f"{name} [N]" for name in recording.lane_names]) + "\n"
    with open(tmp, "wb") as handle:
        handle.write(header.encode("utf-8"))
        pacsv.write_csv(pa.table(columns), handle, write_options=pacsv.WriteOptions(include_header=False))


def _write_tdms(tmp: Path, recording: Recording) -> None:
    from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

    objects = [RootObject({"name": Path(str(recording.source)).name or "fruitimpact", "source": recording.source}),
               GroupObject("fruitimpact")]
    for name in recording.lane_names:
        properties = {"wf_increment": 1.0 / recording.rate, "wf_start_offset": recording.start_time,
                      "wf_samples": recording.samples, "unit_string": "N"}
        if recording.clip_low is not None:
            properties["clip_low"] = recording.clip_low
        if recording.clip_high is not None:
            properties["clip_high"] = recording.clip_high
        objects.append(ChannelObject("fruitimpact", name, np.asarray(recording.lanes[name]), properties=properties))
    with open(tmp, "wb") as handle, TdmsWriter(handle) as writer:
        writer.write_segment(objects)


def truth_path(path) -> Path:
    """Where the truth of a recording goes: ``FILE.truth.json`` for ``FILE.<ext>`` (a path ending
    in ``.json`` is kept as it is)."""
    path = Path(path)
    if path.suffix.lower() == ".json":
        return path
    return path.with_name(path.stem + ".truth.json") if path.suffix else path.with_name(path.name + ".truth.json")


def write_truth(truth: dict, path) -> Path:
    """Write ``truth`` as JSON (atomically) to ``truth_path(path)``: give the recording's path
    (``run.csv`` → ``run.truth.json``) or a ``.json`` path.  Returns the path written.
    ``ValueError`` for values JSON cannot hold (NaN, infinities, objects)."""
    from fruitimpact.impact.outputs import atomic_write, check_output

    if not isinstance(truth, dict):
        raise InputError(f"truth must be a dict; got {type(truth).__name__}", "truth")
    try:
        text = json.dumps(truth, indent=1, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise InputError(f"truth cannot be written as JSON: {exc}", "truth") from None
    target = check_output(truth_path(path), "path")
    return atomic_write(target, lambda tmp: tmp.write_text(text + "\n", encoding="utf-8"), "path")


__all__ = ["TAIL", "Impact", "Population", "SensorModel", "synthesize", "truth_path", "write_recording",
           "write_truth"]
