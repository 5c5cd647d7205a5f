"""The output transaction (brainpainter.io.transaction) and the CLI guard, in-process and fast."""

from __future__ import annotations

import json
import os
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from brainpainter.errors import BrainPainterError
from brainpainter.io.output import png_bytes
from brainpainter.io.transaction import FileTransaction, FolderTransaction
from brainpainter.io.verify import gif_info, mp4_boxes, verify_file


def _png(w: int = 8, h: int = 6) -> bytes:
    return png_bytes(np.full((h, w, 4), 200, np.uint8))


def _gif(path: Path, n: int = 5, size: tuple[int, int] = (40, 30)) -> Path:
    from brainpainter.media.movie import _GifWriter

    rng = np.random.default_rng(1)
    frames = [rng.integers(0, 255, (size[1], size[0], 3), dtype=np.uint8) for _ in range(n)]
    writer = _GifWriter(path, size, 10.0, (255, 255, 255), frames[:2])
    for f in frames:
        writer.write(f)
    writer.close()
    return path


def _mp4(path: Path, n: int = 6) -> Path:
    from brainpainter.media.movie import _Mp4Writer

    writer = _Mp4Writer(path, (32, 32), 10.0)
    for i in range(n):
        writer.write(np.full((32, 32, 3), 20 * i, np.uint8))
    writer.close()
    return path


# -- verification ---------------------------------------------------------------------------------
def test_whole_files_verify(tmp_path):
    (tmp_path / "a.png").write_bytes(_png())
    verify_file(tmp_path / "a.png", size=(8, 6))
    verify_file(_gif(tmp_path / "a.gif"), size=(40, 30), frames=5)
    verify_file(_mp4(tmp_path / "a.mp4"), frames=6)
    assert gif_info(tmp_path / "a.gif") == ((40, 30), 5)
    assert {"ftyp", "moov", "mdat"} <= set(mp4_boxes(tmp_path / "a.mp4")["boxes"])


@pytest.mark.parametrize("cut", [1, 10, 100])
def test_truncated_files_are_caught(tmp_path, cut):
    for name, data in (("a.png", _png()), ("a.gif", _gif(tmp_path / "g.gif").read_bytes()),
                       ("a.mp4", _mp4(tmp_path / "m.mp4").read_bytes())):
        path = tmp_path / name
        path.write_bytes(data[:-cut])
        with pytest.raises(BrainPainterError, match="failed"):
            verify_file(path)


def test_wrong_size_and_frame_count_are_caught(tmp_path):
    (tmp_path / "a.png").write_bytes(_png())
    with pytest.raises(BrainPainterError, match="not"):
        verify_file(tmp_path / "a.png", size=(9, 6))
    with pytest.raises(BrainPainterError, match="frames"):
        verify_file(_gif(tmp_path / "a.gif"), frames=6)
    with pytest.raises(BrainPainterError, match="frames"):
        verify_file(_mp4(tmp_path / "a.mp4"), frames=7)
    (tmp_path / "e.png").write_bytes(b"")
    with pytest.raises(BrainPainterError, match="empty"):
        verify_file(tmp_path / "e.png")


def test_damaged_png_chunk_is_caught(tmp_path):
    data = bytearray(_png(64, 64))
    data[60] ^= 0xFF  # inside IDAT: the CRC no longer matches
    (tmp_path / "a.png").write_bytes(bytes(data))
    with pytest.raises(BrainPainterError, match=r"damaged|truncated"):
        verify_file(tmp_path / "a.png")


# -- publishing -------------------------------------------------------------------------------------
def _publish(out: Path, names: list[str], manifest: dict) -> None:
    with FolderTransaction(out) as tx:
        for n in names:
            tx.path(n).write_bytes(_png())
            tx.expect(n, size=(8, 6))
        tx.commit(manifest)


def test_folder_transaction_publishes_all_and_the_manifest_last(tmp_path):
    out = tmp_path / "out"
    _publish(out, ["a.png", "b.png"], {"files": ["a.png", "b.png"]})
    assert sorted(p.name for p in out.iterdir()) == ["a.png", "b.png", "manifest.json"]
    assert json.loads((out / "manifest.json").read_text()) == {"files": ["a.png", "b.png"]}


def test_an_error_publishes_nothing_and_removes_a_new_folder(tmp_path):
    out = tmp_path / "new" / "out"
    with pytest.raises(RuntimeError), FolderTransaction(out) as tx:
        tx.path("a.png").write_bytes(_png())
        tx.expect("a.png")
        raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []


def test_a_failed_verification_keeps_the_previous_output(tmp_path):
    out = tmp_path / "out"
    _publish(out, ["a.png"], {"run": 1})
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    with pytest.raises(BrainPainterError, match="truncated"), FolderTransaction(out) as tx:
        tx.path("a.png").write_bytes(_png()[:-5])
        tx.expect("a.png")
        tx.commit({"run": 2})
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_publishing_cut_short_leaves_no_stale_manifest(tmp_path, monkeypatch):
    out = tmp_path / "out"
    _publish(out, ["a.png", "b.png"], {"run": 1})
    real = os.replace
    calls = []

    def flaky(src, dst):
        calls.append(dst)
        if len(calls) == 2:
            raise OSError(28, "No space left on device")
        real(src, dst)

    monkeypatch.setattr(os, "replace", flaky)
    with pytest.raises(BrainPainterError, match="disk is full"):
        _publish(out, ["a.png", "b.png"], {"run": 2})
    assert not (out / "manifest.json").exists()  # a.png is new, b.png old: no manifest may describe them


def test_non_finite_manifest_is_refused_before_publishing(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(BrainPainterError, match="not a finite number"):
        _publish(out, ["a.png"], {"zoom": float("nan")})
    assert not out.exists()


def test_file_transaction(tmp_path):
    target = tmp_path / "fig.png"
    with FileTransaction(target) as tx:
        tx.tmp.write_bytes(_png())
        tx.commit(size=(8, 6))
    assert target.read_bytes() == _png() and sorted(os.listdir(tmp_path)) == ["fig.png"]
    with pytest.raises(BrainPainterError), FileTransaction(target) as tx:
        tx.tmp.write_bytes(b"\x89PNG")
        tx.commit()
    assert target.read_bytes() == _png() and sorted(os.listdir(tmp_path)) == ["fig.png"]


def test_stale_staging_folders_are_removed_by_the_next_run(tmp_path):
    out = tmp_path / "out"
    (out / ".brainpainter-staging-dead").mkdir(parents=True)
    (out / ".brainpainter-staging-dead" / "x.png").write_bytes(b"x")
    _publish(out, ["a.png"], {"run": 1})
    assert sorted(p.name for p in out.iterdir()) == ["a.png", "manifest.json"]


def test_lock_is_exclusive(tmp_path):
    out = tmp_path / "out"
    with FolderTransaction(out), pytest.raises(BrainPainterError, match="in use by another"):
        with FolderTransaction(out):
            pass


def test_template_folder_rules(tmp_path, monkeypatch):
    from brainpainter.io.transaction import replace_folder

    def ours(p: Path) -> bool:
        return (p / "mine").is_file()

    monkeypatch.chdir(tmp_path)
    target = tmp_path / "t"
    target.mkdir()
    (target / "mine").write_text("old")
    with replace_folder(target, ours, "template folder", "") as stage:
        (stage / "mine").write_text("new")
    assert (target / "mine").read_text() == "new" and sorted(os.listdir(tmp_path)) == ["t"]
    (tmp_path / "user").mkdir()
    (tmp_path / "user" / "data.csv").write_text("keep")
    with pytest.raises(BrainPainterError, match="not made by brainpainter"):
        with replace_folder(tmp_path / "user", ours, "template folder", ""):
            pass
    assert (tmp_path / "user" / "data.csv").read_text() == "keep"
    with pytest.raises(BrainPainterError, match="current folder"):
        with replace_folder(Path(""), ours, "template folder", ""):
            pass


# -- bounded memory for GIFs -------------------------------------------------------------------------------
def test_gif_memory_does_not_grow_with_frames(tmp_path):
    from brainpainter.media.movie import _GifWriter

    size = (320, 240)
    frame = np.random.default_rng(2).integers(0, 255, (size[1], size[0], 3), dtype=np.uint8)

    def peak(n: int) -> int:
        writer = _GifWriter(tmp_path / f"{n}.gif", size, 25.0, (255, 255, 255), [frame])
        tracemalloc.start()
        for _ in range(n):
            writer.write(frame)
        writer.close()
        _, top = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        assert gif_info(tmp_path / f"{n}.gif") == (size, n)
        return top

    small, large = peak(5), peak(60)
    frame_bytes = frame.nbytes
    assert large < small + 2 * frame_bytes  # 55 more frames cost (almost) nothing: frames are not kept
    assert not hasattr(_GifWriter, "frames")


# -- the CLI guard -------------------------------------------------------------------------------------------
def test_sigterm_cleans_up_and_exits_143(tmp_path, monkeypatch, tiny):
    from brainpainter.cli.guard import Terminated, run
    from brainpainter.cli.main import cli
    from brainpainter.testing import StandInRenderer, stand_in

    dies = StandInRenderer.with_(fail=lambda n: Terminated() if n == 2 else None)  # SIGTERM at image 2
    (tmp_path / "in.csv").write_text("Image-name-unique,Left-insula\na,1\nb,2\nc,3\n")
    monkeypatch.chdir(tmp_path)
    with stand_in("dies", dies), CliRunner().isolation() as (_out, err, _):
        code = run(cli, ["render", "in.csv", "--out", "o", "--renderer", "dies", "--template", str(tiny),
                         "--views", "lateral-left", "--size", "16x16", "-q"])
    assert code == 143
    assert err.getvalue().decode().strip().startswith("terminated")
    assert not (tmp_path / "o").exists()


def test_internal_error_is_one_line(monkeypatch):
    import click

    from brainpainter.cli.guard import run

    @click.command()
    def boom() -> None:
        raise ZeroDivisionError("x" * 5000)

    with CliRunner().isolation() as (_out, err, _):
        code = run(boom, [])
    text = err.getvalue().decode()
    assert code == 1 and len(text.strip().splitlines()) == 1 and len(text) < 600


def test_check_and_render_agree_on_every_check_case(tmp_path, monkeypatch, tiny):
    """Every table 'check' refuses, 'render' refuses with the same line (one shared validation)."""
    from bad_inputs import corpus

    from brainpainter.cli.guard import run
    from brainpainter.cli.main import cli
    from brainpainter.testing import stand_in

    cases = [c for c in corpus.CASES if c.command == "check" and not c.env and c.id != "50-MB-file"]
    assert len(cases) > 40
    for case in cases:
        folder = tmp_path / case.id
        corpus.write(case, folder)
        monkeypatch.chdir(folder)
        answers = []
        for command in (["check"], ["render", "--out", "o", "--renderer", "solid", "--template", str(tiny),
                                    "--views", "lateral-left", "--size", "16x16", "-q"]):
            with stand_in("solid"), CliRunner().isolation() as (_out, err, _):
                code = run(cli, [command[0], *case.args, *command[1:]])
            answers.append((code, err.getvalue().decode().strip()))
        assert answers[0] == answers[1], case.id
        assert not (folder / "o").exists(), case.id


def test_a_cycle_of_group_atlases_is_one_short_line(tmp_path, monkeypatch):
    from brainpainter.atlas import registry
    from brainpainter.atlas.user import atlases_dir
    from brainpainter.cli.guard import run
    from brainpainter.cli.main import cli

    for name, base in (("aa", "bb"), ("bb", "aa")):
        folder = atlases_dir() / name
        folder.mkdir(parents=True)
        (folder / "atlas.toml").write_text(f'[atlas]\nbase = "{base}"\n[groups]\nf = ["insula"]\n')
    (tmp_path / "in.csv").write_text("Image-name-unique,Left-f\nA,1\n")
    monkeypatch.chdir(tmp_path)
    registry.atlases.reset()
    try:
        with CliRunner().isolation() as (_out, err, _):
            code = run(cli, ["check", "in.csv", "--atlas", "aa"])
    finally:
        registry.atlases.reset()
    line = err.getvalue().decode().strip()
    assert code == 2 and len(line.splitlines()) == 1 and len(line) < 600, line
    assert "leads back to this atlas" in line


@pytest.mark.render
def test_real_render_writes_nothing_outside_the_output_folder(tmp_path):
    """Blender and matplotlib caches go to the run's temporary folder, which is removed; only
    brainpainter's own cache folder (the installed plugins, Mesa's compiled shaders) is kept."""
    import subprocess
    import sys

    home, tmp = tmp_path / "home", tmp_path / "tmp"
    home.mkdir()
    tmp.mkdir()
    (tmp_path / "a.csv").write_text("Image-name-unique,Left-insula\nA,1\n")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("XDG_", "MPLCONFIGDIR", "BLENDER_USER"))}
    proc = subprocess.run([sys.executable, "-m", "brainpainter", "render", "a.csv", "--out", "out", "--views",
                           "lateral-left", "--size", "160x120", "--quality", "fast", "-q"], cwd=tmp_path,
                          env={**env, "HOME": str(home), "TMPDIR": str(tmp)}, capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr
    kept = home / ".cache" / "brainpainter"
    assert {p for p in home.rglob("*") if not p.is_relative_to(kept)} == {home / ".cache"}
    assert (kept / "entry-points.json").is_file() and any((kept / "mesa-shaders").rglob("*"))
    assert list(tmp.rglob("*")) == []
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["A_lateral-left.png", "manifest.json"]


@pytest.mark.parametrize(("function", "kwargs", "message"), [
    ("render", {"width": float("nan")}, "between 16 and 8192 pixels"),
    ("render", {"height": float("inf")}, "between 16 and 8192 pixels"),
    ("render", {"vmin": float("nan")}, "finite"),
    ("render", {"center": float("inf")}, "finite"),
    ("render", {"glass_opacity": float("nan")}, "glass opacity"),
    ("render", {"views": ["camera:nan:0"]}, "azimuth"),
    ("figure", {"font_size": float("nan")}, "font size"),
    ("figure", {"fig_width": float("inf")}, "font size"),
    ("figure", {"dpi": float("nan")}, "dpi"),
    ("movie", {"fps": float("nan")}, "fps"),
    ("movie", {"orbit": float("inf")}, "orbit"),
])
def test_library_api_refuses_non_finite_numbers(tmp_path, function, kwargs, message, tiny):
    from brainpainter.media.figure import make_figure
    from brainpainter.media.movie import make_movie
    from brainpainter.rendering.run import render
    from brainpainter.testing import stand_in

    table = {"A": {"Left-insula": 1.0}, "B": {"Left-insula": 2.0}}
    out = {"render": tmp_path / "o", "figure": tmp_path / "o" / "f.png", "movie": tmp_path / "o" / "m.gif"}
    call = {"render": render, "figure": make_figure, "movie": make_movie}[function]
    with stand_in("solid"), pytest.raises(BrainPainterError, match=message):
        call(table, "dk", out=out[function], template=str(tiny), renderer="solid", progress=False, **kwargs)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("out", ["", "   "])
def test_an_empty_out_is_refused_not_the_current_folder(tmp_path, monkeypatch, out):
    """``render(out="")`` (an unset variable in a script) must not write into the current folder."""
    from brainpainter.io.transaction import FileTransaction, FolderTransaction

    monkeypatch.chdir(tmp_path)
    for make in (FolderTransaction, FileTransaction):
        with pytest.raises(BrainPainterError, match="is empty"):
            make(out)
    assert list(tmp_path.iterdir()) == []
