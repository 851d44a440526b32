"""The web app's signal pages (issue 16 items 3–5): the recording page and the live monitor.

References: every table the page shows is ``fruitimpact.analyze`` on the same file with the same options (the
function behind ``fruitimpact analyze``; the same code, so the same numbers to the bit); every count the monitor
shows is the count its stream reported (``StreamAnalyzer.summary``) and the count ``analyze`` finds in the same
samples offline.  The recordings are written by ``tests/linegen.py``, a generator that shares no code with
fruitimpact (its own Hunt–Crossley integration with SciPy, hum, drift, plate ringing, jittered chain feed), and one
is a TDMS file from the nptdms wheel, written by LabVIEW.  Browser tests as in test_app.py.
"""

from __future__ import annotations

import asyncio
import dataclasses
import glob
import http.client
import json
import math
import os
import socket
import subprocess
import time
import urllib.parse

import numpy as np
import pytest

import fruitimpact as fi
from test_app import _post, _wait, browser_page, server  # noqa: F401 - the server fixture

pytest.importorskip("tornado")
RATE = 20_000.0


@pytest.fixture(scope="module")
def line_recording(tmp_path_factory):
    """A 4-lane line at 10 fruit/s per lane (the monitor's load), 2.5 s, raw float32, by the independent
    generator: (path, truth)."""
    import linegen

    scenario = dataclasses.replace(linegen.SCENARIOS["lanes4"], name="monitor", fruit_rate=10.0, rate=RATE,
                                   kinds=((linegen.APPLE, 1.0),))
    return linegen.write(scenario, tmp_path_factory.mktemp("line"), size=25)


def _upload(server: str, name: str, data: bytes):
    url = server + "api/upload?" + urllib.parse.urlencode({"name": name})
    return _post(url, None, raw=data)


def _same(page_rows: list, frame) -> None:
    """The page's rows are ``analyze``'s rows: every column, NaN shown as null."""
    assert len(page_rows) == len(frame)
    for row, (_, expected) in zip(page_rows, frame.iterrows()):
        for key, value in expected.items():
            shown = row.get(key)
            if isinstance(value, float) and math.isnan(value):
                assert shown is None, key
            elif isinstance(value, (float, np.floating)):
                assert shown == float(value), key
            elif value is None or (not isinstance(value, (list, dict, str)) and value != value):
                assert shown is None, key
            else:
                assert shown == value, key


def test_an_uploaded_recording_is_analysed_as_analyze_does(server, line_recording):
    path, truth = line_recording
    status, stored = _upload(server, path.name, path.read_bytes())
    assert status == 200 and stored["file"] == path.name and stored["size"] == path.stat().st_size
    options = {"rate": "20kHz", "lanes": "4", "hum": "50Hz", "fit": True, "drop_height": "5cm",
               "sort_by": "firmness_c_star", "thresholds": "1e7,2e7"}
    status, body = _post(server + "api/recording", {"upload": stored["upload"], **options})
    assert status == 200 and "refused" not in body, body
    expected = fi.analyze(path, rate=RATE, lanes=4, hum="50Hz", fit=True, drop_height="5cm",
                          sort_by="firmness_c_star", thresholds="1e7,2e7")
    _same(body["impacts"], expected)
    # and true to the generator's own contacts (not only to analyze): none invented, the peak forces within the
    # 1 % of issue 13's goal; recall 0.99 here, the 2 contacts missed of 200 lie inside overlaps (issue 13's open
    # work), hence 0.98 and not 1
    import linegen

    card = linegen.score(body["impacts"], truth)
    assert card["extra"] == 0 and card["recall"] >= 0.98 and card["peak_force_p95"] <= 0.01, card
    assert body["command"] == (f"fruitimpact analyze {path.name} --rate 20kHz --lanes 4 --hum 50Hz --fit "
                               "--drop-height 5cm --sort-by firmness_c_star --thresholds 1e7,2e7")
    # the histogram counts the fruit (first contacts), the classes sum to them
    fruit = expected[~expected["rebound"].astype(bool)]
    indexed = fruit[np.isfinite(fruit["firmness_c_star"].astype(float))]  # an overlap has no firmness
    assert body["fruit"] == len(fruit) and 0 < len(indexed) <= len(fruit)
    assert sum(body["histogram"]["counts"]) == body["histogram"]["fruit"] == len(indexed)
    assert body["classes"] == fruit["class"].dropna().value_counts().to_dict()
    assert body["histogram"]["thresholds"] == [1e7, 2e7]
    # what the detector found of the sensor: the hum given (50 Hz) removed; no τ given, none shown on this line
    assert body["hum"] == 50.0 and body["discharge"] == {lane: None for lane in body["lanes"]}
    # the overview keeps every peak: its greatest force is the recording's
    samples = np.fromfile(path, dtype="<f4").reshape(-1, 4)
    for k, lane in enumerate(body["lanes"]):
        assert max(body["overview"]["lanes"][lane]["high"]) == pytest.approx(samples[:, k].max(), rel=1e-6)

    # one impact: its samples, and the fitted model over them (the fit's own residual says how close)
    index = next(i for i, row in enumerate(body["impacts"]) if row["fit_converged"] and not row["rebound"])
    status, shown = _post(server + "api/impact", {"analysis": body["analysis"], "index": index})
    assert status == 200 and shown["row"] == body["impacts"][index]
    # the samples are the window the indices came from: their greatest is the raw peak plus at most the noise the
    # detector smooths away (the generator's noise is 1 % of the median peak; 3 σ of it at a small peak ≈ 5 %)
    assert max(shown["force"]) == pytest.approx(shown["row"]["raw_peak_force"], rel=0.05)
    # the model drawn is the fit's own pulse: its greatest on 600 points over the window is the fitted peak force
    # to the grid's resolution (a parabola's top sampled at spacing h: relative error ~ (π h / T)²/8 ≈ 1e-4)
    model_peak = max(shown["model"]["force"])
    assert model_peak == pytest.approx(shown["row"]["peak_force"], rel=1e-3)
    assert shown["row"]["fit_residual_relative"] < 0.05  # the fit's residual is the noise, ~1 % of the peak


def test_a_real_tdms_file_from_labview(server):
    # npTDMS's LabVIEW example (not a force, so refused as the CLI refuses it), and one it reads
    import importlib.resources

    folder = importlib.resources.files("nptdms") / "test" / "data"
    raw = folder / "raw1.tdms"
    if not raw.is_file():
        pytest.skip("nptdms ships no raw1.tdms here")
    status, stored = _upload(server, "raw1.tdms", raw.read_bytes())
    status, body = _post(server + "api/recording", {"upload": stored["upload"]})
    assert body["refused"] and body["argument"] == "file"
    from conftest import console_script

    cli = subprocess.run([console_script(), "analyze", "raw1.tdms"], cwd=str(folder), capture_output=True,
                         text=True, timeout=120)
    assert cli.returncode == 2
    assert body["error"] == cli.stderr.strip().removeprefix("fruitimpact analyze: error: ")


@pytest.mark.parametrize("name,data,expected", [
    ("line.xlsx", b"PK\x03\x04", "argument FILE: unsupported format .xlsx of 'line.xlsx' (allowed: .csv, .txt, .npy, "
                                  ".f32, .bin, .raw, .tdms; or give format=)"),
    ("empty.csv", b"", "argument FILE: cannot read 'empty.csv': empty file"),
])
def test_an_upload_is_refused_with_its_reason(server, tmp_path, name, data, expected):
    status, body = _upload(server, name, data)
    assert status == 200 and body["refused"] and body["argument"] == "file"
    assert body["error"] == expected
    from conftest import console_script  # the CLI's own line for the same file

    (tmp_path / name).write_bytes(data)
    cli = subprocess.run([console_script(), "analyze", name], cwd=tmp_path, capture_output=True, text=True,
                         timeout=120)
    assert cli.returncode == 2 and cli.stderr.strip() == f"fruitimpact analyze: error: {expected}"


def test_a_malformed_recording_is_refused_as_the_cli_refuses_it(server, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("time [s],force [N]\n0,1\n0.00005,2\n0.0001,oops\n0.00015,3\n")
    status, stored = _upload(server, bad.name, bad.read_bytes())
    status, body = _post(server + "api/recording", {"upload": stored["upload"]})
    from conftest import console_script

    cli = subprocess.run([console_script(), "analyze", bad.name], cwd=tmp_path, capture_output=True, text=True,
                         timeout=120)
    assert cli.returncode == 2 and body["refused"]
    # the same line, the file named as the user named it (never the server's own stored path)
    assert body["error"] == cli.stderr.strip().removeprefix("fruitimpact analyze: error: ")
    assert "fruitimpact-app-" not in body["error"]


def test_refused_options_name_their_control(server, line_recording):
    path, _ = line_recording
    _, stored = _upload(server, path.name, path.read_bytes())
    for options, argument in [({"rate": "20kHz", "lanes": "4", "hum": "-5"}, "hum"),
                              ({"rate": "20kHz", "lanes": "4", "thresholds": "1e7"}, "thresholds"),
                              ({"lanes": "4"}, "rate"), ({"rate": "20kHz", "bogus": 1}, "bogus"),
                              ({"rate": "20kHz", "lanes": "0"}, "lanes")]:
        _, body = _post(server + "api/recording", {"upload": stored["upload"], **options})
        assert body.get("refused") and body["argument"] == argument, (options, body)
    _, body = _post(server + "api/recording", {"upload": "0123456789abcdef"})
    assert body["refused"] and body["argument"] == "upload"
    _, body = _post(server + "api/impact", {"analysis": "nope", "index": 0})
    assert body["refused"] and body["argument"] == "analysis"


def test_an_upload_beyond_the_limit_is_refused_before_it_is_read(server):
    from fruitimpact.app.uploads import MAX_UPLOAD

    address = urllib.parse.urlparse(server)
    connection = http.client.HTTPConnection(address.hostname, address.port, timeout=30)
    connection.putrequest("POST", "/api/upload?name=huge.f32")
    connection.putheader("Content-Length", str(MAX_UPLOAD + 1))
    connection.endheaders()
    response = connection.getresponse()  # answered at once: the 200 MB are never sent
    assert response.status == 413 and "at most" in json.loads(response.read())["error"]
    connection.close()


def test_a_stored_upload_changed_on_disk_is_not_read():
    from fruitimpact.app.uploads import UploadStore

    store = UploadStore(max_uploads=2)
    try:
        writer = store.begin("a.csv")
        writer.write(b"time,force\n0,1\n")
        upload = writer.finish()
        assert upload.checked_path().read_bytes() == b"time,force\n0,1\n"
        upload.path.write_bytes(b"time,force\n0,2\n")
        with pytest.raises(ValueError, match="changed on disk"):
            store.get(upload.id).checked_path()
        for name in ("b.csv", "c.csv"):  # the oldest goes when a third arrives, and only the server's files
            writer = store.begin(name)
            writer.write(b"x")
            writer.finish()
        with pytest.raises(ValueError, match="no upload"):
            store.get(upload.id)
        assert not upload.path.exists()
    finally:
        store.close()
    assert not store.folder.exists()


def test_the_upload_folder_goes_with_the_server():
    from conftest import console_script

    before = set(glob.glob(os.path.join(os.environ.get("TMPDIR", "/tmp"), "fruitimpact-app-*")))
    process = subprocess.Popen([console_script(), "serve", "--port", "0"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    process.stdout.readline()
    mine = set(glob.glob(os.path.join(os.environ.get("TMPDIR", "/tmp"), "fruitimpact-app-*"))) - before
    assert len(mine) == 1
    process.terminate()  # SIGTERM: a clean stop
    assert process.wait(timeout=20) == 0
    assert not any(os.path.exists(folder) for folder in mine)


# --------------------------------------------------------------------------- the monitor's channel

async def _monitor(server: str, start: dict, feed=None, timeout: float = 120.0, summaries: int = 1) -> dict:
    """Run one monitor over the WebSocket; ``feed(started)`` (in a thread) sends samples for a tcp source.
    Stops the monitor once ``summaries`` clients were summed up.  Returns the started message, every report,
    every source message and the last figures."""
    import tornado.websocket

    url = server.replace("http://", "ws://") + "ws/monitor"
    socket_ = await tornado.websocket.websocket_connect(url)
    await socket_.write_message(json.dumps({"action": "start", **start}))
    started = json.loads(await socket_.read_message())
    if started["type"] != "started":
        socket_.close()
        return {"started": started}
    feeding = asyncio.get_running_loop().run_in_executor(None, feed, started) if feed else None
    reports, messages, figures = [], [], None
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        message = json.loads(await socket_.read_message())
        if message["type"] == "end":
            break
        if message["type"] == "frame":
            reports += message["reports"]
            messages += message["messages"]
            figures = message["figures"]
            if feed and sum(m["type"] == "summary" for m in messages) >= summaries:
                await socket_.write_message(json.dumps({"action": "stop"}))
    if feeding:
        await feeding
    socket_.close()
    return {"started": started, "reports": reports, "messages": messages, "figures": figures}


def test_the_monitor_replays_a_recording_and_counts_what_the_stream_reports(server, line_recording):
    path, truth = line_recording
    _, stored = _upload(server, path.name, path.read_bytes())
    run = asyncio.run(_monitor(server, {"source": "replay", "upload": stored["upload"], "speed": "max",
                                        "rate": "20kHz", "lanes": "4", "drop_height": "5cm"}))
    summaries = [m["summary"] for m in run["messages"] if m["type"] == "summary"]
    assert len(summaries) == 1 and summaries[0]["impacts"] == len(run["reports"])
    # the same samples offline: the same contacts (a replay is the stream; the stream is analyze)
    offline = fi.analyze(path, rate=RATE, lanes=4, drop_height="5cm")
    assert len(run["reports"]) == len(offline)
    assert [r["peak_force"] for r in run["reports"]] == list(offline["peak_force"])  # same order, same bits
    assert summaries[0]["samples"] == np.fromfile(path, dtype="<f4").size // 4
    assert run["figures"]["dropped"] == 0 and run["figures"]["latency_p99"] is not None


def test_the_monitor_is_the_streams_tcp_source(server, line_recording):
    path, _ = line_recording
    samples = np.fromfile(path, dtype="<f4").reshape(-1, 4)[: int(1.5 * RATE)]
    text = "\n".join(" ".join(f"{v:.6g}" for v in row) for row in samples) + "\n"
    text = text.replace("\n", "\nnot a number\n", 1)  # one malformed line: skipped and counted as dropped

    def send(started):
        with socket.create_connection(("127.0.0.1", started["port"]), timeout=30) as connection:
            connection.sendall(text.encode())

    run = asyncio.run(_monitor(server, {"source": "tcp", "rate": "20kHz", "lanes": "4", "port": "0"}, send))
    assert run["started"]["port"] > 0 and run["started"]["lanes"] == ["lane0", "lane1", "lane2", "lane3"]
    summaries = [m["summary"] for m in run["messages"] if m["type"] == "summary"]
    assert summaries and summaries[0]["impacts"] == len(run["reports"]) and summaries[0]["malformed_lines"] == 1
    assert run["figures"]["dropped"] == 1
    # what `fruitimpact stream` finds in the same text (its detector on the parsed samples)
    parsed = np.array([[float(v) for v in line.split()] for line in text.splitlines() if line != "not a number"])
    assert len(run["reports"]) == len(fi.analyze(parsed, rate=RATE))


def test_a_monitor_refuses_what_stream_refuses(server, line_recording):
    uploaded = _upload(server, line_recording[0].name, line_recording[0].read_bytes())[1]["upload"]
    for start, argument in [({"source": "tcp"}, "rate"), ({"source": "tcp", "rate": "20kHz", "port": "70000"}, "port"),
                            ({"source": "replay"}, "file"), ({"source": "pipe"}, "source"),
                            ({"source": "tcp", "rate": "20kHz", "hum": "abc"}, "hum"),
                            ({"source": "replay", "upload": "x"}, "upload"),
                            ({"source": "replay", "upload": uploaded, "speed": "3"}, "speed"),
                            ({"source": "tcp", "rate": "20kHz", "fit": True, "velocity": "1", "mass": "0.1"}, "mass")]:
        run = asyncio.run(_monitor(server, start))
        assert run["started"]["type"] == "refused" and run["started"]["argument"] == argument, (start, run)


# --------------------------------------------------------------------------- in a real browser

def test_the_recording_page_in_a_real_browser(server, line_recording):
    path, _ = line_recording
    with browser_page(server) as page:
        page.goto(server + "recording")
        page.check("input[name=fit]")  # off by default: the fit needs the drop height or the mass
        page.fill("input[name=rate]", "20kHz")
        page.fill("input[name=lanes]", "4")
        page.fill("input[name=drop_height]", "5cm")
        page.set_input_files("#file", str(path))
        _wait(page, "window.fruitimpact.analyses >= 1 && window.fruitimpact.impact !== null", 120)
        expected = fi.analyze(path, rate=RATE, lanes=4, fit=True, drop_height="5cm")
        assert page.evaluate("window.fruitimpact.last.contacts") == len(expected)
        assert page.locator("#impacts tbody tr").count() == len(expected)
        # every row's status is in sight without scrolling the table sideways, also where the table is wider than
        # its panel (it had been the last column, past the panel's edge: "ok, ambiguous" cut at 1300 px)
        page.set_viewport_size({"width": 1000, "height": 1000})
        frame = page.locator(".table-scroll").first.bounding_box()
        assert page.evaluate("document.querySelector('.table-scroll').scrollWidth") > frame["width"]
        status = page.locator("#impacts thead th", has_text="status").bounding_box()
        assert status["x"] + status["width"] <= frame["x"] + frame["width"]
        page.set_viewport_size({"width": 1400, "height": 1000})
        # a click on an impact: its curve with the fitted model over it
        # the click's request races a re-analysis the page may still start from its inputs' change events (then
        # the answer belongs to a replaced analysis and is dropped): click again until the impact is shown
        for attempt in range(4):
            page.click('#impacts tbody tr[data-index="4"]')
            try:
                _wait(page, "window.fruitimpact.impact !== null && window.fruitimpact.impact.index === 4 && "
                            "document.getElementById('impact-caption').textContent.startsWith('impact 5 (')", 20)
                break
            except AssertionError:
                if attempt == 3:
                    raise
        assert page.locator("#chart-impact path").count() >= 2  # samples and model
        peak = float(page.text_content("#impact-numbers tr:first-child td.value").replace(",", ""))
        assert peak == pytest.approx(expected["peak_force"][4], rel=1e-3)  # 4 significant digits shown
        # a refused option: the CLI's line next to it, the results kept and marked stale
        page.fill("input[name=hum]", "-5")
        page.wait_for_selector(".field-error")
        assert "argument --hum" in page.text_content(".field-error")
        assert "stale" in page.get_attribute("#results", "class")


def test_the_monitor_in_a_real_browser_keeps_up_with_four_lanes(server, line_recording):
    path, truth = line_recording
    with browser_page(server) as page:
        page.goto(server + "monitor")
        page.set_input_files("#file", str(path))
        _wait(page, "document.querySelector('#status').textContent.includes('ready')")
        page.fill("input[name=rate]", "20kHz")
        page.fill("input[name=lanes]", "4")
        page.fill("input[name=drop_height]", "5cm")
        page.select_option("select[name=sort_by]", "firmness_c_star")
        page.fill("input[name=thresholds]", "1e7,2e7")
        page.click("#start")  # real time: 2.5 s of 4 lanes at 10 fruit/s
        _wait(page, "window.fruitimpact.ended", 120)
        summaries = page.evaluate("window.fruitimpact.summaries")
        contacts = page.evaluate("window.fruitimpact.contacts")
        assert len(summaries) == 1 and contacts == summaries[0]["impacts"] > 0  # every report reached the page
        assert int(page.text_content("#contacts").replace(",", "")) == contacts
        assert page.locator(".lane").count() == 4
        assert "(all)" in page.text_content("#messages")
        # news in the ink colour, not a problem's: the summary of a stream whose every report arrived
        summary = page.locator("#messages li", has_text="(all)")
        assert summary.get_attribute("class") in (None, "")
        assert page.evaluate("getComputedStyle(document.querySelector('#messages li')).color") == "rgb(29, 38, 48)"


def test_a_reset_connection_ends_one_client_and_the_monitor_takes_the_next(server):
    # an acquisition that reconnects after a network glitch loses only what was in flight (stream --listen
    # does the same); the reset used to kill the monitor's thread, and the next client was refused
    import struct

    def send(started):
        for attempt in range(2):
            connection = socket.create_connection(("127.0.0.1", started["port"]), timeout=30)
            connection.sendall(b"1.0\n" * 100 + (b"0.5\n" * 100 if attempt else b""))
            if attempt == 0:  # a reset, not a close: SO_LINGER 0
                connection.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
            connection.close()
            time.sleep(0.5)

    run = asyncio.run(_monitor(server, {"source": "tcp", "rate": "20kHz", "port": "0"}, send, timeout=60,
                               summaries=2))
    summaries = [m["summary"] for m in run["messages"] if m["type"] == "summary"]
    assert [s["samples"] for s in summaries][-1] == 200 and len(summaries) == 2
    clients = [m for m in run["messages"] if m["type"] == "client"]
    assert len(clients) == 2


def test_a_cut_float32_sample_is_counted_as_dropped(server):
    def send(started):
        with socket.create_connection(("127.0.0.1", started["port"]), timeout=30) as connection:
            connection.sendall(np.zeros(4 * 100, dtype="<f4").tobytes() + b"\x00\x00\x00")

    run = asyncio.run(_monitor(server, {"source": "tcp", "rate": "20kHz", "lanes": "4", "format": "f32",
                                        "port": "0"}, send))
    summaries = [m["summary"] for m in run["messages"] if m["type"] == "summary"]
    assert summaries[0]["dropped_bytes"] == 3 and run["figures"]["dropped"] == 1


def test_an_option_refused_on_the_page_is_the_clis_line_once(server, line_recording):
    path, _ = line_recording
    _, stored = _upload(server, path.name, path.read_bytes())
    _, body = _post(server + "api/recording", {"upload": stored["upload"], "rate": "20kHz", "lanes": "4",
                                               "drop_height": "-5cm"})
    from conftest import console_script

    cli = subprocess.run([console_script(), "analyze", str(path), "--rate", "20kHz", "--lanes", "4",
                          "--drop-height", "-5cm"], capture_output=True, text=True, timeout=120)
    assert body["error"] == cli.stderr.strip().removeprefix("fruitimpact analyze: error: ")
    assert body["error"].count("argument --drop-height") == 1 and body["argument"] == "drop_height"
    # the fit without a drop height or a mass: said next to the drop height
    _, body = _post(server + "api/recording", {"upload": stored["upload"], "rate": "20kHz", "lanes": "4",
                                               "fit": True})
    assert body["refused"] and body["argument"] == "drop_height"


def test_stream_listen_on_a_port_in_use_is_one_line():
    from conftest import console_script

    with socket.create_server(("127.0.0.1", 0)) as taken:
        port = taken.getsockname()[1]
        done = subprocess.run([console_script(), "stream", "--rate", "20kHz", "--listen", str(port)],
                              capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert done.stderr.strip().startswith(f"fruitimpact stream: error: argument --listen: cannot listen on "
                                          f"127.0.0.1:{port}:")


def test_a_nan_in_a_request_is_refused_on_its_control(server, line_recording):
    # Python's JSON reader takes NaN: it reaches the inputs, where a NaN is refused, never a default
    path, _ = line_recording
    _, stored = _upload(server, path.name, path.read_bytes())
    raw = ('{"upload": "%s", "rate": "20kHz", "lanes": 4, "hum": NaN}' % stored["upload"]).encode()
    body = _post(server + "api/recording", None, raw=raw)[1]
    assert body["refused"] and body["argument"] == "hum", body


def test_the_upload_folder_of_a_killed_server_is_removed_by_the_next(tmp_path, monkeypatch):
    import tempfile

    from fruitimpact.app import uploads

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    dead = subprocess.Popen(["true"])
    dead.wait()  # a process id that is gone
    orphan = tmp_path / (uploads.PREFIX + "killed")
    orphan.mkdir()
    (orphan / uploads.MARKER).write_text(f"uploads of a fruitimpact serve\npid={dead.pid}\n")
    (orphan / "0123456789abcdef.csv").write_text("time,force\n")
    alive = tmp_path / (uploads.PREFIX + "alive")
    alive.mkdir()
    (alive / uploads.MARKER).write_text(f"pid={os.getpid()}\n")
    unmarked = tmp_path / (uploads.PREFIX + "not-ours")
    unmarked.mkdir()  # no marker: not the app's, never touched
    store = uploads.UploadStore()
    try:
        assert not orphan.exists() and alive.exists() and unmarked.exists()
    finally:
        store.close()
