"""The live monitor: a sorting line's detector, watched from the page.

A monitor runs the detector of ``fruitimpact stream`` (:class:`~fruitimpact.signals.stream.StreamAnalyzer`, with
the options of ``stream``) on one of two sources, in a thread of its own:

* ``tcp``: the stream's TCP source.  The monitor listens on 127.0.0.1:PORT (0: a free one, said to the page) and
  takes the samples a line's acquisition sends, exactly as ``fruitimpact stream --listen PORT`` would (text lines
  or raw float32, lanes interleaved; one client at a time, a fresh detector per client);
* ``replay``: a recording uploaded from the page, fed at real time (or ``speed`` times faster; ``max``: as fast as
  the detector goes), in chunks of ``CHUNK_SECONDS`` paced by the wall clock.

Every report the detector emits reaches the page: the reports are gathered and sent in frames every
``FRAME_SECONDS`` (a page draws at most that often, whatever the line's rate), each frame with every report since
the last, the latest force curve of each lane that had a contact, and the running figures: fruit per second per
lane, samples fed, samples dropped (malformed text lines, bytes of a cut sample), the latency of each report
(wall time from the arrival of the chunk that held the contact's last sample to the report), and for a replay how
far it runs behind the clock.  When the source ends, the detector is flushed and its summary (``impacts``: the
count the stream reports) is the last message: the page's count must equal it.
"""

from __future__ import annotations

import bisect
import math
import socket
import threading
import time
from collections import deque

import numpy as np

from fruitimpact.signals.settings import MAX_LANES
from fruitimpact.impact.validation import InputError, check_choice, read_count
from fruitimpact.signals.options import ANALYSIS_OPTIONS

#: Samples fed at once in a replay [s of signal].
CHUNK_SECONDS = 0.005
#: A frame to the page at most this often [s].
FRAME_SECONDS = 0.1
#: Replay speeds (times real time); ``max``: unpaced.
SPEEDS = {"1": 1.0, "2": 2.0, "5": 5.0, "10": 10.0, "max": math.inf}
#: Inputs of a monitor's start message (a contract of the page).
MONITOR_INPUTS = ("source", "upload", "speed", "port", "format", "rate", "lanes", "column", *ANALYSIS_OPTIONS)
#: Points of a lane's latest curve sent to the page (the window is decimated beyond).
CURVE_POINTS = 400
#: Latest report latencies the percentiles are taken over.
LATENCIES_KEPT = 2000
#: Seconds of arrivals kept for the latency of late reports.
ARRIVALS_KEPT = 30.0


class Monitor:
    """One monitor (module docstring): ``start()`` the thread, ``frame()`` what is new for the page, ``stop()``."""

    def __init__(self, request: dict, uploads):
        from fruitimpact.signals.options import analysis_settings
        from fruitimpact.signals.read import open_recording
        from fruitimpact.signals.settings import check_rate

        from fruitimpact.app.recording import read_request, refusal

        inputs = read_request(request, MONITOR_INPUTS)
        self.kind = check_choice("source", inputs.pop("source", "replay"), ("replay", "tcp"))
        options = {key: inputs.pop(key) for key in list(inputs) if key in ANALYSIS_OPTIONS}
        self.recording = None
        self.speed = math.inf
        if self.kind == "replay":
            for name in ("port", "format"):
                if name in inputs:
                    raise InputError(f"{name} applies to the tcp source; a replay reads its upload", name)
            if "upload" not in inputs:
                raise InputError("upload a recording to replay (CSV, NPY, raw float32 or TDMS)", "file")
            upload = uploads.get(inputs.pop("upload"))
            speed = str(inputs.pop("speed", "1"))
            if speed not in SPEEDS:
                raise InputError(f"speed must be one of {', '.join(SPEEDS)} (times real time); got {speed!r}",
                                 "speed")
            self.speed = SPEEDS[speed]
            reading = {key: inputs.pop(key) for key in ("rate", "column", "lanes") if key in inputs}
            if "lanes" in reading:
                reading["lanes"] = read_count("lanes", reading["lanes"], 1, MAX_LANES)
            path = upload.checked_path()
            try:
                self.recording = open_recording(path, **reading)
            except ValueError as error:
                raise refusal(error, path, upload.name) from None
            self.rate, self.lane_names = self.recording.rate, list(self.recording.lane_names)
            self.file = upload.name
        else:
            for name in ("upload", "speed", "column"):
                if name in inputs:
                    raise InputError(f"{name} applies to a replay; the tcp source takes samples as they come", name)
            self.rate = check_rate(inputs.pop("rate", None))
            if self.rate is None:
                raise InputError("rate is required for the tcp source (the sample rate of the stream [Hz])", "rate")
            lanes = read_count("lanes", inputs.pop("lanes", 1), 1, MAX_LANES)
            self.format = check_choice("format", inputs.pop("format", "text"), ("text", "f32"))
            self.port = read_count("port", inputs.pop("port", 0), 0, 65535)
            self.lane_names = [f"lane{k}" for k in range(lanes)]
            self.file = None
        try:
            self.settings, self.analysis = analysis_settings(self.rate, True, **options)
        except ValueError as error:
            raise refusal(error) from None
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._reports: list[dict] = []
        self._curves: dict[str, dict] = {}
        self._latencies: deque = deque(maxlen=LATENCIES_KEPT)  # a tcp monitor runs for days
        self._messages: list[dict] = []  # source events for the page (a client connected, a summary)
        self._arrivals: deque = deque()  # (samples fed after a chunk, wall time it arrived)
        self._fed = 0
        self._fed_sent = -1  # samples fed when the last frame went
        self._started = None
        self._lag = 0.0
        self._dropped = 0
        self._clients = 0
        self.finished = False
        self._thread: threading.Thread | None = None
        self._server: socket.socket | None = None
        self.bound_port = None
        if self.kind == "tcp":  # bound now, so that a port in use is refused with the request
            try:
                self._server = socket.create_server(("127.0.0.1", self.port))
            except OSError as error:
                raise InputError(f"cannot listen on 127.0.0.1:{self.port}: {error.strerror or error}", "port") from None
            self._server.settimeout(0.2)
            self.bound_port = self._server.getsockname()[1]

    # ------------------------------------------------------------------ the detector's thread
    def start(self) -> dict:
        """Start the thread; returns what the page needs to draw (lanes, rate, port of a tcp source)."""
        self._thread = threading.Thread(target=self._run, name="fruitimpact-monitor", daemon=True)
        self._started = time.monotonic()
        self._thread.start()
        return {"type": "started", "source": self.kind, "lanes": self.lane_names, "rate": self.rate,
                "port": self.bound_port, "file": self.file, "speed": None if self.speed == math.inf else self.speed,
                "classes": self.analysis.classes.to_dict() if self.analysis.classes is not None else None}

    def request_stop(self) -> None:
        """Stop feeding: the thread flushes the detector (its last reports and summary still come) and ends."""
        self._stop.set()

    def stop(self) -> None:
        """Stop feeding, wait for the thread, and close the listening socket."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
        if self._server is not None:
            self._server.close()

    def _analyzer(self, source: str = "text"):
        from fruitimpact.signals.stream import StreamAnalyzer

        return StreamAnalyzer(self.rate, len(self.lane_names), self.settings, self._report, source=source,
                              on_problem=lambda message: self._message({"type": "problem", "message": message}),
                              on_detected=self._detected, analysis=self.analysis, lane_names=self.lane_names)

    def _run(self) -> None:
        try:
            if self.kind == "replay":
                self._replay()
            else:
                self._listen()
        except ValueError as error:  # a bad row of the recording, binary on a text stream: said on the page
            self._message({"type": "error", "message": str(error).replace(str(getattr(self.recording, "source", "")),
                                                                          self.file or "")})
        finally:
            self.finished = True

    def _replay(self) -> None:
        analyzer = self._analyzer()
        chunk = max(1, int(round(CHUNK_SECONDS * self.rate)))
        begin = time.monotonic()
        try:
            for block in self.recording.chunks(chunk):
                if self._stop.is_set():
                    break
                due = begin + (self._fed + block.shape[0]) / self.rate / self.speed
                wait = due - time.monotonic()
                if wait > 0:
                    self._stop.wait(wait)
                self._lag = max(self._lag, -wait) if self.speed != math.inf else 0.0
                self._feed(analyzer, block)
        finally:
            self._close(analyzer)

    def _listen(self) -> None:
        from fruitimpact.signals.stream import CHUNK_SIZE

        while not self._stop.is_set():
            try:
                connection, address = self._server.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            self._clients += 1
            self._message({"type": "client", "address": f"{address[0]}:{address[1]}", "client": self._clients})
            analyzer = self._analyzer("float32" if self.format == "f32" else "text")
            with connection:
                connection.settimeout(0.2)
                try:
                    while not self._stop.is_set():
                        try:
                            data = connection.recv(CHUNK_SIZE)
                        except TimeoutError:
                            continue
                        except OSError as error:  # a reset: this client's stream ends, the next one is taken
                            self._message({"type": "problem", "message": f"client {self._clients}: the connection "
                                           f"was lost ({error.strerror or error}); its contacts so far are kept"})
                            break
                        if not data:
                            break
                        arrived = time.monotonic()
                        samples = analyzer.source.parse(data)
                        self._feed(analyzer, samples, arrived)
                finally:
                    self._close(analyzer)
            with self._lock:  # a new client: a new stream, its samples counted from 0
                self._fed = 0
                self._arrivals.clear()

    def _feed(self, analyzer, samples: np.ndarray, arrived: float | None = None) -> None:
        with self._lock:
            self._fed += samples.shape[0]
            self._arrivals.append((self._fed, arrived if arrived is not None else time.monotonic()))
            while self._arrivals and self._arrivals[0][1] < self._arrivals[-1][1] - ARRIVALS_KEPT:
                self._arrivals.popleft()
        analyzer.feed(samples)

    def _close(self, analyzer) -> None:
        analyzer.close()
        summary = analyzer.summary()
        source = analyzer.source
        cut = int(getattr(source, "dropped_bytes", 0))  # the bytes of a cut sample: one sample dropped
        self._dropped = int(getattr(source, "malformed", 0)) + -(-cut // (4 * len(self.lane_names)))
        self._message({"type": "summary", "summary": summary, "dropped": self._dropped})

    # ------------------------------------------------------------------ reports
    def _detected(self, impact, report) -> None:
        # only kept here: the curve (and its model) is built for the latest contact of a lane when a frame goes
        with self._lock:
            self._curves[report["lane"]] = (impact.window_start, impact.window, report.get("_fit"),
                                            report.get("start_time"), report.get("peak_force"))

    def _curve(self, window_start: int, window: np.ndarray, fit, start_time, peak_force) -> dict:
        """A lane's latest contact for the page: its samples (decimated to ``CURVE_POINTS``) over time in its
        window [ms], and the fitted model at the same times when the fit converged."""
        step = max(1, window.size // CURVE_POINTS)
        index = np.arange(0, window.size, step)
        curve = {"time": (index / self.rate * 1e3).tolist(), "force": window[::step].astype(float).tolist(),
                 "model": None, "start_time": start_time, "peak_force": peak_force}
        if fit and fit.get("converged"):
            from fruitimpact.signals.fit import model_curve

            model = model_curve((window_start + index) / self.rate, fit)
            if np.isfinite(model).all():
                curve["model"] = model.tolist()
        return curve

    def _report(self, report: dict) -> None:
        from fruitimpact.signals.reports import public

        now = time.monotonic()
        start = report.get("raw_start_time", report.get("start_time"))
        duration = report.get("raw_contact_duration", report.get("contact_duration"))
        row = public(report)
        with self._lock:
            latency = None
            if start is not None and duration is not None and math.isfinite(start + duration):
                last_sample = int(math.ceil((start + duration) * self.rate))
                fed = [count for count, _ in self._arrivals]
                k = bisect.bisect_left(fed, last_sample)
                if k < len(self._arrivals):
                    latency = now - self._arrivals[k][1]
            row["latency"] = latency
            if latency is not None:
                self._latencies.append(latency)
            self._reports.append(row)

    def _message(self, message: dict) -> None:
        with self._lock:
            self._messages.append(message)

    # ------------------------------------------------------------------ frames for the page
    def frame(self) -> dict | None:
        """Everything new since the last frame (None when nothing is), with the running figures."""
        finished = self.finished  # read first: when set, every message of the source is already queued
        with self._lock:
            reports, self._reports = self._reports, []
            curves, self._curves = self._curves, {}
            messages, self._messages = self._messages, []
            latencies = list(self._latencies)
            fed = self._fed
        if not (reports or curves or messages) and (finished or fed == self._fed_sent):
            return None  # no news: no frame (an idle tcp source between clients sends nothing)
        self._fed_sent = fed
        elapsed = time.monotonic() - self._started
        figures = {"samples": fed, "signal_seconds": fed / self.rate, "elapsed": elapsed, "lag": self._lag,
                   "dropped": self._dropped, "finished": finished,
                   "latency_p50": _percentile(latencies, 50), "latency_p99": _percentile(latencies, 99)}
        curves = {lane: self._curve(*latest) for lane, latest in curves.items()}
        return {"type": "frame", "reports": reports, "curves": curves, "messages": messages, "figures": figures}



def _percentile(values, q: float):
    return float(np.percentile(values, q)) if values else None


__all__ = ["CHUNK_SECONDS", "FRAME_SECONDS", "MONITOR_INPUTS", "Monitor", "SPEEDS"]
