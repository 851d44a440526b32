"""The web app's latency (issue 16 item 1): a control changed → the page redrawn, in a real browser.

Starts ``fruitimpact serve`` (the console script), drives Debian's Chromium headless through Playwright and reads
the page's own measure, ``window.fruitimpact.latency``: from the control's change event to the last chart drawn,
including the page's pause after a keystroke (120 ms) and after a select or the slider (10–30 ms).  Beside it,
the same computation called in process (``app.explorer.explore``), the server's share.  Goal: ≤ 300 ms.

    python benchmarks/app.py [--screenshots docs/img]

``--screenshots DIR`` also writes the explorer as a user sees it (``DIR/explorer.png``) and the line-audit page as
it opens (``DIR/line-audit.png``).
"""

from __future__ import annotations

import argparse
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_common import console_script, machine  # noqa: E402

CHROMIUM = "/usr/bin/chromium"


def wait(page, expression: str, timeout: float = 30.0) -> None:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if page.evaluate(expression):
            return
        page.wait_for_timeout(5)
    raise TimeoutError(expression)


def measure(page, action, repeats: int) -> list[float]:
    """The page's latency [ms] of ``action(i)`` over ``repeats`` changes."""
    out = []
    for i in range(repeats):
        count = page.evaluate("window.fruitimpact.updates")
        action(i)
        wait(page, f"window.fruitimpact.updates > {count}")
        out.append(page.evaluate("window.fruitimpact.latency"))
    return out


def line_screenshot(browser, url: str, folder: Path) -> Path:
    """The line-audit page as it opens (the example line audited), a 1400 × 1000 window: ``folder/line-audit.png``."""
    page = browser.new_page(viewport={"width": 1400, "height": 1000})
    page.goto(url + "line")
    wait(page, "window.fruitimpact.updates >= 1")
    page.wait_for_timeout(300)
    path = folder / "line-audit.png"
    page.screenshot(path=str(path))
    page.close()
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--screenshots", metavar="DIR")
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args()
    from playwright.sync_api import sync_playwright

    from fruitimpact.app import explorer

    print(machine())
    request = {"fruit": "apple", "surface": "steel", "drop_height": "30cm", "criterion": "shear"}
    explorer.explore(request)
    inproc = []
    for i in range(args.repeats):
        start = time.perf_counter()
        explorer.explore({**request, "drop_height": f"{20 + i}cm"})
        inproc.append((time.perf_counter() - start) * 1e3)

    process = subprocess.Popen([console_script(), "serve", "--port", "0"], stdout=subprocess.PIPE, text=True)
    url = re.search(r"(http://\S+/)", process.stdout.readline()).group(1)
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            page.goto(url)
            wait(page, "window.fruitimpact.updates >= 1")
            page.select_option("select[name=fruit]", "apple")
            page.select_option("select[name=surface]", "steel")
            page.select_option("select[name=criterion]", "shear")
            page.check("input[name=mode][value=drop_height]")
            page.fill("input[name=drop_height]", "30cm")
            wait(page, "document.querySelector('#command').textContent.includes('30cm')")
            surfaces = ["wood", "concrete", "pvc-belt", "steel"]
            rows = {
                "select (surface)": measure(page, lambda i: page.select_option("select[name=surface]",
                                                                               surfaces[i % 4]), args.repeats),
                "slider (drop height)": measure(page, lambda i: page.fill("#height-slider", str(400 + 20 * i)),
                                                args.repeats),
                "typed value (drop height)": measure(page, lambda i: page.fill("input[name=drop_height]",
                                                                              f"{25 + i}cm"), args.repeats),
            }
            if args.screenshots:
                page.fill("input[name=drop_height]", "30cm")
                wait(page, "document.querySelector('#command').textContent.includes('30cm')")
                page.click("#risk-button")
                page.wait_for_selector("#chart-risk rect:nth-child(20)")
                folder = Path(args.screenshots)
                folder.mkdir(parents=True, exist_ok=True)
                # the whole page in one tall viewport (a full-page capture scrolls, and moves the sticky controls)
                page.set_viewport_size({"width": 1400, "height": page.evaluate("document.body.scrollHeight")})
                page.wait_for_timeout(300)
                page.screenshot(path=str(folder / "explorer.png"))
                print(f"screenshot written to {folder / 'explorer.png'}")
                print(f"screenshot written to {line_screenshot(browser, url, folder)}")
            browser.close()
    finally:
        process.terminate()
    print(f"{'change':<30}{'median ms':>10}{'p90 ms':>10}{'max ms':>10}   goal ≤ 300 ms")
    for name, values in rows.items():
        ordered = sorted(values)
        print(f"{name:<30}{statistics.median(values):>10.0f}{ordered[int(0.9 * (len(values) - 1))]:>10.0f}"
              f"{max(values):>10.0f}")
    print(f"{'in process: explorer.explore':<30}{statistics.median(inproc):>10.0f}"
          f"{sorted(inproc)[int(0.9 * (len(inproc) - 1))]:>10.0f}{max(inproc):>10.0f}   (the server's share)")


if __name__ == "__main__":
    main()
