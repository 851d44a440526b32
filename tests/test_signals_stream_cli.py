"""``fruitimpact stream`` writes the same JSON objects as ``analyze`` on the same samples (issue 8, contract
and acceptance), whatever the size of the reads; malformed text lines are skipped, not fatal.
The detector-level check on a million samples in random chunks is in tests/test_signals_detect.py."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from conftest import console_script


def _reports(text: str) -> list[dict]:
    rows = [json.loads(line) for line in text.splitlines() if line.strip()]
    return sorted(rows, key=lambda r: (r["start_time"], r["lane"]))


def test_stream_in_random_chunks_equals_analyze(cli, tmp_path, monkeypatch):
    """analyze reads the file in chunks (here of 7,919 samples, cutting contacts apart) through the same
    detector and analysis as stream: the same JSON objects, whatever the chunk and read sizes."""
    from fruitimpact.signals import offline

    recording = tmp_path / "line.f32"
    cli.ok("synth", "-o", recording, "--count", "12", "--lanes", "2", "--seed", "5")
    monkeypatch.setattr(offline, "ANALYZE_CHUNK", 7919)
    status, out, err = cli.run("analyze", recording, "--rate", "20000", "--lanes", "2", "--fit", "--drop-height",
                               "5cm", "--json")
    assert status == 0, err
    expected = _reports(out)
    monkeypatch.setattr(offline, "ANALYZE_CHUNK", 1 << 18)
    status, whole, err = cli.run("analyze", recording, "--rate", "20000", "--lanes", "2", "--fit", "--drop-height",
                                 "5cm", "--json")
    assert status == 0, err
    assert _reports(whole) == expected  # one chunk or 16: the same
    assert len(expected) >= 24
    data = recording.read_bytes()
    # a writer that sends the bytes in random pieces (cutting samples and lanes apart), flushing each
    feeder = ("import sys, random; random.seed(7); data = open(sys.argv[1], 'rb').read(); i = 0\n"
              "while i < len(data):\n    n = random.randint(1, 50000); sys.stdout.buffer.write(data[i:i + n]);"
              " sys.stdout.buffer.flush(); i += n\n")
    writer = subprocess.Popen([sys.executable, "-c", feeder, str(recording)], stdout=subprocess.PIPE)
    reader = subprocess.run([console_script(), "stream", "--rate", "20000", "--lanes", "2", "--format", "f32",
                             "--fit", "--drop-height", "5cm"], stdin=writer.stdout, capture_output=True, text=True,
                            timeout=300)
    writer.wait()
    assert reader.returncode == 0, reader.stderr
    assert _reports(reader.stdout) == expected
    assert len(data) % 8 == 0


def test_text_stream_skips_malformed_lines_and_reports_them(tmp_path):
    rng = np.random.default_rng(1)
    samples = rng.normal(0.0, 0.3, 6000)
    t = np.arange(400) / 20000.0
    samples[3000:3400] += 80.0 * np.sin(np.pi * t / t[-1]) ** 1.5  # one pulse
    lines = [f"{v:.6f}" for v in samples]
    lines.insert(1000, "not a number")
    lines.insert(2000, "1.0, 2.0")
    text = "\n".join(lines) + "\n"
    result = subprocess.run([console_script(), "stream", "--rate", "20000"], input=text, capture_output=True,
                            text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    reports = _reports(result.stdout)
    assert len(reports) == 1 and abs(reports[0]["peak_force"] - 80.0) < 2.0
    assert "warning" in result.stderr and "2 malformed lines skipped" in result.stderr


def test_stream_refuses_bad_options_in_one_line(cli):
    assert "--rate" in cli.error("stream")
    assert "--format" in cli.error("stream", "--rate", "20000", "--format", "csv")
    assert "--listen" in cli.error("stream", "--rate", "20000", "--listen", "70000")
    assert "exactly one of" in cli.error("stream", "--rate", "20000", "--fit")
    for bad in ("fifty", "1", "1e-300", "3333"):  # a mains supply's: 16.7 Hz railways to 400 Hz aircraft
        assert cli.error("stream", "--rate", "20000", "--hum", bad).startswith(
            "fruitimpact stream: error: argument --hum: must be auto, none or the mains frequency in [16, 400] Hz")
    # a discharge time constant: auto, none or at least 10 ms (faster chains keep too little of a contact)
    for bad in ("5ms", "-1s", "nan", "fast", "3kg"):
        line = cli.error("stream", "--rate", "20000", "--discharge-time", bad)
        assert line.startswith("fruitimpact stream: error: argument --discharge-time: must be auto, none or a time "
                               "constant in [0.01, 1e+06] s"), line


def test_raw_float32_fed_as_text_is_refused_early_in_one_line():
    """Issue 13 item 7: float32 bytes without --format f32 end with one clear line (exit 2) after the first few
    hundred 'lines', not a warning after reading everything; --json is accepted as for analyze."""
    samples = np.random.default_rng(2).normal(0.0, 0.5, 400_000).astype("<f4").tobytes()
    result = subprocess.run([console_script(), "stream", "--rate", "20000", "--json"], input=samples,
                            capture_output=True, timeout=120)
    err = result.stderr.decode()
    assert result.returncode == 2, err
    assert "looks like binary" in err and "--format f32" in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_text_with_another_count_of_numbers_than_lanes_is_refused_early():
    """One number per line fed with --lanes 2: every line would be skipped; one clear line instead (exit 2)."""
    text = "".join(f"{v:.4f}\n" for v in np.random.default_rng(3).normal(0.0, 0.3, 2000))
    result = subprocess.run([console_script(), "stream", "--rate", "20000", "--lanes", "2"], input=text,
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 2, result.stderr
    assert "--lanes" in result.stderr and len(result.stderr.strip().splitlines()) == 1


def test_sigterm_mid_file_ends_analyze_with_whole_lines_only(tmp_path):
    """A real SIGTERM to `analyze` half-way through a long file: the chunk in flight finishes (a detector update
    is never cut), the contacts in progress are reported, every line written is a whole JSON object, and the
    command ends with one "interrupted" line, exit 130 (the shared loop, signals.offline.feed_all)."""
    import signal

    import fruitimpact as fi

    rate = 20_000.0
    curves = fi.simulate(fruit="apple", drop_height="4cm").curves
    pulse = np.interp(np.arange(0.0, curves.time[-1], 1 / rate), curves.time, curves.force)
    period = np.zeros(int(0.1 * rate))
    period[200:200 + pulse.size] = pulse
    force = np.tile(period, 6000) + np.random.default_rng(1).normal(0.0, 0.05, period.size * 6000)  # 600 s
    path = tmp_path / "long.f32"
    force.astype("<f4").tofile(path)
    process = subprocess.Popen([console_script(), "analyze", str(path), "--rate", "20000", "--fit", "--drop-height",
                                "4cm", "--json"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    # the first line is written from inside the analysis loop, where the signal guard is in place: a signal then
    # is never one that reaches the interpreter's default handler during start-up (a fixed sleep could be either)
    first = process.stdout.readline()
    assert first, process.communicate()
    process.send_signal(signal.SIGTERM)
    out, err = process.communicate(timeout=60)
    assert process.returncode == 130, (process.returncode, err)
    assert err.splitlines()[-1] == "fruitimpact analyze: interrupted" and "Traceback" not in err, err
    lines = [first, *out.splitlines()]
    assert len(lines) < 3000  # stopped early: well before the 6000 contacts of the file
    for line in lines:
        json.loads(line)  # whole objects only


def test_stream_equals_analyze_where_a_rebound_is_read_a_second_time(cli, tmp_path):
    """The second readings of a rebound (``rebounds.reassigned``: a bounce re-read as another contact's rebound;
    ``rebounds.held_alternative``: a parent read as a fruit alone) change the analysis's books after a contact has
    been reported.  On recordings of the independent generator (tests/linegen.py, chain10 at seeds 8 and 27) where
    each fires (seed 28, where the re-reading was first seen, is judged right without it since a rebound's damping
    may follow either law, ``rebounds.rebound_x``), ``stream`` fed through a pipe in random pieces writes the same
    objects as ``analyze``."""
    import dataclasses

    import linegen as lg

    fired = set()
    for seed in (8, 27):
        path, truth = lg.write(dataclasses.replace(lg.SCENARIOS["chain10"], seed=seed), tmp_path)
        options = lg.analyze_options(truth)
        status, out, err = cli.run("analyze", path, *options)
        assert status == 0, err
        expected = _reports(out)
        for report in expected:
            evidence = report.get("rebound_evidence") or {}
            fired |= {key for key in ("reassigned", "held_rebound") if evidence.get(key) is not None}
        feeder = ("import sys, random; random.seed(3); data = open(sys.argv[1], 'rb').read(); i = 0\n"
                  "while i < len(data):\n    n = random.randint(1, 40000); sys.stdout.buffer.write(data[i:i + n]);"
                  " sys.stdout.buffer.flush(); i += n\n")
        writer = subprocess.Popen([sys.executable, "-c", feeder, str(path)], stdout=subprocess.PIPE)
        stream_options = [o for o in options if o != "--json"] + ["--format", "f32"]
        reader = subprocess.run([console_script(), "stream", *stream_options], stdin=writer.stdout,
                                capture_output=True, text=True, timeout=300)
        writer.wait()
        assert reader.returncode == 0, reader.stderr
        assert _reports(reader.stdout) == expected, seed
    assert fired == {"reassigned", "held_rebound"}, fired  # both readings happened: the check ran


@pytest.mark.parametrize("cutoff", ["10000", "10kHz", "10001"])
def test_a_lowpass_at_or_above_nyquist_is_refused_with_an_open_range(cutoff):
    """A Butterworth cutoff must lie below the Nyquist frequency (rate/2): at it the digital design has no
    pass band.  The refusal states the open range it checks, (0, rate/2), the same for rate/2 itself and beyond
    (rate/2 had been refused by the detector's check while the option's message said (0, rate/2])."""
    done = subprocess.run([console_script(), "stream", "--rate", "20000", "--lowpass", cutoff], input=b"0\n0\n",
                          capture_output=True, timeout=60)
    assert done.returncode == 2
    assert done.stderr.decode().strip().splitlines() == [
        f"fruitimpact stream: error: argument --lowpass: must be a number in (0, 10000); got {cutoff!r}"]


@pytest.mark.parametrize("stop, status", [("SIGINT", 130), ("SIGTERM", 0)])
def test_a_listening_stream_summarises_each_client_and_exits_as_on_stdin(stop, status):
    """``stream --listen``: each client's stream ends with the line stdin's ends with (samples, impacts, the mains
    hum --hum auto found), prefixed by the client's address; Ctrl-C (SIGINT) ends the server with 130, as on
    stdin, and SIGTERM (a server's normal stop) with 0.  The signal is a 60 Hz hum of 0.05 N on quiet noise: a
    client's line must name 60 Hz (it had printed nothing per client, and exited 0 on Ctrl-C)."""
    import re
    import select
    import signal
    import socket
    import time

    from conftest import sigint_default

    rate = 20000
    t = np.arange(int(0.5 * rate)) / rate
    noise = np.random.default_rng(3).normal(0.0, 0.002, t.size)
    samples = (0.05 * np.sin(2 * np.pi * 60 * t) + noise).astype("<f4").tobytes()
    server = subprocess.Popen([console_script(), "stream", "--rate", str(rate), "--format", "f32", "--listen", "0"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, preexec_fn=sigint_default)

    def next_line(seconds=60.0) -> bytes:  # b"" when none came (the old code wrote no line per client)
        ready, _, _ = select.select([server.stderr], [], [], seconds)
        return server.stderr.readline() if ready else b""

    try:
        port = int(re.search(rb"listening on 127\.0\.0\.1:(\d+)", next_line()).group(1))
        with socket.create_connection(("127.0.0.1", port)) as client:
            client.sendall(samples)
        line = next_line().decode()  # the client's summary, once its stream is analysed
        time.sleep(0.2)
        server.send_signal(getattr(signal, stop))
        _, rest = server.communicate(timeout=60)
    finally:
        if server.poll() is None:
            server.kill()
    found = re.fullmatch(r"fruitimpact stream: client 127\.0\.0\.1:\d+: 10000 samples, 0 impacts; mains hum found "
                         r"at 60 Hz \((\S+) N on the first 0\.2 s\) and removed \(--hum auto\)\n", line)
    assert found, line
    assert float(found.group(1)) == pytest.approx(0.05, rel=0.02)  # its amplitude (noise 0.002 N over 4,000 samples)
    assert server.returncode == status, rest
    assert b"Traceback" not in rest
