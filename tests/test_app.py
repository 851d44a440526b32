"""The web app (issue 16): ``fruitimpact serve``, its JSON API and its explorer page in a real browser.

The server is the console script, started as a user starts it (``--port 0``: a free port, printed).  The page is
driven by Debian's Chromium through Playwright.  Every number the page shows is checked against the library
function the CLI runs (``simulate``, ``safe_height``), the reference being the library, not the page's own
arithmetic; every error against the CLI's own line.  Browser tests skip only outside CI when Chromium or
Playwright is missing; ``.ci/run`` sets FRUITIMPACT_BROWSER_TESTS=required and installs Chromium.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import subprocess
import time
import urllib.error
import urllib.request
from pathlib import Path

import pytest

import fruitimpact as fi

pytest.importorskip("tornado")
CHROMIUM = "/usr/bin/chromium"
REQUIRED = os.environ.get("FRUITIMPACT_BROWSER_TESTS") == "required"


@pytest.fixture(scope="module")
def server():
    from conftest import console_script

    process = subprocess.Popen([console_script(), "serve", "--port", "0"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    line = process.stdout.readline()
    match = re.match(r"fruitimpact serve: (http://127\.0\.0\.1:\d+/) \(Ctrl-C to stop\)", line)
    assert match, (line, process.stderr.read() if process.poll() is not None else "")
    yield match.group(1)
    process.terminate()
    process.wait(timeout=10)


def _post(url: str, body, raw: bytes | None = None):
    data = raw if raw is not None else json.dumps(body).encode()
    request = urllib.request.Request(url, data=data, headers={"Content-Type": "application/json"})
    try:
        with urllib.request.urlopen(request, timeout=60) as response:
            return response.status, json.loads(response.read())
    except urllib.error.HTTPError as error:
        text = error.read()
        return error.code, json.loads(text) if error.headers.get_content_type() == "application/json" else text


def _cli_error(*argv) -> str:
    """The one line ``fruitimpact simulate ARGV`` prints for a refused input, without its prefix."""
    from conftest import console_script

    done = subprocess.run([console_script(), "simulate", *argv], capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    return done.stderr.strip().removeprefix("fruitimpact simulate: error: ")


def test_serve_listens_on_loopback_and_says_where(server):
    assert server.startswith("http://127.0.0.1:")
    with urllib.request.urlopen(server, timeout=30) as response:
        page = response.read().decode()
        policy = response.headers["Content-Security-Policy"]
    # nothing from another origin: every script and style is the app's own, and the policy forbids the rest
    assert "default-src 'self'" in policy and "https://" not in page and "http://" not in page


def test_explorer_api_agrees_with_the_library(server):
    status, body = _post(server + "api/explore", {})
    assert status == 200 and body["status"] == "ok"
    reference = fi.simulate()  # the page opens on `fruitimpact simulate`'s default impact
    shown = {row["name"]: row["si"] for row in body["characteristics"]}
    for name in ("peak_force", "time_to_peak", "contact_duration", "max_deflection", "restitution"):
        assert shown[name] == getattr(reference.characteristics, name)  # the same call: the same bits
    assert body["command"] == "fruitimpact simulate"
    request = {"fruit": "apple", "surface": "steel", "drop_height": "30cm", "criterion": "shear"}
    status, body = _post(server + "api/explore", request)
    reference = fi.simulate("apple", surface="steel", drop_height="30cm", criterion="shear")
    safe = fi.safe_height(fruit="apple", surface="steel", criterion="shear", sensitivity=False)
    assert body["verdict"]["bruised"] is True and body["verdict"]["margin"] == reference.damage["bruise_margin"]
    assert body["safe_height"]["height"] == safe["safe_height"]
    assert body["command"] == "fruitimpact simulate --fruit apple --surface steel --drop-height 30cm --criterion shear"
    drop = fi.drop("30cm", fruit="apple", surface="steel", criterion="shear")  # the command shown, as run
    assert [i["peak_force"] for i in body["drop"]["impacts"]] == [i["peak_force"] for i in drop["impacts"]]


@pytest.mark.parametrize("request_, argv", [({"mass": "-1"}, ("--mass", "-1")),
                                            ({"drop_height": "3 parsecs"}, ("--drop-height", "3 parsecs")),
                                            ({"velocity": "2", "drop_height": "1"}, ("--velocity", "2", "--drop-height", "1")),
                                            ({"model": "nope"}, ("--model", "nope"))])
def test_a_refused_input_gets_the_clis_line_and_names_its_control(server, request_, argv):
    status, body = _post(server + "api/explore", request_)
    assert status == 200 and body["refused"] is True
    if "--model" in argv:  # argparse words a bad choice itself ("invalid choice"); the library's line names both
        assert body["error"].startswith("argument --model: model must be one of hertz, hunt-crossley")
    else:
        assert body["error"] == _cli_error(*argv)
    assert body["argument"] in (list(request_)[0], list(request_))


def test_the_risk_map_needs_a_criterion(server):
    """Without one, risk_map judged by its own default while the page said "no criterion"."""
    body = _post(server + "api/risk", {"fruit": "apple"})[1]
    assert body["refused"] is True and body["argument"] == "criterion"
    body = _post(server + "api/risk", {"fruit": "apple", "criterion": "shear"})[1]
    safe = fi.safe_height(fruit="apple", surface="steel", criterion="shear", sensitivity=False)["safe_height"]
    assert body["safe_height"]["steel"] == pytest.approx(safe, rel=1e-3)  # one root search of the whole grid


def test_a_drop_that_has_not_come_to_rest_says_so(server):
    """An undamped fruit still bounces after drop's impacts: the library's warning reaches the page."""
    body = _post(server + "api/explore", {"fruit": "apple", "model": "hertz", "drop_height": "30cm"})[1]
    assert any("still" in warning for warning in body["drop"]["warnings"]), body["drop"]["warnings"]


def test_the_server_survives_every_bad_request(server):
    assert _post(server + "api/explore", None, raw=b"{not json")[0] == 400
    assert _post(server + "api/explore", None, raw=b"\xff\xfe")[0] == 400
    assert _post(server + "api/explore", None, raw=b"[1, 2]")[1]["refused"] is True
    assert _post(server + "api/explore", {"mass": [1, 2]})[1]["refused"] is True
    assert _post(server + "api/explore", {"bogus": 1})[1]["argument"] == "bogus"
    assert _post(server + "api/explore", None, raw=b"{" + b" " * 300_000 + b"}")[0] == 413
    with pytest.raises((ConnectionError, urllib.error.URLError)):  # beyond 1 MB: not even read
        _post(server + "api/explore", None, raw=b" " * 3_000_000)
    assert _post(server + "api/explore", {"mass": "1e400"})[1]["refused"] is True
    assert _post(server + "api/explore", None, raw=b"null")[1]["refused"] is True
    assert _post(server + "api/explore", None, raw=b"[" * 5000)[0] == 400  # nested too deep to parse
    assert _post(server + "api/explore", None, raw=b"9" * 60_000)[0] == 400  # beyond Python's int digits
    assert _post(server + "api/nothing", {})[0] == 404
    with pytest.raises(urllib.error.HTTPError) as refused:  # the explorer is a POST: a GET is 405, as JSON
        urllib.request.urlopen(server + "api/explore", timeout=30)
    assert refused.value.code == 405 and "error" in json.loads(refused.value.read())
    # and it still answers
    status, body = _post(server + "api/explore", {})
    assert status == 200 and body["status"] == "ok"


def _browser():
    playwright = pytest.importorskip("playwright.sync_api") if not REQUIRED else __import__(
        "playwright.sync_api", fromlist=["sync_playwright"])
    if not os.path.exists(CHROMIUM):
        if REQUIRED:
            pytest.fail(f"{CHROMIUM} is missing: .ci/run installs it (apt-get install chromium)")
        pytest.skip("no Chromium here")
    return playwright


@contextlib.contextmanager
def browser_page(server: str):
    """A page of Debian's Chromium (1400 × 1000, downloads accepted) that fails the test, once closed, on any
    console error, any script error and any request to a host other than the server (the app must work
    offline)."""
    playwright = _browser()
    problems, foreign = [], []
    local = (server, server.replace("http://", "ws://"), "data:", "blob:")
    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        page = browser.new_page(viewport={"width": 1400, "height": 1000}, accept_downloads=True)
        page.on("console", lambda message: problems.append(message.text) if message.type == "error" else None)
        page.on("pageerror", lambda error: problems.append(str(error)))
        page.on("request", lambda request: foreign.append(request.url)
                if not request.url.startswith(local) else None)
        try:
            yield page
        finally:
            browser.close()
    assert not foreign, foreign
    assert not problems, problems


def _wait(page, expression: str, timeout: float = 30.0):
    """Poll a JavaScript expression (page.wait_for_function evaluates strings, which the page's CSP forbids)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if page.evaluate(expression):
            return
        page.wait_for_timeout(50)
    raise AssertionError(f"timed out waiting for {expression}")


def _cell(page, name: str) -> float:
    return float(page.text_content(f'#characteristics tr[data-name="{name}"] td.value').replace(",", ""))


def screenshots(tmp_path) -> Path:
    """Where a browser test keeps its screenshots: ``FRUITIMPACT_SCREENSHOTS`` if set (to look at them), else the
    test's own folder."""
    shots = Path(os.environ.get("FRUITIMPACT_SCREENSHOTS", tmp_path))
    shots.mkdir(parents=True, exist_ok=True)
    return shots


def test_the_explorer_in_a_real_browser(server, tmp_path):
    shots = screenshots(tmp_path)
    with browser_page(server) as page:
        page.goto(server)
        _wait(page, "window.fruitimpact.updates >= 1")
        # opens on `fruitimpact simulate`'s impact: the numbers are the library's (5 significant digits shown)
        reference = fi.simulate().characteristics
        assert _cell(page, "peak_force") == pytest.approx(reference.peak_force, rel=1e-4)
        assert _cell(page, "contact_duration") == pytest.approx(reference.contact_duration * 1e3, rel=1e-4)
        assert page.text_content("#command") == "fruitimpact simulate"

        # a control moved: the numbers change to what the library computes for the new inputs
        page.select_option("select[name=fruit]", "apple")
        page.select_option("select[name=surface]", "steel")
        page.select_option("select[name=criterion]", "shear")
        page.check("input[name=mode][value=drop_height]")
        page.fill("input[name=drop_height]", "30cm")
        _wait(page, "document.querySelector('#command').textContent.includes('30cm')")
        expected = fi.simulate("apple", surface="steel", drop_height="30cm", criterion="shear")
        assert _cell(page, "peak_force") == pytest.approx(expected.characteristics.peak_force, rel=1e-4)
        assert page.text_content("#verdict-word") == "bruised"
        safe = fi.safe_height(fruit="apple", surface="steel", criterion="shear", sensitivity=False)["safe_height"]
        assert page.text_content("#safe-height") == f"{safe * 100:.3g} cm"
        assert page.is_visible("#safe-mark")
        # the slider follows a typed height: log scale, 5 mm to 2 m over 0..1000
        assert float(page.input_value("#height-slider")) == pytest.approx(1000 * math.log(0.3 / 0.005) / math.log(400),
                                                                           abs=1)

        # the slider is the drop height: moved below the safe height, the verdict turns
        updates = page.evaluate("window.fruitimpact.updates")
        page.fill("#height-slider", "150")  # 5 mm × 400^0.15 = 1.23 cm
        _wait(page, f"window.fruitimpact.updates > {updates}")
        assert page.input_value("input[name=drop_height]") == "1.23cm"
        _wait(page, "document.querySelector('#verdict-word').textContent === 'no bruise'")

        # a refused input: the CLI's line next to its control, and the page keeps going
        page.click("#custom summary")
        page.fill("input[name=mass]", "-1")
        page.wait_for_selector(".field-error")
        assert page.text_content(".field-error") == _cli_error("--mass", "-1")
        assert "stale" in page.get_attribute(".results", "class")  # the last good results, shown as such
        page.fill("input[name=mass]", "")
        _wait(page, "document.querySelectorAll('.field-error').length === 0")

        # the risk map and an export
        page.click("#risk-button")
        page.wait_for_selector("#chart-risk rect")
        # its colour key: the share bruised from 0 % to 100 %, beside the map
        assert page.eval_on_selector_all("#chart-risk g[data-part=key] text", "ts => ts.map(t => t.textContent)") == \
            ["0 %", "50 %", "100 %", "bruised"]
        assert page.locator("#chart-risk g[data-part=key] rect").count() == 41
        page.locator("#chart-risk").screenshot(path=str(shots / "risk-map.png"))
        with page.expect_download() as download:
            page.click("[data-export=csv]")
        lines = (download.value.path().read_text() if hasattr(download.value.path(), "read_text")
                 else open(download.value.path()).read()).splitlines()
        assert lines[0] == "time_s,deflection_m,force_N" and len(lines) > 100
