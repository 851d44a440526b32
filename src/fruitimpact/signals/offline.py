"""A whole recording analysed at once: a file or an array of force samples → one row per impact.

The samples go through the streaming detector and analysis (:class:`~fruitimpact.signals.stream.StreamAnalyzer`)
in chunks, exactly as ``fruitimpact analyze`` does, so the rows are those of ``analyze --json`` and memory is
bounded by the chunk, not the recording.
"""

from __future__ import annotations

from dataclasses import dataclass

#: Samples per lane read and analysed at once (memory is bounded by this, not by the recording).
ANALYZE_CHUNK = 1 << 18


def analyze(source, *, rate=None, column: str | None = None, format: str | None = None, lanes: int = 1,
            **options):
    """Detect and analyse every impact of a force recording.

    Parameters
    ----------
    source : str, path, array or Recording
        A recording file (``.csv``/``.txt``, ``.npy``, ``.f32``/``.bin``/``.raw``, ``.tdms``), an array of force
        samples [N] of shape (n,) or (n, lanes) (then ``rate`` is required), or a
        :class:`~fruitimpact.signals.recording.Recording`.
    rate : float or str, optional
        Sample rate [Hz]; required for arrays, ``.npy`` and raw files and CSV files without a time column.
    column : str, optional
        Analyse only this lane of a file.
    format : str, optional
        ``csv``, ``npy``, ``f32`` or ``tdms`` (default: from the extension).
    lanes : int
        Interleaved lanes of a raw float32 file.
    **options
        The analysis options of ``fruitimpact analyze`` by their Python names
        (:data:`fruitimpact.signals.options.ANALYSIS_OPTIONS`): ``hum`` [Hz], ``"auto"`` (the default: 50 or 60 Hz
        found on the first 0.2 s) or ``"none"``, ``lowpass`` [Hz], ``discharge_time`` [s] (a piezo sensor's),
        ``"auto"`` (the default: measured on each lane's contacts) or ``"none"``, ``k_on``, ``k_off``,
        ``clip`` (``"LOW,HIGH"`` [N]), ``rebound_window`` [s], ``pitch`` [s] or ``fruit_rate`` [Hz], ``fit`` (bool),
        ``velocity`` [m/s] or ``drop_height`` [m], ``mass`` [kg], ``diameter`` [m], ``poisson``, ``sort_by``,
        ``thresholds`` (``"A,B"``), ``classes`` (``"soft,firm,…"``).  Numbers [SI] or strings with units.

    Returns
    -------
    pandas.DataFrame
        One row per contact in time order per lane, with the columns of ``fruitimpact analyze --json``
        (``lane``, ``start_time`` [s], ``peak_force`` [N], ``time_to_peak`` [s], ``contact_duration`` [s],
        ``firmness_c`` [N/s], ``firmness_c_star`` [N/s²], ``status``, ``rebound_of`` …; with ``fit`` the fitted
        stiffness, restitution and, with a velocity or mass, the modulus; ``rebound_of`` is the parent's
        ``sequence``, NaN for a fruit and for a rebound whose parent was not measured as it was).
        ``attrs["warnings"]``: what the
        file's reader found odd but could read (a TDMS file cut short), one line each.

    Raises
    ------
    ValueError
        An unreadable file, a rate that is missing or disagrees with the file, an unknown option or a value out
        of range; the message names the option as the CLI spells it.

    Examples
    --------
    >>> import fruitimpact as fi
    >>> impacts = fi.analyze("line.csv", fit=True, drop_height="4cm", hum="50Hz")  # doctest: +SKIP
    >>> impacts[["lane", "peak_force", "firmness_c_star", "restitution"]]  # doctest: +SKIP

    References
    ----------
    The firmness indices C = F_max/t_c and C* = F_max/t_c² are eqs 1–2 of "Theoretical aspects about simulating
    the reaction to impact of apples on rigid plane surfaces"; the fitted force law is its Hunt–Crossley model.
    """
    import pandas as pd

    run = run_analysis(source, rate=rate, column=column, format=format, lanes=lanes, **options)
    frame = pd.DataFrame(run.rows, columns=run.columns)
    frame.attrs["warnings"] = list(run.notes)
    return frame


@dataclass
class AnalysisRun:
    """What :func:`run_analysis` found: the rows of ``analyze``'s table, its columns, the recording's lanes,
    rate [Hz], first sample's time [s] and samples per lane fed, the firmness classes used (or None), and what the
    detector found of the sensor: the hum removed and each lane's discharge restored."""

    rows: list
    columns: list
    lane_names: list
    rate: float
    start_time: float
    samples: int
    classes: object = None
    notes: tuple = ()  # what the file's reader found odd but could read (RecordingSource.notes)
    #: the mains frequency [Hz] whose hum was removed (given, or found: ``--hum auto``), None when none
    hum: float | None = None
    #: each lane's sensor discharge τ [s] measured and restored at the end (``StreamAnalyzer.discharge_times``;
    #: None when τ was given or declared none)
    discharge: dict | None = None


def run_analysis(source, *, rate=None, column: str | None = None, format: str | None = None, lanes: int = 1,
                 on_detected=None, on_chunk=None, **options) -> AnalysisRun:
    """:func:`analyze`'s work, with two hooks for a caller that shows more than the table (the web app):
    ``on_detected(impact, report)`` with each ``DetectedImpact`` (its window of samples) and its full report
    (the fit included), and ``on_chunk(samples)`` with each chunk of samples (n, lanes) as it is fed."""
    import numpy as np

    from fruitimpact.impact.validation import InputError, check_integer
    from fruitimpact.signals.reports import public, report_columns
    from fruitimpact.signals.options import analysis_settings
    from fruitimpact.signals.read import open_recording
    from fruitimpact.signals.recording import Recording
    from fruitimpact.signals.read.common import RATE_TOLERANCE
    from fruitimpact.signals.settings import check_rate
    from fruitimpact.signals.stream import StreamAnalyzer

    lanes = check_integer("lanes", lanes, 1)
    rate_value = check_rate(rate)
    analysis_settings(rate_value if rate_value is not None else 1e12, rate_value is not None, **options)
    from_file = isinstance(source, (str, bytes)) or hasattr(source, "__fspath__")
    if not from_file:
        for name, value, default in (("column", column, None), ("format", format, None), ("lanes", lanes, 1)):
            if value != default:
                raise InputError(f"{name} applies to a recording file; the samples given are already lanes", name)
    if isinstance(source, Recording):
        if rate_value is not None and abs(rate_value - source.rate) > RATE_TOLERANCE * source.rate:
            raise InputError(f"rate {rate_value:g} Hz disagrees with the recording's {source.rate:g} Hz (leave it "
                             f"out)", "rate")
        names, start, chunks, rate_value = list(source.lanes), source.start_time, None, source.rate
        samples = np.column_stack([source.lanes[name] for name in names])
    elif from_file:
        reader = open_recording(source, rate=rate_value, column=column, format=format, lanes=lanes)
        names, start, rate_value, samples = list(reader.lane_names), reader.start_time, reader.rate, None
        notes = reader.notes
        chunks = reader.chunks(ANALYZE_CHUNK)
    else:
        if rate_value is None:
            raise InputError("rate is required for an array of samples (the sample rate [Hz])", "rate")
        try:
            samples = np.asarray(source, dtype=float)
        except (TypeError, ValueError):
            raise InputError("source must be a recording file, a Recording or force samples [N] (numbers) of shape "
                             "(n,) or (n, lanes)", "source") from None
        if samples.ndim == 1:
            samples = samples[:, None]
        if samples.ndim != 2 or samples.shape[0] == 0 or samples.shape[1] == 0:
            raise InputError(f"source must be force samples of shape (n,) or (n, lanes), at least one sample and one "
                             f"lane; got shape {samples.shape}", "source")
        names, start, chunks = [f"lane{k}" for k in range(samples.shape[1])], 0.0, None
    if not from_file or isinstance(source, Recording):
        notes = ()
    if chunks is None:
        chunks = (samples[i:i + ANALYZE_CHUNK] for i in range(0, samples.shape[0], ANALYZE_CHUNK))
    settings, analysis = analysis_settings(rate_value, True, **options)
    rows = []

    def detected(impact, report):
        rows.append(public(report))
        if on_detected is not None:
            on_detected(impact, report)

    analyzer = StreamAnalyzer(rate_value, len(names), settings, lambda report: None, on_detected=detected,
                              analysis=analysis, lane_names=names, start_time=start)
    if on_chunk is not None:
        chunks = _watched(chunks, on_chunk)
    samples_fed = feed_all(analyzer, chunks)
    # the same columns in the same order whatever the contacts (a quiet recording, a fit that never converged)
    columns = list(report_columns(analysis))
    columns += [key for key in dict.fromkeys(k for row in rows for k in row) if key not in columns]
    return AnalysisRun(rows, columns, names, rate_value, start, samples_fed, analysis.classes, notes,
                       analyzer.detector.hum_frequency, analyzer.discharge_times())


def _watched(chunks, on_chunk):
    for chunk in chunks:
        on_chunk(chunk)
        yield chunk


def feed_all(analyzer, chunks, on_chunk=None) -> int:
    """Feed every chunk of samples to a :class:`~fruitimpact.signals.stream.StreamAnalyzer`, then close it;
    returns the samples fed per lane.  The one loop of ``analyze`` (CLI and API).

    SIGINT and SIGTERM (main thread) wait for the chunk in flight, so a detector update is never cut; then, as
    on a bad row of the file (``ValueError``), the analyzer is closed first (the contacts in progress are
    reported, marked truncated) and the interruption (``KeyboardInterrupt``) or the error is raised.
    ``on_chunk(samples_fed, impacts_reported)`` is called after each chunk (progress)."""
    from fruitimpact.signals.stream import _Interrupted, _SignalGuard

    done = 0
    with _SignalGuard() as guard:
        try:
            for chunk in chunks:
                with guard.section():
                    analyzer.feed(chunk)
                done += chunk.shape[0]
                if on_chunk is not None:
                    on_chunk(done, analyzer.impacts)
                if guard.pending is not None:
                    raise _Interrupted(guard.pending)
        except _Interrupted:
            with guard.section():
                analyzer.close()
            raise KeyboardInterrupt from None
        except BaseException:  # a bad row mid-file, or an interruption from elsewhere
            with guard.section():
                analyzer.close()
            raise
        with guard.section():
            analyzer.close()
    return done
