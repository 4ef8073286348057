"""The browsable report opened in a real headless browser (Debian's chromium + chromedriver
through Selenium): every figure loads and every table has rows.

The page comes from a real study run (the stability study on a 10x1x1 bar, tiny grids), so
its figures are the study's PNGs and its tables the study's CSVs. Skipped with one line when
the browser, its driver or Selenium is missing (``.ci/run`` installs them).
"""

from __future__ import annotations

import re
import shutil

import pytest

from studies.cache import CaseCache
from studies.html import read_outputs, write_index, write_output
from studies.registry import StudyContext, StudyOutput
from studies.study_stability import run as stability
from studies.study_stability.cases import Settings, bar

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
DRIVER = shutil.which("chromedriver")


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    root = tmp_path_factory.mktemp("report")
    q = Settings(dt_meshes=((6, 1),), dt_steps=200, dt_bisections=2, load_factors=(1, 100),
                 load_mesh=(6, 1), nus=(0.3, 0.49), lock_mesh=(6, 1), map_loads=(1, 100),
                 map_dt_factors=(0.5, 1.1), map_steps=200, map_mesh=(6, 1))  # fmt: skip
    scenes = [bar(6, 1, ("dt", "load", "lock", "map"))]
    ctx = StudyContext("stability", root / "stability", True, CaseCache(root / ".c", "s"), False)
    out = stability(ctx, scenes, q)
    write_output(ctx.out, out, "springfem study stability --quick")
    return write_index(root, "Test report"), out


def test_the_page_holds_what_the_study_wrote(page):
    """Without a browser: every table and figure of the study is in the page, the figures
    embedded (no file reference left), the command named."""
    path, out = page
    text = path.read_text()
    assert text.count("<table") >= len(out.tables) and len(out.tables) == 5
    assert text.count("data:image/png;base64,") == len(out.figures) == 3
    assert "springfem study stability --quick" in text
    assert 'src="' not in text.replace('src="data:image/png;base64,', "")  # self-contained
    ((folder, summary),) = read_outputs(path.parent)
    assert summary["title"] == out.title and folder.name == "stability"


NO_BROWSER = "no chromium/chromedriver (apt install chromium chromium-driver)"


@pytest.mark.skipif(CHROMIUM is None or DRIVER is None, reason=NO_BROWSER)
def test_every_figure_loads_and_every_table_has_rows_in_a_browser(page):
    webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed")
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By

    path, out = page
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for flag in ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                 "--no-first-run", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync"):  # fmt: skip
        opts.add_argument(flag)
    driver = webdriver.Chrome(service=Service(DRIVER), options=opts)
    try:
        driver.get(path.as_uri())
        images = driver.find_elements(By.TAG_NAME, "img")
        assert len(images) == len(out.figures)
        for img in images:
            assert driver.execute_script(
                "return arguments[0].complete && arguments[0].naturalWidth > 0", img
            ), img.get_attribute("alt")
        tables = driver.find_elements(By.CSS_SELECTOR, "section table")
        assert len(tables) == len(out.tables)
        for t in tables:
            assert len(t.find_elements(By.CSS_SELECTOR, "tbody tr")) > 0
        assert driver.title == "Test report"
    finally:
        driver.quit()


def _many_studies(root):
    """Eleven studies of long findings: more than the summary shows."""
    for i in range(11):
        findings = [f"Finding {i}: " + "word " * 80, "A second finding stays in the section."]
        out = StudyOutput(f"study{i}", f"Study number {i}", findings=findings)
        write_output(root / f"study{i}", out, f"springfem study study{i}")
    return write_index(root, "Many")


def test_the_page_opens_with_the_contents_and_a_short_summary(tmp_path):
    """The contents come before any section and before the summary; the summary has at most
    ten lines, each linking to a section that exists, and leaves the full findings to the
    sections."""
    text = _many_studies(tmp_path).read_text()
    nav, summary = text.index('<nav id="contents">'), text.index('<ul class="summary">')
    assert nav < summary < text.index("<section")
    block = text[summary : text.index("</ul>", summary)]
    assert 1 <= block.count("<li>") <= 10
    ids = set(re.findall(r'<section id="([^"]+)"', text))
    links = set(re.findall(r'href="#([^"]+)"', block))
    assert links == ids and len(ids) == 11  # every study reachable from the summary
    assert "A second finding" not in block and "word " * 80 not in block


@pytest.mark.skipif(CHROMIUM is None or DRIVER is None, reason=NO_BROWSER)
def test_the_first_screen_holds_the_contents_in_a_browser(tmp_path):
    webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed")
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By

    path = _many_studies(tmp_path)
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for flag in ("--headless", "--no-sandbox", "--disable-gpu", "--window-size=1280,800"):
        opts.add_argument(flag)
    driver = webdriver.Chrome(service=Service(DRIVER), options=opts)
    try:
        driver.get(path.as_uri())
        height = driver.execute_script("return window.innerHeight")
        nav = driver.find_element(By.ID, "contents")
        bottom = driver.execute_script("return arguments[0].getBoundingClientRect().bottom", nav)
        assert 0 < bottom <= height  # the whole table of contents on the first screen
        assert len(nav.find_elements(By.TAG_NAME, "a")) == 11
    finally:
        driver.quit()
