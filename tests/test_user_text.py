"""User text is drawn as text (issue 46): a title, a colour-bar label, an image name or a category name
with ``$`` is never read as matplotlib mathtext, and a label map's key stays bounded however many and
however long its names."""

from __future__ import annotations

import time

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image
from test_figure import THREE, H, W, stripes, table  # noqa: F401  (the stripes fixture)

from brainpainter.color.scale import ColourScale
from brainpainter.media.plain_text import plain

MATHTEXT = [r"$\undefinedmacro$", "$" + "{" * 98 + "$", r"cost $5 and $10"]


def test_plain_escapes_every_dollar_and_cuts_long_names():
    assert plain(r"$\undefinedmacro$") == r"\$\undefinedmacro\$"
    assert plain("a\x1bb\nc") == "a b c"
    assert plain("x" * 50, 40) == "x" * 39 + "\u2026"


@pytest.mark.parametrize("text", MATHTEXT)
def test_the_figure_command_draws_mathtext_as_its_text(tmp_path, stripes, tiny, text):  # noqa: F811
    """Before: ``--label '$\\undefinedmacro$'`` failed with exit 1, "internal error"."""
    from brainpainter.cli.main import cli

    data = table(tmp_path, THREE.replace("stage-1", text.replace(",", " ")))
    out = tmp_path / "f.png"
    args = ["figure", str(data), "--atlas", "dk", "--views", "lateral-left", "--size", f"{W}x{H}",
            "--template", str(tiny), "--renderer", stripes, "--dpi", "100", "-q"]
    result = CliRunner().invoke(cli, [*args, "--out", str(out), "--label", text, "--title", text])
    assert result.exit_code == 0, result.output
    plain_out = tmp_path / "plain.png"
    assert CliRunner().invoke(cli, [*args, "--out", str(plain_out)]).exit_code == 0
    dark = [(np.asarray(Image.open(p).convert("L")) < 100).sum() for p in (out, plain_out)]
    assert dark[0] > dark[1] + 200  # the title and the label are drawn, as text


def scale_of(n: int, chars: int) -> ColourScale:
    rng = np.random.default_rng(0)
    cats = tuple((f"{i:05d}" + "x" * chars, tuple(float(c) for c in rng.random(3))) for i in range(n))
    return ColourScale(np.zeros((2, 3)), 0.0, float(n), categories=cats)


def test_a_key_of_many_long_names_is_laid_out_in_a_second():
    """Before: 1500 names of 200 characters took 13 s to size, 8000 of 900 more than 20 minutes."""
    from brainpainter.media.colorbar import colorbar_height

    colorbar_height(scale_of(3, 3), 6.0)  # matplotlib's first use
    for n, chars in [(1500, 200), (8000, 900)]:
        t0 = time.perf_counter()
        colorbar_height(scale_of(n, chars), 6.0, label="labels")
        assert time.perf_counter() - t0 < 2.0, (n, chars)


def test_a_key_names_at_most_60_categories_each_at_most_40_characters():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from brainpainter.media.colorbar import draw_colorbar

    fig, ax = plt.subplots(figsize=(6, 0.6))
    draw_colorbar(ax, scale_of(61, 0))
    assert [t.get_text() for t in ax.get_xticklabels()] == ["61 categories"]
    fig2, ax2 = plt.subplots(figsize=(6, 0.6))
    draw_colorbar(ax2, scale_of(3, 100))
    assert [len(t.get_text()) for t in ax2.get_xticklabels()] == [40, 40, 40]
    plt.close(fig)
    plt.close(fig2)
