"""Measured impacts: ``analyze`` (a recording), ``stream`` (samples arriving), ``synth`` (a synthetic
sensor with its truth) and ``classes`` (firmness thresholds calibrated on labelled fruit)."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from fruitimpact.cli.common import PROG, UsageError, _library_call, check_outputs, dump_json, read_option_count
from fruitimpact.impact.validation import conflict_message
from fruitimpact.impact.outputs import FIGURE_FORMATS
from fruitimpact.signals.settings import MAX_LANES


def _float(option: str, text, dimension: str, low: float = 0.0, low_inclusive: bool = False, high=math.inf):
    """``signals.options._number`` with its error as the CLI's one line."""
    from fruitimpact.signals.options import _number

    return _library_call(_number, option, text, dimension, low, low_inclusive, high)


def _rate(text):
    """``--rate`` [Hz]: ``signals.settings.check_rate``, the one check of a sample rate (None when not given)."""
    from fruitimpact.signals.settings import check_rate

    return _library_call(check_rate, text)


def _json_line(obj) -> str:
    return dump_json(obj, indent=None)


def add_analysis_options(parser) -> None:
    """Options shared by ``analyze`` and ``stream`` (the same analysis of every impact)."""
    det = parser.add_argument_group("detection (defaults suit fruit on a force plate at 10-50 kHz)")
    det.add_argument("--hum", metavar="HZ|auto|none",
                     help="remove mains hum at this frequency (50 or 60) and its 3rd harmonic; auto (default): "
                          "found on the first 0.2 s (50 or 60 Hz, or none); none: no hum removal")
    det.add_argument("--lowpass", metavar="HZ", help="causal Butterworth low-pass (order 4) at this frequency")
    det.add_argument("--discharge-time", metavar="S|auto|none",
                     help="a piezoelectric sensor chain's discharge time constant (data sheet; >= 10 ms): the force "
                          "its high-pass took away is restored; auto (default): measured on each lane's contacts and "
                          "restored where it shows; none: the sensor holds a static force (strain gauge)")
    det.add_argument("--rebound-window", metavar="S",
                     help="longest rebound flight considered; 0: no rebound detection (default 1.25 x 2V/g + 10 ms "
                          "with the velocity or drop height, else 0.3 s). A contact is a rebound only when its flight, "
                          "speed, peak, time to peak and shape are those of the same fruit")
    det.add_argument("--pitch", metavar="S", help="the feed's time between fruit of a lane, when known (a prior "
                                                   "for the rebound decision)")
    det.add_argument("--fruit-rate", metavar="HZ", help="fruit per second per lane, instead of --pitch")
    det.add_argument("--k-on", default="6", metavar="K", help="onset threshold in noise σ (default 6)")
    det.add_argument("--k-off", default="3", metavar="K", help="offset threshold in noise σ (default 3)")
    det.add_argument("--clip", metavar="LOW,HIGH", help="the acquisition's limits [N]: impacts reaching them are flagged")
    fit = parser.add_argument_group("fit of the simulator's force law (--fit)")
    fit.add_argument("--fit", action="store_true", help="fit the Hunt–Crossley pulse to every impact")
    fit.add_argument("--drop-height", metavar="H", help="the line's drop height: V = √(2 g h) (the fit gives the mass)")
    fit.add_argument("--velocity", metavar="V", help="impact velocity (the fit gives the mass)")
    fit.add_argument("--mass", metavar="M", help="fruit mass (the fit gives the velocity)")
    fit.add_argument("--diameter", metavar="D", help="fruit diameter, with --poisson: the fit gives E")
    fit.add_argument("--poisson", metavar="NU", help="Poisson's ratio, with --diameter")
    sort = parser.add_argument_group("firmness classes")
    sort.add_argument("--sort-by", metavar="INDEX", help="firmness_c, firmness_c_star, modulus, stiffness or peak_force")
    sort.add_argument("--thresholds", metavar="A,B,...", help="ascending thresholds of --sort-by [SI]")
    sort.add_argument("--classes", metavar="NAMES", help="class names, softest first (default soft,medium,firm,...)")


def analysis_from(args, rate: float, rate_known: bool = True):
    """(DetectorSettings, Analysis) from the options: ``signals.options.analysis_settings``, the one check."""
    from fruitimpact.signals.options import ANALYSIS_OPTIONS, analysis_settings

    options = {name: getattr(args, name, None) for name in ANALYSIS_OPTIONS}
    return _library_call(analysis_settings, rate, rate_known, **options)


# ------------------------------------------------------------------------------------------- analyze


def _table_header(analysis) -> str:
    header = f"{'lane':<10}{'#':>6}{'t [s]':>10}{'F_max [N]':>11}{'t_c [ms]':>10}{'T [ms]':>9}{'C [N/ms]':>10}" \
             f"{'C* [N/ms²]':>12}{'impulse':>10}  status/flags"
    if analysis.fit:
        header += "   k_c, e, m|V"
    return header


def _table_row(r: dict, analysis) -> str:
    flags = [r["status"]] if r.get("status") != "ok" else []
    if r.get("rebound"):
        flags.append(f"rebound of #{r['rebound_of']}" if r.get("rebound_of") is not None else "rebound (parent unmeasured)")
    if r.get("rebound_ambiguous"):
        flags.append("ambiguous")
    line = (f"{r['lane']:<10}{r['sequence']:>6d}{r['start_time']:>10.5f}{r['peak_force']:>11.4g}{r['time_to_peak'] * 1e3:>10.4g}"
            f"{r['contact_duration'] * 1e3:>9.4g}{r['firmness_c'] / 1e3:>10.4g}"
            f"{r['firmness_c_star'] / 1e6:>12.4g}{r['impulse']:>10.4g}  {','.join(flags) or '-'}")
    if analysis.fit:
        other = "mass" if analysis.mass is None else "velocity"
        line += f"   {r.get('stiffness', math.nan):.4g}, {r.get('restitution', math.nan):.3g}, " \
                f"{r.get(other, math.nan):.4g}"
    if r.get("class"):
        line += f"   {r['class']}"
    return line


class _Progress:
    """``--progress``: one self-overwriting line on stderr, at most every half second."""

    def __init__(self, total: int | None, rate: float):
        import time

        self.clock = time.monotonic
        self.total, self.rate, self.start, self.shown = total, rate, self.clock(), 0.0

    def update(self, done: int, impacts: int, final: bool = False) -> None:
        now = self.clock()
        if not final and now - self.shown < 0.5:
            return
        self.shown = now
        elapsed = max(now - self.start, 1e-9)
        share = f"{100.0 * done / self.total:5.1f} % " if self.total else ""
        print(f"\r{PROG} analyze: {share}{done / self.rate:.1f} s of signal, {impacts} impacts, "
              f"{done / self.rate / elapsed:.0f}x real time", end="\n" if final else "", file=sys.stderr, flush=True)


def cmd_analyze(args) -> int:
    rate = _rate(args.rate)
    lanes = read_option_count("--lanes", args.lanes, 1)  # more than MAX_LANES: the detector refuses them
    check_outputs(("--plot", args.plot, FIGURE_FORMATS), args=args)
    # every option checked before the file is read, and before the detector and the fit (numba) are imported
    analysis_from(args, rate if rate is not None else 1e12, rate_known=rate is not None)
    from fruitimpact.signals.read import open_recording

    try:
        source = open_recording(args.file, rate=rate, column=args.column, format=args.format, lanes=lanes)
    except ValueError as exc:
        raise UsageError(_reading_error(exc, args)) from None
    for note in source.notes:
        print(f"{PROG} analyze: warning: {args.file}: {note}", file=sys.stderr, flush=True)
    settings, analysis = analysis_from(args, source.rate)  # the options against the file's own rate
    from fruitimpact.signals import offline  # the detector and the fit (numba) once the file opened and the options hold
    from fruitimpact.signals.reports import public
    from fruitimpact.signals.stream import StreamAnalyzer

    keep = bool(args.plot)  # a figure of the recording needs its samples and windows
    impacts, reports = [], []

    def emit(impact, report):
        if keep:
            impacts.append(impact)
            reports.append(report)
        print(_json_line(public(report)) if args.json else _table_row(report, analysis), flush=False)

    analyzer = _library_call(StreamAnalyzer, source.rate, len(source.lane_names), settings, lambda report: None,
                             on_detected=emit, analysis=analysis, lane_names=source.lane_names,
                             start_time=source.start_time)
    if not args.json:
        print(f"{args.file}: {len(source.lane_names)} lane(s) at {source.rate:g} Hz"
              + (" (fitted)" if analysis.fit else ""))
        print(_table_header(analysis))
    progress = _Progress(source.samples, source.rate) if args.progress else None
    fed = [0]  # samples fed so far, for the progress line of a file that fails mid-way

    def on_chunk(done, count):
        fed[0] = done
        if progress is not None:
            progress.update(done, count)

    try:  # Ctrl-C or SIGTERM: what is known is written (the contacts in progress, truncated), then "interrupted"
        done = offline.feed_all(analyzer, source.chunks(offline.ANALYZE_CHUNK), on_chunk)
    except ValueError as exc:  # a bad row found mid-file: the samples before its block stand
        if progress is not None:
            progress.update(fed[0], analyzer.impacts, final=True)
        sys.stdout.flush()
        raise UsageError(_reading_error(exc, args)) from None
    except KeyboardInterrupt:
        sys.stdout.flush()
        raise
    if progress is not None:
        progress.update(done, analyzer.impacts, final=True)
    if not args.json:
        print(f"{analyzer.impacts} impacts in {done / source.rate:.4g} s")
        speeds = analyzer.line_speeds()
        if speeds is not None:
            print(_speeds_read(speeds))
        for line in (_hum_found(analyzer.hum_found()), _discharge_measured(analyzer.discharge_times())):
            if line:
                print(line)
    if args.plot:
        from fruitimpact.plotting import save_figure
        from fruitimpact.plotting.signals import analysis_figure
        from fruitimpact.signals.read import read_recording

        recording = read_recording(args.file, rate=rate, column=args.column, format=args.format, lanes=lanes)
        _library_call(save_figure, analysis_figure(recording, impacts, reports, analysis), args.plot, "--plot")
        if not args.json:
            print(f"figure written to {args.plot}")
    return 0


def _speeds_read(speeds: dict) -> str:
    """The line of ``analyze``'s summary that says each lane's impact speed read from its rebounds (no drop height
    given), with the drop it stands for (V²/2g), or that its rebounds gave none."""
    from fruitimpact.physics.constants import STANDARD_GRAVITY

    parts = [f"{name} {speed:.3g} m/s (a {speed ** 2 / (2.0 * STANDARD_GRAVITY) * 100:.3g} cm drop)"
             if speed is not None else f"{name} none (fewer than 4 clear rebounds that agree)"
             for name, speed in speeds.items()]
    return "impact speed read from each lane's rebounds (no --drop-height given): " + ", ".join(parts)


def _hum_found(found: dict | None) -> str:
    """The summary line that says which mains hum ``--hum auto`` found and removed (``StreamAnalyzer.hum_found``),
    or "" (none found, or the frequency given)."""
    if found is None:
        return ""
    return (f"mains hum found at {found['frequency']:g} Hz ({found['amplitude']:.3g} N on the first 0.2 s) "
            f"and removed (--hum auto)")


def _discharge_measured(times: dict | None) -> str:
    """The summary line that says each lane's sensor discharge measured on its contacts and restored (no
    --discharge-time given), or "" when no lane showed one."""
    if not times or all(tau is None for tau in times.values()):
        return ""
    parts = [f"{name} τ = {tau:.3g} s" if tau is not None else f"{name} none shown" for name, tau in times.items()]
    return ("sensor discharge measured on each lane's contacts and restored (no --discharge-time given): "
            + ", ".join(parts))


def _reading_error(exc: ValueError, args) -> str:
    text = str(exc)
    option = "--rate" if "rate" in text and ("required" in text or "disagree" in text) else \
        "--column" if "column" in text and args.column else "FILE"
    return f"argument {option}: {text.replace('give rate= [Hz]', 'give --rate HZ')}"


# ------------------------------------------------------------------------------------------- classes
def cmd_classes(args) -> int:
    import csv

    from fruitimpact.signals.sort import SORT_INDICES, calibrate, confusion

    if args.by not in SORT_INDICES:
        raise UsageError(f"argument --by: must be one of {', '.join(SORT_INDICES)}; got {args.by!r}")
    names = tuple(args.classes.split(","))
    try:
        with open(args.file, newline="", encoding="utf-8-sig") as handle:
            if args.file.endswith(".jsonl") or args.file.endswith(".json"):
                rows = [json.loads(line) for line in handle if line.strip()]
            else:
                rows = list(csv.DictReader(line for line in handle if not line.lstrip().startswith("#")))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise UsageError(f"argument FILE: cannot read {args.file}: {exc}") from None
    if not rows:
        raise UsageError(f"argument FILE: {args.file} has no rows")
    for column in (args.by, args.label):
        if column not in rows[0]:
            raise UsageError(f"argument FILE: {args.file} has no column {column!r} (columns: {', '.join(rows[0])})")
    try:
        values = [float(row[args.by]) for row in rows]
    except (TypeError, ValueError):
        raise UsageError(f"argument FILE: column {args.by!r} must hold numbers") from None
    labels = [row[args.label] for row in rows]
    classes = _library_call(calibrate, values, labels, names, args.by)
    report = {**classes.to_dict(), **confusion(labels, classes.classify(values), names), "reference_fruit": len(rows)}
    if args.json:
        print(dump_json(report))
    else:
        print(f"thresholds of {args.by}: " + ", ".join(f"{t:.6g}" for t in classes.thresholds)
              + f"  ({len(rows)} reference fruit)")
        corner = "true / sorted"
        print(f"{corner:<14}" + "".join(f"{n:>10}" for n in names) + f"{'accuracy':>10}")
        for name, row in zip(names, report["matrix"]):
            print(f"{name:<14}" + "".join(f"{v:>10d}" for v in row)
                  + f"{report['accuracy_per_class'][name] * 100:>9.3g}%")
        print(f"accuracy {report['accuracy'] * 100:.3g} %, balanced {report['balanced_accuracy'] * 100:.3g} %")
        print(f"use: --sort-by {args.by} --thresholds {','.join(f'{t:.6g}' for t in classes.thresholds)} "
              f"--classes {','.join(names)}")
    return 0


def add_parsers(sub) -> None:
    an = sub.add_parser("analyze", help="find impacts in a force recording: indices, fitted physics, classes",
                        description="Find the impacts in a force recording (CSV, NPY, raw float32, TDMS) and "
                                    "report their indices, one JSON object per line with --json.")
    an.add_argument("file", metavar="FILE", help="the recording")
    an.add_argument("--rate", metavar="HZ", help="sample rate (needed for NPY, raw and CSV without a time column)")
    an.add_argument("--column", metavar="NAME", help="analyse only this lane (a column or TDMS channel)")
    an.add_argument("--format", metavar="FMT", help="csv, npy, f32 or tdms (default: from the extension)")
    an.add_argument("--lanes", default="1", metavar="K", help="interleaved lanes of a raw float32 file (default 1)")
    add_analysis_options(an)
    an.add_argument("--json", action="store_true", help="one JSON object per line, one per impact (SI)")
    an.add_argument("--progress", action="store_true", help="show progress on stderr (long recordings)")
    an.add_argument("--plot", metavar="FILE", help="the recording with its impacts (and fits) (PNG/SVG/PDF)")
    an.set_defaults(func=cmd_analyze)

    cl = sub.add_parser("classes", help="calibrate firmness thresholds on labelled fruit (confusion matrix)",
                        description="Calibrate the thresholds that best separate firmness classes on a labelled "
                                    "reference set (CSV or JSON lines with the index and a label column).")
    cl.add_argument("file", metavar="FILE", help="labelled reference fruit (CSV, or JSON lines from analyze)")
    cl.add_argument("--by", default="firmness_c_star", metavar="INDEX", help="the index (default firmness_c_star)")
    cl.add_argument("--label", default="label", metavar="COLUMN", help="the column of the known class (default label)")
    cl.add_argument("--classes", default="soft,medium,firm", metavar="NAMES", help="class names, softest first")
    cl.add_argument("--json", action="store_true", help="print JSON")
    cl.set_defaults(func=cmd_classes)
    add_synth_parser(sub)
    add_stream_parser(sub)


# --------------------------------------------------------------------------------------------- synth
def _classes_option(text: str):
    """``soft:2.5MPa,medium:4MPa,firm`` → ((label, upper bound of E [Pa]), …, (last, inf))."""
    pairs = []
    for item in text.split(","):
        label, _, bound = item.partition(":")
        if not label:
            raise UsageError(f"argument --classes: expected LABEL:E_MAX,...,LABEL; got {text!r}")
        pairs.append((label, _float("--classes", bound, "modulus") if bound else math.inf))
    if pairs[-1][1] != math.inf:
        pairs.append(("firmer", math.inf))
    return tuple(pairs)


#: ``synth``'s drop height and restitution when neither they nor their alternatives (--velocity, --alpha) are given.
SYNTH_DROP_HEIGHT, SYNTH_RESTITUTION = "5cm", "0.577"


def cmd_synth(args) -> int:
    from fruitimpact.signals import read as reading
    from fruitimpact.signals.options import parse_clip
    from fruitimpact.signals.synth import (MAX_LOG_SPREAD, Population, SensorModel, synthesize, truth_path,
                                           write_recording, write_truth)

    fmt = _library_call(reading.recording_format, args.output, args.format, "--format")
    check_outputs(("-o/--output", args.output, None if args.format else dict(reading.EXTENSIONS)))
    count = read_option_count("--count", args.count, 1, 100_000)
    lanes = read_option_count("--lanes", args.lanes, 1, 64)
    rebounds = read_option_count("--rebounds", args.rebounds, 0, 2)
    clip = _library_call(parse_clip, args.clip)
    for pair in (("velocity", "drop_height"), ("restitution", "alpha")):
        if all(getattr(args, name) is not None for name in pair):
            raise UsageError(conflict_message(["--" + name.replace("_", "-") for name in pair]))
    if args.velocity is None and args.drop_height is None:
        args.drop_height = SYNTH_DROP_HEIGHT
    if args.alpha is None and args.restitution is None:
        args.restitution = SYNTH_RESTITUTION
    sensor_kwargs = dict(
        rate=_rate(args.rate),
        noise=_float("--noise", args.noise, "dimensionless", low_inclusive=True, high=1.0),
        drift=_float("--drift", args.drift, "dimensionless", low=-math.inf),
        hum_amplitude=_float("--hum", args.hum, "force", low_inclusive=True),
        hum_frequency=_float("--hum-frequency", args.hum_frequency, "frequency"),
        adc_bits=read_option_count("--adc-bits", args.adc_bits, 0, 32),
        clip_low=clip[0], clip_high=clip[1],
        plate_frequency=_float("--plate-frequency", args.plate_frequency, "frequency", low_inclusive=True),
        plate_damping=_float("--plate-damping", args.plate_damping, "dimensionless") if args.plate_damping else None,
        antialias_cutoff=_float("--antialias", args.antialias, "frequency", low_inclusive=True),
        seed=read_option_count("--seed", args.seed, 0))
    sensor = _library_call(SensorModel, **sensor_kwargs)
    height = _float("--drop-height", args.drop_height, "length", high=10.0) if args.drop_height is not None else None
    population = _library_call(
        Population, count=int(count), interval=_float("--interval", args.interval, "time"),
        mass=_float("--mass", args.mass, "mass"), diameter=_float("--diameter", args.diameter, "length"),
        modulus=_float("--modulus", args.modulus, "modulus"),
        poisson=_float("--poisson", args.poisson, "dimensionless", low_inclusive=True, high=0.4999999),
        classes=_classes_option(args.classes), velocity=_float("--velocity", args.velocity, "velocity"),
        drop_height=height,
        restitution=_float("--restitution", args.restitution, "dimensionless", high=1.0)
        if args.restitution is not None else None,
        alpha=_float("--alpha", args.alpha, "alpha", low_inclusive=True) if args.alpha is not None else None,
        modulus_spread=_float("--modulus-spread", args.modulus_spread, "dimensionless", low_inclusive=True,
                              high=MAX_LOG_SPREAD),
        mass_spread=_float("--mass-spread", args.mass_spread, "dimensionless", low_inclusive=True,
                           high=MAX_LOG_SPREAD),
        jitter=_float("--jitter", args.jitter, "time", low_inclusive=True), rebounds=int(rebounds),
        lanes=int(lanes), seed=sensor_kwargs["seed"] + 1)
    recording, truth = _library_call(synthesize, sensor, population, lanes=int(lanes))
    path = _library_call(write_recording, recording, args.output, fmt)
    # the truth names its recording by checksum: a run stopped between the two files (each written atomically)
    # leaves a new recording beside an earlier truth, which the checksum then shows not to be its own
    from fruitimpact.runs.sources import file_digest

    truth["recording"] = {"file": Path(path).name, "sha256": file_digest(path)}
    truth_file = _library_call(write_truth, truth, truth_path(args.output))
    print(f"{len(truth['impacts'])} impacts ({sum(1 for i in truth['impacts'] if i['rebound'])} rebounds) in "
          f"{recording.duration:.4g} s at {recording.rate:g} Hz, {len(recording.lanes)} lane(s): written to {path}, "
          f"truth to {truth_file}")
    return 0


def add_synth_parser(sub) -> None:
    sy = sub.add_parser("synth", help="a synthetic force-sensor recording with its ground truth",
                        description="Impacts from the simulator through a sensor model (noise, drift, hum, ADC, "
                                    "clipping, plate resonance, anti-alias filter, rebounds, fruit spacing, a "
                                    "population of firmness), written as CSV/NPY/float32/TDMS with FILE.truth.json.")
    sy.add_argument("-o", "--output", required=True, metavar="FILE", help="the recording (.csv, .npy, .f32, .tdms)")
    sy.add_argument("--format", metavar="FMT", help="csv, npy, f32 or tdms (default: from the extension)")
    sensor = sy.add_argument_group("sensor")
    sensor.add_argument("--rate", default="20000", metavar="HZ", help="sample rate (default 20 kHz)")
    sensor.add_argument("--noise", default="0.01", metavar="FRACTION",
                        help="noise sd as a fraction of the median peak force (default 0.01)")
    sensor.add_argument("--drift", default="0", metavar="N/S", help="baseline drift [N/s] (default 0)")
    sensor.add_argument("--hum", default="0", metavar="N", help="mains hum amplitude (default 0)")
    sensor.add_argument("--hum-frequency", default="50", metavar="HZ", help="mains frequency (default 50)")
    sensor.add_argument("--adc-bits", default="0", metavar="B", help="ADC resolution over --clip (0: none)")
    sensor.add_argument("--clip", metavar="LOW,HIGH", help="ADC limits [N]: samples beyond are clipped")
    sensor.add_argument("--plate-frequency", default="0", metavar="HZ", help="plate resonance (0: none)")
    sensor.add_argument("--plate-damping", metavar="ZETA", help="damping ratio of the plate resonance")
    sensor.add_argument("--antialias", default="0", metavar="HZ", help="anti-alias low-pass cutoff (0: none)")
    sensor.add_argument("--seed", default="0", metavar="S", help="random seed (default 0)")
    fruit = sy.add_argument_group("fruit (default: the paper's Jonathan apple dropped 5 cm)")
    fruit.add_argument("--count", default="20", metavar="N", help="fruit (default 20)")
    fruit.add_argument("--interval", default="0.25", metavar="S", help="time between fruit (default 0.25 s)")
    fruit.add_argument("--jitter", default="0", metavar="S", help="random shift of each fruit (at most interval/2)")
    fruit.add_argument("--lanes", default="1", metavar="K", help="lanes (default 1)")
    fruit.add_argument("--drop-height", metavar="H", help=f"drop height (default {SYNTH_DROP_HEIGHT} without --velocity)")
    fruit.add_argument("--velocity", metavar="V", help="impact velocity instead of the drop height")
    fruit.add_argument("--mass", default="115g", metavar="M")
    fruit.add_argument("--diameter", default="65mm", metavar="D")
    fruit.add_argument("--modulus", default="3MPa", metavar="E", help="median Young's modulus")
    fruit.add_argument("--modulus-spread", default="0.15", metavar="SD", help="lognormal sd of E (default 0.15)")
    fruit.add_argument("--mass-spread", default="0", metavar="SD", help="lognormal sd of the mass (default 0)")
    fruit.add_argument("--poisson", default="0.37", metavar="NU")
    fruit.add_argument("--restitution", metavar="E",
                       help=f"restitution at the drop (default {SYNTH_RESTITUTION} without --alpha)")
    fruit.add_argument("--alpha", metavar="A", help="Hunt–Crossley α instead of the restitution")
    fruit.add_argument("--rebounds", default="1", metavar="K", help="rebounds followed, 0-2 (default 1)")
    fruit.add_argument("--classes", default="soft:2.5MPa,medium:3.5MPa,firm", metavar="LABEL:E_MAX,...",
                       help="firmness classes by E (default soft:2.5MPa,medium:3.5MPa,firm)")
    sy.set_defaults(func=cmd_synth)


# -------------------------------------------------------------------------------------------- stream
def cmd_stream(args) -> int:
    rate = _rate(args.rate)
    if rate is None:
        raise UsageError("argument --rate: required (the sample rate of the stream [Hz])")
    lanes = read_option_count("--lanes", args.lanes, 1, MAX_LANES)
    source = {"text": "text", "f32": "float32"}.get(args.format)
    if source is None:
        raise UsageError(f"argument --format: must be text or f32; got {args.format!r}")
    port = None
    if args.listen is not None:
        port = read_option_count("--listen", args.listen, 0, 65535)
    settings, analysis = analysis_from(args, rate)  # plain checks first: a usage error imports no numba
    from fruitimpact.signals.reports import public
    from fruitimpact.signals.stream import StreamAnalyzer, iter_chunks, serve

    def emit(report):
        sys.stdout.write(_json_line(public(report)) + "\n")
        sys.stdout.flush()  # one line per contact as soon as it is known

    def problem(message):
        print(f"{PROG} stream: warning: {message}", file=sys.stderr, flush=True)

    if port is not None:
        def listening(actual):
            _settle_the_heap()
            print(f"{PROG} stream: listening on 127.0.0.1:{actual}", file=sys.stderr, flush=True)

        def client_done(address, summary):
            print(f"{PROG} stream: client {address[0]}:{address[1]}: {_summary_text(summary)}", file=sys.stderr,
                  flush=True)

        stopped: list[str] = []
        try:
            _library_call(serve, port, rate, lanes, settings, emit, source=source, on_problem=problem,
                          on_listening=listening, on_client=client_done, analysis=analysis, on_stop=stopped.append)
        except OSError as error:  # the port taken, or not ours to bind
            raise UsageError(f"argument --listen: cannot listen on 127.0.0.1:{port}: "
                             f"{error.strerror or error}") from None
        return 130 if stopped == ["SIGINT"] else 0  # Ctrl-C, as on stdin; SIGTERM is a server's normal stop
    analyzer = _library_call(StreamAnalyzer, rate, lanes, settings, emit, source=source, on_problem=problem,
                             analysis=analysis)
    _settle_the_heap()
    summary = _library_call(analyzer.run, iter_chunks(sys.stdin.buffer))
    print(f"{PROG} stream: {_summary_text(summary)}", file=sys.stderr)
    return 130 if summary["interrupted"] == "SIGINT" else 0


def _summary_text(summary: dict) -> str:
    """A stream's summary (``StreamAnalyzer.summary``) as the line ``stream`` ends it with (and, with --listen,
    each client): samples, impacts, lines skipped, the hum and discharge found, and the signal that stopped it."""
    found = "; ".join(line for line in (_hum_found(summary["hum_found"]),
                                        _discharge_measured(summary["discharge_times"])) if line)
    return (f"{summary['samples']} samples, {summary['impacts']} impacts"
            + (f", {summary['malformed_lines']} malformed lines skipped" if summary["malformed_lines"] else "")
            + (f"; {found}" if found else "")
            + (f"; stopped by {summary['interrupted']}, held impacts flushed" if summary["interrupted"] else ""))


def _settle_the_heap() -> None:
    """Move what start-up made (modules, compiled code, tables: ~110,000 objects) out of the garbage collector's
    generations (``gc.freeze``), once the analyzer is warm: a full collection, which Python starts on its own
    after enough allocations, then walks only what the stream made since (a full walk took 12-18 ms here,
    a fruit's latency budget; the stream's own objects die young)."""
    import gc

    gc.collect()
    gc.freeze()


def add_stream_parser(sub) -> None:
    st = sub.add_parser("stream", help="real time: samples in (stdin or TCP), one JSON line per impact out",
                        description="Read force samples continuously (stdin as text lines or raw float32, or a "
                                    "TCP socket on localhost) and write one JSON line per contact as soon as it "
                                    "has ended (a later rebound is its own line with rebound_of): the same "
                                    "objects as analyze --json.")
    st.add_argument("--rate", metavar="HZ", help="sample rate [Hz] (required)")
    st.add_argument("--lanes", default="1", metavar="K", help="numbers per sample (default 1)")
    st.add_argument("--format", default="text", metavar="FMT", help="text (one sample per line) or f32 (raw "
                                                                     "little-endian float32, lanes interleaved)")
    st.add_argument("--listen", metavar="PORT", help="serve a TCP socket on 127.0.0.1:PORT instead of stdin")
    st.add_argument("--json", action="store_true", help="JSON lines (what stream always writes; as analyze --json)")
    add_analysis_options(st)
    st.set_defaults(func=cmd_stream)
