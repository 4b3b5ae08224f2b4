"""The leaderboard pages in a real browser: the site built with ``mkdocs build --strict`` into a
temporary folder, served on localhost, every board page and the summary opened in Debian's
Chromium, headless. Each page loads with no SEVERE console message, every image has a natural
width, clicking a numeric header sorts its table (the cells read back), and the filter hides rows.

Slow (the build and the browser): not in CI. Needs ``apt-get install chromium chromium-driver``
and ``pip install -e '.[browser]'`` (selenium); skipped, saying which is missing, otherwise."""

from __future__ import annotations

import functools
import http.server
import importlib.util
import math
import os
import shutil
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

pytestmark = pytest.mark.slow

REPO = Path(__file__).resolve().parents[1]
CHROMIUM, CHROMEDRIVER = Path("/usr/bin/chromium"), Path("/usr/bin/chromedriver")
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync", "--window-size=1280,900",
         "--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1")  # no host but the local server is reached


def _missing() -> str | None:
    """Why the browser test cannot run here, or None."""
    if not CHROMIUM.is_file():
        return f"{CHROMIUM} missing (apt-get install -y chromium chromium-driver)"
    if not CHROMEDRIVER.is_file():
        return f"{CHROMEDRIVER} missing (apt-get install -y chromium-driver)"
    if importlib.util.find_spec("selenium") is None:
        return "selenium missing (pip install -e '.[browser]')"
    if shutil.which("mkdocs", path=str(Path(sys.executable).parent)) is None and importlib.util.find_spec("mkdocs") is None:
        return "mkdocs missing (pip install -e '.[docs]')"
    return None


@pytest.fixture(scope="module", autouse=True)
def _browser_at_hand() -> None:
    """Skip, saying what is missing, where the browser test cannot run (a fixture: when CI deselects
    the slow tests, nothing is reported as skipped)."""
    if (reason := _missing()) is not None:
        pytest.skip(reason)


class _Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - the base class's name
        pass


@pytest.fixture(scope="module")
def base_url(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """The site, built strict into a temporary folder, served on a free localhost port."""
    site = tmp_path_factory.mktemp("site")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1", "MPLBACKEND": "Agg"}
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d", str(site)],
                          cwd=REPO, env=env, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(_Quiet, directory=str(site)))
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_port}"
    finally:
        server.shutdown()
        server.server_close()


@pytest.fixture(scope="module")
def browser(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Any]:
    """Headless Chromium through chromedriver, a new empty profile, its console log kept."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = str(CHROMIUM)
    for flag in (*FLAGS, f"--user-data-dir={tmp_path_factory.mktemp('chromium-profile')}"):
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(str(CHROMEDRIVER)), options=options)
    driver.set_page_load_timeout(60)
    try:
        yield driver
    finally:
        driver.quit()


def _page_urls() -> list[str]:
    """The address of every leaderboard page (the summary first), as MkDocs makes them."""
    from tcbench.leaderboard.pages.render import build_site

    out = []
    for page in build_site(REPO / "leaderboards").pages:
        path = str(page.path)
        out.append("leaderboards/" + ("" if path == "index.md" else path.removesuffix("index.md").removesuffix(".md")
                                      + ("" if path.endswith("index.md") else "/")))
    return out


PAGES = _page_urls() if _missing() is None else ["leaderboards/"]  # where it cannot run, one to skip: no site built

# the table and column to sort: of the page's first table with a numeric column whose cells are not
# already in ascending order, the first such median (a board's metric), else the first such column
PICK_COLUMN = """
const num = c => { const v = c.getAttribute('data-value'); return v === null || v === '' ? NaN : Number(v); };
const tables = Array.from(document.querySelectorAll('.tcb-board table'));
for (let t = 0; t < tables.length; t++) {
  const heads = Array.from(tables[t].tHead.rows[0].cells);
  const rows = Array.from(tables[t].tBodies[0].rows);
  const out = heads.map((h, i) => i).filter(i => heads[i].getAttribute('data-type') === 'num').filter(i => {
    const xs = rows.map(r => num(r.cells[i])).filter(x => !isNaN(x));
    return xs.some((x, k) => k > 0 && xs[k - 1] > x);
  });
  const median = out.find(i => (heads[i].querySelector('code') || heads[i]).textContent.startsWith('median'));
  if (out.length) return [t, median === undefined ? out[0] : median];
}
return [-1, -1];
"""
READ_COLUMN = """
const table = document.querySelectorAll('.tcb-board table')[arguments[0]];
return Array.from(table.tBodies[0].rows).filter(r => r.style.display !== 'none')
  .map(r => r.cells[arguments[1]].getAttribute('data-value'));
"""
# the column to filter on: the method (or board, record), else the first text column
PICK_TEXT = """
const heads = Array.from(document.querySelectorAll('.tcb-board table')[arguments[0]].tHead.rows[0].cells);
const keys = heads.map(h => (h.querySelector('code') || h).textContent.trim());
for (const k of ['method', 'board', 'record']) { if (keys.includes(k)) return keys.indexOf(k); }
return heads.findIndex(h => h.getAttribute('data-type') === 'text');
"""
# the text of the rows the filter left shown (rows scrolled out of the table's box count too)
SHOWN_ROWS = """
return Array.from(document.querySelectorAll('.tcb-board table')[arguments[0]].tBodies[0].rows)
  .filter(r => getComputedStyle(r).display !== 'none').map(r => r.textContent);
"""
IMAGES = """
return Array.from(document.querySelectorAll('article img'))
  .map(i => [i.getAttribute('src'), i.complete, i.naturalWidth]);
"""


def _elsewhere(entry: dict[str, Any], base_url: str) -> bool:
    """A resource the theme asks of another host failed to load: Material's Google Fonts and the
    GitHub API it asks for the repository's stars, both unreachable here (and blocked by
    --host-resolver-rules); anything of the site itself counts."""
    message = str(entry.get("message", ""))
    return entry.get("source") == "network" and message.startswith("http") and not message.startswith(base_url)


def _numbers(values: list[str | None]) -> list[float]:
    return [math.nan if v in (None, "") else float(v) for v in values]  # "Infinity" reads as inf


def _sorted(xs: list[float], descending: bool = False) -> bool:
    """Numbers in order, the missing ones (NaN) last."""
    present = [x for x in xs if not math.isnan(x)]
    missing_last = all(math.isnan(x) for x in xs[len(present):])
    pairs = zip(present, present[1:], strict=False)
    return missing_last and all((a >= b) if descending else (a <= b) for a, b in pairs)


def _wait(condition: Any, timeout_s: float = 20.0) -> Any:
    end = time.monotonic() + timeout_s
    while True:
        value = condition()
        if value or time.monotonic() > end:
            return value
        time.sleep(0.1)


@pytest.mark.parametrize("page", PAGES)
def test_a_board_page_loads_sorts_filters_and_shows_its_plots(page: str, base_url: str, browser: Any) -> None:
    from selenium.webdriver.common.by import By

    browser.get_log("browser")  # what earlier pages logged
    browser.get(f"{base_url}/{page}")
    _wait(lambda: browser.execute_script("return document.readyState") == "complete")
    loaded = _wait(lambda: (lambda xs: (xs,) if all(c for _, c, _ in xs) else None)(browser.execute_script(IMAGES)))
    assert loaded is not None, "images still loading"
    (images,) = loaded
    assert page == "leaderboards/" or page.endswith("claims/") or images, "a board page without a plot"
    assert all(width > 0 for _, _, width in images), [src for src, _, width in images if not width]
    severe = [e for e in browser.get_log("browser") if e["level"] == "SEVERE" and not _elsewhere(e, base_url)]
    assert severe == [], severe

    table, column = browser.execute_script(PICK_COLUMN)
    assert column >= 0, "no numeric column out of order to sort"
    board = browser.find_elements(By.CSS_SELECTOR, ".tcb-board")[table]
    header = board.find_elements(By.CSS_SELECTOR, "table thead th")[column]
    browser.execute_script("arguments[0].scrollIntoView({block: 'center'})", header)
    header.click()
    assert header.get_attribute("aria-sort") == "ascending"
    assert _sorted(_numbers(browser.execute_script(READ_COLUMN, table, column)))
    header.click()
    assert header.get_attribute("aria-sort") == "descending"
    assert _sorted(_numbers(browser.execute_script(READ_COLUMN, table, column)), descending=True)

    box = board.find_element(By.CSS_SELECTOR, ".tcb-filter")
    rows = board.find_elements(By.CSS_SELECTOR, "table tbody tr")
    cell = rows[0].find_elements(By.TAG_NAME, "td")[browser.execute_script(PICK_TEXT, table)]
    word = cell.get_attribute("textContent").split()[0]  # the first row's method (board, record)
    total = len(rows)
    browser.execute_script("arguments[0].scrollIntoView({block: 'center'})", box)
    box.send_keys(word)
    shown = browser.execute_script(SHOWN_ROWS, table)
    assert 0 < len(shown) < total or total == 1, (word, len(shown), total)
    assert all(word.lower() in text.lower() for text in shown), word
    count = board.find_element(By.CSS_SELECTOR, ".tcb-count").text
    assert count == f"{len(shown)} of {total} rows"
    box.send_keys("zzz-no-such-row")
    assert browser.execute_script(SHOWN_ROWS, table) == [] and not any(r.is_displayed() for r in rows)
