"""A real browser on the page: headless Chromium (Debian's ``chromium``) driven by Playwright.

It loads the page from a real ``brainpainter serve`` (Blender renderer) on
127.0.0.1, uploads the bundled example, changes the gradient and sees the
preview change, renders everything, downloads the zip and checks its PNGs,
and takes a screenshot (``BRAINPAINTER_SCREENSHOT=path`` keeps a copy).
"""

from __future__ import annotations

import os
import re
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from web_support import EXAMPLE, Server, env_with_site, png_pixels, wait_for, zip_pngs

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


#: The preview image's box against the window: True when all of it is inside.
IN_VIEW = ("() => { const r = document.getElementById('preview').getBoundingClientRect(); "
           "return r.height > 20 && r.top >= 0 && r.left >= 0 && r.bottom <= innerHeight "
           "&& r.right <= innerWidth; }")
#: Scroll an element to the middle of the window, as while editing it.
TO_MIDDLE = "(sel) => document.querySelector(sel).scrollIntoView({block: 'center'})"


def _shot(page: Any, tmp_path: Path, name: str) -> None:
    """A screenshot of the window, kept beside BRAINPAINTER_SCREENSHOT when it is set."""
    shot = tmp_path / name
    page.screenshot(path=str(shot))
    if os.environ.get("BRAINPAINTER_SCREENSHOT"):
        shutil.copy(shot, Path(os.environ["BRAINPAINTER_SCREENSHOT"]).with_name(name))


def test_preview_stays_in_sight_and_the_page_says_how_to_make_it_again(served, tmp_path):
    """Issue 38 (items 3, 4, 6, 7): the preview stays inside the window while the colour map or the last
    options fieldset is edited (1440x900 and 400x900); only the options of a table are shown; the page
    shows the `brainpainter render` command and the Python call of the current options, the scale drawn,
    rounded; a skip link leads to the preview, the hidden file input is no tab stop, and the report's live
    region says one line; a movie says its length before it starts and plays in the page, a figure is
    shown at least 400 px wide."""
    from playwright.sync_api import expect

    with _page(tmp_path) as (page, errors):
        page.set_viewport_size({"width": 1440, "height": 900})
        page.goto(served.url + "/")
        expect(page.locator("#atlas option[value=dk]")).to_have_count(1)
        page.keyboard.press("Tab")
        skip = page.locator(":focus")
        expect(skip).to_have_text("Skip to the preview")
        assert page.locator("#file").get_attribute("tabindex") == "-1"
        page.locator("#size").fill("320x240")
        page.get_by_role("button", name="Use the example table").click()
        expect(page.locator("#preview-status")).to_contain_text("rendered in", timeout=120_000)
        command = page.locator("#command")
        expect(command).to_contain_text("brainpainter render brainpainter_dk.csv -o brainpainter-out")
        expect(command).to_contain_text("--size 320x240")
        page.locator("#gradient").fill("white,blue")
        page.locator("#vmax").fill("1.5")
        expect(command).to_contain_text("--gradient white,blue", timeout=60_000)
        expect(command).to_contain_text("--vmax 1.5")
        expect(page.locator("#python")).to_contain_text(
            "brainpainter.render('brainpainter_dk.csv', out='brainpainter-out'")
        expect(page.get_by_role("button", name="Copy command")).to_be_visible()
        expect(page.locator("#scale-used")).to_contain_text("Drawn: white,blue, 0 to 1.5")
        expect(page.locator("#scale-used")).to_contain_text("above 1.5 are saturated")
        # what applies to a table: no tract options, no map-only fields
        expect(page.locator("#tract-options")).to_be_hidden()
        expect(page.locator("#underlay")).to_be_hidden()
        expect(page.locator("#outline")).to_be_visible()
        assert page.locator("#report").get_attribute("aria-live") is None
        summary = page.locator("#report-summary")  # one line, not the report's lists
        expect(summary).to_contain_text("Checked: wide (BrainPainter names), atlas dk (inferred): 4 image(s)")
        assert "\n" not in summary.inner_text() and summary.locator("li").count() == 0
        for width in (1440, 1024, 400):
            page.set_viewport_size({"width": width, "height": 900})
            for sel in ("#cmap", "#hide"):
                page.evaluate(TO_MIDDLE, sel)
                page.wait_for_timeout(100)
                assert page.evaluate(IN_VIEW), (width, sel, page.locator("#preview").bounding_box())
            _shot(page, tmp_path, f"page-editing-{width}.png")
        page.locator("#quality").select_option("high")
        expect(page.locator("#preview-status")).to_contain_text("previews are drawn at default quality",
                                                                timeout=60_000)
        page.locator("#quality").select_option("default")
        # jobs (item 6): a movie's length before it starts, an MP4 playing in the page, a figure to judge,
        # and what a figure job does after its images
        page.set_viewport_size({"width": 1440, "height": 900})
        length = page.locator("#movie-length")
        expect(length).to_contain_text("A movie of these 4 rows: 73 frames, 3.0 s at 24 frames per second")
        assert page.evaluate("jobStep({kind: 'figure', status: 'running', progress: 12, total: 12})") == (
            "composing figure (12 images drawn)")
        page.locator("summary", has_text="Figure and movie options").click()
        page.locator("#frames_per_step").fill("2")
        page.locator("#hold").fill("12")
        expect(length).to_contain_text("55 frames, 2.3 s at 24 frames per second, holding each row 0.5 s")
        page.locator('#views input[value="medial-left"]').uncheck()
        page.locator('#views input[value="subcortical"]').uncheck()
        page.get_by_role("button", name="Movie (MP4)").click()
        video = page.locator(".job video")
        expect(video).to_have_count(1, timeout=240_000)
        # the page's CSP forbids eval (wait_for_function): poll with evaluate
        assert wait_for(lambda: page.evaluate("document.querySelector('.job video').readyState >= 1"), 30)
        assert page.evaluate("document.querySelector('.job video').duration") > 2
        page.get_by_role("button", name="Figure (PNG)").click()
        figure = page.locator(".job").first.locator(".gallery.wide img")
        expect(figure).to_be_visible(timeout=240_000)
        assert wait_for(lambda: figure.evaluate("i => i.complete && i.naturalWidth > 0"), 30)
        assert figure.evaluate("i => i.getBoundingClientRect().width") >= 400
        # item 8: the row shown as the CLI's interactive HTML export
        page.get_by_role("button", name="Interactive 3D (HTML)").click()
        expect(page.get_by_role("link", name="Download stage-4.html")).to_be_visible(timeout=240_000)
        _shot(page, tmp_path, "page-jobs.png")
        assert errors == []


def test_refused_uploads_keep_their_message_and_the_last_good_one(served, tmp_path):
    """Issue 38 (items 1, 2, 5): after a good table, a refused table leaves the good one in use (a view
    change re-renders it); dipy's minimal_bundles.zip (subject folders) draws its first subject's tracts
    in the preview and lets another subject be chosen; a refused tract upload keeps its message beside
    its field after the next preview, and the tracts drawn before stay."""
    import dipy
    from playwright.sync_api import expect

    bundles = Path(dipy.__file__).parent / "data" / "files" / "minimal_bundles.zip"
    (tmp_path / "bad.csv").write_text("nothing,here\n1,2\n")
    (tmp_path / "AF_L.trk").write_bytes(b"not a tractogram\n" * 20)
    with _page(tmp_path) as (page, errors):
        page.goto(served.url + "/")
        expect(page.locator("#atlas option[value=dk]")).to_have_count(1)
        page.locator("#size").fill("320x240")
        page.locator("#pview").select_option("subcortical")
        page.get_by_role("button", name="Use the example table").click()
        status = page.locator("#preview-status")
        expect(status).to_contain_text("subcortical · rendered in", timeout=120_000)
        table = png_pixels(page.locator("#preview").screenshot())
        page.locator("#file").set_input_files(str(tmp_path / "bad.csv"))
        error = page.locator("#error")
        expect(error).to_contain_text("bad.csv was refused")
        expect(error).to_contain_text("Still in use: brainpainter_dk.csv")
        page.locator("#pview").select_option("lateral-left")
        expect(status).to_contain_text("lateral-left · rendered in", timeout=60_000)
        expect(error).to_be_visible()
        expect(page.locator("#render-all")).to_be_enabled()
        expect(page.locator("#report")).to_contain_text("OK: wide")

        page.locator("#pview").select_option("subcortical")
        expect(status).to_contain_text("subcortical · rendered in", timeout=60_000)
        seq = page.locator("#preview").get_attribute("data-seq")  # before the upload: its preview is quick
        page.locator("#tract-files").set_input_files(str(bundles))
        tract_status = page.locator("#tract-status")
        expect(tract_status).to_contain_text("subject sub_1 of 5", timeout=60_000)
        expect(page.locator("#tract-options")).to_be_visible()
        expect(page.locator("#command")).to_contain_text("--tracts minimal_bundles/sub_1", timeout=60_000)
        expect(page.locator("#preview")).not_to_have_attribute("data-seq", seq, timeout=60_000)
        expect(status).to_contain_text("rendered in", timeout=60_000)
        expect(page.locator("#command")).to_contain_text("--tracts minimal_bundles/sub_1", timeout=60_000)
        drawn = png_pixels(page.locator("#preview").screenshot())
        changed = np.abs(drawn[..., :3].astype(int) - table[..., :3].astype(int)).max(-1) > 60
        assert changed.mean() > 0.005, changed.mean()  # the bundles, in their direction colours
        _shot(page, tmp_path, "page-tracts.png")
        page.locator("#subject").select_option("sub_3")
        expect(tract_status).to_contain_text("subject sub_3 of 5", timeout=60_000)

        page.locator("#tract-files").set_input_files(str(tmp_path / "AF_L.trk"))
        tract_error = page.locator("#tract-error")
        expect(tract_error).to_contain_text("AF_L.trk was refused", timeout=60_000)
        expect(tract_status).to_contain_text("Still drawn: tracts: AF_left")
        page.locator("#pview").select_option("lateral-left")
        expect(status).to_contain_text("lateral-left · rendered in", timeout=60_000)
        expect(tract_error).to_be_visible()
        _shot(page, tmp_path, "page-refused.png")
        assert errors == []


def test_page_draws_a_map_over_the_table_each_with_its_own_colour_bar(served, tmp_path):
    """Issue 35, item 6: the example table, then a map pair in 'Map over the table' with its own colour
    map and label: the preview (real renderer) shows the map's colours over the regions, two labelled
    colour bars (the table's gradient and the map's magma), and the command line draws both layers; a
    contour of a mask adds its lines and --contour."""
    import nibabel as nib
    from playwright.sync_api import expect

    for hemi in ("lh", "rh"):  # the front half of each hemisphere: 1 to 3, the back: no value
        values = np.full(10242, np.nan, np.float32)
        values[:5000] = np.linspace(1.0, 3.0, 5000)
        nib.freesurfer.write_morph_data(str(tmp_path / f"{hemi}.thickness"), values)
        mask = np.isfinite(values).astype(np.float32).reshape(-1, 1, 1)
        nib.save(nib.MGHImage(mask, np.eye(4)), str(tmp_path / f"{hemi}.mask.mgh"))
    with _page(tmp_path) as (page, errors):
        page.goto(served.url + "/")
        expect(page.locator("#map_cmap option[value=magma]")).to_have_count(1)
        page.locator("#size").fill("320x240")
        page.get_by_role("button", name="Use the example table").click()
        expect(page.locator("#preview-status")).to_contain_text("rendered in", timeout=120_000)
        expect(page.locator(".cbar:visible")).to_have_count(1)
        before = png_pixels(page.locator("#preview").screenshot())
        page.locator("#map-files").set_input_files([str(tmp_path / f"{h}.thickness") for h in ("lh", "rh")])
        expect(page.locator("#map-status")).to_contain_text("OK: map: lh.thickness + rh.thickness")
        expect(page.locator("#map_cmap")).to_be_visible()
        page.locator("#map_cmap").select_option("magma")
        page.locator("#map_label").fill("thickness (mm)")
        bars = page.locator(".cbar:visible")
        expect(bars).to_have_count(2, timeout=120_000)
        expect(bars.nth(0).locator(".cbar-label")).to_have_text("Regions: brainpainter_dk.csv")
        expect(bars.nth(1).locator(".cbar-label")).to_have_text("Map: thickness (mm)", timeout=120_000)
        expect(bars.nth(1)).to_have_attribute("aria-label", re.compile("magma"))
        expect(page.locator("#command")).to_contain_text("--lh lh.thickness --rh rh.thickness")
        expect(page.locator("#command")).to_contain_text("--map-cmap magma")
        expect(page.locator("#preview-status")).to_contain_text("rendered in", timeout=120_000)
        page.wait_for_function("() => !document.querySelector('#preview-status').textContent"
                               ".includes('Rendering')", timeout=120_000)
        after = png_pixels(page.locator("#preview").screenshot())
        brain = _brain(after)
        assert brain.mean() > 0.1
        changed = np.abs(after[..., :3].astype(int) - before[..., :3].astype(int)).max(-1) > 40
        assert 0.05 < changed[brain].mean() < 0.95, changed[brain].mean()  # the map over part, regions beside
        # a contour of a mask over the map: its lines on the preview, --contour in the command
        masks = [str(tmp_path / f"{h}.mask.mgh") for h in ("lh", "rh")]
        page.locator("#contour-files").set_input_files(masks)
        expect(page.locator("#contour-status")).to_contain_text("OK: map: lh.mask.mgh + rh.mask.mgh")
        expect(page.locator("#command")).to_contain_text("--contour lh.mask.mgh,rh.mask.mgh", timeout=120_000)
        page.wait_for_function("() => !document.querySelector('#preview-status').textContent"
                               ".includes('Rendering')", timeout=120_000)
        lined = png_pixels(page.locator("#preview").screenshot())
        dark = [int((img[..., :3].astype(int).max(-1) < 50).sum()) for img in (after, lined)]
        assert dark[1] > dark[0] + 100, dark
        _shot(page, tmp_path, "layers-page.png")
        assert errors == []


def test_page_draws_a_connectome_alone_with_its_bars_and_command(served, tmp_path):
    """Issue 36: a matrix of two DK regions and its node values chosen in the Connectome field (no
    table): the report counts the nodes, the preview from above (real renderer) draws the edge in its
    scale's colour through the glass cortex, the colour bars are the edges' and the nodes', and the
    command line is render --connectome with the files as uploaded and the page's threshold."""
    from playwright.sync_api import expect

    (tmp_path / "m.csv").write_text(",Left-precentral,Right-precentral\nLeft-precentral,0,0.8\n"
                                    "Right-precentral,0.8,0\n")
    (tmp_path / "v.txt").write_text("1\n3\n")
    with _page(tmp_path) as (page, errors):
        page.goto(served.url + "/")
        expect(page.locator("#tracts_space option[value=template]")).to_have_count(1)
        page.locator("#size").fill("320x240")
        page.locator("#atlas").select_option("dk")
        page.locator("#edge_threshold").fill("0.5")
        page.locator("#pview").select_option("dorsal")
        page.locator("#connectome-values").set_input_files(str(tmp_path / "v.txt"))
        expect(page.locator("#connectome-status")).to_contain_text("Choose the matrix first")
        page.locator("#connectome-matrix").set_input_files(str(tmp_path / "m.csv"))
        expect(page.locator("#connectome-status")).to_contain_text("OK: 2 nodes, 2 weights")
        expect(page.locator("#preview-status")).to_contain_text("dorsal · rendered in", timeout=120_000)
        bars = page.locator(".cbar:visible")
        expect(bars).to_have_count(2, timeout=120_000)
        expect(bars.nth(0).locator(".cbar-label")).to_have_text("Edges: m.csv")  # the files as uploaded
        expect(bars.nth(1).locator(".cbar-label")).to_have_text("Nodes: v.txt")
        expect(page.locator("#command")).to_contain_text("--connectome m.csv --node-values v.txt")
        expect(page.locator("#command")).to_contain_text("--edge-threshold 0.5")
        img = png_pixels(page.locator("#preview").screenshot())
        assert _brain(img).mean() > 0.05
        # the edge (0.8: the top of the page's white-yellow-orange-red gradient, clipped at 0.8) is
        # saturated; the right node (value 3) is drawn larger than the left (value 1)
        warm = (img[..., 0].astype(int) > 200) & (img[..., 2].astype(int) < 120)
        cols = np.nonzero(warm)[1]
        assert warm.sum() > 30 and cols.max() > img.shape[1] / 2 > cols.min(), warm.sum()
        _shot(page, tmp_path, "connectome-page.png")
        page.locator("#node_labels_top").fill("1")  # the page's node labels: the CLI's option
        page.locator("#node_labels_top").dispatch_event("change")
        expect(page.locator("#command")).to_contain_text("--node-labels-top 1", timeout=60_000)
        assert errors == []


def test_the_preview_shows_its_own_command_as_soon_as_it_is_drawn(served, tmp_path):
    """Issue 44 item 18: once the preview is drawn (no job), the page shows the `brainpainter render`
    command and the Python call of that preview (its row, its view) beside it, with copy buttons, and
    follows the row and view chosen."""
    from playwright.sync_api import expect

    with _page(tmp_path) as (page, errors):
        page.goto(served.url + "/")
        page.locator("#size").fill("320x240")
        page.get_by_role("button", name="Use the example table").click()
        expect(page.locator("#preview-status")).to_contain_text("rendered in", timeout=120_000)
        shown = page.locator("#preview-command")
        expect(shown).to_be_visible(timeout=60_000)
        expect(shown).to_contain_text("brainpainter render brainpainter_dk.csv -o brainpainter-out ")
        expect(shown).to_contain_text(" --size 320x240 --rows stage-4 --views lateral-left")
        expect(page.locator("#preview-python")).to_contain_text("rows='stage-4', views='lateral-left'")
        expect(page.get_by_role("button", name="Copy preview command")).to_be_visible()
        expect(page.get_by_role("button", name="Copy preview Python")).to_be_visible()
        expect(page.locator("#jobs")).to_be_empty()  # no job was made
        page.locator("#row").select_option(label="stage-2")
        page.locator("#pview").select_option("medial-left")
        expect(shown).to_contain_text("--rows stage-2 --views medial-left", timeout=60_000)
        assert not errors, errors


def test_page_draws_a_volume_as_blobs_cut_open(served, tmp_path):
    """Issue 45: the page's volume upload drawn as blobs (its clusters above the threshold as surfaces) in a
    cut-away view, on the blobs' bar; the command says --volume-surface and --clip."""
    from playwright.sync_api import expect
    from test_web_maps import mni_volume

    (tmp_path / "zstat1.nii.gz").write_bytes(mni_volume())
    with _page(tmp_path) as (page, errors):
        page.goto(served.url + "/")
        expect(page.locator("#atlas option[value=dk]")).to_have_count(1)
        page.locator("#size").fill("320x240")
        page.locator("#file").set_input_files([str(tmp_path / "zstat1.nii.gz")])
        expect(page.locator("#report")).to_contain_text("OK: volume: zstat1.nii.gz", timeout=120_000)
        page.locator("#threshold").fill("2.3")
        page.locator("#volume_surface").check()
        page.locator("#clip").fill("x<0")
        command = page.locator("#command")
        expect(command).to_contain_text("--volume-surface zstat1.nii.gz", timeout=120_000)
        expect(command).to_contain_text("--clip 'x<0'")
        assert "--volume " not in command.inner_text()   # the volume is the blobs, not projected
        expect(page.locator("#preview-status")).to_contain_text("rendered in", timeout=120_000)
        pixels = png_pixels(page.locator("#preview").screenshot())[..., :3].astype(int)
        yellow = (pixels[..., 0] > 150) & (pixels[..., 1] > 150) & (pixels[..., 2] < 90)  # 5: viridis' top
        assert yellow.sum() > 30, yellow.sum()
        shot = tmp_path / "blobs.png"
        page.screenshot(path=str(shot))
        if os.environ.get("BRAINPAINTER_SCREENSHOT"):
            shutil.copy(shot, Path(os.environ["BRAINPAINTER_SCREENSHOT"]).with_name("blobs-page.png"))
        assert errors == []
