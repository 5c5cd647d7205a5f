"""Movies: key-frame planning, interpolation, encoding, atomic writing, errors.

A stand-in renderer paints one stripe per region in the region's colour, so
colours in the decoded frames say exactly which value each region had. One
test renders with the real Blender renderer (marked ``render``).
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from brainpainter.color.scale import make_scale
from brainpainter.errors import BrainPainterError
from brainpainter.media.movie import (
    ease,
    format_clock,
    make_movie,
    plan_frames,
)
from brainpainter.table.rows import interpolate
from brainpainter.testing import StandInRenderer, registered_renderer, stand_in

REGIONS = ("Left-insula", "Left-precuneus")
W, H = 160, 120


def _fails_after_three(n: int) -> BaseException | None:
    return BrainPainterError("stand-in renderer failed on purpose") if n > 3 else None


#: The stand-in paints stripe k (of the middle half of the image) in the colour of REGIONS[k].
Stripes = StandInRenderer.with_(layout="band", regions=REGIONS)


def stripe_centre(k: int) -> tuple[int, int]:
    """(row, column) of the middle of region k's stripe in a W x H render."""
    edges = np.linspace(W // 8, W - W // 8, len(REGIONS) + 1)
    return H // 2, int((edges[k] + edges[k + 1]) / 2)


@pytest.fixture
def stripes():
    with stand_in("stripes", Stripes) as registered:
        yield registered


def table(tmp_path, text, name="in.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def read_mp4(path):
    """Decode with the ffmpeg of imageio-ffmpeg: ``({"codec", "size", "fps"}, [RGB frames])``."""
    import re

    import imageio_ffmpeg

    exe = imageio_ffmpeg.get_ffmpeg_exe()
    info = subprocess.run([exe, "-hide_banner", "-i", str(path)], capture_output=True, text=True).stderr
    m = re.search(r"Video: (\w+).*?, (\d+)x(\d+)[, ].*?([\d.]+) fps", info)
    assert m, info
    codec, w, h, fps = m.group(1), int(m.group(2)), int(m.group(3)), float(m.group(4))
    raw = subprocess.run([exe, "-v", "error", "-i", str(path), "-f", "rawvideo", "-pix_fmt", "rgb24", "-"],
                         capture_output=True, check=True).stdout
    frames = np.frombuffer(raw, np.uint8).reshape(-1, h, w, 3)
    return {"codec": codec, "size": (w, h), "fps": fps}, list(frames)


def read_gif(path):
    """``(frames, durations in ms)``; pillow merges identical consecutive frames (adding durations),
    so the frames are repeated by duration to count the movie's frames."""
    from PIL import Image, ImageSequence

    frames, durations = [], []
    with Image.open(path) as im:
        for f in ImageSequence.Iterator(im):
            frames.append(np.asarray(f.convert("RGB")))
            durations.append(f.info["duration"])
    return frames, durations


def patch(frame, k, r=4):
    y, x = stripe_centre(k)
    return frame[y - r:y + r, x - r:x + r].reshape(-1, 3).mean(axis=0)


# -- planning and interpolation -------------------------------------------------------
def test_plan_frames_counts_and_clock():
    plan = plan_frames([0, 1, 2, 3], 5)
    assert len(plan) == 3 * 5 + 1
    assert [(f.a, f.b) for f in plan[:2]] == [(0, 0), (0, 1)]
    assert plan[-1].a == plan[-1].b == 3 and plan[-1].clock == 3.0
    assert np.all(np.diff([f.clock for f in plan]) > 0)
    held = plan_frames([0, 1, 2, 3], 5, hold=2)
    assert len(held) == 16 + 4 * 2
    # with times, steps get frames in proportion to their gaps (4 on average here)
    timed = plan_frames([0, 3, 7, 10], 4, proportional=True)
    assert len(timed) == 4 + 5 + 4 + 1
    assert np.allclose(np.diff([f.clock for f in timed])[:4], 0.75)


def test_easing_is_monotonic_and_ends_at_the_keys():
    t = np.linspace(0, 1, 101)
    for name in ("linear", "smooth"):
        e = ease(t, name)
        assert e[0] == 0 and e[-1] == 1 and np.all(np.diff(e) >= 0)
    assert ease(0.1, "smooth") < 0.1 and ease(0.9, "smooth") > 0.9  # slow near the key frames
    with pytest.raises(BrainPainterError, match="easing must be one of"):
        ease(0.5, "cubic")


def test_interpolation_keeps_nan_between_key_frames_only():
    a, b = np.array([0.0, np.nan, 1.0]), np.array([2.0, 1.0, np.nan])
    mid = interpolate(a, b, 0.25)
    assert mid[0] == 0.5 and np.isnan(mid[1]) and np.isnan(mid[2])
    assert np.array_equal(interpolate(a, b, 0.0), a, equal_nan=True)
    assert np.array_equal(interpolate(a, b, 1.0), b, equal_nan=True)


@settings(max_examples=60, deadline=None)
@given(keys=st.integers(2, 6), per_step=st.integers(1, 30), hold=st.integers(0, 3),
       easing=st.sampled_from(["linear", "smooth"]))
def test_plan_frames_properties(keys, per_step, hold, easing):
    plan = plan_frames(list(range(keys)), per_step, easing, hold)
    assert len(plan) == (keys - 1) * per_step + 1 + keys * hold
    assert all(0.0 <= f.weight < 1.0 and f.b - f.a in (0, 1) for f in plan)
    assert np.all(np.diff([f.clock for f in plan]) >= 0)
    assert sum(f.a == f.b for f in plan) == keys * (1 + hold)  # every key frame shown, in order
    assert [f.a for f in plan if f.a == f.b][:: 1 + hold] == list(range(keys))


@given(a=st.floats(-1e6, 1e6), b=st.floats(-1e6, 1e6), w=st.floats(0, 1))
def test_interpolated_values_lie_between_the_key_values(a, b, w):
    v = interpolate(np.array([a]), np.array([b]), w)[0]
    assert min(a, b) - 1e-6 * (abs(a) + abs(b)) <= v <= max(a, b) + 1e-6 * (abs(a) + abs(b))


def test_clock_format_follows_the_keys():
    assert format_clock(3.4567, [0, 3, 7]) == "3.5"
    assert format_clock(0.125, [0, 0.25, 0.5]) == "0.12"


# -- whole movies with the stand-in renderer -------------------------------------------
def test_mp4_frame_count_size_and_monotonic_colours(tmp_path, stripes, tiny):
    data = table(tmp_path, "Image-name-unique,Left-insula,Left-precuneus\nA,0,1\nB,3,1\n")
    out = tmp_path / "out" / "m.mp4"
    result = make_movie(data, "dk", out=out, views="lateral-left", frames_per_step=8, fps=12,
                        template=tiny, renderer=stripes, width=W, height=H, progress=False)
    assert result.n_frames == 9 and result.keys == ["A", "B"]
    meta, frames = read_mp4(out)
    assert len(frames) == 9
    assert meta["size"] == result.frame_size and all(s % 2 == 0 for s in result.frame_size)
    assert result.frame_size[0] == W and result.frame_size[1] > H  # caption and colour bar below
    assert meta["codec"] == "h264" and meta["fps"] == 12
    insula = np.array([patch(f, 0) for f in frames])
    # white (0) -> yellow -> orange -> red (3): red stays, green and blue fall monotonically
    assert np.all(np.diff(insula[:, 1]) <= 2) and np.all(np.diff(insula[:, 2]) <= 2)
    assert insula[0, 1] - insula[-1, 1] > 200 and insula[0, 2] - insula[-1, 2] > 200
    assert np.all(insula[:, 0] > 235)
    # the frame half-way shows the value 1.5 (linear interpolation), within codec error
    scale = make_scale()
    assert np.abs(insula[4] - scale(1.5) * 255).max() < 12
    precuneus = np.array([patch(f, 1) for f in frames])
    assert np.ptp(precuneus, axis=0).max() < 6  # unchanged region, unchanged colour
    assert sorted(p.name for p in out.parent.iterdir()) == ["m.mp4"]  # no temporary files left


def test_gif_with_smooth_easing_nan_and_holds(tmp_path, stripes, tiny):
    data = table(tmp_path, "Image-name-unique,Left-insula,Left-precuneus\nA,0,2\nB,3,\n")
    out = tmp_path / "m.gif"
    result = make_movie(data, "dk", out=out, views="lateral-left", frames_per_step=6, hold=2,
                        easing="smooth", fps=10, template=tiny, renderer=stripes, width=W, height=H,
                        nan_color="#0000ff", progress=False)
    stored, durations = read_gif(out)
    assert sum(durations) == 100 * result.n_frames and result.n_frames == 6 + 1 + 2 * 2
    frames = [f for f, d in zip(stored, durations, strict=True) for _ in range(d // 100)]
    assert frames[0].shape[:2] == result.frame_size[::-1]
    assert tuple(frames[0][1, 1]) == (255, 255, 255)  # the background exactly, not dithered
    insula = np.array([patch(f, 0) for f in frames])
    green = insula[:, 1]
    assert np.all(np.diff(green) <= 3) and green[0] - green[-1] > 200
    # holds: the first three frames are the key frame A
    assert np.ptp(green[:3]) < 3
    # smooth easing: the first in-between step is smaller than the middle one
    steps = -np.diff(green[2:10])
    assert steps[0] < steps[3]
    # precuneus is NaN in B: its own colour at A, the NaN colour from the first in-between frame on
    precuneus = np.array([patch(f, 1) for f in frames])
    assert np.abs(precuneus[0] - np.array([255, 165, 0])).max() < 12
    assert all(np.abs(p - np.array([0, 0, 255])).max() < 12 for p in precuneus[3:])


def test_time_column_sorts_key_frames_and_spaces_frames_by_time(tmp_path, stripes, tiny):
    data = table(tmp_path, "subject,Years,Left-insula\nlate,10,3\nearly,0,0\nmid,2,1\n")
    result = make_movie(data, "dk", out=tmp_path / "t.mp4", views="lateral-left", frames_per_step=6,
                        time_column="years", template=tiny, renderer=stripes, width=W, height=H,
                        progress=False)
    assert result.keys == ["early", "mid", "late"] and result.key_times == [0.0, 2.0, 10.0]
    assert result.n_frames == 2 + 10 + 1  # 12 in-between frames shared 2:10 by the time gaps


def test_orbit_turns_the_camera_at_a_fixed_scale(tmp_path, stripes, tiny):
    data = table(tmp_path, "Image-name-unique,Left-insula\nA,0\nB,3\n")
    # anterior: both hemispheres (two spheres side by side in the tiny template), from the front
    result = make_movie(data, "dk", out=tmp_path / "o.gif", views="anterior", frames_per_step=4,
                        orbit=360, template=tiny, renderer=stripes, width=W, height=H, progress=False)
    az = [view.azimuth for _, view in Stripes.calls]
    assert len(az) == result.n_frames == 5 and az[0] == 90.0
    assert np.allclose(np.diff(az) % 360, 72.0)  # 360 degrees over 5 frames: the loop closes
    zooms = np.array([view.zoom for _, view in Stripes.calls])
    # every direction is framed at the scale of the widest one (tight framing / zoom), so the
    # brain keeps its size on screen as it turns
    assert zooms.max() <= 1.0 + 1e-9 and zooms.min() < 0.9
    assert zooms[0] == pytest.approx(1.0)  # from the front the pair is widest


def test_several_views_side_by_side(tmp_path, stripes, tiny):
    data = table(tmp_path, "Image-name-unique,Left-insula\nA,0\nB,3\n")
    result = make_movie(data, "dk", out=tmp_path / "v.mp4", views="lateral-left,medial-left",
                        frames_per_step=2, template=tiny, renderer=stripes, width=W, height=H,
                        title="progression", progress=False)
    assert result.frame_size[0] == 2 * W
    assert [view.name for _, view in Stripes.calls[:2]] == ["lateral-left", "medial-left"]


def test_a_failure_while_rendering_leaves_no_file(tmp_path, stripes, tiny):
    data = table(tmp_path, "Image-name-unique,Left-insula\nA,0\nB,3\n")
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    for name in ("m.mp4", "m.gif"):
        failing = Stripes.with_(fail=_fails_after_three)  # the 4th image of each movie fails
        with registered_renderer(stripes, failing), pytest.raises(BrainPainterError, match="on purpose"):
            make_movie(data, "dk", out=out_dir / name, views="lateral-left", frames_per_step=6,
                       template=tiny, renderer=stripes, width=W, height=H, progress=False)
    assert list(out_dir.iterdir()) == []


def test_cli_movie_with_stand_in_renderer(tmp_path, stripes, tiny):
    from brainpainter.cli.main import cli

    data = table(tmp_path, "Image-name-unique,Left-insula\nA,0\nB,3\n")
    out = tmp_path / "m.mp4"
    result = CliRunner().invoke(cli, [
        "movie", str(data), "--atlas", "dk", "--out", str(out), "--views", "lateral-left",
        "--frames-per-step", "3", "--fps", "6", "--size", f"{W}x{H}", "--template", str(tiny),
        "--renderer", stripes, "--label", "atrophy", "-q"])
    assert result.exit_code == 0, result.output
    assert "4 frames" in result.output and out.is_file()


def test_cli_movie_warns_of_a_column_it_did_not_draw(tmp_path, stripes, tiny):
    from brainpainter.cli.main import cli

    data = table(tmp_path, "Image-name-unique,Left-insula,Left-hipocampus\nA,0,1\nB,3,2\n")
    result = CliRunner().invoke(cli, [
        "movie", str(data), "--atlas", "dk", "--out", str(tmp_path / "m.gif"), "--views", "lateral-left",
        "--frames-per-step", "2", "--size", f"{W}x{H}", "--template", str(tiny), "--renderer", stripes, "-q"])
    assert result.exit_code == 0, result.output
    assert "warning: 1 name(s) match no dk region and were not drawn: 'Left-hipocampus'" in result.output


# -- errors: one line, exit code 2, no file -----------------------------------------------
@pytest.mark.parametrize(
    ("rows", "args", "message"),
    [
        ("A,1\n", [], "a movie needs at least 2 rows"),
        ("A,1\nB,2\n", ["--time-column", "year"], "--time-column 'year' is not a column"),
        ("A,1\nB,2\n", ["--frames-per-step", "0"], "frames per step must be between"),
        ("A,1\nB,2\n", ["--transparent"], "a movie has no transparency"),
    ],
)
def test_bad_options_fail_with_one_line_and_no_file(tmp_path, rows, args, message):
    data = table(tmp_path, "Image-name-unique,Left-insula\n" + rows)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    proc = subprocess.run([sys.executable, "-m", "brainpainter", "movie", str(data), "--atlas", "dk",
                           "--out", str(out_dir / "m.mp4"), *args], capture_output=True, text=True)
    assert proc.returncode == 2, proc.stderr
    assert message in proc.stderr and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert list(out_dir.iterdir()) == []


def test_unwritable_output_fails_before_rendering(tmp_path):
    data = table(tmp_path, "Image-name-unique,Left-insula\nA,1\nB,2\n")
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    for out, message in ((blocker / "m.mp4", "is a file, not a folder"),
                         (tmp_path / "m.avi", "must be a file name ending in .mp4, .gif")):
        proc = subprocess.run([sys.executable, "-m", "brainpainter", "movie", str(data), "--atlas", "dk",
                               "--out", str(out)], capture_output=True, text=True)
        assert proc.returncode == 2 and message in proc.stderr, proc.stderr
        assert len(proc.stderr.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file", "in.csv"]


def test_time_column_errors(tmp_path, stripes, tiny):
    kw = {"views": "lateral-left", "template": tiny, "renderer": stripes, "width": W, "height": H,
          "progress": False}
    bad = table(tmp_path, "Image-name-unique,years,Left-insula\nA,0,1\nB,soon,2\n")
    with pytest.raises(BrainPainterError, match=r"line 3 of .* is 'soon', not a finite number"):
        make_movie(bad, "dk", out=tmp_path / "m.mp4", time_column="years", **kw)
    same = table(tmp_path, "Image-name-unique,years,Left-insula\nA,1,1\nB,1,2\n", "same.csv")
    with pytest.raises(BrainPainterError, match="'A' and 'B' have the same time 1"):
        make_movie(same, "dk", out=tmp_path / "m.mp4", time_column="years", **kw)
    typo = table(tmp_path, "Image-name-unique,years,Left-insula\nA,1,1\nB,2,2\n", "typo.csv")
    with pytest.raises(BrainPainterError, match="Did you mean 'years'"):
        make_movie(typo, "dk", out=tmp_path / "m.mp4", time_column="yeras", **kw)
    # --strict accepts the time column, but not other unknown names
    make_movie(typo, "dk", out=tmp_path / "ok.gif", time_column="years", strict=True, frames_per_step=1, **kw)
    extra = table(tmp_path, "Image-name-unique,years,Left-insula,Left-insulla\nA,1,1,1\nB,2,2,2\n", "x.csv")
    with pytest.raises(BrainPainterError, match="'Left-insulla' matches no region"):
        make_movie(extra, "dk", out=tmp_path / "m.mp4", time_column="years", strict=True, **kw)
    assert sorted(p.name for p in tmp_path.glob("*.mp4")) == []


# -- the real renderer ---------------------------------------------------------------------
@pytest.mark.render
def test_movie_with_blender_on_the_bundled_template(tmp_path):
    from conftest import EXAMPLES

    out = tmp_path / "progression.mp4"
    result = make_movie(EXAMPLES / "brainpainter_dk.csv", "dk", out=out, rows="stage-1,stage-4",
                        views="lateral-left,subcortical", frames_per_step=3, width=200, height=150,
                        quality="fast", label="atrophy", progress=False)
    meta, frames = read_mp4(out)
    assert len(frames) == result.n_frames == 4
    assert meta["size"] == result.frame_size and result.frame_size[0] == 400
    brain = [f[:150, :200].astype(int) for f in frames]
    assert np.abs(brain[0] - brain[-1]).max() > 60  # stage-1 and stage-4 differ
    # stage-4 is redder than stage-1 somewhere in the lateral view
    redness = [(b[..., 0] - b[..., 2]).clip(0).sum() for b in brain]
    assert redness[-1] > redness[0]
