"""MkDocs hook: run every ``python`` code block of the getting-started and task pages while the site builds.

The blocks of a page run in order in one namespace, from the repository root (so ``examples/line.csv`` is
found); what a block prints is shown under it.  A block that raises fails the build, so the docs never show
an example that does not work (issue 15 item 3).  Other pages' code blocks are shown, not run.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
from pathlib import Path

from mkdocs.exceptions import PluginError

ROOT = Path(__file__).resolve().parents[2]
RUN = re.compile(r"^```python\n(.*?)^```\n", re.S | re.M)


def _executed(page) -> bool:
    return page.file.src_uri == "index.md" or page.file.src_uri.startswith("tasks/")


def on_page_markdown(markdown, page, config, files):
    if not _executed(page):
        return markdown
    namespace = {"__name__": "__docs__"}
    here = os.getcwd()

    def run(match):
        code = match.group(1)
        out = io.StringIO()
        os.chdir(ROOT)
        try:
            with contextlib.redirect_stdout(out):
                exec(compile(code, f"{page.file.src_uri} example", "exec"), namespace)
        except Exception as exc:  # the build fails and names the page and the error
            raise PluginError(f"{page.file.src_uri}: an example failed: {type(exc).__name__}: {exc}") from exc
        finally:
            os.chdir(here)
        shown = out.getvalue().rstrip()
        return match.group(0) + (f"\n```text\n{shown}\n```\n" if shown else "")

    return RUN.sub(run, markdown)
