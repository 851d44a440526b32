"""The shape of the code (issue 6, items 21–25): one table of quantities drives options,
columns, validation and results; outputs are named; the numeric core imports no I/O,
tables, plots or CLI (an import-linter contract); ``fruitimpact --help`` starts no numba.
"""

from __future__ import annotations

import dataclasses
import re
import subprocess
import sys
from pathlib import Path

import pytest

from fruitimpact import Characteristics, simulate
from fruitimpact.impact.evaluation import OUTPUT_COLUMNS, evaluate
from fruitimpact.cli import build_parser
from fruitimpact.engine.powerlaw import CHARACTERISTIC_COLUMNS
from fruitimpact.impact.quantities import CHARACTERISTIC_NAMES, INPUTS, OUTPUTS
from fruitimpact.impact.validation import InputError

ROOT = Path(__file__).resolve().parents[1]
SOURCE = ROOT / "src" / "fruitimpact"


def _options(command: str) -> set[str]:
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command").choices[command]
    return {option for action in sub._actions for option in action.option_strings}


@pytest.mark.parametrize("command", ["simulate", "sweep", "population"])
def test_every_input_of_the_table_is_an_option(command):
    options = _options(command)
    missing = [q.option for q in INPUTS.values() if q.option not in options]
    assert not missing, missing


def test_every_input_of_the_table_is_a_batch_column():
    for name, quantity in INPUTS.items():
        value = quantity.default if quantity.default is not None else {
            "stiffness": 8e5, "velocity": 1.0, "drop_height": 0.1, "restitution": 0.5, "alpha": 0.1,
            "damping": 1e5, "bioyield_force": 20.0, "failure_stress": 3e5, "bruise_susceptibility": 4e-6,
            "bruise_energy": 0.05, "surface_crush_stress": 2e5, "bruise_width_ratio": 1.4}[name]
        # bruise inputs mean something only with a criterion; a layer only with a finite thickness
        extra = {"criterion": ["energy"]} if name in ("failure_stress", "bruise_susceptibility", "bruise_energy",
                                                      "bruise_width_ratio") \
            else {"surface_thickness": [0.01], "surface_modulus": [1e6]} if name == "surface_model" \
            else {"surface": ["cardboard"]} if name == "surface_crush_stress" else {}
        if name == "surface_model":
            value = "layer"
        result = evaluate({name: [value], **extra} if name != "bruise_energy" else {name: [value], **extra})
        if name in ("failure_stress", "bruise_susceptibility", "bruise_width_ratio"):
            result = evaluate({"failure_stress": [3e5], name: [value], "criterion": ["pressure"]})
        assert result.loc[0, "status"] == "ok", (name, result.loc[0, "message"])


def test_outputs_are_named_by_the_table():
    assert CHARACTERISTIC_NAMES == CHARACTERISTIC_COLUMNS
    assert set(OUTPUTS) <= set(OUTPUT_COLUMNS)
    fields = {f.name for f in dataclasses.fields(Characteristics)}
    assert set(CHARACTERISTIC_NAMES) <= fields
    report = simulate().to_dict()
    assert set(CHARACTERISTIC_NAMES) <= set(report)


@pytest.mark.parametrize("name", [q.name for q in INPUTS.values() if q.numeric])
def test_refused_inputs_name_their_argument(name):
    with pytest.raises(InputError) as info:
        if name in ("mass", "diameter", "modulus", "poisson", "stiffness"):
            from fruitimpact import Fruit

            Fruit(**{name: "not a number"})
        elif name.startswith("surface_"):
            from fruitimpact import Surface

            Surface(**{name[len("surface_"):]: "not a number"})
        else:
            simulate(**{name: "not a number"})
    assert info.value.argument == name
    assert str(info.value).startswith(name + " ")


def test_no_family_dispatch_by_if_chains_outside_the_engine():
    """Force families are records (models.families); only the compiled engine branches on codes."""
    offenders = []
    for path in SOURCE.rglob("*.py"):
        if "engine" in path.parts:
            continue
        for number, line in enumerate(path.read_text().splitlines(), 1):
            if re.search(r"\bfamily\s*==|==\s*forces\.", line):
                offenders.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()}")
    assert not offenders, offenders


def test_the_package_root_holds_topic_packages_only():
    """Issue 15 item 1: no loose module at the root; every topic is a package with a docstring that says
    what it holds (the reader's map)."""
    loose = sorted(p.name for p in SOURCE.glob("*.py") if p.name not in ("__init__.py", "__main__.py"))
    assert not loose, loose
    packages = sorted(p for p in SOURCE.iterdir() if p.is_dir() and p.name != "__pycache__")
    assert {p.name for p in packages} >= {"cli", "damage", "engine", "handling", "impact", "library", "physics",
                                          "plotting", "reference", "runs", "signals"}
    for package in packages:
        init = package / "__init__.py"
        assert init.is_file(), package
        import ast
        assert ast.get_docstring(ast.parse(init.read_text())), f"{package.name}/__init__.py has no docstring"


def test_import_contracts_hold():
    """The import-linter contracts of pyproject.toml: the layers (cli > reference | runs > plotting >
    handling | signals > impact > damage | library > physics > engine: no package imports one above or
    beside it, so no two import each other), the numeric core imports no pandas, pyarrow, SciPy or
    matplotlib, and matplotlib stays out of every computing package."""
    lint = Path(sys.executable).with_name("lint-imports")
    command = [str(lint)] if lint.exists() else [sys.executable, "-m", "importlinter.cli"]
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "0 broken" in done.stdout


@pytest.mark.parametrize("argv", [["--help"], ["simulate", "--help"], ["simulate", "--mass", "-1"],
                                  ["drop", "--model", "nonsense"], ["safe-height", "--diameter", "65 parsecs"],
                                  ["analyze", "examples/line.csv", "--hum", "-5"],
                                  ["stream", "--rate", "20000", "--poisson", "0.5"]])
def test_the_console_path_answers_help_and_usage_errors_without_numba(argv):
    """Issue 15 item 4: the console script (``main()`` with no argv: the path that starts numba's target for
    the CLI) answers --help and a usage error before numba or pandas are imported, so in a fraction of
    a second (the time itself is measured in benchmarks/startup.py, not here)."""
    code = ("import sys\nfrom fruitimpact.cli import main\nsys.argv = ['fruitimpact'] + sys.argv[1:]\n"
            "try:\n    status = main()\nexcept SystemExit as exc:\n    status = exc.code\n"
            "print('STATUS', status, file=sys.stderr)\n"
            "for name in ('numba', 'pandas', 'pyarrow', 'matplotlib'):\n"
            # numba.core: numba itself (``simulate`` installs an interpreted stand-in named numba: cli.interpreted)
            "    print(name, (name + '.core' if name == 'numba' else name) in sys.modules, file=sys.stderr)\n")
    done = subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True, timeout=120, cwd=ROOT)
    lines = done.stderr.splitlines()
    loaded = dict(line.split() for line in lines if line.split()[-1:] in (["True"], ["False"]))
    assert loaded == {"numba": "False", "pandas": "False", "pyarrow": "False", "matplotlib": "False"}, done.stderr
    status = next(line.split()[1] for line in lines if line.startswith("STATUS"))
    if argv[-1] == "--help":
        assert status in ("0", "None") and "usage:" in done.stdout
    else:
        assert status == "2"
        message = [line for line in lines if line.startswith("fruitimpact")]
        assert len(message) == 1 and f"argument {argv[-2]}" in message[0], done.stderr


def test_help_starts_no_numba_and_no_pandas():
    code = ("import sys\nfrom fruitimpact.cli import main\ntry:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
            "for name in ('numba', 'pandas', 'matplotlib', 'pyarrow'):\n"
            "    print(name, name in sys.modules)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    loaded = dict(line.split() for line in done.stdout.splitlines()
                  if len(line.split()) == 2 and line.split()[1] in ("True", "False"))
    assert loaded == {"numba": "False", "pandas": "False", "matplotlib": "False", "pyarrow": "False"}, done.stdout


def test_every_model_in_the_index_exists():
    """docs/architecture.md's index from a published model to its implementation: every dotted name in it
    imports (a renamed function breaks the reader's one step, so it breaks this test)."""
    import importlib

    text = (ROOT / "docs" / "architecture.md").read_text()
    index = text[text.index("## Find a published model"):]
    names = re.findall(r"`(fruitimpact(?:\.\w+)+)`", index)
    assert len(names) >= 25, names
    for name in names:
        module, attribute = name.rsplit(".", 1)
        assert hasattr(importlib.import_module(module), attribute), name


def test_the_tree_in_the_docs_is_the_tree_on_disk():
    """docs/architecture.md draws the package tree; it lists every package and no package that is gone."""
    text = (ROOT / "docs" / "architecture.md").read_text()
    drawn = set(re.findall(r"[├└]── (\w+)/", text))
    on_disk = {p.name for p in SOURCE.iterdir() if p.is_dir() and (p / "__init__.py").is_file()}
    assert drawn == on_disk, (drawn ^ on_disk)
