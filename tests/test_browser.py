"""The diagnosis report as a person sees it: opened in a real browser (headless Chromium), not parsed as text.

``scripts/test.sh`` installs Chromium and its driver from the distribution's packages when they are missing
and it may (root with apt-get). Without them this module is skipped with the reason, unless
``BOUC_WEN_ID_REQUIRE_BROWSER=1`` (set by ``.ci/run``) makes their absence a failure.
``BOUC_WEN_ID_SCREENSHOT=path.png`` also keeps the page's full-height screenshot (``docs/report.png`` is one).
"""

from __future__ import annotations

import base64
import os
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import pytest

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
DRIVER = shutil.which("chromedriver")
REQUIRED = os.environ.get("BOUC_WEN_ID_REQUIRE_BROWSER") == "1"

if CHROMIUM is None or DRIVER is None:
    _why = "headless Chromium and chromedriver are not installed (apt-get install chromium chromium-driver)"
    if REQUIRED:
        raise RuntimeError(f"BOUC_WEN_ID_REQUIRE_BROWSER=1 but {_why}")
    pytest.skip(_why, allow_module_level=True)

webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed (the [test] extra)")


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A diagnosis report of a plant that hides viscous damping, written as the CLI writes it."""
    from bouc_wen_id.diagnosis.report import identify_plain, write_report

    plant = bw.WienerPlant(
        bw.TransferFunction([20.0], [1.0, 20.0]),  # first-order G, corner at 20 rad/s
        bw.BoucWen(beta=1.2, gamma=0.3, mu=1.5, alpha=1.5),
        terms=(bw.terms.Viscous(0.02),),
    )
    plan = bw.SinePlan(
        frequencies=[2.0, 4.0, 8.0, 16.0],
        amplitudes=1.0,
        settle_periods=10,
        periods=12,
        samples_per_period=256,
        noise_sd=0.003,
        seed=3,
    )
    recs = bw.simulate(plant, plan)
    d = bw.diagnose(recs, y_unit="N", u_unit="mm")
    identified, notes = identify_plain(recs)
    out = tmp_path_factory.mktemp("report")
    write_report(d, out, identified=identified, identify_warnings=notes, u_unit="mm", y_unit="N")
    return out / "report.html"


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = str(CHROMIUM)
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"):
        options.add_argument(arg)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(executable_path=str(DRIVER)), options=options)
    driver.set_page_load_timeout(60)
    try:
        yield driver
    finally:
        driver.quit()


def test_report_opens_in_a_browser_with_the_verdict_first_and_every_figure_decoded(
    report: Path, browser: Any
) -> None:
    browser.set_window_size(1100, 900)
    browser.get(report.resolve().as_uri())
    images = browser.execute_script(
        "return Array.from(document.images).map(i => [i.alt, i.complete, i.naturalWidth, i.naturalHeight]);"
    )
    assert len(images) >= 3, f"the page shows {len(images)} figures: {images}"
    undecoded = [alt for alt, complete, w, h in images if not (complete and w > 0 and h > 0)]
    assert not undecoded, f"figures that did not decode: {undecoded}"

    # The first text a reader meets is the verdict (the status and its sentence), not a heading.
    first = browser.execute_script(
        "const w = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT,"
        " {acceptNode: n => n.textContent.trim() ? NodeFilter.FILTER_ACCEPT : NodeFilter.FILTER_REJECT});"
        " const n = w.nextNode(); return n ? n.parentElement.closest('.verdict') !== null : false;"
    )
    assert first, "the first text of the page is not inside the verdict"
    verdict = browser.find_element("css selector", ".verdict").text
    assert "explained" in verdict.lower() or "adequate" in verdict.lower(), verdict

    # The identified model comes right after the verdict's evidence, above the diagnosis's own tables.
    headings = browser.execute_script(
        "return Array.from(document.querySelectorAll('h2')).map(h => h.textContent);"
    )
    assert headings and headings[0] == "Identified model", headings
    model = browser.execute_script(
        "const h = Array.from(document.querySelectorAll('h2'))"
        ".find(h => h.textContent == 'Identified model');"
        " let n = h.nextElementSibling, text = '';"
        " while (n && n.tagName != 'H2') { text += n.innerText + '\\n'; n = n.nextElementSibling; }"
        " return text;"
    )
    for name in ("beta", "gamma", "mu", "95 % interval", "phase lag (deg)"):
        assert name in model, (name, model)

    errors = [e for e in browser.get_log("browser") if e.get("level") == "SEVERE"]
    assert not errors, f"console errors: {errors}"

    keep = os.environ.get("BOUC_WEN_ID_SCREENSHOT")
    height = int(browser.execute_script("return document.documentElement.scrollHeight"))
    browser.set_window_size(1100, min(max(height, 900), 12000))
    shot = base64.b64decode(browser.get_screenshot_as_base64())
    assert shot[:8] == b"\x89PNG\r\n\x1a\n" and len(shot) > 10_000
    if keep:
        Path(keep).write_bytes(shot)
