"""A real browser on the page: headless Chromium (Debian's ``chromium``) driven by Playwright.

It loads the page from a real ``brainpainter serve`` (Blender renderer) on
127.0.0.1, uploads the bundled example, changes the gradient and sees the
preview change, renders everything, downloads the zip and checks its PNGs,
and takes a screenshot (``BRAINPAINTER_SCREENSHOT=path`` keeps a copy).
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from web_support import EXAMPLE, Server, env_with_site, png_pixels, zip_pngs

pytestmark = pytest.mark.render

CHROMIUM = Path("/usr/bin/chromium")
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync"]


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    pytest.importorskip("bpy")
    pytest.importorskip("playwright")
    if not CHROMIUM.exists():
        pytest.skip("Debian's chromium is not installed (.ci/run installs it)")
    tmp = tmp_path_factory.mktemp("served")
    env = env_with_site(tmp)  # no extra site: the real renderer
    server = Server(tmp / "data", env, tmp / "server.log", ["--workers", "1"])
    server.start(timeout=240)
    yield server
    server.stop()


def _brain(pixels: np.ndarray) -> np.ndarray:
    """Mask of pixels that are not the white background, shape (h, w)."""
    return (pixels[..., :3].astype(int).sum(axis=2) < 740) & (pixels[..., 3] > 0)


@contextmanager
def _page(tmp_path: Path, *, console: bool = False, **context: Any) -> Iterator[tuple[Any, list[str]]]:
    """A Chromium page (1440x1000, a fresh profile) and the page errors it collects (with `console`,
    console errors too)."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch_persistent_context(
            str(tmp_path / "profile"), executable_path=str(CHROMIUM), headless=True, args=FLAGS,
            viewport={"width": 1440, "height": 1000}, **context)
        try:
            page = browser.pages[0] if browser.pages else browser.new_page()
            errors: list[str] = []
            if console:
                page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            page.on("pageerror", lambda e: errors.append(str(e)))
            yield page, errors
        finally:
            browser.close()


def test_page_end_to_end_in_chromium(served, tmp_path):
    from playwright.sync_api import expect

    with _page(tmp_path, accept_downloads=True, console=True) as (page, errors):
        page.goto(served.url + "/")
        expect(page.locator("#atlas option[value=dk]")).to_have_count(1)
        # keyboard: the drop zone opens the file chooser with Enter
        with page.expect_file_chooser() as chooser:
            page.locator("#drop").press("Enter")
        page.locator("#size").fill("320x240")
        page.locator('#views input[value="medial-left"]').uncheck()
        chooser.value.set_files(str(EXAMPLE))
        report = page.locator("#report")
        expect(report).to_contain_text("OK: wide (BrainPainter names), atlas dk (inferred)")
        expect(report).to_contain_text("4 image(s)")
        expect(page.locator("#preview-status")).to_contain_text("rendered in", timeout=60_000)
        first = page.locator("#preview").get_attribute("data-seq")
        before = png_pixels(page.locator("#preview").screenshot())

        page.locator("#gradient").fill("white,blue")
        expect(page.locator("#preview")).not_to_have_attribute("data-seq", first, timeout=60_000)
        expect(page.locator("#preview-status")).to_contain_text("rendered in", timeout=60_000)
        after = png_pixels(page.locator("#preview").screenshot())
        expect(report).to_contain_text("white,blue: 0 .. 1")  # the report follows the scale
        brain = _brain(before) & _brain(after)
        assert brain.mean() > 0.2
        b, a = before[brain].astype(float), after[brain].astype(float)
        assert b[:, 0].mean() - b[:, 2].mean() > 40  # stage-4 on white..red: red brain
        assert a[:, 2].mean() - a[:, 0].mean() > 40  # white..blue: blue brain

        page.get_by_role("button", name="Render all").click()
        link = page.get_by_role("link", name="Download all")
        expect(link).to_be_visible(timeout=180_000)
        expect(page.locator(".gallery img")).to_have_count(8)
        with page.expect_download() as dl:
            link.click()
        zipped = zip_pngs(Path(dl.value.path()).read_bytes())
        assert sorted(zipped) == sorted(f"stage-{i}_{v}.png" for i in range(1, 5)
                                        for v in ("lateral-left", "subcortical"))
        for name, pixels in zipped.items():
            assert pixels.shape == (240, 320, 4), name
            assert _brain(pixels).mean() > 0.1, name
        # more atrophy at stage 4: bluer brain on the white..blue gradient than at stage 1
        blue = {n: 255 - px[_brain(px)][:, 0].mean() for n, px in zipped.items()}
        assert blue["stage-4_lateral-left.png"] > blue["stage-1_lateral-left.png"] + 20

        shot = tmp_path / "page.png"
        page.screenshot(path=str(shot), full_page=False)
        assert _brain(png_pixels(shot.read_bytes())).mean() > 0.05
        if os.environ.get("BRAINPAINTER_SCREENSHOT"):
            shutil.copy(shot, os.environ["BRAINPAINTER_SCREENSHOT"])
        assert errors == []


OVERFLOW = "document.documentElement.scrollWidth - document.documentElement.clientWidth"
#: The elements that reach past the right edge (for the message).
WIDEST = ("[...document.querySelectorAll('body *')].filter(e => e.getBoundingClientRect().right > "
          "document.documentElement.clientWidth + 0.5).slice(-5).map(e => e.tagName + '#' + e.id + '.' + "
          "e.className + ' ' + Math.round(e.getBoundingClientRect().right))")


def _contrast(fg: str, bg: str) -> float:
    """WCAG contrast ratio of two CSS ``rgb(r, g, b)`` colours."""
    def lum(css: str) -> float:
        r, g, b = (int(v) / 255 for v in css[css.index("(") + 1:css.index(")")].split(",")[:3])
        return sum(w * (c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4)
                   for w, c in zip((0.2126, 0.7152, 0.0722), (r, g, b), strict=True))
    hi, lo = sorted((lum(fg), lum(bg)), reverse=True)
    return (hi + 0.05) / (lo + 0.05)


def test_page_as_a_new_user_finds_it(served, tmp_path):
    """No broken-image icon before the first preview, no horizontal scroll bar at any width, a readable
    hovered primary button, a colour bar under the preview, option errors next to their field (named as on
    the page), and figure/movie options with the CLI's defaults; a movie job counts frames."""
    from playwright.sync_api import expect

    with _page(tmp_path) as (page, errors):
        page.goto(served.url + "/")
        expect(page.locator("#atlas option[value=dk]")).to_have_count(1)
        assert not page.locator("#preview").is_visible()  # no broken-image icon before a preview
        assert not page.locator("#preview-bar").is_visible()
        api = page.evaluate("fetch('/openapi.json').then(r => r.json())")["components"]["schemas"]
        fields = (("frames_per_step", "MovieParams"), ("hold", "MovieParams"), ("fps", "MovieParams"),
                  ("dpi", "FigureParams"), ("font_size", "FigureParams"))
        for field, model in fields:
            default = api[model]["properties"][field]["default"]
            assert float(page.locator(f"#{field}").input_value()) == default, field
        easing = api["MovieParams"]["properties"]["easing"]["default"]
        assert page.locator("#easing").input_value() == easing
        for width in (320, 375, 480, 720, 800, 1024, 1100, 1440):
            page.set_viewport_size({"width": width, "height": 900})
            over = page.evaluate(OVERFLOW)
            assert over <= 0, (f"horizontal scroll of {over} px at width {width}", page.evaluate(WIDEST))
        page.set_viewport_size({"width": 1440, "height": 1000})
        page.locator("#size").fill("160x120")
        page.get_by_role("button", name="Use the example table").click()
        expect(page.locator("#preview-status")).to_contain_text("rendered in", timeout=120_000)
        bar = page.locator("#preview-bar")
        expect(bar).to_be_visible()
        expect(bar.locator(".ticks span")).to_have_count(4)  # white,yellow,orange,red: 0 1 2 3
        expect(bar.locator(".ticks")).to_contain_text("3")
        assert page.evaluate(OVERFLOW) <= 0
        button = page.locator("#render-all")
        expect(button).to_be_enabled()
        button.hover()
        fg, bg = button.evaluate("b => [getComputedStyle(b).color, getComputedStyle(b).backgroundColor]")
        assert _contrast(fg, bg) >= 4.5, (fg, bg)
        # an option error: next to its field, named as on the page
        page.locator("#size").fill("5x5")
        note = page.locator("#size-error")
        expect(note).to_be_visible(timeout=60_000)
        expect(note).to_contain_text("Size (WIDTHxHEIGHT)")
        assert "--size" not in note.inner_text()
        expect(page.locator("#size")).to_have_attribute("aria-invalid", "true")
        page.locator("#size").fill("160x120")
        expect(note).to_have_count(0, timeout=60_000)
        # a movie job reports progress per frame
        page.locator("summary", has_text="Figure and movie options").click()
        page.locator("#frames_per_step").fill("2")
        page.get_by_role("button", name="Movie (GIF)").click()
        job = page.locator(".job").first
        expect(job).to_contain_text("done", timeout=180_000)
        expect(job.locator("p").first).to_contain_text("movie (GIF): done")
        status = page.evaluate("fetch(document.querySelector('.job a').href.split('/files/')[0])"
                               ".then(r => r.json())")
        assert status["total"] == 7 and status["progress"] == 7, status  # 4 key frames, 2 per step
        assert errors == []


def test_page_takes_a_map_pair(served, tmp_path):
    """Two files chosen at once (lh and rh) are one map: the report says what was understood, and the
    preview (real renderer) shows the left cortex red and the right blue (signed map: RdBu_r about 0)."""
    import nibabel as nib
    from playwright.sync_api import expect

    for hemi, value in (("lh", 2.0), ("rh", -2.0)):
        nib.freesurfer.write_morph_data(str(tmp_path / f"{hemi}.thickness"),
                                        np.full(10242, value, np.float32))
    with _page(tmp_path) as (page, errors):
        page.goto(served.url + "/")
        expect(page.locator("#atlas option[value=dk]")).to_have_count(1)
        page.locator("#size").fill("320x240")
        page.locator("#file").set_input_files([str(tmp_path / f"{h}.thickness") for h in ("lh", "rh")])
        report = page.locator("#report")
        expect(report).to_contain_text("OK: map: lh.thickness + rh.thickness, fsaverage5, 1 image")
        expect(page.locator("#preview-status")).to_contain_text("rendered in", timeout=120_000)
        expect(report).to_contain_text("RdBu_r")
        left = png_pixels(page.locator("#preview").screenshot())
        brain = _brain(left)
        assert brain.mean() > 0.1
        rgb = left[brain][:, :3].astype(float)
        assert rgb[:, 0].mean() - rgb[:, 2].mean() > 40  # lh is +2: red
        shot = tmp_path / "map.png"
        page.screenshot(path=str(shot))
        if os.environ.get("BRAINPAINTER_SCREENSHOT"):
            shutil.copy(shot, Path(os.environ["BRAINPAINTER_SCREENSHOT"]).with_name("map-page.png"))
        assert errors == []


def test_page_takes_tracts_alone(served, tmp_path):
    """Tractograms and their values table chosen in the Tracts field (no region table): the report says
    what is drawn, and the preview (real renderer, from above) shows AF_left red left of CST_right blue."""
    from playwright.sync_api import expect
    from test_tracts import bundle, write

    write(tmp_path / "AF_L.trk", bundle(-30.0, n=40, z=30.0, length=60.0))
    write(tmp_path / "CST_R.tck", bundle(30.0, n=40, seed=1, z=30.0, length=60.0))
    (tmp_path / "fa.csv").write_text("AF_left,CST_right\n0,1\n")
    with _page(tmp_path) as (page, errors):
        page.goto(served.url + "/")
        expect(page.locator("#tracts_space option[value=template]")).to_have_count(1)
        page.locator("#size").fill("320x240")
        page.locator("#gradient").fill("red,blue")
        page.locator("#vmin").fill("0")
        page.locator("#vmax").fill("1")
        page.locator("#shading").select_option("flat")
        page.locator("#glass_opacity").fill("0")
        page.locator("#tract_radius").fill("1")
        page.locator("#tracts_space").select_option("template")
        page.locator("#pview").select_option("subcortical-dorsal")
        page.locator("#tract-files").set_input_files([str(tmp_path / n) for n in ("AF_L.trk", "CST_R.tck",
                                                                                  "fa.csv")])
        expect(page.locator("#tract-status")).to_contain_text(
            "OK: tracts: AF_left, CST_right (80 streamlines of 80); values: fa.csv")
        expect(page.locator("#preview-status")).to_contain_text("subcortical-dorsal · rendered in",
                                                                timeout=120_000)
        img = png_pixels(page.locator("#preview").screenshot())
        red = np.abs(img[..., :3].astype(int) - [255, 0, 0]).max(-1) < 40
        blue = np.abs(img[..., :3].astype(int) - [0, 0, 255]).max(-1) < 40
        assert red.sum() > 50 and blue.sum() > 50, (red.sum(), blue.sum())
        assert np.nonzero(red)[1].mean() < np.nonzero(blue)[1].mean()
        shot = tmp_path / "tracts.png"
        page.screenshot(path=str(shot))
        if os.environ.get("BRAINPAINTER_SCREENSHOT"):
            shutil.copy(shot, Path(os.environ["BRAINPAINTER_SCREENSHOT"]).with_name("tracts-page.png"))
        assert errors == []
