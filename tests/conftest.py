"""Fixtures shared by the test modules: the CLI run in-process and as the installed
console script, with the checks every refused command must pass (exit status 2,
one line on stderr, no traceback)."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from fruitimpact.cli import main

#: Standard gravity [m/s²] (CGPM 1901), written here, not imported, for independent checks.
G = 9.80665
#: The paper's Jonathan apple: the defaults of every command.
DEFAULT_INPUTS = dict(mass=0.115, diameter=0.065, modulus=3e6, poisson=0.37, velocity=1.0)


class CLI:
    """``fruitimpact ARGV`` in this process: ``run`` → (status, stdout, stderr)."""

    def __init__(self, capsys):
        self.capsys = capsys

    def run(self, *argv):
        status = main([str(a) for a in argv])
        out, err = self.capsys.readouterr()
        return status, out, err

    def ok(self, *argv) -> str:
        """stdout of a command that must succeed (exit 0)."""
        status, out, err = self.run(*argv)
        assert status == 0, (status, err)
        return out

    def json(self, *argv) -> dict:
        """The JSON object printed by ``ARGV --json`` (exit 0; on stderr at most warning lines,
        which must also be in the object's ``warnings``)."""
        status, out, err = self.run(*argv, "--json")
        assert status == 0, (status, err)
        report = json.loads(out)
        for line in err.splitlines():
            assert ": warning: " in line, err
            assert line.split(": warning: ", 1)[1] in report.get("warnings", []), line
        return report

    def error(self, *argv) -> str:
        """The single stderr line of a refused command (exit 2, one line, no traceback, nothing on stdout)."""
        status, out, err = self.run(*argv)
        assert status == 2, (status, out, err)
        assert out == "", out
        assert "Traceback" not in err, err
        lines = err.splitlines()
        assert len(lines) == 1, err
        assert err.endswith("\n")
        return lines[0]


@pytest.fixture
def cli(capsys) -> CLI:
    return CLI(capsys)


def sigint_default() -> None:
    """``preexec_fn`` of a subprocess that a test sends SIGINT: its SIGINT at the default action, so that Python
    installs its own handler in it.  A suite started in the background by a shell without job control (``cmd &``,
    ``nohup ... &``) runs with SIGINT ignored, and an ignored signal stays ignored across exec: such a child would
    never see the Ctrl-C the test sends (the command ran to its end, or a test accepting exit 0 proved nothing)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_DFL)


def console_script() -> str:
    """The installed ``fruitimpact`` entry point (beside this interpreter, else on PATH)."""
    beside = Path(sys.executable).with_name("fruitimpact")
    found = str(beside) if beside.exists() else shutil.which("fruitimpact")
    assert found, "console script 'fruitimpact' is not installed (pip install -e .)"
    return found


@pytest.fixture
def script():
    """Run the installed console script: ``script(*argv, cwd=None, timeout=120)`` → CompletedProcess."""

    def run(*argv, cwd=None, timeout=120, **kwargs):
        return subprocess.run([console_script(), *map(str, argv)], capture_output=True, text=True, cwd=cwd,
                              timeout=timeout, **kwargs)

    return run
