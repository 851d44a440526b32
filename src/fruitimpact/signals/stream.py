"""Streaming analysis: bytes in, one dict of indices per impact out (issue 8, item 6; for the CLI).

* ``TextSource``: text, one sample per line, ``lanes`` numbers per line separated by whitespace and/or
  commas.  A malformed line (wrong count of numbers, something that is not a number, NaN or infinity)
  is skipped and counted; the first line with each kind of problem is reported through ``on_problem``
  (one message per kind), the rest only counted.  Blank lines are skipped silently.  A skipped line
  removes one sample, so later samples move 1/rate earlier.  Input that is not text at all (NUL bytes
  or invalid UTF-8 in most of the first ``BINARY_LINES`` lines, as raw float32 is) ends the stream with
  one ``ValueError``: "looks like binary: give --format f32".
* ``Float32Source``: raw little-endian float32, lanes interleaved (sample 0 lane 0, sample 0 lane 1, …).
  A sample cut by a read boundary waits for the next read; bytes left at the end are reported and
  dropped.  A NaN or infinite value is replaced by the lane's previous value (0 before any) and reported
  once, so the timing of later samples is kept.
* ``StreamAnalyzer``: a ``Detector`` plus an ``analysis.Analysis``: each contact becomes one report (the
  raw indices, the rebound decision, the fit and the class as configured) passed to ``on_impact`` as
  soon as the detector emits it.  ``run(chunks)`` consumes an iterable of byte chunks,
  and on its end, on SIGTERM or on Ctrl-C (SIGINT) flushes the detector — emitting the impact in
  progress as ``truncated`` and everything held — before it returns a summary.
* ``serve(port, ...)``: a TCP server on 127.0.0.1 that takes one client at a time and analyses its bytes
  as one stream (a fresh analyzer per client: sample indices restart at 0).
* ``iter_chunks(file)``: the chunks of a binary file object as soon as they arrive (``read1``).
"""

from __future__ import annotations

import contextlib
import math
import signal
import socket
import sys
import threading
from collections.abc import Callable, Iterable

import numpy as np

from fruitimpact.impact.validation import check_integer
from fruitimpact.signals.analysis import Analysis
from fruitimpact.signals.detect import DetectedImpact, Detector, DetectorSettings
from fruitimpact.signals.settings import MAX_LANES

__all__ = ["Float32Source", "StreamAnalyzer", "TextSource", "iter_chunks", "serve"]

CHUNK_SIZE = 1 << 16
#: Lines after which text input that is mostly not text is refused as binary.
BINARY_LINES = 256
#: Longest text line accepted [bytes].
MAX_LINE = 1 << 16


def _default_problem(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def _lanes(lanes) -> int:
    return check_integer("lanes", lanes, 1, MAX_LANES)


class _Problems:
    """Counts problems by kind; reports the first of each kind."""

    def __init__(self, on_problem: Callable[[str], None] | None):
        self.on_problem = on_problem if on_problem is not None else _default_problem
        self.counts: dict[str, int] = {}

    def add(self, kind: str, message: str, count: int = 1) -> None:
        first = kind not in self.counts
        self.counts[kind] = self.counts.get(kind, 0) + count
        if first:
            self.on_problem(message + " (skipped; further problems of this kind are only counted)")


class _Source:
    """What both sources keep: the lane count, the problems seen (by kind) and a partial record."""

    def __init__(self, lanes: int = 1, on_problem: Callable[[str], None] | None = None):
        self.lanes = _lanes(lanes)
        self._problems = _Problems(on_problem)
        self._partial = b""

    @property
    def problems(self) -> dict[str, int]:
        return dict(self._problems.counts)


class TextSource(_Source):
    """Parse text samples (module docstring): ``parse(chunk)`` → float64 array (n, lanes) of the complete
    lines in ``chunk`` (a partial last line waits for the next chunk); ``finish()`` parses what is left.

    Counters: ``lines`` (non-blank lines seen), ``samples`` (lines accepted), ``malformed`` (lines
    skipped) and ``problems`` (skipped lines by kind)."""

    def __init__(self, lanes: int = 1, on_problem: Callable[[str], None] | None = None):
        super().__init__(lanes, on_problem)
        self.lines = 0
        self.samples = 0
        self.malformed = 0
        self._line_number = 0
        self._binary_lines = 0
        self._wrong_count = 0
        self._counted = 0

    def parse(self, chunk: bytes) -> np.ndarray:
        data = self._partial + bytes(chunk)
        cut = data.rfind(b"\n")
        if cut < 0:
            if len(data) > MAX_LINE:
                binary = b"\x00" in data or "\ufffd" in data.decode("utf-8", errors="replace")
                raise ValueError("argument --format: the input looks like binary (no line end in its first "
                                 f"{len(data)} bytes): give --format f32 for raw float32" if binary else
                                 f"a text line longer than {MAX_LINE} bytes: one sample per line is expected")
            self._partial = data
            return np.empty((0, self.lanes))
        self._partial = data[cut + 1:]
        return self._parse_lines(data[:cut + 1])

    def finish(self) -> np.ndarray:
        data, self._partial = self._partial, b""
        return self._parse_lines(data) if data.strip() else np.empty((0, self.lanes))

    def _parse_lines(self, data: bytes) -> np.ndarray:
        text = data.decode("utf-8", errors="replace")
        raw_lines = text.split("\n")
        if self._line_number < BINARY_LINES:
            self._check_text(raw_lines[:BINARY_LINES - self._line_number])
        if raw_lines and raw_lines[-1] == "":
            raw_lines.pop()
        first_number = self._line_number + 1
        self._line_number += len(raw_lines)
        tokens = [line.replace(",", " ").split() for line in raw_lines]
        lanes = self.lanes
        # fast path: every non-blank line has the right count and everything parses
        good = [t for t in tokens if t]
        self.lines += len(good)
        if all(len(t) == lanes for t in good):
            try:
                values = np.array(good, dtype=float).reshape(len(good), lanes)
            except ValueError:
                values = None
            if values is not None and np.isfinite(values).all():
                self.samples += len(good)
                return values
        rows = []
        for offset, t in enumerate(tokens):
            if not t:
                continue
            number = first_number + offset
            if len(t) != lanes:
                self._bad("count", f"line {number}: expected {lanes} number{'s' if lanes > 1 else ''}, "
                                   f"got {len(t)}")
                continue
            try:
                row = [float(v) for v in t]
            except ValueError:
                bad = next(v for v in t if not _is_float(v))
                self._bad("number", f"line {number}: not a number: {bad[:40]!r}")
                continue
            if not all(math.isfinite(v) for v in row):
                self._bad("finite", f"line {number}: NaN or infinite value")
                continue
            rows.append(row)
        self.samples += len(rows)
        return np.array(rows, dtype=float).reshape(len(rows), lanes)

    def _check_text(self, raw_lines: list[str]) -> None:
        """Refuse input that is mostly not text within its first BINARY_LINES lines (module docstring)."""
        self._binary_lines += sum(1 for line in raw_lines if "\x00" in line or "\ufffd" in line)
        lines = self._line_number + len(raw_lines)
        counts = [len(line.replace(",", " ").split()) for line in raw_lines if line.strip()]
        self._wrong_count += sum(1 for n in counts if n != self.lanes)
        self._counted += len(counts)
        if self._counted >= BINARY_LINES // 2 and self._wrong_count == self._counted and not self._binary_lines:
            raise ValueError(f"argument --lanes: every one of the first {self._counted} lines holds another count "
                             f"of numbers than --lanes {self.lanes} (e.g. {counts[0]}): give --lanes as in the input")
        if self._binary_lines > 8 and self._binary_lines > lines // 2:
            raise ValueError(f"argument --format: the input looks like binary ({self._binary_lines} of its first "
                             f"{lines} lines hold NUL bytes or invalid UTF-8): give --format f32 for raw float32")

    def _bad(self, kind: str, message: str) -> None:
        self.malformed += 1
        self._problems.add(kind, message)


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


class Float32Source(_Source):
    """Parse raw little-endian float32 with ``lanes`` interleaved values per sample (module docstring).

    Counters: ``samples`` (complete samples), ``replaced`` (non-finite values replaced), ``dropped_bytes``
    (an incomplete final sample) and ``problems`` (by kind)."""

    def __init__(self, lanes: int = 1, on_problem: Callable[[str], None] | None = None):
        super().__init__(lanes, on_problem)
        self._last = np.zeros(self.lanes, dtype=np.float32)
        self.samples = 0
        self.replaced = 0
        self.dropped_bytes = 0

    def parse(self, chunk: bytes) -> np.ndarray:
        data = self._partial + bytes(chunk) if self._partial else bytes(chunk)
        size = 4 * self.lanes
        usable = len(data) - len(data) % size
        self._partial = data[usable:]
        if usable == 0:
            return np.empty((0, self.lanes))
        values = np.frombuffer(data, dtype="<f4", count=usable // 4).reshape(-1, self.lanes)
        bad = ~np.isfinite(values)
        if bad.any():
            values = values.copy()
            count = int(bad.sum())
            first = int(np.argmax(bad.any(axis=1)))
            self.replaced += count
            self._problems.add("finite", f"sample {self.samples + first}: NaN or infinite value replaced by the "
                                         f"lane's previous value", count)
            for lane in range(self.lanes):
                column = values[:, lane]
                rows = np.flatnonzero(bad[:, lane])
                if rows.size:
                    # forward fill: each bad value takes the last good value before it
                    good = np.where(~bad[:, lane], np.arange(column.shape[0]), -1)
                    last_good = np.maximum.accumulate(good)
                    filled = np.where(last_good >= 0, column[np.maximum(last_good, 0)], self._last[lane])
                    values[:, lane] = filled
        self._last = values[-1].copy()
        self.samples += values.shape[0]
        return values.astype(np.float64)

    def finish(self) -> np.ndarray:
        if self._partial:
            self.dropped_bytes = len(self._partial)
            self._problems.add("partial", f"the stream ended inside a sample: {len(self._partial)} byte(s) "
                                          f"dropped ({4 * self.lanes} bytes per sample)")
            self._partial = b""
        return np.empty((0, self.lanes))


_SOURCES = {"text": TextSource, "float32": Float32Source}


class _Interrupted(Exception):
    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


class _SignalGuard:
    """While active (main thread only): SIGTERM and SIGINT raise ``_Interrupted`` — or, inside a critical
    section, are remembered and acted on when it ends — so a stream is never cut in the middle of a
    detector update."""

    def __init__(self):
        self.pending: int | None = None
        self.critical = False
        self._previous: dict = {}

    def _handler(self, signum, frame):
        if self.critical:
            self.pending = signum
        else:
            raise _Interrupted(signum)

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGTERM, signal.SIGINT):
                self._previous[sig] = signal.signal(sig, self._handler)
        return self

    def __exit__(self, *exc):
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)
        self._previous.clear()
        return False

    @contextlib.contextmanager
    def section(self):
        self.critical = True
        try:
            yield
        finally:
            self.critical = False


class StreamAnalyzer:
    """Detector + analysis over a byte stream or parsed samples (module docstring).

    Parameters
    ----------
    rate : float
        Sample rate [Hz].
    lanes : int
        Numbers per sample.
    settings : DetectorSettings, optional
        Detector settings (defaults if None).
    on_impact : callable, optional
        Called with each contact's report (``analysis.LineAnalyzer.report``, its ``lane`` the lane's
        name), in emission order.  If None, the reports are collected in ``results``.
    source : "text" or "float32"
        Input format (``TextSource`` or ``Float32Source``).
    on_problem : callable, optional
        Called with one line per kind of input problem (default: print to stderr).
    on_detected : callable, optional
        Also called with each ``DetectedImpact`` and its report (e.g. for a figure of its window).
    analysis : Analysis, optional
        How each contact is analysed (default: ``Analysis(rate)``: raw indices and rebounds).
    lane_names : sequence of str, optional
        The lanes' names in the reports (default ``lane0``, ``lane1``, …).
    start_time : float
        Time of the first sample [s], added to the reports' ``start_time`` (default 0).
    """

    def __init__(self, rate: float, lanes: int = 1, settings: DetectorSettings | None = None,
                 on_impact: Callable[[dict], None] | None = None, *, source: str = "text",
                 on_problem: Callable[[str], None] | None = None,
                 on_detected: Callable[[DetectedImpact, dict], None] | None = None,
                 analysis: Analysis | None = None, lane_names=None, start_time: float = 0.0):
        if source not in _SOURCES:
            raise ValueError(f"source must be one of {', '.join(map(repr, _SOURCES))}; got {source!r}")
        self.detector = Detector(rate, settings, lanes)
        self.rate = self.detector.rate
        self.lanes = self.detector.lanes
        if analysis is None:
            analysis = Analysis(self.rate)
        if not isinstance(analysis, Analysis) or analysis.rate != self.rate:
            raise ValueError("analysis must be an Analysis at the stream's rate")
        self.analysis = analysis
        self._analyzer = analysis.analyzer()
        names = tuple(lane_names) if lane_names is not None else tuple(f"lane{k}" for k in range(self.lanes))
        if len(names) != self.lanes:
            raise ValueError(f"lane_names must name the {self.lanes} lane(s); got {len(names)} name(s)")
        self.lane_names = names
        self.start_time = float(start_time)
        self.source = _SOURCES[source](self.lanes, on_problem)
        self.results: list[dict] = []
        self.on_impact = on_impact if on_impact is not None else self.results.append
        self.on_detected = on_detected
        self.impacts = 0
        self.closed = False
        self.interrupted: str | None = None

    def feed_bytes(self, chunk: bytes) -> int:
        """Parse and analyse a chunk of input; returns the number of impacts emitted."""
        return self.feed(self.source.parse(chunk))

    def feed(self, samples) -> int:
        """Analyse already parsed samples, shape (n,) or (n, lanes); returns the number of impacts emitted."""
        if self.closed:
            raise RuntimeError("this StreamAnalyzer is closed (its stream ended)")
        return self._emit(self.detector.feed(samples))

    def close(self) -> int:
        """End of stream: parse what the source holds, flush the detector; idempotent."""
        if self.closed:
            return 0
        count = self._emit(self.detector.feed(self.source.finish()))
        self.closed = True
        return count + self._emit(self.detector.flush())

    def _emit(self, impacts: list[DetectedImpact]) -> int:
        count = 0
        for impact in impacts:
            for report in self._analyzer.reports(impact):
                report["lane"] = self.lane_names[impact.lane]
                if self.start_time:
                    for key in ("start_time", "raw_start_time"):
                        if key in report:
                            report[key] += self.start_time
                count += 1
                if self.on_detected is not None:
                    self.on_detected(impact, report)
                self.on_impact(report)
        self.impacts += count
        return count

    def run(self, chunks: Iterable[bytes]) -> dict:
        """Consume ``chunks`` (bytes) to their end, or until SIGTERM/SIGINT (main thread) or
        KeyboardInterrupt, then ``close()``; returns ``summary()``."""
        with _SignalGuard() as guard:
            try:
                for chunk in chunks:
                    with guard.section():
                        self.feed_bytes(chunk)
                    if guard.pending is not None:
                        self.interrupted = signal.Signals(guard.pending).name
                        break
            except _Interrupted as stop:
                self.interrupted = signal.Signals(stop.signum).name
            except KeyboardInterrupt:
                self.interrupted = "SIGINT"
            with guard.section():
                self.close()
        return self.summary()

    def line_speeds(self) -> dict | None:
        """Each lane's impact speed [m/s] read from its rebounds (``LineAnalyzer.line_speed``; None for a lane whose
        rebounds gave none), by lane name; None when the speed is not read from rebounds (given as a drop height
        or velocity, or found by each fit from the mass: ``LineAnalyzer.reads_speed``)."""
        if not self._analyzer.reads_speed():
            return None
        return {name: self._analyzer.line_speed(lane) for lane, name in enumerate(self.lane_names)}

    def discharge_times(self) -> dict | None:
        """Each lane's sensor discharge τ [s] measured on its contacts and restored now (None for a lane that
        showed none), by lane name; None when τ was given or declared none (``DetectorSettings.discharge_time``)."""
        if self.detector.settings.discharge_time is not None:
            return None
        return {name: self.detector.discharge_time(lane) for lane, name in enumerate(self.lane_names)}

    def hum_found(self) -> dict | None:
        """The mains hum found on the first samples and removed (``hum_frequency="auto"``): its ``frequency``
        [Hz] and ``amplitude`` [N]; None when none was found, or the frequency was given or declared none."""
        found = self.detector.hum_found
        if found is None or self.detector.hum_frequency is None:
            return None
        return {"frequency": float(found[0]), "amplitude": float(found[1])}

    def summary(self) -> dict:
        """Samples per lane, impacts emitted, input problems by kind, how the stream ended, and what it found of
        the sensor's chain: the mains hum (``hum_found``) and each lane's discharge (``discharge_times``)."""
        source = self.source
        return {"samples": self.detector.samples_fed, "impacts": self.impacts,
                "malformed_lines": getattr(source, "malformed", 0),
                "replaced_values": getattr(source, "replaced", 0),
                "dropped_bytes": getattr(source, "dropped_bytes", 0),
                "problems": source.problems, "interrupted": self.interrupted,
                "hum_found": self.hum_found(), "discharge_times": self.discharge_times()}


def iter_chunks(file, size: int = CHUNK_SIZE):
    """The chunks of a binary file object as soon as they are available (``read1``), until EOF."""
    read = getattr(file, "read1", None) or file.read
    while True:
        chunk = read(size)
        if not chunk:
            return
        yield chunk


def serve(port: int, rate: float, lanes: int = 1, settings: DetectorSettings | None = None,
          on_impact: Callable[[dict], None] | None = None, *, source: str = "text",
          on_problem: Callable[[str], None] | None = None, host: str = "127.0.0.1",
          max_clients: int | None = None, on_listening: Callable[[int], None] | None = None,
          on_client: Callable[[tuple, dict], None] | None = None,
          on_detected: Callable[[DetectedImpact, dict], None] | None = None,
          analysis: Analysis | None = None, on_stop: Callable[[str], None] | None = None) -> list[dict]:
    """Listen on ``host``:``port`` (0: any free port) and analyse each client's bytes as one stream, one
    client at a time, until ``max_clients`` clients were served (None: until SIGTERM/SIGINT).

    ``on_impact``, ``source``, ``on_problem``, ``on_detected`` and ``analysis`` are those of ``StreamAnalyzer``;
    ``on_listening(port)`` is called once the socket listens; ``on_client(address, summary)`` after each
    client; ``on_stop(name)`` with the signal's name ("SIGTERM", "SIGINT") when one stops the server, between
    clients or during one.  Returns the clients' summaries.  Arguments are checked (by building an analyzer) before
    the socket is opened.
    """
    check_integer("port", port, 0, 65535)
    if max_clients is not None:
        check_integer("max_clients", max_clients, 1)
    StreamAnalyzer(rate, lanes, settings, on_impact, source=source, on_problem=on_problem,
                   analysis=analysis)  # checks the arguments
    summaries: list[dict] = []
    with _SignalGuard() as guard, socket.create_server((host, port)) as server:
        try:  # a signal while the callback runs (the CLI's collection there takes ~40 ms) stops the server
            if on_listening is not None:
                on_listening(server.getsockname()[1])
            while max_clients is None or len(summaries) < max_clients:
                connection, address = server.accept()
                with connection:
                    analyzer = StreamAnalyzer(rate, lanes, settings, on_impact, source=source,
                                              on_problem=on_problem, on_detected=on_detected, analysis=analysis)
                    summary = _serve_client(analyzer, connection, guard)
                summaries.append(summary)
                if on_client is not None:
                    on_client(address, summary)
                if summary["interrupted"]:
                    if on_stop is not None:
                        on_stop(summary["interrupted"])
                    break
        except _Interrupted as stop:
            if on_stop is not None:
                on_stop(signal.Signals(stop.signum).name)
    return summaries


def _serve_client(analyzer: StreamAnalyzer, connection: socket.socket, guard: _SignalGuard) -> dict:
    try:
        while True:
            chunk = connection.recv(CHUNK_SIZE)
            if not chunk:
                break
            with guard.section():
                analyzer.feed_bytes(chunk)
            if guard.pending is not None:
                analyzer.interrupted = signal.Signals(guard.pending).name
                break
    except _Interrupted as stop:
        analyzer.interrupted = signal.Signals(stop.signum).name
    except (ConnectionResetError, BrokenPipeError):
        pass
    with guard.section():
        analyzer.close()
    return analyzer.summary()
