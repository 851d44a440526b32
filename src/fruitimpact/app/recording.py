"""The recording page's numbers: an uploaded force recording analysed as ``fruitimpact analyze`` analyses it.

``analyze(request)`` runs :func:`fruitimpact.signals.offline.run_analysis` (the function behind ``analyze``,
CLI and API) on a stored upload with the options the page offers, named as the API names them (``rate``,
``hum``, ``fit``, ``drop_height``, ``sort_by``, ``thresholds``…, values as typed: ``"20kHz"``, ``"4cm"``).  It
answers the impacts table (the rows of ``analyze --json``), the firmness histogram of the fruit (first contacts,
rebounds left out) with the class thresholds, the class counts, an overview of every lane (the least and greatest
force in each of ``OVERVIEW_BINS`` spans, so that a peak is never lost between two drawn points) and the
``fruitimpact analyze`` command that gives the same table.  Each impact's window of samples and its fit are kept
with the analysis, so that ``impact(request)`` answers one impact's force curve with the fitted model over it.
"""

from __future__ import annotations

import math
import secrets
import shlex
import threading
from collections import OrderedDict

import numpy as np

from fruitimpact.app import inputs
from fruitimpact.signals.settings import MAX_LANES
from fruitimpact.impact.validation import InputError
from fruitimpact.signals.options import ANALYSIS_OPTIONS

#: Inputs of an analysis request (a contract of the page): the upload, how to read it, and the options of
#: ``fruitimpact analyze``.
RECORDING_INPUTS = ("upload", "rate", "column", "lanes", *ANALYSIS_OPTIONS)
#: Spans of the overview of each lane.
OVERVIEW_BINS = 1500
#: Analyses kept for the impact view (the oldest goes first).
MAX_ANALYSES = 6
#: Impacts whose windows are kept per analysis (beyond, the table is complete but the curve is not kept).
MAX_WINDOWS = 50_000
#: Points of the fitted model drawn over an impact's samples.
MODEL_POINTS = 600
#: Largest number of histogram bins.
MAX_BINS = 40
#: Options given as a flag (a JSON true/false) rather than a value.
_FLAGS = ("fit",)


class _Analyses:
    """The last ``MAX_ANALYSES`` analyses: their impacts' windows and fits, by analysis id."""

    def __init__(self):
        self._kept: OrderedDict[str, dict] = OrderedDict()
        self._lock = threading.Lock()

    def add(self, analysis: dict) -> str:
        key = secrets.token_hex(8)
        with self._lock:
            self._kept[key] = analysis
            while len(self._kept) > MAX_ANALYSES:
                self._kept.popitem(last=False)
        return key

    def get(self, key) -> dict:
        with self._lock:
            found = self._kept.get(key) if isinstance(key, str) else None
        if found is None:
            raise InputError("this analysis is no longer kept by the server (it keeps the last "
                             f"{MAX_ANALYSES}): analyse the recording again", "analysis")
        return found


ANALYSES = _Analyses()


def read_request(request, names=RECORDING_INPUTS) -> dict:
    """The inputs of a request: names checked, empty texts and false flags dropped, values as typed."""
    return inputs.read_request(request, names, _FLAGS)


def refusal(error: ValueError, stored=None, shown: str = "") -> InputError:
    """A library refusal as the page shows it: the ``stored`` file's path replaced by the name the user's file had
    (``shown``), about the input the error names (the reader's ``path`` is the page's ``file``)."""
    text = str(error) if stored is None else str(error).replace(str(stored), shown)
    argument = getattr(error, "argument", None)
    return InputError(text, "file" if argument == "path" else argument)


def command(name: str, inputs: dict) -> str:
    """The ``fruitimpact analyze`` command that gives the same table (the file by the name it was uploaded as)."""
    words = ["fruitimpact", "analyze", name]
    for key in ("rate", "column", "lanes", *ANALYSIS_OPTIONS):
        if key not in inputs:
            continue
        option = ANALYSIS_OPTIONS.get(key) or f"--{key}"
        words += [option] if key in _FLAGS else [option, str(inputs[key])]
    return " ".join(shlex.quote(word) for word in words)


class _Overview:
    """The least and greatest force of each lane in fixed spans of samples, fed chunk by chunk."""

    def __init__(self, samples: int | None):
        # an unknown length (a long CSV): spans of a guessed size, merged pairwise whenever there are too many
        self.span = max(1, math.ceil((samples or OVERVIEW_BINS * 64) / OVERVIEW_BINS))
        self.low: list[np.ndarray] = []
        self.high: list[np.ndarray] = []
        self.pending: np.ndarray | None = None

    def feed(self, chunk: np.ndarray) -> None:
        data = chunk if self.pending is None else np.concatenate([self.pending, chunk])
        whole = data.shape[0] // self.span * self.span
        if whole:
            blocks = data[:whole].reshape(-1, self.span, data.shape[1])
            self.low.append(blocks.min(axis=1))
            self.high.append(blocks.max(axis=1))
        self.pending = data[whole:] if whole < data.shape[0] else None
        if sum(len(block) for block in self.low) > 2 * OVERVIEW_BINS:
            self._halve()

    def _halve(self) -> None:
        low, high = np.concatenate(self.low), np.concatenate(self.high)
        even = len(low) // 2 * 2
        self.low = [np.minimum(low[:even:2], low[1:even:2])] + ([low[even:]] if even < len(low) else [])
        self.high = [np.maximum(high[:even:2], high[1:even:2])] + ([high[even:]] if even < len(high) else [])
        self.span *= 2

    def result(self, rate: float, start: float, names) -> dict:
        if self.pending is not None:
            self.low.append(self.pending.min(axis=0, keepdims=True))
            self.high.append(self.pending.max(axis=0, keepdims=True))
            self.pending = None
        if not self.low:
            return {"time": [], "lanes": {}}
        low, high = np.concatenate(self.low), np.concatenate(self.high)
        time = start + (np.arange(len(low)) * self.span) / rate
        return {"time": time.tolist(), "span": self.span / rate,
                "lanes": {name: {"low": low[:, k].tolist(), "high": high[:, k].tolist()}
                          for k, name in enumerate(names)}}


def _histogram(rows: list, index: str, thresholds) -> dict:
    """The fruit's ``index`` (first contacts: a rebound is the same fruit again) binned for the page."""
    values = np.array([row.get(index) for row in rows if not row.get("rebound")], dtype=float)
    values = values[np.isfinite(values)]
    if values.size == 0:
        return {"index": index, "edges": [], "counts": [], "fruit": 0, "thresholds": list(thresholds or [])}
    bins = int(min(MAX_BINS, max(5, math.ceil(math.sqrt(values.size)))))
    low, high = float(values.min()), float(values.max())
    if thresholds:  # the thresholds inside the drawn range
        low, high = min(low, *thresholds), max(high, *thresholds)
    if high <= low:
        high = low + (abs(low) * 0.01 or 1.0)
    counts, edges = np.histogram(values, bins=bins, range=(low, high))
    return {"index": index, "edges": edges.tolist(), "counts": counts.tolist(), "fruit": int(values.size),
            "thresholds": list(thresholds or [])}


def analyze(request, uploads) -> dict:
    """Everything the recording page shows for one analysis request (module docstring); ``InputError`` naming
    the input for a refused one, the stored file named by the user's own file name."""
    from fruitimpact.signals.offline import run_analysis
    from fruitimpact.signals.read import open_recording

    inputs = read_request(request)
    if "upload" not in inputs:
        raise InputError("upload a recording first (CSV, NPY, raw float32 or TDMS)", "file")
    upload = uploads.get(inputs.pop("upload"))
    path = upload.checked_path()
    reading = {key: inputs.pop(key) for key in ("rate", "column", "lanes") if key in inputs}
    if "lanes" in reading:
        from fruitimpact.impact.validation import read_count

        reading["lanes"] = read_count("lanes", reading["lanes"], 1, MAX_LANES)
    try:
        source = open_recording(path, **reading)
    except ValueError as error:
        raise refusal(error, path, upload.name) from None
    overview = _Overview(source.samples)
    windows = []

    def keep(impact, report):
        if len(windows) < MAX_WINDOWS:
            windows.append((impact.window_start, impact.window.astype(np.float32), report.get("_fit")))

    try:
        run = run_analysis(str(path), on_detected=keep, on_chunk=overview.feed, **reading, **inputs)
    except ValueError as error:
        raise refusal(error, path, upload.name) from None
    rows = run.rows  # the server's JSON writer makes NaN null (impact.outputs.dump_json)
    index = run.classes.by if run.classes is not None else "firmness_c_star"
    thresholds = list(run.classes.thresholds) if run.classes is not None else []
    classes = {}
    for row in rows:
        if row.get("class") is not None and not row.get("rebound"):  # an overlap has no class
            classes[row["class"]] = classes.get(row["class"], 0) + 1
    key = ANALYSES.add({"windows": windows, "rate": run.rate, "rows": rows})
    fruit = sum(1 for row in rows if not row.get("rebound"))
    return {
        "analysis": key, "file": upload.name, "size": upload.size, "format": source.format,
        "rate": run.rate, "lanes": run.lane_names, "samples": run.samples, "duration": run.samples / run.rate,
        "start_time": run.start_time, "columns": run.columns, "impacts": rows, "contacts": len(rows),
        "fruit": fruit, "rebounds": len(rows) - fruit, "hum": run.hum, "discharge": run.discharge,
        "by_lane": {name: sum(1 for row in rows if row["lane"] == name) for name in run.lane_names},
        "histogram": _histogram(rows, index, thresholds), "classes": classes,
        "class_names": list(run.classes.labels) if run.classes is not None else [],
        "overview": overview.result(run.rate, run.start_time, run.lane_names),
        "windows_kept": len(windows),
        "command": command(upload.name, {**reading, **inputs}),
    }


def impact(request) -> dict:
    """One impact of a kept analysis: its samples [N] over time [ms from the window's start], the fitted model
    over them (when the fit converged), and its row of the table."""
    from fruitimpact.signals.fit import model_curve

    if not isinstance(request, dict):
        raise InputError("the request must be a JSON object of inputs", "request")
    unknown = [name for name in request if name not in ("analysis", "index")]
    if unknown:
        raise InputError(f"unknown input {unknown[0]!r} (inputs: analysis, index)", unknown[0])
    kept = ANALYSES.get(request.get("analysis"))
    index = request.get("index")
    if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < len(kept["rows"]):
        raise InputError(f"index must be an impact of this analysis, 0 to {len(kept['rows']) - 1}; got {index!r}",
                         "index")
    if index >= len(kept["windows"]):
        raise InputError(f"impact {index}: its samples were not kept (the page keeps the first {MAX_WINDOWS:,})",
                         "index")
    start, window, fit = kept["windows"][index]
    rate = kept["rate"]
    time = (start + np.arange(window.size)) / rate
    out = {"index": index, "row": kept["rows"][index], "time": ((time - time[0]) * 1e3).tolist(),
           "force": [float(v) for v in window], "model": None}
    if fit and fit.get("converged"):
        fine = np.linspace(time[0], time[-1], MODEL_POINTS)
        model = model_curve(fine, fit)
        if np.isfinite(model).all():
            out["model"] = {"time": ((fine - time[0]) * 1e3).tolist(), "force": model.tolist()}
    return out


__all__ = ["ANALYSES", "MAX_WINDOWS", "RECORDING_INPUTS", "analyze", "command", "impact", "read_request", "refusal"]
