"""--jobs and Dask runs give exactly the serial result; options, errors, retries, a killed worker.

Fast tests use stand-in renderers (no Blender) that worker processes import
by name; ``test_real_renderer_*`` renders with Blender, since determinism of
the real renderer across processes is the point.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from brainpainter.cli.main import cli
from brainpainter.errors import BrainPainterError
from brainpainter.rendering.parallel import chunk_size, chunked, drive, resolve_jobs
from brainpainter.rendering.run import render
from brainpainter.testing import StandInRenderer, registered_renderer, stand_in

sys.path.insert(0, str(Path(__file__).parent))  # so that this process and its workers import the module
from _parallel_renderers import FlakyStandIn, SlowStandIn

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "brainpainter_dk.csv"


@pytest.fixture
def table(tmp_path):
    rows = "".join(f"S{i:02d},{i % 4},{(i * 7) % 5},{i / 3:.3f}\n" for i in range(8))
    path = tmp_path / "in.csv"
    path.write_text("Image-name-unique,Left-insula,Right-insula,Left-precuneus\n" + rows)
    return path


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    # not the default client: brainpainter must use the client it is given, not a global one
    with local_cluster(distributed) as c, distributed.Client(c, set_as_default=False) as client:
        yield client


def local_cluster(distributed):
    """Two single-threaded worker processes; every server on loopback, on free ports."""
    return distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                    dashboard_address="127.0.0.1:0")


def same_files(a: Path, b: Path) -> list[str]:
    """File names of `a` and `b` (equal lists asserted) whose bytes differ."""
    names = sorted(p.name for p in a.iterdir())
    assert names == sorted(p.name for p in b.iterdir())
    return [n for n in names if (a / n).read_bytes() != (b / n).read_bytes()]


KW = {"views": "lateral-left,medial-left,subcortical", "width": 40, "height": 30, "progress": False}


# -- options ---------------------------------------------------------------------------
def test_jobs_values():
    assert resolve_jobs(1) == 1 and resolve_jobs("3") == 3 and resolve_jobs(" AUTO ") >= 1
    for bad in (0, -2, "0", "x", 1.5, True, "2.5"):
        with pytest.raises(BrainPainterError, match="--jobs must be a positive whole number"):
            resolve_jobs(bad)


def test_chunks_cover_every_item_once():
    items = list(range(23))
    for workers in (1, 2, 8, 64):
        size = chunk_size(len(items), workers)
        assert 1 <= size <= 8
        assert [x for c in chunked(items, size) for x in c] == items


def test_drive_keeps_order_and_window():
    """Ordered results come in chunk order although chunks finish in any order; at most `window` are out."""
    order = [3, 0, 2, 1, 5, 4]
    pending: list[int] = []
    most = 0

    def submit(chunk):
        pending.append(chunk[0])
        return chunk[0]

    def wait_any(futures):
        nonlocal most
        most = max(most, len(futures))
        return [min(futures, key=order.index)]  # the one that "finishes" first

    chunks = [[i] for i in range(6)]
    got = list(drive(chunks, submit, wait_any, lambda f, c: [f * 10], window=3, ordered=True))
    assert got == [(i, [i * 10]) for i in range(6)]
    assert most <= 3


# -- local processes ----------------------------------------------------------------------
def test_jobs_2_writes_the_serial_files_and_manifest(tmp_path, tiny, table):
    with stand_in() as renderer:
        serial = render(table, "dk", out=tmp_path / "serial", template=str(tiny), renderer=renderer, **KW)
        par = render(table, "dk", out=tmp_path / "jobs", template=str(tiny), renderer=renderer, jobs=2, **KW)
    assert same_files(tmp_path / "serial", tmp_path / "jobs") == []
    assert par.workers["backend"] == "LocalRunner" and par.workers["workers"] == 2
    assert par.manifest == serial.manifest and par.files == [
        tmp_path / "jobs" / p.name for p in serial.files]
    assert len(serial.files) == 24


def test_jobs_in_memory_gives_the_same_arrays_in_the_same_order(tiny, table):
    with stand_in() as renderer:
        serial = render(table, "dk", template=str(tiny), renderer=renderer, **KW)
        par = render(table, "dk", template=str(tiny), renderer=renderer, jobs=2, **KW)
    assert list(par.images) == list(serial.images)
    for key, pixels in serial.images.items():
        assert par.images[key].dtype == np.uint8 and np.array_equal(par.images[key], pixels)
    # the stand-in paints the region colours: the images differ from row to row
    assert not np.array_equal(serial.images[("S00", "lateral-left")], serial.images[("S01", "lateral-left")])


def test_cli_jobs_errors_are_one_line_and_write_nothing(tmp_path, table):
    out = tmp_path / "out"
    for args, msg in ((["--jobs", "0"], "--jobs must be"),
                      (["--jobs", "2", "--scheduler", "tcp://127.0.0.1:1"], "not both")):
        result = CliRunner().invoke(cli, ["render", str(table), "--out", str(out), *args])
        assert result.exit_code != 0
        assert msg in str(result.exception) or msg in result.output
    assert not out.exists()


def test_scheduler_without_dask_names_the_pip_command(tmp_path, table, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # as if not installed
    with pytest.raises(BrainPainterError, match=r"pip install 'brainpainter\[cluster\]'"):
        render(table, "dk", out=tmp_path / "out", scheduler="tcp://127.0.0.1:8786", progress=False)
    monkeypatch.setenv("BRAINPAINTER_SCHEDULER", "tcp://127.0.0.1:8786")
    result = CliRunner().invoke(cli, ["render", str(table), "--out", str(tmp_path / "out")])
    assert isinstance(result.exception, BrainPainterError)
    assert "brainpainter[cluster]" in str(result.exception)
    assert not (tmp_path / "out").exists()


# -- Dask ------------------------------------------------------------------------------------
def test_dask_cluster_writes_the_serial_files_and_manifest(tmp_path, tiny, table, cluster):
    with stand_in() as renderer:
        serial = render(table, "dk", out=tmp_path / "serial", template=str(tiny), renderer=renderer, **KW)
        par = render(table, "dk", out=tmp_path / "dask", template=str(tiny), renderer=renderer,
                     client=cluster, **KW)
        mem = render(table, "dk", template=str(tiny), renderer=renderer, client=cluster, **KW)
    assert same_files(tmp_path / "serial", tmp_path / "dask") == []
    assert par.manifest == serial.manifest and par.workers["backend"] == "DaskRunner"
    assert list(mem.images) == [(f["image"], f["view"]) for f in serial.manifest["files"]]
    for (image, view), pixels in mem.images.items():  # PNG bytes decoded: the exact pixels
        with Image.open(tmp_path / "serial" / f"{image}_{view}.png") as png:
            assert np.array_equal(pixels, np.asarray(png))
    # the run's worker plugin is gone afterwards (its painters closed)
    plugins = cluster.run(lambda dask_worker: sorted(dask_worker.plugins))
    assert not any(name.startswith("brainpainter-") for names in plugins.values() for name in names)


def test_dask_retries_a_failed_task_and_reports_it(tmp_path, tiny, table, cluster, capsys):
    with registered_renderer("flaky", StandInRenderer):  # the same images, named as the flaky one
        serial = render(table, "dk", out=tmp_path / "serial", template=str(tiny), renderer="flaky", **KW)
    with registered_renderer("flaky", FlakyStandIn):
        par = render(table, "dk", out=tmp_path / "dask", template=str(tiny), renderer="flaky",
                     client=cluster, **KW)
    assert par.workers["retried"], "the first task on each worker fails and must be retried"
    assert "retrying" in capsys.readouterr().err
    assert same_files(tmp_path / "serial", tmp_path / "dask") == []
    assert par.manifest["files"] == serial.manifest["files"]


def test_killing_a_dask_worker_mid_run_loses_no_image(tmp_path, tiny, table, cluster):
    rows = "".join(f"S{i:02d},{i % 4},{i % 3},{i}\n" for i in range(24))
    table.write_text("Image-name-unique,Left-insula,Right-insula,Left-precuneus\n" + rows)
    kw = {**KW, "views": "lateral-left"}
    with registered_renderer("slow", StandInRenderer):  # the same images, without the wait
        render(table, "dk", out=tmp_path / "serial", template=str(tiny), renderer="slow", **kw)
    out = tmp_path / "dask"
    killed: list[int] = []
    client = cluster  # its nanny restarts the killed worker for the tests after this one
    with registered_renderer("slow", SlowStandIn):
        pids = client.run(os.getpid)

        def kill_when_started():
            deadline = time.monotonic() + 60
            while time.monotonic() < deadline:
                if out.is_dir() and len(list(out.rglob("*.png"))) >= 2:  # staged, not yet published
                    victim = next(iter(pids.values()))
                    os.kill(victim, signal.SIGKILL)
                    killed.append(victim)
                    return
                time.sleep(0.01)

        killer = threading.Thread(target=kill_when_started)
        killer.start()
        result = render(table, "dk", out=out, template=str(tiny), renderer="slow", client=client, **kw)
        killer.join()
        after = client.run(os.getpid)
    assert killed and killed[0] not in after.values(), "a worker was killed mid-run"
    assert result.workers["workers"] >= 1
    assert len(list(out.glob("*.png"))) == 24
    assert same_files(tmp_path / "serial", out) == []
    assert len(result.files) == 24


# -- the real renderer ---------------------------------------------------------------------
def test_tracts_travel_to_jobs_and_dask_workers(tmp_path, tiny, cluster):
    from test_tracts import bundle, write

    folder = tmp_path / "bundles"
    folder.mkdir()
    write(folder / "AF_L.trk", bundle(-25.0))
    write(folder / "CST_R.tck", bundle(25.0, seed=1))
    table = tmp_path / "t.csv"
    table.write_text("Image-name-unique,Left-insula,Right-insula,AF_L,CST_R\n"
                     + "".join(f"S{i},{i},{4 - i},{(i * 3) % 5},{i % 2 * 4}\n" for i in range(4)))
    kw = {**KW, "views": "lateral-left,subcortical", "tracts": [str(folder)], "tracts_space": "template",
          "vmin": 0, "vmax": 4, "cortex": "glass"}  # the insulas carry values: auto would be opaque
    with stand_in() as renderer:
        serial = render(table, "dk", out=tmp_path / "serial", template=str(tiny), renderer=renderer, **kw)
        render(table, "dk", out=tmp_path / "jobs", template=str(tiny), renderer=renderer, jobs=2, **kw)
        render(table, "dk", out=tmp_path / "dask", template=str(tiny), renderer=renderer, client=cluster,
               **kw)
        opaque = render(table, "dk", template=str(tiny), renderer=renderer, **{**kw, "cortex": "opaque"})
    assert same_files(tmp_path / "serial", tmp_path / "jobs") == []
    assert same_files(tmp_path / "serial", tmp_path / "dask") == []
    assert len(serial.files) == 8
    # the workers drew the bundles: in the subcortical view and through the glass cortex of lateral-left
    with Image.open(tmp_path / "jobs" / "S1_lateral-left.png") as png:
        assert not np.array_equal(np.asarray(png), opaque.images[("S1", "lateral-left")])
    with Image.open(tmp_path / "dask" / "S1_subcortical.png") as png:
        drawn = {tuple(c) for c in np.asarray(png)[0, :, :3]}
    af = tuple(round(255 * float(c)) for c in serial.scale(np.array([3.0]))[0][:3])
    assert af in drawn  # AF_left's value 3 on the scale


@pytest.mark.render
@pytest.mark.integration
def test_real_renderer_jobs_and_dask_are_byte_identical_to_serial(tmp_path, cluster):
    kw = {"views": "lateral-left,subcortical", "width": 96, "height": 72, "progress": False}
    # two rows of the example (stage-1, stage-4) keep it short
    lines = EXAMPLE.read_text().splitlines()
    data = tmp_path / "two.csv"
    data.write_text("\n".join([lines[0], lines[1], lines[4]]) + "\n")
    serial = render(data, "dk", out=tmp_path / "serial", **kw)
    render(data, "dk", out=tmp_path / "jobs", jobs=2, **kw)
    render(data, "dk", out=tmp_path / "dask", client=cluster, **kw)
    assert same_files(tmp_path / "serial", tmp_path / "jobs") == []
    assert same_files(tmp_path / "serial", tmp_path / "dask") == []
    # and they are real renders: a brain on white, stage-4 redder than stage-1
    early = np.asarray(Image.open(tmp_path / "jobs" / "stage-1_lateral-left.png"))[..., :3].astype(int)
    late = np.asarray(Image.open(tmp_path / "dask" / "stage-4_lateral-left.png"))[..., :3].astype(int)
    brain = (early < 245).any(axis=-1)
    assert 0.2 < brain.mean() < 0.9
    redness = [float(((im[..., 0] - im[..., 2]) * brain).sum() / brain.sum()) for im in (early, late)]
    assert redness[1] > redness[0]
    assert len(serial.files) == 4


def test_ctrl_c_stops_every_worker_process(tmp_path, tiny, table):
    """SIGINT to the parent (workers ignore it): the run stops at once and no worker is left behind."""
    psutil = pytest.importorskip("psutil")
    rows = "".join(f"S{i:02d},{i % 4},{i % 3},{i}\n" for i in range(200))
    table.write_text("Image-name-unique,Left-insula,Right-insula,Left-precuneus\n" + rows)
    out = tmp_path / "out"
    # Ctrl-C as a terminal delivers it: a test run started in the background (``pytest &``, some CI
    # runners) passes SIGINT on ignored, and Python then leaves it ignored, so the run went on to exit 0.
    script = (
        "import signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "sys.path.insert(0, sys.argv[1])\n"
        "from _parallel_renderers import SlowStandIn\n"
        "from brainpainter.rendering.run import render\n"
        "from brainpainter.testing import registered_renderer\n"
        "if __name__ == '__main__':\n"
        "    with registered_renderer('slow', SlowStandIn):\n"
        "        render(sys.argv[2], 'dk', out=sys.argv[3], template=sys.argv[4], renderer='slow', jobs=2,\n"
        "               views='lateral-left', width=40, height=30, progress=False)\n"
    )
    proc = subprocess.Popen([sys.executable, "-c", script, str(Path(__file__).parent), str(table), str(out),
                             str(tiny)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not (out.is_dir() and len(list(out.rglob("*.png"))) >= 2):
        time.sleep(0.05)
    workers = psutil.Process(proc.pid).children(recursive=True)
    assert len(workers) >= 2
    proc.send_signal(signal.SIGINT)
    t0 = time.monotonic()
    _, err = proc.communicate(timeout=60)
    assert proc.returncode != 0 and "KeyboardInterrupt" in err
    assert time.monotonic() - t0 < 15  # not after the remaining ~200 images
    assert not list(out.rglob("*.png")) and not (out / "manifest.json").exists()  # nothing published
    psutil.wait_procs(workers, timeout=10)
    assert not [w.pid for w in workers if w.is_running() and w.status() != psutil.STATUS_ZOMBIE]


def test_figure_and_movie_with_jobs_match_serial(tmp_path, tiny, table):
    from brainpainter.media.figure import make_figure
    from brainpainter.media.movie import make_movie

    kw = {"template": str(tiny), "views": "lateral-left,subcortical", "width": 40, "height": 30,
          "progress": False}
    with stand_in() as renderer:
        fig = make_figure(table, "dk", renderer=renderer, rows="S01,S03,S02", **kw)
        fig2 = make_figure(table, "dk", renderer=renderer, rows="S01,S03,S02", jobs=2, **kw)
        movie = dict(rows="S00,S05,S07", frames_per_step=4, hold=2, **kw)
        a = make_movie(table, "dk", out=tmp_path / "serial.gif", renderer=renderer, **movie)
        b = make_movie(table, "dk", out=tmp_path / "jobs.gif", renderer=renderer, jobs=2, **movie)
    assert list(fig2.images) == list(fig.images)
    assert all(np.array_equal(fig2.images[k], v) for k, v in fig.images.items())
    assert a.n_frames == b.n_frames == 2 * 4 + 1 + 3 * 2
    # frames rendered in parallel, encoded in order: the same file
    assert (tmp_path / "jobs.gif").read_bytes() == (tmp_path / "serial.gif").read_bytes()
