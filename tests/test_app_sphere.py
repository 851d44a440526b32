"""The line-audit page's sphere log (issue 18 item 5): ``POST /api/sphere`` and the page in a real browser.

The reference of every number is the library call ``fruitimpact sphere`` runs, ``sphere_audit``, on the same files
with the same options and the same lot (same rows, same seed: the same fruit), compared exactly; the files are
named in it as the user named them (the call runs in their folder), as the page names them.  The reference of
every refusal and every skipped row is the line the console script prints for the same files.  Server and browser
as in tests/test_app.py: the console script, and Debian's Chromium through Playwright, failing on any request to
another host and on any console error.
"""

from __future__ import annotations

import json
import shlex
import shutil
import subprocess
from pathlib import Path

import pytest

from fruitimpact.impact.outputs import dump_json
from fruitimpact.spheres.audit import sphere_audit
from test_app import _post, _wait, browser_page, screenshots, server  # noqa: F401 - server is a fixture
from test_app_signals import _upload

pytest.importorskip("tornado")
from fruitimpact.app import line as line_page  # noqa: E402 - the app needs tornado's extra

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
LOG, CALIBRATION = "sphere-log.csv", "sphere-calibration.csv"
#: The sphere of the example log, as the page's fields give it.
SPHERE = {"sphere": "is-1987", "logger_rate": "3kHz"}
#: The command of the example log with the page's lot.
COMMAND = ("fruitimpact sphere sphere-log.csv --sphere is-1987 --sphere-calibration sphere-calibration.csv "
           "--logger-rate 3kHz --fruit apple -n 500 --seed 0")


def _strict(report: dict) -> dict:
    return json.loads(dump_json(report, indent=None))


def _stored(server: str, path: Path, name: str | None = None) -> str:
    status, body = _upload(server, name or path.name, path.read_bytes())
    assert status == 200 and "refused" not in body, body
    return body["upload"]


def _reference(folder: Path, monkeypatch, log: str = LOG, **options) -> dict:
    """``sphere_audit`` on the files of ``folder``, named as the page names them (their names, in their folder)."""
    monkeypatch.chdir(folder)
    return _strict(sphere_audit(log, **options))


def _cli(folder: Path, *argv) -> subprocess.CompletedProcess:
    from conftest import console_script

    return subprocess.run([console_script(), *argv], capture_output=True, text=True, timeout=300, cwd=folder)


def _cli_error(folder: Path, *argv) -> str:
    """The one line ``fruitimpact sphere ARGV`` prints (run in ``folder``) for a refused file or option."""
    done = _cli(folder, "sphere", *argv)
    assert done.returncode == 2, (done.stdout, done.stderr)
    return done.stderr.strip().removeprefix("fruitimpact sphere: error: ")


@pytest.fixture
def uploaded(server):
    """The example log and its calibration, uploaded afresh (the server keeps the last six uploads): {name: id}."""
    return {name: _stored(server, EXAMPLES / name) for name in (LOG, CALIBRATION)}


def test_the_sphere_api_agrees_with_the_library(server, uploaded, monkeypatch):
    """The answer's report is sphere_audit's on the same files, options and lot, to the bit."""
    request = {"log": uploaded[LOG], "sphere_calibration": uploaded[CALIBRATION], **SPHERE}
    status, body = _post(server + "api/sphere", request)
    assert status == 200 and "refused" not in body, body
    reference = _reference(EXAMPLES, monkeypatch, sphere_calibration=CALIBRATION, rows=line_page.PAGE_ROWS,
                           seed=0, fruit="apple", **SPHERE)
    assert body["report"] == reference
    assert body["worst_point"] == reference["worst_point"] == "bin-filler"
    assert body["skipped"] == [] and (body["file"], body["calibration_file"]) == (LOG, CALIBRATION)
    assert body["command"] == COMMAND
    # what the page shows per point is there: the cushion advice and what it saves
    points = {point["name"]: point for point in body["report"]["points"]}
    assert points["receiving-belt"]["cushion"]["surface"] == "foam-pad"
    assert points["receiving-belt"]["cushion"]["saved_per_10000"] > 0
    assert points["padded-chute"]["cushion"] is None  # below the 5 % target
    text = json.dumps(body)
    assert "fruitimpact-app-" not in text  # the server's own paths never reach the page

    # the sphere by its values (no profile, no calibration), another lot
    request = {"log": uploaded[LOG], "sphere_mass": "312g", "sphere_diameter": "89mm", "sphere_modulus": "45MPa",
               "sphere_poisson": "0.3", "logger_rate": "3kHz", "fruit": "apple", "criterion": "pressure",
               "mass": "normal(180g, 20g)", "rows": "300", "seed": "7", "spreads": False}
    body = _post(server + "api/sphere", request)[1]
    reference = _reference(EXAMPLES, monkeypatch, sphere_mass="312g", sphere_diameter="89mm", sphere_modulus="45MPa",
                           sphere_poisson="0.3", logger_rate="3kHz", fruit="apple", criterion="pressure",
                           mass="normal(180g, 20g)", rows=300, seed=7, spreads=False)
    assert body["report"] == reference
    assert body["command"] == ("fruitimpact sphere sphere-log.csv --sphere-mass 312g --sphere-diameter 89mm "
                               "--sphere-modulus 45MPa --sphere-poisson 0.3 --logger-rate 3kHz --fruit apple "
                               "--criterion pressure --mass 'normal(180g, 20g)' -n 300 --seed 7 --no-spreads")


def test_the_command_reproduces_the_report(server, uploaded, tmp_path):
    """The command shown, run on the files by their names, prints the page's report (the console script's --json)."""
    request = {"log": uploaded[LOG], "sphere_calibration": uploaded[CALIBRATION], **SPHERE, "rows": "200",
               "seed": "3", "failure_stress": "0.3MPa"}
    body = _post(server + "api/sphere", request)[1]
    for name in (LOG, CALIBRATION):
        shutil.copy(EXAMPLES / name, tmp_path / name)
    argv = shlex.split(body["command"])
    assert argv[:3] == ["fruitimpact", "sphere", LOG]
    done = _cli(tmp_path, *argv[1:], "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout) == body["report"]


def test_skipped_rows_are_listed_as_the_cli_prints_them(server, tmp_path, monkeypatch):
    lines = (EXAMPLES / LOG).read_text().splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith("time,"))
    lines[header + 3] = lines[header + 3].replace("88.0", "lots")  # a cell not a number
    lines[header + 5] = lines[header + 5].replace("2.131", "-2.131")  # an impossible velocity change
    (tmp_path / "survey.csv").write_text("\n".join(lines) + "\n")
    shutil.copy(EXAMPLES / CALIBRATION, tmp_path / CALIBRATION)
    request = {"log": _stored(server, tmp_path / "survey.csv"),
               "sphere_calibration": _stored(server, tmp_path / CALIBRATION), **SPHERE}
    body = _post(server + "api/sphere", request)[1]
    assert "refused" not in body, body
    done = _cli(tmp_path, *shlex.split(body["command"])[1:])
    printed = [line.removeprefix("fruitimpact sphere: warning: ") for line in done.stderr.splitlines()
               if line.endswith("; row skipped")]
    assert len(body["skipped"]) == 2 and body["skipped"] == printed
    assert body["report"] == _reference(tmp_path, monkeypatch, "survey.csv", sphere_calibration=CALIBRATION,
                                        rows=line_page.PAGE_ROWS, seed=0, fruit="apple", **SPHERE)


def test_a_bad_log_is_refused_with_the_clis_line_at_its_control(server, uploaded, tmp_path):
    shutil.copy(EXAMPLES / CALIBRATION, tmp_path / CALIBRATION)
    cases = {
        "vendor.csv": "time,Peak G,velocity_change\n1.0,100,1.5\n",  # a vendor's header, not mapped
        "empty-rows.csv": "time,peak_acceleration,velocity_change,duration,point\n1.0,oops,1.5,3ms,a\n",
        "no-header.csv": "# only a comment\n",
    }
    for name, text in cases.items():
        (tmp_path / name).write_text(text)
        request = {"log": _stored(server, tmp_path / name), "sphere_calibration": uploaded[CALIBRATION], **SPHERE}
        status, body = _post(server + "api/sphere", request)
        assert status == 200 and body["refused"] is True and body["argument"] == "log", body
        # the CLI's line for the same file (by its name: never the server's own path)
        assert body["error"] == _cli_error(tmp_path, name, "--sphere-calibration", CALIBRATION, "--sphere", "is-1987",
                                           "--logger-rate", "3kHz", "--fruit", "apple")
        assert body["error"].startswith(f"argument LOG: {name}") and "fruitimpact-app-" not in body["error"]
    # a log file given as the calibration: refused at the calibration's control, the CLI's line
    shutil.copy(EXAMPLES / LOG, tmp_path / LOG)
    body = _post(server + "api/sphere", {"log": uploaded[LOG], "sphere_calibration": uploaded[LOG], **SPHERE})[1]
    assert body["argument"] == "sphere_calibration"
    assert body["error"] == _cli_error(tmp_path, LOG, "--sphere-calibration", LOG, "--sphere", "is-1987",
                                       "--logger-rate", "3kHz", "--fruit", "apple")


def test_refused_sphere_and_lot_inputs_name_their_control(server, uploaded, tmp_path):
    shutil.copy(EXAMPLES / LOG, tmp_path / LOG)
    shutil.copy(EXAMPLES / CALIBRATION, tmp_path / CALIBRATION)
    url = server + "api/sphere"
    both = {"log": uploaded[LOG], "sphere_calibration": uploaded[CALIBRATION]}
    for request, argument, argv in (
            ({"log": uploaded[LOG], "sphere": "is-1987"}, "sphere_modulus", ["--sphere", "is-1987"]),
            ({"log": uploaded[LOG]}, "sphere_mass", []),
            ({**both, **SPHERE, "sphere_modulus": "40MPa"}, "sphere_modulus",
             ["--sphere", "is-1987", "--sphere-calibration", CALIBRATION, "--sphere-modulus", "40MPa"]),
            ({**both, "sphere": "is-1987", "logger_rate": "3 parsecs"}, "logger_rate",
             ["--sphere", "is-1987", "--sphere-calibration", CALIBRATION, "--logger-rate", "3 parsecs"]),
            ({**both, "sphere_mass": "-3g", "sphere_diameter": "89mm"}, "sphere_mass",
             ["--sphere-calibration", CALIBRATION, "--sphere-mass", "-3g", "--sphere-diameter", "89mm"]),
            ({**both, **SPHERE, "mass": "-1"}, "mass",
             ["--sphere-calibration", CALIBRATION, "--sphere", "is-1987", "--logger-rate", "3kHz", "--mass", "-1"]),
            ({**both, **SPHERE, "seed": "-1"}, "seed",
             ["--sphere-calibration", CALIBRATION, "--sphere", "is-1987", "--logger-rate", "3kHz", "--seed", "-1"])):
        status, body = _post(url, request)
        assert status == 200 and body["refused"] is True and body["argument"] == argument, (request, body)
        assert body["error"] == _cli_error(tmp_path, LOG, "--fruit", "apple", *argv), request
    # what only the page refuses: no log, an upload the server does not hold, an unknown name, a lot too large
    for request, argument in (({}, "log"), ({"log": "0123456789abcdef"}, "log"),
                              ({"log": uploaded[LOG], "sphere_calibration": "nope"}, "sphere_calibration"),
                              ({"log": uploaded[LOG], "bogus": 1}, "bogus"), ({"log": uploaded[LOG], "rows": 10**6}, "rows"),
                              ({"log": uploaded[LOG], "spreads": "yes"}, "spreads"),
                              ({"log": uploaded[LOG], "sphere_mass": {"g": 3}}, "sphere_mass"), ([1], "request")):
        status, body = _post(url, request)
        assert status == 200 and body["refused"] is True and body["argument"] == argument, (request, body)
    assert "10,000,000" in _post(url, {"log": uploaded[LOG], "rows": 10**6})[1]["error"]
    assert _post(url, None, raw=b"{not json")[0] == 400


# --------------------------------------------------------------------------- in a real browser

def _number(text: str) -> float:
    return float(text.split()[0].replace(",", ""))


def _audit_example_log(view) -> None:
    """On the line page with the sphere as the source: the example log and its calibration chosen, the sphere's
    fields filled, and the audit's answer awaited."""
    view.select_option("select[name=sphere]", "is-1987")
    view.fill("input[name=logger_rate]", "3kHz")
    view.set_input_files("#sphere-calibration", str(EXAMPLES / CALIBRATION))
    view.set_input_files("#sphere-log", str(EXAMPLES / LOG))
    _wait(view, "window.fruitimpact.sphere !== null && window.fruitimpact.sphere.calibration_file !== null "
                "&& window.fruitimpact.sphere.request.logger_rate === '3kHz'", 120)


def test_a_sphere_log_in_place_of_the_table_in_a_real_browser(server, tmp_path, monkeypatch):
    shots = screenshots(tmp_path)
    reference = _reference(EXAMPLES, monkeypatch, sphere_calibration=CALIBRATION, rows=line_page.PAGE_ROWS, seed=0,
                           fruit="apple", **SPHERE)
    with browser_page(server) as view:
        view.goto(server + "line")
        _wait(view, "window.fruitimpact.updates >= 1")
        assert view.is_hidden("#sphere") and view.is_visible("#points")
        view.check("input[name=source][value=sphere]")
        assert view.is_visible("#sphere") and view.is_hidden("#points") and view.is_hidden("#what-if")
        assert view.is_hidden("#sphere-results")  # nothing to show before a log
        _audit_example_log(view)
        view.wait_for_selector("#sphere-points tbody tr.point")

        # the table: one row per transfer point, the worst one highlighted, each figure the library's (as shown:
        # 3 significant digits)
        assert view.text_content("#sphere-worst-point") == reference["worst_point"] == "bin-filler"
        assert view.eval_on_selector_all("#sphere-points tbody tr.point", "rows => rows.map(r => r.dataset.name)") == \
            [point["name"] for point in reference["points"]]
        assert view.eval_on_selector_all("#sphere-points tbody tr.worst", "rows => rows.map(r => r.dataset.name)") == \
            ["bin-filler"]
        for point in reference["points"]:
            row = f'#sphere-points tr[data-name="{point["name"]}"]'
            assert _number(view.text_content(f"{row} td.drop")) == pytest.approx(point["drop_height"] * 100, rel=5e-3)
            surface = view.text_content(f"{row} td.surface")
            if point["surface_modulus"] is None:
                assert surface.startswith("rigid")
            else:
                assert _number(surface) == pytest.approx(point["surface_modulus"] / 1e6, rel=5e-3)
            assert surface.endswith(f"nearest: {point['surface']}")
            cells = view.eval_on_selector_all(f"{row} td", "cells => cells.map(c => c.textContent)")
            assert _number(cells[7]) == pytest.approx(point["incidence"] * 100, abs=0.06)  # bruised here [%]
            advice = point["cushion"]
            if advice is None:
                assert cells[10].startswith("not needed")
            elif advice["surface"] is None:
                assert cells[10] == advice["message"]  # no cushion brings it below the target: the library's words
            else:  # the cushion, and the bruised fruit it saves per 10,000 (4 significant digits)
                assert cells[10].startswith(f"{advice['surface']} → ")
                assert cells[10].endswith(f"saves {advice['saved_per_10000']:,.0f} per 10,000")
        assert view.text_content("#sphere-command") == COMMAND
        assert view.locator("#sphere-warnings li").count() == len(reference["warnings"])
        assert view.locator("#sphere-skipped li").count() == 0
        assert view.locator("#sphere-chart-incidence rect").count() > 10  # bars drawn
        view.screenshot(path=str(shots / "sphere-1400.png"), full_page=True)
        view.set_viewport_size({"width": 900, "height": 1000})
        view.wait_for_timeout(200)
        # narrow: neither the page nor the table scrolls sideways
        assert view.evaluate("document.documentElement.scrollWidth") <= 900
        assert view.evaluate("(t => t.scrollWidth <= t.parentElement.clientWidth)(document.getElementById('sphere-points'))")
        view.screenshot(path=str(shots / "sphere-900.png"), full_page=True)
        view.set_viewport_size({"width": 1400, "height": 1000})

        # a refused field: the CLI's line next to it, the last good numbers pale; then good again
        count = view.evaluate("window.fruitimpact.sphereUpdates")
        view.fill("input[name=sphere_modulus]", "40MPa")
        view.wait_for_selector("#sphere .field-error")
        (tmp_path / LOG).write_bytes((EXAMPLES / LOG).read_bytes())
        (tmp_path / CALIBRATION).write_bytes((EXAMPLES / CALIBRATION).read_bytes())
        assert view.text_content("#sphere .field-error") == _cli_error(
            tmp_path, LOG, "--sphere", "is-1987", "--sphere-calibration", CALIBRATION, "--sphere-modulus", "40MPa",
            "--fruit", "apple")
        assert "invalid" in view.get_attribute("input[name=sphere_modulus]", "class")
        assert "stale" in view.get_attribute("#sphere-results", "class")
        view.fill("input[name=sphere_modulus]", "")
        _wait(view, f"window.fruitimpact.sphereUpdates > {count}")
        assert view.locator(".field-error").count() == 0

        # a lot input edited: the sphere's points audited again with it
        count = view.evaluate("window.fruitimpact.sphereUpdates")
        view.fill("input[name=rows]", "200")
        _wait(view, f"window.fruitimpact.sphereUpdates > {count} && window.fruitimpact.sphere.report.rows === 200")

        # back to the typed table: its controls and numbers again, and it still audits
        updates = view.evaluate("window.fruitimpact.updates")
        view.check("input[name=source][value=table]")
        _wait(view, f"window.fruitimpact.updates > {updates}")
        assert view.is_visible("#points") and view.is_visible("#results") and view.is_visible("#what-if")
        assert view.is_hidden("#sphere") and view.is_hidden("#sphere-results")
        assert view.evaluate("window.fruitimpact.last.report.rows") == 200
        updates = view.evaluate("window.fruitimpact.updates")
        view.fill('#points tr.point[data-index="2"] [data-column=drop_height]', "2cm")
        _wait(view, f"window.fruitimpact.updates > {updates}")
        assert view.evaluate("window.fruitimpact.last.report.points[2].drop_height") == pytest.approx(0.02)
        view.screenshot(path=str(shots / "table-1400.png"))


def test_a_failed_audit_says_so_in_its_headline_in_a_real_browser(server, tmp_path):
    """A log whose last transfer point holds only a reading no impact reproduces (40 m/s: an 80 m drop) is a failed
    audit (``sphere_audit``'s status): the verdict at the top of the results says "failed" and why before the share
    bruised, which counts only the points computed, and its frame turns red; an audit that is ok shows no such
    line (the example log)."""
    shots = screenshots(tmp_path)
    bad = tmp_path / "cannon-log.csv"
    bad.write_text((EXAMPLES / LOG).read_text() + "400.000,900,40,0.0005,cannon\n")
    with browser_page(server) as view:
        view.goto(server + "line")
        _wait(view, "window.fruitimpact.updates >= 1")
        view.check("input[name=source][value=sphere]")
        _audit_example_log(view)
        assert view.evaluate("window.fruitimpact.sphere.report.status") == "ok"
        assert view.locator("#sphere-verdict-status").count() == 0
        assert "not-ok" not in view.get_attribute("#sphere-verdict", "class")
        count = view.evaluate("window.fruitimpact.sphereUpdates")
        view.set_input_files("#sphere-log", str(bad))
        _wait(view, f"window.fruitimpact.sphereUpdates > {count} && window.fruitimpact.sphere.file === 'cannon-log.csv'",
              120)
        report = view.evaluate("window.fruitimpact.sphere.report")
        assert report["status"] == "failed"
        headline = view.text_content("#sphere-verdict-status")
        assert headline.startswith("the audit is not ok") and f"failed: {report['message']}" in headline
        assert view.is_visible("#sphere-verdict-status")
        assert "not-ok" in view.get_attribute("#sphere-verdict", "class")
        assert "of the points computed" in view.text_content("#sphere-verdict")
        view.locator("#sphere-verdict").screenshot(path=str(shots / "sphere-failed-verdict.png"))
