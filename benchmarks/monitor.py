"""The live monitor's throughput (issue 16 item 4): does the page keep up with a sorting line?

The recording is a line of 4 lanes at 10 fruit/s per lane (tests/linegen.py, the independent generator: its own
Hunt–Crossley contacts, rebounds, hum, drift, plate ringing), 20 kHz, raw float32.

1. In process, no browser: the monitor (``app.monitor.Monitor``: the detector in its thread, the reports gathered
   into frames) replays the recording as fast as it goes; the baseline in the same run is ``fruitimpact.analyze``
   on the same file (the same detector and analysis with no pacing, thread or frames).  Figure: seconds of signal
   per second of wall time, and the ratio monitor / analyze.  With and without the fit.
2. In Chromium, through ``fruitimpact serve``: the recording replayed at real time and at 5× and 10× real time
   (4 lanes × 10, 50 and 100 fruit/s), with the fit and firmness classes.  Figures: contacts counted by the page
   against the count the stream reported, frames drawn, how far the replay fell behind the clock, and the
   latency of the reports (from the arrival of a contact's last sample to its report).

    python benchmarks/monitor.py [--seconds 20] [--screenshots docs/img]

``--screenshots DIR`` also writes the recording page and the monitor as a user sees them.
"""

from __future__ import annotations

import argparse
import dataclasses
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(ROOT / "tests"))

from bench_common import console_script, machine  # noqa: E402

import linegen as lg  # noqa: E402  (tests/linegen.py: the independent generator)

CHROMIUM = "/usr/bin/chromium"
RATE = 20_000.0
OPTIONS = {"rate": "20kHz", "lanes": "4", "drop_height": "5cm"}
CLASSES = {"sort_by": "firmness_c_star", "thresholds": "1.5e7,2.5e7"}


def wait(page, expression: str, timeout: float = 300.0) -> None:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if page.evaluate(expression):
            return
        page.wait_for_timeout(20)
    raise TimeoutError(expression)


def in_process(path: Path, fit: bool) -> tuple[float, float, int, int]:
    """(monitor's, analyze's) seconds of signal per wall second, and their contact counts."""
    import fruitimpact as fi
    from fruitimpact.app.monitor import Monitor
    from fruitimpact.app.uploads import UploadStore

    fi.analyze(path, rate=RATE, lanes=4, drop_height="5cm", fit=fit)  # warm: neither pays the compilation
    store = UploadStore()
    try:
        writer = store.begin(path.name)
        writer.write(path.read_bytes())
        upload = writer.finish()
        monitor = Monitor({"source": "replay", "upload": upload.id, "speed": "max", "fit": fit, **OPTIONS}, store)
        start = time.perf_counter()
        monitor.start()
        reports = 0
        while True:
            frame = monitor.frame()
            if frame is None:  # no news: the end once the source has ended, else a chunk still in the detector
                if monitor.finished:
                    break
            else:
                reports += len(frame["reports"])
            time.sleep(0.02)
        wall = time.perf_counter() - start
        signal = monitor._fed / RATE
        monitor.stop()
        start = time.perf_counter()
        offline = fi.analyze(path, rate=RATE, lanes=4, drop_height="5cm", fit=fit)
        offline_wall = time.perf_counter() - start
        return signal / wall, signal / offline_wall, reports, len(offline)
    finally:
        store.close()


def in_browser(url: str, path: Path, speeds, screenshots: Path | None) -> list[dict]:
    from playwright.sync_api import sync_playwright

    rows = []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        page = browser.new_page(viewport={"width": 1400, "height": 1000})
        page.goto(url + "monitor")
        page.check("input[name=fit]")
        page.set_input_files("#file", str(path))
        wait(page, "document.querySelector('#status').textContent.includes('ready')")
        page.fill("input[name=rate]", OPTIONS["rate"])
        page.fill("input[name=lanes]", OPTIONS["lanes"])
        page.fill("input[name=drop_height]", OPTIONS["drop_height"])
        page.select_option("select[name=sort_by]", CLASSES["sort_by"])
        page.fill("input[name=thresholds]", CLASSES["thresholds"])
        for speed in speeds:
            page.select_option("select[name=speed]", speed)
            start = time.perf_counter()
            page.click("#start")
            if screenshots and speed == "1":
                page.wait_for_timeout(6000)
                page.screenshot(path=str(screenshots / "monitor.png"))
            wait(page, "window.fruitimpact.ended")
            wall = time.perf_counter() - start
            state = page.evaluate("({contacts: window.fruitimpact.contacts, fruit: window.fruitimpact.fruit, "
                                  "summaries: window.fruitimpact.summaries, frames: window.fruitimpact.frames})")
            figures = page.text_content("#clock"), page.text_content("#latency")
            rows.append({"speed": speed, "wall": wall, **state, "clock": figures[0], "latency": figures[1]})
        if screenshots:
            page.goto(url + "recording")
            page.check("input[name=fit]")
            page.fill("input[name=rate]", OPTIONS["rate"])
            page.fill("input[name=lanes]", OPTIONS["lanes"])
            page.fill("input[name=drop_height]", OPTIONS["drop_height"])
            page.select_option("select[name=sort_by]", CLASSES["sort_by"])
            page.fill("input[name=thresholds]", CLASSES["thresholds"])
            page.set_input_files("#file", str(path))
            wait(page, "window.fruitimpact.analyses >= 1 && window.fruitimpact.impact !== null")
            page.click('#impacts tbody tr[data-index="6"]')
            wait(page, "window.fruitimpact.impact.index === 6")
            page.set_viewport_size({"width": 1400, "height": page.evaluate("document.body.scrollHeight")})
            page.wait_for_timeout(300)
            page.screenshot(path=str(screenshots / "recording.png"))
        browser.close()
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0, help="seconds of line recorded (default 20)")
    parser.add_argument("--screenshots", metavar="DIR")
    args = parser.parse_args()
    print(machine())
    folder = Path(tempfile.mkdtemp(prefix="monitor-bench-"))  # removed at the end (the recording is ~13 MB)
    scenario = dataclasses.replace(lg.SCENARIOS["lanes4"], name="line4x10", fruit_rate=10.0, rate=RATE,
                                   kinds=((lg.APPLE, 1.0),))
    path, truth = lg.write(scenario, folder, size=int(args.seconds * 10))
    print(f"recording: {path.name}, 4 lanes × 10 fruit/s, {truth['samples'] / RATE:.1f} s, "
          f"{len(truth['contacts'])} contacts in the truth")
    print(f"{'in process (speed max)':<28}{'monitor s/s':>12}{'analyze s/s':>12}{'ratio':>8}{'contacts':>10}")
    for fit in (False, True):
        monitor, offline, reports, expected = in_process(path, fit)
        if reports != expected:
            raise SystemExit(f"the monitor reported {reports} contacts, analyze {expected}: a report was lost")
        print(f"{'with the fit' if fit else 'indices only':<28}{monitor:>12.1f}{offline:>12.1f}"
              f"{monitor / offline:>8.2f}{reports:>6} = {expected}")
    screenshots = Path(args.screenshots) if args.screenshots else None
    if screenshots:
        screenshots.mkdir(parents=True, exist_ok=True)
    process = subprocess.Popen([console_script(), "serve", "--port", "0"], stdout=subprocess.PIPE, text=True)
    url = re.search(r"(http://\S+/)", process.stdout.readline()).group(1)
    try:
        rows = in_browser(url, path, ["1", "5", "10"], screenshots)
    finally:
        process.terminate()
        shutil.rmtree(folder, ignore_errors=True)
    print(f"{'in Chromium (fit, classes)':<28}{'fruit/s':>9}{'page':>7}{'stream':>8}{'frames':>8}  signal / wall      "
          f"latency p50 / p99")
    for row in rows:
        stream = sum(s["impacts"] for s in row["summaries"])
        print(f"{row['speed'] + ' × real time':<28}{40 * float(row['speed']):>9.0f}{row['contacts']:>7}{stream:>8}"
              f"{row['frames']:>8}  {row['clock']:<18}{row['latency']}")


if __name__ == "__main__":
    main()
