"""What the signal-path benchmarks share: the installed console script they run, and the machine they name."""

from __future__ import annotations

import os
import platform
import shutil
import sys
from pathlib import Path

import numpy as np


def console_script() -> str:
    """The installed ``fruitimpact`` console script (beside this Python, else on PATH)."""
    here = Path(sys.executable).with_name("fruitimpact")
    found = str(here) if here.exists() else shutil.which("fruitimpact")
    if not found:
        raise SystemExit("fruitimpact console script not found: activate the venv (pip install -e .)")
    return found


def machine() -> str:
    """CPU model, cores, RAM, OS, Python and NumPy versions, as one line."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        mem = int(next(l for l in Path("/proc/meminfo").read_text().splitlines()
                       if l.startswith("MemTotal")).split()[1]) / 1024 ** 2
        mem_text = f"{mem:.0f} GiB RAM"
    except (OSError, StopIteration, ValueError):
        mem_text = "RAM unknown"
    return (f"{cpu}, {os.cpu_count()} cores, {mem_text}; {platform.system()} {platform.release()}; "
            f"Python {platform.python_version()}, NumPy {np.__version__}")
