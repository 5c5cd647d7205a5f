"""PNG encoding: lossless pixels and the metadata chunks, with fpng and with the Pillow fallback."""

from __future__ import annotations

import io
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from brainpainter.io.output import png_bytes

META = {"Software": "brainpainter 0.1", "brainpainter:image": "Stage é/1",
        "brainpainter:settings": '{"views": ["lateral-left"], "quality": "default"}'}


@pytest.mark.parametrize("use_fpng", [True, False])
def test_png_is_lossless_and_keeps_metadata(monkeypatch, use_fpng):
    if not use_fpng:
        # as if fpng were not installed: the Pillow fallback
        from brainpainter.io import output

        monkeypatch.setitem(output._encoder, "fpng", None)
    rng = np.random.default_rng(3)
    img = rng.integers(0, 256, (37, 53, 4), dtype=np.uint8)
    img[:10] = (255, 255, 255, 0)  # transparent rows stay transparent
    data = png_bytes(img, META)
    with Image.open(io.BytesIO(data)) as im:
        im.load()
        assert im.mode == "RGBA"
        assert np.array_equal(np.asarray(im), img)
        assert im.text == META


def test_fpng_is_used_when_installed():
    pytest.importorskip("fpng")
    img = np.zeros((8, 8, 4), np.uint8)
    # fpng marks its streams with a private fdEC chunk; Pillow never writes one
    assert b"fdEC" in png_bytes(img, {})


def test_the_encoder_loads_without_fpngs_package_init():
    """fpng's ``__init__`` walks the interpreter stack (lazy_loader): 0.15 s of a first image."""
    code = ("import sys, numpy as np\nfrom brainpainter.io.output import load_encoder, png_bytes\n"
            "enc = load_encoder()\nassert enc is not None\n"
            "png_bytes(np.zeros((4, 4, 4), np.uint8))\n"
            "print('lazy_loader' in sys.modules, 'fpng' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False"]
