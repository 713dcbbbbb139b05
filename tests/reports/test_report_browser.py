"""The report in a real browser: headless Chromium (Debian's chromium and chromium-driver, driven by
selenium) opens every page of a generated site from disk (file://) and checks that it renders (a
screenshot that is not blank), that every image and link inside the site resolves to an existing
file (and every image decodes), and that the console has no errors; that the interactive
work-precision diagrams draw from ``file://`` with no network (plotly.js copied into the site),
show a point's cell on hover and hide a family from every panel when its legend entry is
clicked; and that hostile strings stay text, in the page and in the hover text.

Skipped only when Chromium or its driver is not installed (``.ci/run`` installs them with apt-get),
with a loud message. ``GNIBENCH_SCREENSHOTS=DIR`` keeps the screenshots for a reviewer to look at.
"""
from __future__ import annotations

import io
import json
import os
import shutil
import sys
import tempfile
from pathlib import Path
from urllib.parse import unquote, urlparse

import pytest
from gnibench.reports.site import build_site
from support_reports import make_results

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
DRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--hide-scrollbars", "--window-size=1400,1000")


@pytest.fixture(scope="module")
def browser():
    if not (Path(CHROMIUM).exists() and Path(DRIVER).exists()):
        message = ("\n" + "!" * 78 + "\nBROWSER TESTS SKIPPED: chromium / chromium-driver are not "
                   "installed (apt-get install -y chromium chromium-driver)\n" + "!" * 78)
        print(message, file=sys.stderr)
        pytest.skip(message)
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    profile = tempfile.mkdtemp(prefix="gnibench-chromium-")
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for flag in (*FLAGS, f"--user-data-dir={profile}"):
        opts.add_argument(flag)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(DRIVER), options=opts)
    yield driver
    driver.quit()
    shutil.rmtree(profile, ignore_errors=True)


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    root = tmp_path_factory.mktemp("browser")
    with pytest.MonkeyPatch.context() as mp:
        results = make_results(root, mp)
    bench = root / "bench" / "Linux-CPython-3.11-64bit"
    bench.mkdir(parents=True)
    for i, median in enumerate((1.0e-3, 1.1e-3, 1.5e-3)):
        run = {"commit_info": {"id": f"abc{i}"}, "datetime": f"2026-01-0{i + 1}T10:00:00",
               "benchmarks": [{"name": "kernel", "fullname": "benchmarks/x.py::kernel",
                               "group": "g", "stats": {"median": median, "min": median * 0.9}}]}
        (bench / f"{i + 1:04d}_abc{i}.json").write_text(json.dumps(run))
    out = root / "site"
    build_site([results], out, benchmarks=root / "bench")
    return out


def non_blank(png: bytes) -> tuple[int, float]:
    """(distinct colours, fraction of pixels that are not white) of a PNG screenshot."""
    import numpy as np
    from PIL import Image

    img = Image.open(io.BytesIO(png)).convert("RGB")
    img.thumbnail((650, 650))
    pixels = np.asarray(img).reshape(-1, 3)
    colours = len(np.unique(pixels, axis=0))
    return colours, float(np.mean(np.any(pixels != 255, axis=1)))


def local_target(url: str) -> Path | None:
    """The file a file:// URL points at (None for other schemes)."""
    parsed = urlparse(url)
    return Path(unquote(parsed.path)) if parsed.scheme == "file" else None


@pytest.mark.parametrize("page", ["index.html", "hostile.html", "timing.html"])
def test_page_renders_with_resolving_links_and_no_console_errors(browser, site, page):
    browser.get((site / page).as_uri())
    browser.get_log("browser")       # drop messages of earlier pages
    browser.refresh()
    height = browser.execute_script("return document.documentElement.scrollHeight")
    browser.set_window_size(1400, min(max(height, 600), 8000))
    png = browser.get_screenshot_as_png()
    keep = os.environ.get("GNIBENCH_SCREENSHOTS")
    if keep:
        Path(keep).mkdir(parents=True, exist_ok=True)
        (Path(keep) / f"{page}.png").write_bytes(png)
    colours, inked = non_blank(png)
    assert colours > 50 and inked > 0.03, (colours, inked)
    images = browser.find_elements("tag name", "img")
    for img in images:
        src = img.get_attribute("src")
        target = local_target(src)
        assert target is not None and target.is_file(), src
        assert target.resolve().is_relative_to(site.resolve()), src
        assert browser.execute_script("return arguments[0].complete && arguments[0].naturalWidth > 0",
                                      img), f"image does not decode: {src}"
    for link in browser.find_elements("tag name", "a"):
        href = link.get_attribute("href")
        target = local_target(href)
        assert target is not None, f"a link leaves the site: {href}"
        assert target.is_file(), href
        fragment = urlparse(href).fragment
        if fragment and target == local_target(browser.current_url):
            assert browser.find_elements("id", fragment), href
    errors = [e for e in browser.get_log("browser") if e["level"] in ("SEVERE", "ERROR")]
    assert not errors, errors
    if page != "timing.html":
        assert images or page == "index.html"


def test_hostile_strings_do_not_become_markup(browser, site):
    browser.get((site / "hostile.html").as_uri())
    scripts = browser.find_elements("tag name", "script")
    sources = {s.get_attribute("src") or s.get_attribute("type") or "inline" for s in scripts}
    assert sources == {(site / "assets" / "plotly.min.js").as_uri(), "application/json",
                       "inline"}, sources
    assert len([s for s in scripts if not s.get_attribute("src")
                and not s.get_attribute("type")]) == 1          # ours: hands the JSON to plotly
    h1 = browser.find_element("tag name", "h1").text
    assert h1.startswith("<script>alert('t')</script>")            # shown as text
    assert not browser.find_elements("css selector", "img[src='x']")
    assert browser.execute_script("return window.alerted === undefined")


def test_interactive_work_precision_hover_and_toggle(browser, site):
    """The plotly diagram of the hostile page: drawn offline, one trace group per family across
    its panels; hovering a point names its cell, spec, error, nfev and wall time (the spec as
    text); clicking the first family's legend entry hides it in every panel, clicking again
    shows it; no console errors."""
    import time

    from selenium.webdriver.common.action_chains import ActionChains

    browser.set_window_size(1400, 1200)
    browser.get((site / "hostile.html").as_uri())
    browser.get_log("browser")
    browser.refresh()
    div = browser.find_elements("css selector", ".wp-plot")[0]
    assert browser.execute_script("return window.Plotly !== undefined && "
                                  "arguments[0].data.length > 0", div)
    browser.execute_script("arguments[0].scrollIntoView()", div)
    points = div.find_elements("css selector", "g.points path.point")
    assert points
    ActionChains(browser).move_to_element(points[0]).perform()
    time.sleep(0.5)
    hover = " ".join(h.text for h in div.find_elements("css selector", "g.hovertext"))
    assert "cell" in hover and "nfev" in hover and "wall" in hover and "error" in hover, hover
    keep = os.environ.get("GNIBENCH_SCREENSHOTS")
    if keep:
        (Path(keep) / "hover.png").write_bytes(browser.get_screenshot_as_png())
    groups = browser.execute_script(
        "return arguments[0].data.map(t => t.legendgroup)", div)
    first = groups[0]
    assert groups.count(first) >= 2                             # one trace per panel
    div.find_elements("css selector", "g.legend g.traces")[0].click()
    time.sleep(0.5)
    hidden = browser.execute_script(
        "return arguments[0].data.filter(t => t.visible === 'legendonly').map(t => t.legendgroup)",
        div)
    assert hidden and set(hidden) == {first} and len(hidden) == groups.count(first)
    div.find_elements("css selector", "g.legend g.traces")[0].click()
    time.sleep(0.5)
    assert not browser.execute_script(
        "return arguments[0].data.filter(t => t.visible === 'legendonly').length", div)
    errors = [e for e in browser.get_log("browser") if e["level"] in ("SEVERE", "ERROR")]
    assert not errors, errors
