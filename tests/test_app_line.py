"""The web app's line-audit page (issue 16 item 2): ``POST /api/line`` and the page in a real browser.

The reference of every number is the library call ``fruitimpact line`` runs, ``fi.audit_line``, with the same
line and the same lot (same rows, same seed): the lot is drawn from the seed, so the figures are the same to the
bit and are compared exactly, except where a figure is summed in another order (said where it is).  The
reference of every refusal is the line the console script prints for the same line file or option.  The server is
the console script (``test_app.server``); the page runs in Debian's Chromium through Playwright, as in
tests/test_app.py, and fails on any request to another host and on any console error.
"""

from __future__ import annotations

import copy
import json
import shlex
import subprocess

import pytest

import fruitimpact as fi
from fruitimpact.handling.line import TransferPoint, read_line
from fruitimpact.impact.outputs import dump_json
from test_app import _post, _wait, browser_page, screenshots, server  # noqa: F401 - server is a fixture

pytest.importorskip("tornado")
from fruitimpact.app import line as page  # noqa: E402 - the app needs tornado's extra

EXAMPLE = "examples/line.csv"
#: A line with one harsh point (docs/tasks/line.md): there a change of surface saves fruit, not only volume.
GENTLE = [{"name": "conveyor", "drop_height": "2cm", "surface": "pvc-belt", "fruit_on_fruit": False},
          {"name": "singulator", "drop_height": "3cm", "surface": "steel", "fruit_on_fruit": False},
          {"name": "bin", "drop_height": "10cm", "surface": "wood", "fruit_on_fruit": False}]


def _strict(report: dict) -> dict:
    """A library report as the API sends it: strict JSON (NaN and infinity null), read back."""
    return json.loads(dump_json(report, indent=None))


def _points(rows: list[dict]) -> list[TransferPoint]:
    from fruitimpact.handling.line import measured_surface
    from fruitimpact.impact.units import parse_quantity

    return [TransferPoint(r["name"], parse_quantity(r["drop_height"], "length"), r["surface"], r["fruit_on_fruit"],
                          *measured_surface(r, r["name"])) for r in rows]


def read_line_text(text: str) -> list[TransferPoint]:
    """``read_line`` of a line CSV's text."""
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as directory:
        path = Path(directory) / "line.csv"
        path.write_text(text, encoding="utf-8")
        return read_line(path)


def _cli(*argv, cwd=None) -> subprocess.CompletedProcess:
    from conftest import console_script

    return subprocess.run([console_script(), *argv], capture_output=True, text=True, timeout=300, cwd=cwd)


def _cli_line_error(tmp_path, csv_text: str, *argv) -> str:
    """The one line ``fruitimpact line line.csv ARGV`` prints for a refused line file or option, without its
    prefix (the line file written as ``line.csv`` in ``tmp_path``, as the page names it)."""
    (tmp_path / "line.csv").write_text(csv_text)
    done = _cli("line", "line.csv", *argv, cwd=tmp_path)
    assert done.returncode == 2, (done.stdout, done.stderr)
    return done.stderr.strip().removeprefix("fruitimpact line: error: ")


def _csv(rows: list[dict]) -> str:
    """A line CSV with the rows' cells as they are, any of them bad (the page's line.csv is only written for a
    line it accepts)."""
    measured = any(column in r for r in rows for column in ("surface_modulus", "surface_poisson"))
    lines = ["name,drop_height,surface,fruit_on_fruit" + (",surface_modulus,surface_poisson" if measured else "")]
    lines += [f"{r['name']},{r['drop_height']},{r['surface']},{str(r['fruit_on_fruit']).lower()}"
              + (f",{r.get('surface_modulus', '')},{r.get('surface_poisson', '')}" if measured else "") for r in rows]
    return "\n".join(lines) + "\n"


def test_the_page_opens_on_the_example_line():
    assert _points(list(page.DEFAULT_POINTS)) == read_line(EXAMPLE)


def test_the_line_api_agrees_with_the_library(server):
    """The answer's report is audit_line's for the same line and lot, to the bit (same seed: the same fruit)."""
    status, body = _post(server + "api/line", {})
    assert status == 200 and "refused" not in body
    reference = fi.audit_line(EXAMPLE, rows=page.PAGE_ROWS, seed=0, fruit="apple")
    assert body["report"] == _strict(reference)
    assert body["worst_point"] == reference["worst_point"]
    assert body["command"] == f"fruitimpact line line.csv --fruit apple -n {page.PAGE_ROWS} --seed 0"

    request = {"points": GENTLE + [{"name": "pack, \"A\"", "drop_height": 0.05, "surface": "cardboard",
                                    "fruit_on_fruit": "yes"}],
               "fruit": "apple", "criterion": "pressure", "rows": "300", "seed": "7", "spreads": False,
               "mass": "normal(180g, 20g)", "modulus": "3MPa", "alternatives": ["foam-pad", "rubber-belt"]}
    status, body = _post(server + "api/line", request)
    line = _points(GENTLE) + [TransferPoint('pack, "A"', 0.05, "cardboard", True)]
    reference = fi.audit_line(line, rows=300, seed=7, criterion="pressure", spreads=False, fruit="apple",
                              mass="normal(180g, 20g)", modulus="3MPa", alternatives=["foam-pad", "rubber-belt"])
    assert body["report"] == _strict(reference)
    assert body["command"] == ("fruitimpact line line.csv --fruit apple --criterion pressure "
                               "--mass 'normal(180g, 20g)' --modulus 3MPa -n 300 --seed 7 --no-spreads "
                               "--alternatives foam-pad,rubber-belt")
    # the page's line.csv reads back as the very points audited (the quoted name too)
    assert read_line_text(body["line_csv"]) == line


def test_the_command_and_line_csv_reproduce_the_audit(server, tmp_path):
    """The command shown, run on the line.csv offered, prints the page's report (the console script's --json)."""
    request = {"points": [dict(row) for row in page.DEFAULT_POINTS], "rows": "200", "seed": "3",
               "failure_stress": "0.3MPa", "alternatives": ["foam-pad", "cardboard"]}
    body = _post(server + "api/line", request)[1]
    (tmp_path / body["file"]).write_text(body["line_csv"])
    argv = shlex.split(body["command"])
    assert argv[:3] == ["fruitimpact", "line", "line.csv"]
    done = _cli(*argv[1:], "--json", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout) == body["report"]


@pytest.mark.parametrize("column, bad", [("drop_height", "3 parsecs"), ("drop_height", "-3cm"), ("drop_height", "30m"),
                                         ("surface", "lava"), ("name", ""), ("fruit_on_fruit", "maybe"),
                                         ("surface_modulus", "soft"), ("surface_modulus", "-2MPa"),
                                         ("surface_poisson", "0.7")])
def test_a_refused_cell_gets_the_clis_line_and_names_the_cell(server, tmp_path, column, bad):
    rows = [dict(row) for row in page.DEFAULT_POINTS]
    if column.startswith("surface_"):  # a measured surface: both cells, one of them bad
        rows[1].update(surface_modulus="20MPa", surface_poisson="0.3")
    rows[1][column] = bad
    status, body = _post(server + "api/line", {"points": rows})
    assert status == 200 and body["refused"] is True
    assert body["argument"] == ["points", 1, column]
    assert body["error"] == _cli_line_error(tmp_path, _csv(rows), "--fruit", "apple")


def test_a_measured_surface_reads_as_the_line_csv_reads_it(server, tmp_path):
    """A row with surface_modulus and surface_poisson (an instrumented sphere's reading) is the point the line CSV
    gives: the page's line.csv carries both columns, the command reproduces the audit, and the point's report
    names the measured half-space.  A modulus without its Poisson's ratio is refused at the missing cell."""
    rows = [dict(row) for row in page.DEFAULT_POINTS]
    rows[1].update(surface_modulus="20MPa", surface_poisson="0.3")
    body = _post(server + "api/line", {"points": rows, "rows": "200", "seed": "3", "failure_stress": "0.3MPa"})[1]
    assert "surface_modulus,surface_poisson" in body["line_csv"].splitlines()[0]
    point = body["report"]["points"][1]
    assert point["surface_modulus"] == 20e6 and point["surface_poisson"] == 0.3
    (tmp_path / body["file"]).write_text(body["line_csv"])
    done = _cli(*shlex.split(body["command"])[1:], "--json", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout) == body["report"]
    # the report's points sent back: null is a blank cell (the library surface's own values)
    back = [{key: point[key] for key in ("name", "drop_height", "surface", "fruit_on_fruit", "surface_modulus",
                                         "surface_poisson")} for point in body["report"]["points"]]
    again = _post(server + "api/line", {"points": back, "rows": "200", "seed": "3", "failure_stress": "0.3MPa"})[1]
    assert again["report"]["points"] == body["report"]["points"]
    del rows[1]["surface_poisson"]
    refused = _post(server + "api/line", {"points": rows})[1]
    assert refused["argument"] == ["points", 1, "surface_poisson"]
    assert refused["error"] == _cli_line_error(tmp_path, _csv(rows), "--fruit", "apple")


def test_a_name_given_twice_is_refused_at_its_second_row(server, tmp_path):
    rows = [dict(row) for row in page.DEFAULT_POINTS]
    rows[3]["name"] = rows[0]["name"]
    body = _post(server + "api/line", {"points": rows})[1]
    assert body["argument"] == ["points", 3, "name"]
    assert body["error"] == _cli_line_error(tmp_path, _csv(rows), "--fruit", "apple")


def test_unknown_names_and_bad_lot_inputs_are_refused_as_the_cli_refuses_them(server, tmp_path):
    body = _post(server + "api/line", {"bogus": 1})[1]
    assert body["refused"] is True and body["argument"] == "bogus" and "'bogus'" in body["error"]
    body = _post(server + "api/line", {"points": [{**page.DEFAULT_POINTS[0], "colour": "red"}]})[1]
    assert body["argument"] == ["points", 0, "colour"] and "unknown column(s) 'colour'" in body["error"]
    for name, value, option in (("mass", "-1", "--mass"), ("modulus", "normal(3MPa, -1MPa)", "--modulus"),
                                ("criterion", "none", "--criterion"), ("seed", "-1", "--seed"),
                                ("rows", "0", "-n"), ("alternatives", "lava", "--alternatives")):
        body = _post(server + "api/line", {name: value})[1]
        assert body["refused"] is True and body["argument"] == name, body
        # the CLI's line for the same option on the same line (the example file, as the page opens on it)
        assert body["error"] == _cli_line_error(tmp_path, _csv(list(page.DEFAULT_POINTS)), "--fruit", "apple",
                                                option, value)
    # the page takes at most MAX_PAGE_ROWS fruit, and says the command line takes more
    body = _post(server + "api/line", {"rows": page.MAX_PAGE_ROWS + 1})[1]
    assert body["argument"] == "rows" and "10,000,000" in body["error"]


def test_the_what_if_is_the_paired_difference_of_two_library_calls(server, tmp_path):
    """The what-if's line figures before and after = audit_line of the line as it is and of the line with that one
    surface changed, same lot (same seed and rows: the same fruit); its saving = their difference."""
    request = {"points": GENTLE, "rows": "400", "seed": "1", "alternatives": ["rubber-belt"],
               "what_if": {"point": "bin", "surface": "foam-pad"}}
    body = _post(server + "api/line", request)[1]
    before = fi.audit_line(_points(GENTLE), rows=400, seed=1, fruit="apple", alternatives=())
    changed = copy.deepcopy(GENTLE)
    changed[2]["surface"] = "foam-pad"
    after = fi.audit_line(_points(changed), rows=400, seed=1, fruit="apple", alternatives=())
    what_if = body["what_if"]
    assert (what_if["point"], what_if["from"], what_if["to"], what_if["fruit"]) == ("bin", "wood", "foam-pad", 400)
    # incidences are counts over the same 400 fruit: exact
    assert what_if["before"]["incidence"] == before["incidence"]
    assert what_if["after"]["incidence"] == after["incidence"]
    assert what_if["incidence_saved"] == pytest.approx(before["incidence"] - after["incidence"], abs=1e-15)
    assert what_if["incidence_saved"] > 0.1  # foam under the one harsh point saves fruit (docs/tasks/line.md)
    # volumes: the same per-fruit volumes summed in another order (the change's sum skips the point): 1e-12
    assert what_if["before"]["mean_bruise_volume"] == before["mean_bruise_volume"]
    assert what_if["after"]["mean_bruise_volume"] == pytest.approx(after["mean_bruise_volume"], rel=1e-12)
    assert what_if["bruise_volume_saved"] == pytest.approx(
        before["mean_bruise_volume"] - after["mean_bruise_volume"], rel=1e-9)
    # the ranked changes stay those of the alternatives asked for, as a direct call gives them
    direct = fi.audit_line(_points(GENTLE), rows=400, seed=1, fruit="apple", alternatives=["rubber-belt"])
    assert body["report"]["changes"] == _strict(direct)["changes"]

    # the what-if's command, run on the page's line.csv, lists that very change
    (tmp_path / body["file"]).write_text(body["line_csv"])
    done = _cli(*shlex.split(what_if["command"])[1:], "--json", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    listed = next(c for c in json.loads(done.stdout)["changes"] if (c["point"], c["to"]) == ("bin", "foam-pad"))
    assert listed["incidence"] == what_if["after"]["incidence"]
    assert listed["incidence_saved"] == what_if["incidence_saved"]


def test_a_what_if_the_line_cannot_take_is_refused_at_its_control(server):
    for what_if, control in (({"point": "accumulation table", "surface": "steel"}, "point"),  # lands on fruit
                             ({"point": "nowhere", "surface": "steel"}, "point"),
                             ({"point": "bin tipper", "surface": "rubber-belt"}, "surface"),  # its own surface
                             ({"point": "bin tipper", "surface": "rigid"}, "surface")):  # not a library surface
        body = _post(server + "api/line", {"what_if": what_if})[1]
        assert body["refused"] is True and body["argument"] == ["what_if", control], body


def test_the_server_survives_every_bad_line_request(server):
    url = server + "api/line"
    assert _post(url, None, raw=b"{not json")[0] == 400
    for bad in ([1, 2], {"points": "bin,30cm,steel"}, {"points": [1]}, {"points": []},
                {"points": [dict(page.DEFAULT_POINTS[0], name=f"p{i}") for i in range(201)]},
                {"points": [{"name": ["x"], "drop_height": {"m": 1}, "surface": None}]},
                {"rows": 1e400}, {"rows": "1e9999999"}, {"seed": [1]}, {"spreads": "yes"}, {"fruit": {}},
                {"what_if": "bin tipper"}, {"what_if": {"point": ["x"], "surface": {}}}, {"alternatives": {"a": 1}}):
        status, body = _post(url, bad)
        assert status == 200 and body["refused"] is True, (bad, body)
    assert _post(url, None, raw=b'{"points": [{"name": "a", "drop_height": NaN, "surface": "steel"}]}')[1][
        "argument"] == ["points", 0, "drop_height"]
    status, body = _post(url, {"rows": "50"})
    assert status == 200 and body["report"]["rows"] == 50


def _number(text: str) -> float:
    return float(text.split()[0].replace(",", ""))


def _shown(page_, row: int, column: str) -> float:
    return _number(page_.text_content(f'#points tr.point[data-index="{row}"] td[data-out="{column}"]'))


def test_the_line_audit_in_a_real_browser(server, tmp_path):
    with browser_page(server) as view:
        view.goto(server + "line")
        _wait(view, "window.fruitimpact.updates >= 1")
        # opens on the example line: its numbers are audit_line's (shown to 3 significant digits for a share, 4 for
        # a volume: the tolerances are the display's rounding)
        reference = fi.audit_line(EXAMPLE, rows=page.PAGE_ROWS, seed=0, fruit="apple")
        assert view.eval_on_selector_all("#points tr.point [data-column=name]", "inputs => inputs.map(i => i.value)") \
            == [point.name for point in read_line(EXAMPLE)]
        for i, point in enumerate(reference["points"]):
            assert _shown(view, i, "incidence") == pytest.approx(point["incidence"] * 100, rel=5e-3)
            assert _shown(view, i, "cumulative_bruise_volume") == pytest.approx(
                point["cumulative_bruise_volume"] * 1e9, rel=5e-4)
        assert view.text_content("#worst-point") == reference["worst_point"]
        assert view.text_content("#command") == f"fruitimpact line line.csv --fruit apple -n {page.PAGE_ROWS} --seed 0"
        assert view.locator("#chart-incidence rect").count() > 10  # bars drawn

        # a cell edited: the numbers change to audit_line's for the edited line
        updates = view.evaluate("window.fruitimpact.updates")
        view.fill('#points tr.point[data-index="2"] [data-column=drop_height]', "2cm")
        _wait(view, f"window.fruitimpact.updates > {updates}")
        edited = [dict(row) for row in page.DEFAULT_POINTS]
        edited[2]["drop_height"] = "2cm"
        reference = fi.audit_line(_points(edited), rows=page.PAGE_ROWS, seed=0, fruit="apple")
        assert _shown(view, 2, "incidence") == pytest.approx(reference["points"][2]["incidence"] * 100, rel=5e-3)
        assert _shown(view, 2, "mean_bruise_volume") == pytest.approx(
            reference["points"][2]["mean_bruise_volume"] * 1e9, rel=5e-4)
        assert _number(view.text_content("#verdict-volume")) == pytest.approx(
            reference["mean_bruise_volume"] * 1e9, rel=5e-4)

        # a refused cell: the CLI's line next to it, the last good numbers marked stale
        view.fill('#points tr.point[data-index="1"] [data-column=drop_height]', "5 parsecs")
        view.wait_for_selector("#points tr.error-row .field-error")
        bad = [dict(row) for row in edited]
        bad[1]["drop_height"] = "5 parsecs"
        assert view.text_content("#points tr.error-row .field-error") == _cli_line_error(tmp_path, _csv(bad),
                                                                                          "--fruit", "apple")
        assert view.evaluate("document.querySelector('#points tr.point[data-index=\"1\"]').nextElementSibling"
                             ".classList.contains('error-row')")  # right under its row
        assert "invalid" in view.get_attribute('#points tr.point[data-index="1"] [data-column=drop_height]', "class")
        assert "stale" in view.get_attribute(".results", "class")
        updates = view.evaluate("window.fruitimpact.updates")
        view.fill('#points tr.point[data-index="1"] [data-column=drop_height]', "5cm")
        _wait(view, f"window.fruitimpact.updates > {updates}")
        assert view.locator(".field-error").count() == 0

        # rows added, moved and removed: the audit follows the table
        updates = view.evaluate("window.fruitimpact.updates")
        view.click("#add-point")
        _wait(view, f"window.fruitimpact.updates > {updates}")
        assert len(view.evaluate("window.fruitimpact.last.report.points")) == 6
        updates = view.evaluate("window.fruitimpact.updates")
        view.click('#points tr.point[data-index="0"] [data-action=down]')
        _wait(view, f"window.fruitimpact.updates > {updates}")
        assert [p_["name"] for p_ in view.evaluate("window.fruitimpact.last.report.points")][:2] == \
            ["roller conveyor", "bin tipper"]
        updates = view.evaluate("window.fruitimpact.updates")
        view.click('#points tr.point[data-index="5"] [data-action=remove]')
        _wait(view, f"window.fruitimpact.updates > {updates}")
        line = [dict(row) for row in edited]
        line[0], line[1] = line[1], line[0]
        assert view.evaluate("window.fruitimpact.last.report.points.length") == 5

        # a measured half-space typed beside a point (a sphere's reading of the bin tipper): audit_line of that line
        assert "unused" in view.get_attribute('#points tr.point[data-index="3"] [data-column=surface_modulus]',
                                              "class")  # the accumulation table: fruit on fruit, no surface met
        view.fill('#points tr.point[data-index="1"] [data-column=surface_modulus]', "50MPa")
        view.fill('#points tr.point[data-index="1"] [data-column=surface_poisson]', "0.45")
        _wait(view, "window.fruitimpact.last.report.points[1].surface_modulus === 50e6")
        line[1].update(surface_modulus="50MPa", surface_poisson="0.45")
        reference = fi.audit_line(_points(line), rows=page.PAGE_ROWS, seed=0, fruit="apple")
        library = fi.audit_line(_points([{**row, "surface_modulus": "", "surface_poisson": ""} for row in line]),
                                rows=page.PAGE_ROWS, seed=0, fruit="apple")
        volume = reference["points"][1]["mean_bruise_volume"]
        assert volume != pytest.approx(library["points"][1]["mean_bruise_volume"], rel=1e-2)  # it matters: can fail
        assert _shown(view, 1, "mean_bruise_volume") == pytest.approx(volume * 1e9, rel=5e-4)
        assert _shown(view, 1, "incidence") == pytest.approx(reference["points"][1]["incidence"] * 100, rel=5e-3)
        assert view.locator(".field-error").count() == 0

        # a what-if: the saving is the paired difference of the two library audits
        updates = view.evaluate("window.fruitimpact.updates")
        view.select_option("#what-if-point", "packing into the carton")
        view.select_option("#what-if-surface", "foam-pad")
        _wait(view, f"window.fruitimpact.updates > {updates} && window.fruitimpact.last.what_if !== null")
        before = fi.audit_line(_points(line), rows=page.PAGE_ROWS, seed=0, fruit="apple", alternatives=())
        changed = [dict(row) for row in line]
        changed[4]["surface"] = "foam-pad"
        after = fi.audit_line(_points(changed), rows=page.PAGE_ROWS, seed=0, fruit="apple", alternatives=())
        saved = (before["mean_bruise_volume"] - after["mean_bruise_volume"]) * 1e9
        text = view.text_content("#what-if-saved-volume")
        assert text.startswith("saves") and _number(text.removeprefix("saves ")) == pytest.approx(saved, rel=5e-4)

        # exports: the per-point CSV, and the line.csv the command reads, which is the line shown
        with view.expect_download() as download:
            view.click("[data-export=csv]")
        lines = open(download.value.path(), encoding="utf-8").read().splitlines()
        assert lines[0].startswith("name,drop_height_m,surface,fruit_on_fruit,surface_modulus_Pa,surface_poisson") \
            and len(lines) == 6
        with view.expect_download() as download:
            view.click("[data-export=line]")
        assert download.value.suggested_filename == "line.csv"
        assert read_line(download.value.path()) == _points(line)

        # on a narrow screen the page fits its width: its wide tables scroll inside their panels (before, a hidden
        # label of the points table and the changes table made the whole page 981 px wide at 700)
        view.set_viewport_size({"width": 700, "height": 1000})
        view.wait_for_timeout(200)
        assert view.evaluate("document.documentElement.scrollWidth") <= 700
        # and the changes table fits its panel: its words and headings wrap, so each change's numbers and its
        # "what if" button are in view without scrolling the table sideways
        assert view.evaluate("(() => { const t = document.getElementById('changes'); "
                             "return t.scrollWidth <= t.parentElement.clientWidth; })()")
        view.screenshot(path=str(screenshots(tmp_path) / "line-700.png"), full_page=True)



@pytest.mark.parametrize("bruised,count", [(0, 500), (1, 500), (250, 500), (499, 500), (500, 500), (3, 7)])
def test_the_incidence_interval_is_wilsons(bruised, count):
    # reference: SciPy's binomial test, Wilson score interval at 95 % (an implementation not ours)
    from scipy.stats import binomtest

    from fruitimpact.app.line import wilson_interval

    expected = binomtest(bruised, count).proportion_ci(confidence_level=0.95, method="wilson")
    low, high = wilson_interval(bruised / count, count)
    assert low == pytest.approx(expected.low, abs=1e-12) and high == pytest.approx(expected.high, abs=1e-12)
