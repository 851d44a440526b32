"""The options of a recording's analysis, checked in one place for the CLI (``analyze``, ``stream``) and the
Python API (:func:`fruitimpact.analyze`): detection (hum, low-pass, thresholds, clip limits), rebounds
(window, feed pitch), the fit (velocity or drop height, mass, diameter, Poisson's ratio) and firmness
classes.  Values are numbers [SI] or strings with units (``"50Hz"``, ``"4cm"``); every error is one
``ValueError`` line naming the option as the CLI spells it."""

from __future__ import annotations

import math

from fruitimpact.impact.units import parse_quantity
from fruitimpact.impact.validation import InputError, check_flag, conflict_message
from fruitimpact.signals.settings import HUM_AUTO, MIN_DISCHARGE_TIME

#: The analysis options (Python name → CLI option), with their defaults as the CLI gives them.
ANALYSIS_OPTIONS = {"hum": "--hum", "lowpass": "--lowpass", "discharge_time": "--discharge-time",
                    "rebound_window": "--rebound-window", "pitch": "--pitch",
                    "fruit_rate": "--fruit-rate", "k_on": "--k-on", "k_off": "--k-off", "clip": "--clip",
                    "fit": "--fit", "drop_height": "--drop-height", "velocity": "--velocity", "mass": "--mass",
                    "diameter": "--diameter", "poisson": "--poisson", "sort_by": "--sort-by",
                    "thresholds": "--thresholds", "classes": "--classes"}
ANALYSIS_DEFAULTS = {"hum": "auto", "k_on": "6", "k_off": "3", "fit": False}


_NAMES = {option: name for name, option in ANALYSIS_OPTIONS.items()}


def _refusal(option: str, text: str) -> InputError:
    """``argument OPTION: TEXT``, about the option's input (its Python name: the web app shows the line next to
    that control; the first of ``--a/--b``)."""
    return InputError(f"argument {option}: {text}", _NAMES.get(option.split("/")[0]))


def _number(option: str, text, dimension: str, low: float = 0.0, low_inclusive: bool = False, high=math.inf,
            high_inclusive: bool = True):
    if text is None:
        return None
    try:
        value = parse_quantity(text, dimension)
    except ValueError as exc:
        raise _refusal(option, str(exc)) from None
    ok = ((value >= low if low_inclusive else value > low) and (value <= high if high_inclusive else value < high)
          and math.isfinite(value))
    if not ok:
        opening, closing = "[" if low_inclusive else "(", "]" if high_inclusive else ")"
        raise _refusal(option, f"must be a number in {opening}{low:.7g}, {high:.7g}{closing}; got {text!r}")
    return value


#: The CLI option of each detector and analysis setting, so that their errors name what the user typed.
_SETTING_OPTIONS = {"k_on": "--k-on", "k_off": "--k-off", "hum_frequency": "--hum", "hum_q": "--hum",
                    "lowpass_cutoff": "--lowpass", "discharge_time": "--discharge-time", "clip_low": "--clip",
                    "clip_high": "--clip",
                    "max_flight": "--rebound-window", "pitch": "--pitch/--fruit-rate"}
#: The detector's windows, which no option sets: an error about one of them is about the rate.
_WINDOWS = ("offset_hold", "min_duration", "max_duration", "pre_trigger", "post_trigger", "warmup")


def _setting_error(exc: ValueError) -> InputError:
    """The library's error about a setting, prefixed with the option the user gave it by."""
    if isinstance(exc, InputError) and exc.argument is not None:
        return exc  # it names its input already
    text = str(exc)
    name = text.split(" ", 1)[0]
    if name in _WINDOWS:  # the detector's own windows, no option of the command: the rate is too low for them
        return _refusal("--rate", f"the sample rate is too low for the detector: its {text}")
    option = _SETTING_OPTIONS.get(name)
    return _refusal(option, text) if option else InputError(text)


#: The mains frequencies ``--hum`` accepts [Hz]: 16.7 Hz railway supplies to 400 Hz aircraft ones.
HUM_RANGE = (16.0, 400.0)


def parse_hum(text) -> float | str | None:
    """``--hum``: ``auto`` (the default: 50 or 60 Hz found on the stream's first samples, or none), ``none`` (None)
    or the mains frequency [Hz]."""
    word = str(text).strip().lower() if text is not None else "auto"
    if word == HUM_AUTO:
        return HUM_AUTO
    if word == "none":
        return None
    try:
        return _number("--hum", text, "frequency", low=HUM_RANGE[0], low_inclusive=True, high=HUM_RANGE[1])
    except InputError:
        raise _refusal("--hum", f"must be auto, none or the mains frequency in [{HUM_RANGE[0]:g}, {HUM_RANGE[1]:g}] Hz "
                                f"(50 or 60); got {text!r}") from None


def parse_discharge(text) -> float | None:
    """``--discharge-time``: ``auto`` (or not given: None, measured on each lane's contacts), ``none`` (math.inf: a
    sensor that holds a static force) or a time constant [s] ≥ 10 ms."""
    if text is None or str(text).strip().lower() == "auto":
        return None
    if str(text).strip().lower() == "none":
        return math.inf
    try:
        return _number("--discharge-time", text, "time", low=MIN_DISCHARGE_TIME, low_inclusive=True, high=1e6)
    except InputError:
        raise _refusal("--discharge-time", f"must be auto, none or a time constant in [{MIN_DISCHARGE_TIME:g}, 1e+06] "
                                           f"s (the sensor's data sheet); got {text!r}") from None


def parse_clip(text) -> tuple:
    """``--clip LOW,HIGH`` (forces, units allowed; LOW < HIGH) → (low, high) [N]; (None, None) when not given."""
    if not text:
        return None, None
    try:
        low, high = (float(parse_quantity(v, "force")) for v in str(text).split(","))
    except ValueError:
        raise _refusal("--clip", f"expected LOW,HIGH in N; got {text!r}") from None
    if not low < high:
        raise _refusal("--clip", f"LOW must be below HIGH; got {text!r}")
    return low, high


def analysis_settings(rate: float, rate_known: bool = True, **options):
    """(DetectorSettings, Analysis) from the analysis ``options`` (``ANALYSIS_OPTIONS``; numbers [SI] or
    strings with units), every value checked before any work (those that depend on the sample rate only
    when ``rate_known``).  ValueError naming the option for an unknown option or a value out of range."""
    unknown = [name for name in options if name not in ANALYSIS_OPTIONS]
    if unknown:
        raise InputError(f"unknown analysis option {unknown[0]!r} (options: {', '.join(ANALYSIS_OPTIONS)})")
    if options.get("fit") is not None:
        check_flag("fit", options["fit"])
    # the Python API may give a sequence where the CLI gives "A,B"
    options = {name: ",".join(str(v) for v in value) if name in ("clip", "thresholds", "classes")
               and not isinstance(value, (str, bytes)) and hasattr(value, "__iter__") else value
               for name, value in options.items()}
    args = _Options({**ANALYSIS_DEFAULTS, **{k: v for k, v in options.items() if v is not None}})
    from fruitimpact.physics.constants import STANDARD_GRAVITY
    from fruitimpact.signals.settings import DetectorSettings, at_rate

    # every plain check first: a usage error is answered before the detector and the fit (numba) are imported
    hum = parse_hum(args.hum)
    lowpass = _number("--lowpass", args.lowpass, "frequency", high=rate / 2.0, high_inclusive=False)  # below Nyquist
    clip = parse_clip(args.clip)
    discharge = parse_discharge(args.discharge_time)
    velocity = _number("--velocity", args.velocity, "velocity", high=15.0)  # 15 m/s: an 11 m drop
    height = _number("--drop-height", args.drop_height, "length", high=10.0)
    if velocity is not None and height is not None:
        raise InputError(conflict_message(["--velocity", "--drop-height"]))
    if height is not None:
        velocity = math.sqrt(2.0 * STANDARD_GRAVITY * height)
    window = _number("--rebound-window", args.rebound_window, "time", low_inclusive=True, high=10.0)
    pitch = _number("--pitch", args.pitch, "time", low=1e-3, low_inclusive=True, high=60.0)
    fruit_rate = _number("--fruit-rate", args.fruit_rate, "frequency", high=1000.0)
    if pitch is not None and fruit_rate is not None:
        raise InputError(conflict_message(["--pitch", "--fruit-rate"]))
    if fruit_rate is not None:
        pitch = 1.0 / fruit_rate
    k_on = _number("--k-on", args.k_on, "dimensionless")
    k_off = _number("--k-off", args.k_off, "dimensionless")
    mass = _number("--mass", args.mass, "mass")
    diameter = _number("--diameter", args.diameter, "length")
    poisson = _number("--poisson", args.poisson, "dimensionless", low=0.0, low_inclusive=True, high=0.4999999)
    try:
        settings = DetectorSettings(k_on=k_on, k_off=k_off, hum_frequency=hum, hum_harmonics=(1, 3) if hum else (1,),
                                    lowpass_cutoff=lowpass, clip_low=clip[0], clip_high=clip[1],
                                    discharge_time=discharge)
        if rate_known:
            at_rate(settings, rate)  # the checks against the rate (hum harmonics below rate/2, …), without numba
    except ValueError as exc:
        raise _setting_error(exc) from None
    classes = None
    if args.classes and not (args.sort_by or args.thresholds):
        raise _refusal("--classes", "names the classes of --sort-by INDEX --thresholds A,B,...: give them too")
    if args.sort_by or args.thresholds:
        if not (args.sort_by and args.thresholds):
            raise _refusal("--thresholds", "give --sort-by INDEX and --thresholds A,B,... together")
        try:
            thresholds = tuple(float(v) for v in args.thresholds.split(","))
        except ValueError:
            raise _refusal("--thresholds", f"expected numbers A,B,...; got {args.thresholds!r}") from None
        names = tuple(args.classes.split(",")) if args.classes else \
            (("soft", "medium", "firm", "very-firm", "hard", "very-hard")[:len(thresholds) + 1]
             if len(thresholds) < 6 else tuple(f"class{k}" for k in range(len(thresholds) + 1)))
        from fruitimpact.signals.sort import FirmnessClasses

        try:
            classes = FirmnessClasses(args.sort_by, thresholds, names)
        except ValueError as exc:
            raise _refusal("--sort-by/--thresholds", str(exc)) from None
    from fruitimpact.signals.settings import Analysis  # not the analysis itself: no numba before a usage error

    try:
        analysis = Analysis(rate=rate, fit=args.fit, velocity=velocity, mass=mass, diameter=diameter,
                            poisson=poisson, classes=classes, max_flight=window, pitch=pitch)
    except ValueError as exc:
        raise _setting_error(exc) from None
    return settings, analysis


class _Options(dict):
    """The options as attributes (None when not given)."""

    def __getattr__(self, name):
        if name not in ANALYSIS_OPTIONS:
            raise AttributeError(name)
        return self.get(name)
