"""A real browser on the page: headless Chromium (Debian's ``chromium``) driven by Playwright.

It loads the page from a real ``brainpainter serve`` (Blender renderer) on
127.0.0.1, uploads the bundled example, changes the gradient and sees the
preview change, renders everything, downloads the zip and checks its PNGs,
and takes a screenshot (``BRAINPAINTER_SCREENSHOT=path`` keeps a copy).
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

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


def test_page_end_to_end_in_chromium(served, tmp_path):
    from playwright.sync_api import expect, sync_playwright

    with sync_playwright() as p:
        context = p.chromium.launch_persistent_context(
            str(tmp_path / "profile"), executable_path=str(CHROMIUM), headless=True, args=FLAGS,
            accept_downloads=True, viewport={"width": 1440, "height": 1000})
        try:
            page = context.pages[0] if context.pages else context.new_page()
            errors: list[str] = []
            page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            page.on("pageerror", lambda e: errors.append(str(e)))
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
        finally:
            context.close()
