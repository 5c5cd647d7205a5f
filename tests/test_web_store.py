"""The job store and a worker's job loop, in-process (no server): attempts, re-queueing, expiry, resume."""

from __future__ import annotations

import os
import time

import pytest
from web_support import EXAMPLE

from brainpainter.testing import StandInRenderer, stand_in
from brainpainter.web.options import RenderOptions
from brainpainter.web.store import LimitError, Store, valid_id
from brainpainter.web.worker import PainterCache, drawn_folder, run_job

LIMITS = {"max_per_client": 10, "max_queued": 10}


def submit(store: Store, options: dict | None = None, client: str = "c") -> str:
    opts = RenderOptions(**(options or {"size": "32x24", "views": "lateral-left,subcortical"}))
    return store.submit(client, "images", opts.model_dump(), {}, "ex.csv", EXAMPLE.read_bytes(), 8, **LIMITS)


def test_ids_are_random_hex_and_nothing_else_is_a_path(tmp_path):
    store = Store(tmp_path)
    job_id = submit(store)
    assert valid_id(job_id) and job_id != submit(store)
    for bad in ("..", "../x", "A" * 32, "0" * 31, "0" * 32 + "/", ""):
        assert not valid_id(bad) and store.get(bad) is None
        with pytest.raises(ValueError):
            store.job_dir(bad)


def test_a_stale_attempt_cannot_finish_a_job(tmp_path):
    store = Store(tmp_path)
    job_id = submit(store)
    first = store.claim("w1")
    assert first["attempt"] == 1 and store.claim("w2") is None
    # the server restarts: the running job is queued again under a new attempt
    assert store.requeue(max_attempts=3, ttl_s=60) == [job_id]
    second = store.claim("w2")
    assert second["id"] == job_id and second["attempt"] == 3
    assert not store.progress(job_id, first["attempt"], 1)
    assert not store.finish(job_id, first["attempt"], ["x.png"], 60)  # the old worker is ignored
    assert store.finish(job_id, second["attempt"], ["x.png"], 60)
    assert not store.finish(job_id, second["attempt"], ["x.png"], 60)  # and done only once
    job = store.get(job_id)
    assert job["status"] == "done" and job["completions"] == 1 and job["files"] == ["x.png"]
    assert [e["event"] for e in store.events(job_id)] == ["queued", "started", "requeued", "started", "done"]


def test_a_job_that_keeps_killing_its_worker_fails(tmp_path):
    store = Store(tmp_path)
    job_id = submit(store)
    for _ in range(2):
        store.claim("w")
        store.requeue(worker="w", max_attempts=3, ttl_s=60)
    store.claim("w")
    store.requeue(worker="w", max_attempts=3, ttl_s=60)
    job = store.get(job_id)
    assert job["status"] == "failed" and "stopped its worker" in job["error"]


def test_client_and_queue_limits_store_nothing(tmp_path):
    store = Store(tmp_path)
    opts = RenderOptions().model_dump()
    for _ in range(2):
        store.submit("a", "images", opts, {}, "t.csv", b"x", 1, max_per_client=2, max_queued=3)
    with pytest.raises(LimitError) as exc:
        store.submit("a", "images", opts, {}, "t.csv", b"x", 1, max_per_client=2, max_queued=3)
    assert exc.value.status == 429
    store.submit("b", "images", opts, {}, "t.csv", b"x", 1, max_per_client=2, max_queued=3)
    with pytest.raises(LimitError) as exc:
        store.submit("c", "images", opts, {}, "t.csv", b"x", 1, max_per_client=2, max_queued=3)
    assert exc.value.status == 503
    assert len(list((tmp_path / "jobs").iterdir())) == 3 and sum(store.counts().values()) == 3


def test_expired_results_and_uploads_are_deleted(tmp_path):
    store = Store(tmp_path)
    job_id = submit(store)
    job = store.claim("w")
    (store.job_dir(job_id) / "out" / "a.png").write_bytes(b"png")
    store.finish(job_id, job["attempt"], ["a.png"], ttl_s=10)
    upload_id = store.add_upload("c", "t.csv", b"data", ttl_s=10)
    assert store.get_upload(upload_id) == ("t.csv", b"data")
    assert store.expire(time.time() + 5) == 0
    assert store.expire(time.time() + 20) == 2
    assert not store.job_dir(job_id).exists() and store.get(job_id)["status"] == "expired"
    assert store.get_upload(upload_id) is None and not store.upload_path(upload_id).exists()


def test_worker_resumes_a_requeued_job_without_redrawing_what_exists(tmp_path):
    store = Store(tmp_path)
    job_id = submit(store)
    with stand_in() as name:
        painters = PainterCache(name)
        job = store.claim("w")
        out = store.job_dir(job_id) / "out"
        # a previous attempt drew 3 of 8 images before its server died
        done_before = ["stage-1_lateral-left.png", "stage-1_subcortical.png", "stage-2_lateral-left.png"]
        import numpy as np

        from brainpainter.io.output import png_bytes

        drawn = drawn_folder(store.job_dir(job_id))
        for n in done_before:
            (drawn / n).write_bytes(png_bytes(np.zeros((24, 32, 4), np.uint8)))
        StandInRenderer.calls = []
        run_job(store, job, painters, ttl_s=60, time_limit_s=60)
        painters.close()
    job = store.get(job_id)
    assert job["status"] == "done" and len(StandInRenderer.calls) == 5
    assert sorted(p.name for p in out.glob("*.png")) == sorted(f for f in job["files"] if f.endswith(".png"))
    assert len([f for f in job["files"] if f.endswith(".png")]) == 8
    assert not drawn.exists()  # published: the drawn folder went


def test_worker_reports_bad_jobs_as_one_line_and_honours_the_time_limit(tmp_path):
    store = Store(tmp_path)
    with stand_in() as name:
        painters = PainterCache(name)
        bad = store.submit("c", "images", {**RenderOptions().model_dump(), "views": "nope"}, {}, "ex.csv",
                           EXAMPLE.read_bytes(), 1, **LIMITS)
        run_job(store, store.claim("w"), painters, ttl_s=60, time_limit_s=60)
        assert store.get(bad)["status"] == "failed" and "'nope' was given" in store.get(bad)["error"]
        slow = submit(store)
        job = store.claim("w")
        job["started"] = time.time() - 100
        run_job(store, job, painters, ttl_s=60, time_limit_s=50)
        painters.close()
    assert store.get(slow)["status"] == "failed" and "limit of 50 s" in store.get(slow)["error"]


def test_serve_command_refuses_a_data_dir_in_use_and_bad_limits(tmp_path):
    import subprocess
    import sys

    from brainpainter.web.folder_lock import lock_data_dir, unlock_data_dir

    data = tmp_path / "data"
    lock_data_dir(data)
    lock_data_dir(data)  # again in the same process: fine
    for args, message in (
        (["--data-dir", str(data)], "another brainpainter serve is using --data-dir"),
        (["--data-dir", str(tmp_path / "other"), "--max-images", "0"], "--max-images must be at least 1"),
        (["--data-dir", str(tmp_path / "other"), "--renderer", "nope"], "nope"),
    ):
        proc = subprocess.run([sys.executable, "-m", "brainpainter", "serve", "--port", "1", *args],
                              capture_output=True, text=True, timeout=120)
        lines = proc.stderr.strip().splitlines()
        assert proc.returncode == 2 and lines[-1].startswith("error: ") and message in lines[-1], proc.stderr
        assert "Traceback" not in proc.stderr
    # the container image gives the data folder (and host, port) as environment variables
    env = {**os.environ, "BRAINPAINTER_SERVE_DATA_DIR": str(data)}
    proc = subprocess.run([sys.executable, "-m", "brainpainter", "serve", "--port", "1"], env=env,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and "another brainpainter serve is using --data-dir" in proc.stderr
    unlock_data_dir(data)
    help_text = subprocess.run([sys.executable, "-m", "brainpainter", "--help"], capture_output=True,
                               text=True, timeout=60).stdout
    assert "serve" in help_text


def test_uploads_per_client_and_old_rows_are_bounded(tmp_path):
    store = Store(tmp_path)
    ids = [store.add_upload("a", "t.csv", b"x", ttl_s=60, keep=3) for _ in range(5)]
    other = store.add_upload("b", "t.csv", b"y", ttl_s=60, keep=3)
    assert [store.get_upload(i) is not None for i in ids] == [False, False, True, True, True]
    assert store.get_upload(other) == ("t.csv", b"y")
    assert len(list((tmp_path / "uploads").iterdir())) == 4
    job_id = submit(store)
    job = store.claim("w")
    store.finish(job_id, job["attempt"], [], ttl_s=1)
    store.expire(time.time() + 2)
    assert store.get(job_id)["status"] == "expired"
    store.expire(time.time() + 31 * 24 * 3600)
    assert store.get(job_id) is None and store.events(job_id) == []


def _visible(folder) -> list[str]:
    """What a listing of `folder` shows (hidden staging folders aside)."""
    return sorted(p.name for p in folder.iterdir() if not p.name.startswith(".")) if folder.exists() else []


def test_an_images_job_publishes_its_folder_whole_through_the_transaction(tmp_path, monkeypatch):
    """The PNGs and the manifest go into out/ together, manifest last, while signals are held."""
    import json

    import numpy as np
    from web_support import png_pixels

    from brainpainter.io import transaction

    store = Store(tmp_path)
    job_id = submit(store)
    out = store.job_dir(job_id) / "out"
    seen: list[list[str]] = []
    real_replace = transaction.os.replace

    def replace(src, dst):  # what out/ holds at each rename into it (the publish)
        if os.path.dirname(dst) == str(out):
            seen.append(_visible(out))
        real_replace(src, dst)

    monkeypatch.setattr(transaction.os, "replace", replace)
    with stand_in() as name:
        painters = PainterCache(name)
        run_job(store, store.claim("w"), painters, ttl_s=60, time_limit_s=60)
        painters.close()
    job = store.get(job_id)
    pngs = sorted(f for f in job["files"] if f.endswith(".png"))
    assert job["status"] == "done" and len(pngs) == 8
    assert _visible(out) == sorted([*pngs, "manifest.json"])  # complete, nothing else
    assert [p.name for p in out.iterdir() if p.name.startswith(".")] == []  # no staging folder left
    assert not (store.job_dir(job_id) / "drawn").exists()
    assert len(seen) == 9 and seen[0] == [] and all("manifest.json" not in s for s in seen)  # manifest last
    manifest = json.loads((out / "manifest.json").read_text())
    assert sorted(e["file"] for e in manifest["files"]) == pngs
    for f in pngs:  # every image drawn: opaque pixels of the stand-in's stripes
        pixels = png_pixels((out / f).read_bytes())
        assert pixels.shape == (24, 32, 4) and (pixels[..., 3] > 0).mean() > 0.5
        assert len(np.unique(pixels.reshape(-1, 4), axis=0)) > 1


def test_a_job_cancelled_midway_leaves_no_output(tmp_path):
    store = Store(tmp_path)
    job_id = submit(store)
    folder = store.job_dir(job_id)

    def cancel_at_third(n: int) -> None:  # the user cancels while the third image is drawn
        if n == 3:
            assert _visible(folder / "out") == []  # nothing is published before the end
            store.cancel(job_id)

    with stand_in("stand-in", StandInRenderer.with_(fail=cancel_at_third)) as name:
        painters = PainterCache(name)
        run_job(store, store.claim("w"), painters, ttl_s=60, time_limit_s=60)
        painters.close()
    assert store.get(job_id)["status"] == "cancelled"
    assert _visible(folder) == ["input.bin"]  # neither out/ nor drawn/


def test_a_job_killed_midway_shows_nothing_then_resumes_and_publishes_whole(tmp_path):
    """kill -9 of the worker while it draws: out/ stays empty; the re-queued job draws only the rest."""
    import signal
    import subprocess
    import sys

    store = Store(tmp_path)
    job_id = submit(store)
    folder = store.job_dir(job_id)
    code = (
        "import sys\n"
        "from brainpainter.testing import StandInRenderer, stand_in\n"
        "from brainpainter.web.store import Store\n"
        "from brainpainter.web.worker import PainterCache, run_job\n"
        "store = Store(sys.argv[1])\n"
        "with stand_in('slow', StandInRenderer.with_(delay=0.4)) as name:\n"
        "    run_job(store, store.claim('w'), PainterCache(name), ttl_s=60, time_limit_s=600)\n"
    )
    proc = subprocess.Popen([sys.executable, "-c", code, str(tmp_path)])
    try:
        drawn = folder / "drawn"
        end = time.monotonic() + 120
        while len(list(drawn.glob("*.png"))) < 3 and time.monotonic() < end and proc.poll() is None:
            time.sleep(0.05)
        assert _visible(folder / "out") == []
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.wait(timeout=60)
    before = len(list(drawn.glob("*.png")))
    assert 3 <= before < 8 and _visible(folder / "out") == []  # a partial set is never in out/
    assert store.get(job_id)["files"] == []
    assert store.requeue(max_attempts=3, ttl_s=60) == [job_id]  # the next server's start
    with stand_in() as name:
        painters = PainterCache(name)
        run_job(store, store.claim("w"), painters, ttl_s=60, time_limit_s=60)
        painters.close()
        assert len(StandInRenderer.calls) == 8 - before
    job = store.get(job_id)
    assert job["status"] == "done"
    assert _visible(folder / "out") == sorted(f for f in job["files"] if not f.endswith(".zip"))
    assert not drawn.exists()


def test_a_figure_job_publishes_one_file_and_a_cancelled_one_nothing(tmp_path):
    """Figure (and movie) jobs write through the figure's file transaction: staged, then renamed."""
    store = Store(tmp_path)
    opts = RenderOptions(size="32x24", views="lateral-left").model_dump()

    def figure_job() -> str:
        params = {"format": "png", "dpi": 50}
        return store.submit("c", "figure", opts, params, "ex.csv", EXAMPLE.read_bytes(), 4, **LIMITS)

    done, cancelled = figure_job(), figure_job()
    during: list[list[str]] = []

    def cancel_second_job_at_its_second_image(n: int) -> None:
        during.append(_visible(store.job_dir(done if n <= 4 else cancelled) / "out"))
        if n == 6:
            store.cancel(cancelled)

    with stand_in("stand-in", StandInRenderer.with_(fail=cancel_second_job_at_its_second_image)) as name:
        painters = PainterCache(name)
        for _ in range(2):
            run_job(store, store.claim("w"), painters, ttl_s=60, time_limit_s=60)
        painters.close()
    assert during and all(seen == [] for seen in during)  # nothing visible while rendering
    assert store.get(done)["status"] == "done" and store.get(done)["files"] == ["figure.png"]
    out = store.job_dir(done) / "out"
    assert sorted(p.name for p in out.iterdir()) == ["figure.png"]  # no staging folder left
    assert (out / "figure.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert store.get(cancelled)["status"] == "cancelled"
    assert _visible(store.job_dir(cancelled)) == ["input.bin"]


def test_a_figure_job_over_its_pixel_limit_when_composed_fails_in_one_line(tmp_path):
    """The layout before rendering estimates the height; the composed figure is checked before its PNG."""
    store = Store(tmp_path)
    opts = RenderOptions(size="32x24", views="lateral-left").model_dump()
    params = {"format": "png", "dpi": 100, "max_pixels": 10_000}
    job_id = store.submit("c", "figure", opts, params, "ex.csv", EXAMPLE.read_bytes(), 4, **LIMITS)
    with stand_in("stand-in", StandInRenderer) as name:
        painters = PainterCache(name)
        run_job(store, store.claim("w"), painters, ttl_s=60, time_limit_s=60)
        painters.close()
    job = store.get(job_id)
    assert job["status"] == "failed" and job["error"].startswith("the figure would be 350x"), job["error"]
    assert "at most 10000 pixels" in job["error"]
    assert _visible(store.job_dir(job_id) / "out") == []


def test_a_job_out_of_memory_fails_in_one_line(tmp_path):
    store = Store(tmp_path)
    job_id = submit(store)

    def no_memory(n: int) -> None:
        raise MemoryError

    with stand_in("stand-in", StandInRenderer.with_(fail=no_memory)) as name:
        painters = PainterCache(name)
        run_job(store, store.claim("w"), painters, ttl_s=60, time_limit_s=60)
        painters.close()
    job = store.get(job_id)
    assert job["status"] == "failed" and job["error"].startswith("the job needs more memory than this server")
