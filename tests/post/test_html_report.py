"""The HTML validation report: self-contained, the expected table rows; rendered in a real
headless browser where one is available (playwright + Chromium)."""

from __future__ import annotations

import base64
import re
import shutil

import pytest

from icewall.post.html_report import build_report

pytest.importorskip("matplotlib")


@pytest.fixture(scope="module")
def report(small_result, linear_result, tmp_path_factory):
    return build_report([small_result, linear_result],
                        tmp_path_factory.mktemp("report") / "report.html")


def test_report_is_self_contained_with_the_table(report):
    page = report.read_text()
    sources = re.findall(r'<img [^>]*src="([^"]+)"', page)
    assert len(sources) == 2  # one curve figure (CF-4) + the crack pattern at the peak
    for src in sources:
        assert src.startswith("data:image/png;base64,")
        assert base64.b64decode(src.split(",", 1)[1])[:8] == b"\x89PNG\r\n\x1a\n"
    assert "http://" not in page and "https://" not in page and "<script" not in page
    rows = re.findall(r'<tr class="run">(.*?)</tr>', page)
    assert [re.findall(r"<td[^>]*>(.*?)</td>", r)[0] for r in rows] == ["cf4_small",
                                                                        "cf4_linear"]
    assert "4.91 MPa" in rows[0]  # the CF-4 test peak (Table 5.1)
    # the linear run has no state fields and stops at 2 mm: said so instead of a figure
    assert page.count('class="note"') == 3
    assert "outputs.fields" in page


def _browser():
    playwright = pytest.importorskip("playwright.sync_api", reason="playwright not installed")
    exe = next((shutil.which(n) for n in ("chromium", "chromium-browser", "google-chrome")
                if shutil.which(n)), None)
    if exe is None:
        pytest.skip("no Chromium found (apt-get install chromium)")
    return playwright, exe


@pytest.mark.browser
def test_report_renders_in_a_headless_browser(report):
    playwright, exe = _browser()
    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=exe, headless=True,
                                    args=["--no-sandbox"])
        page = browser.new_page()
        page.goto(report.as_uri())
        widths = page.eval_on_selector_all("img", "els => els.map(e => e.complete ? "
                                                  "e.naturalWidth : 0)")
        shown = page.eval_on_selector_all("img", "els => els.map(e => e.getBoundingClientRect()"
                                                 ".height)")
        table = page.eval_on_selector_all("#validation tr.run",
                                          "rows => rows.map(r => r.cells[0].innerText)")
        visible = page.is_visible("#validation")
        browser.close()
    assert len(widths) == 2 and all(w > 0 for w in widths)
    assert all(h > 0 for h in shown)
    assert table == ["cf4_small", "cf4_linear"] and visible
