"""The processes that render: job workers and the preview process.

Each process sets ``LP_NUM_THREADS`` (Mesa's rendering threads) before the
renderer loads, keeps up to two warm :class:`~brainpainter.rendering.painter.Painter`\\ s
(the renderer and template load once per process; a new scene only when the atlas,
surface, hidden structures or image settings change); it stops when its server is gone.

A job worker takes queued jobs from the :class:`~brainpainter.web.store.Store`
one at a time. Outputs are published into ``jobs/<id>/out/`` through the
command line's transaction (:mod:`brainpainter.io.transaction`: staged,
verified, renamed into place with the manifest last, signals held meanwhile),
so a job killed or cancelled midway leaves nothing in ``out/`` and a finished
job's folder is complete. An ``images`` job first draws its
``{image}_{view}.png`` files into ``jobs/<id>/drawn/`` (each written
atomically; never served) and skips those already there, so a job re-queued after a crash or
a server restart resumes where it stopped; then the job is marked done (at most once: see the store).
"""

from __future__ import annotations

import os
import shutil
import sys
import time
import traceback
from collections import OrderedDict
from pathlib import Path
from typing import Any

POLL_S = 0.2
OUT_OF_MEMORY = ("the job needs more memory than this server gives one job (--worker-memory-gb); choose "
                 "fewer rows or views, a smaller size, or a lower dpi.")
HEARTBEAT_S = 5.0

#: Job kinds and the output file name stems they make.
KINDS = ("images", "figure", "movie", "export")
#: What a preview request may add to a painter's scene (:meth:`PainterCache.get`).
SCENE_PARTS = ("contours", "layers")


class PainterCache:
    """Up to `size` painters, keyed by everything that needs a new scene; least recently used closes."""

    def __init__(self, renderer: str, size: int = 2) -> None:
        self.renderer = renderer
        self.size = size
        self._painters: OrderedDict[tuple[Any, ...], Any] = OrderedDict()

    def get(self, atlas: Any, surface: str, hidden: list[str], settings: Any,
            coloring: str = "regions", **parts: Any) -> Any:
        """A loaded painter; `coloring` ``"vertices"`` for a map run (a per-vertex scene); `parts`
        (:data:`SCENE_PARTS`: contours, the scene layers) as :class:`~brainpainter.rendering.
        painter.Painter` takes them (part of the key: the contours and each layer by a digest of what
        it draws, the tracts' spec naming content-addressed files: two uploads never share a painter)."""
        from brainpainter.rendering.painter import Painter

        key = painter_key(atlas.name, surface, hidden, settings, coloring, **parts)
        painter = self._painters.get(key)
        if painter is None:
            painter = Painter(atlas, "fsaverage", surface, hidden, settings, self.renderer, coloring=coloring,
                              **parts)
            painter.load()
            self._painters[key] = painter
            while len(self._painters) > self.size:
                self._painters.popitem(last=False)[1].close()
        self._painters.move_to_end(key)
        return painter

    def warm(self, width: int, height: int) -> None:
        """Load the renderer and the default scene (dk, pial, default settings at this size)."""
        from brainpainter.atlas.registry import get_atlas
        from brainpainter.rendering.settings import RenderSettings
        from brainpainter.rendering.views import get_view

        painter = self.get(get_atlas("dk"), "pial", [], RenderSettings(width=width, height=height))
        painter.paint_colors({}, get_view("lateral-left"))

    def close(self) -> None:
        while self._painters:
            self._painters.popitem()[1].close()


def painter_key(atlas: str, surface: str, hidden: list[str], settings: Any, coloring: str = "regions",
                contours: Any = None, layers: Any = ()) -> tuple[Any, ...]:
    """What makes a painter's scene: a cached painter is reused only for the same key."""
    import hashlib

    lines = None if contours is None else (contours.levels, contours.regions, hashlib.sha256(b"".join(
        h.encode() + v.tobytes() for h, v in sorted(contours.values.items()))).hexdigest())
    return (atlas, surface, tuple(sorted(hidden)), settings, coloring, lines,
            tuple((layer.kind, layer.digest()) for layer in layers))


def _orphaned(parent: int) -> bool:
    return os.getppid() != parent


def die_with_parent() -> None:
    """Ask Linux to kill this process when the process that started it dies (``PR_SET_PDEATHSIG``).

    The signal is ``SIGUSR1``, not ``SIGKILL``: Linux sends it when the *thread* that started this
    process ends, so the handler exits only when the parent process is really gone. Elsewhere (or
    when prctl is unavailable) the per-image and per-frame checks of :func:`_orphaned` remain.
    """
    import signal

    parent = os.getppid()

    def _parent_gone(signum: int, frame: Any) -> None:
        if _orphaned(parent):
            os._exit(0)  # nothing more is written: the next server re-queues what this one held

    if not sys.platform.startswith("linux"):
        return
    try:
        import ctypes

        signal.signal(signal.SIGUSR1, _parent_gone)
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, int(signal.SIGUSR1), 0, 0, 0)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError, ValueError):
        return
    if _orphaned(parent):  # the parent died before prctl
        os._exit(0)


def limit_memory(limit: int | None = None) -> None:
    """Bound this process's data memory (``RLIMIT_DATA``) to `limit` bytes (default: a reading process's
    :data:`brainpainter.web.maps.MEMORY_LIMIT`); more raises ``MemoryError``. A no-op where unsupported."""
    try:
        import resource

        _, hard = resource.getrlimit(resource.RLIMIT_DATA)
        from brainpainter.web.maps import MEMORY_LIMIT

        limit = MEMORY_LIMIT if limit is None else limit
        limit = limit if hard == resource.RLIM_INFINITY else min(limit, hard)
        resource.setrlimit(resource.RLIMIT_DATA, (limit, hard))
    except (ImportError, ValueError, OSError):  # not on this platform: the time limit remains
        pass


def _rendering_process(memory: int | None) -> None:
    """Ready a rendering process: at most `memory` bytes of data memory (None: no limit), and tqdm locks
    with a thread lock, not its default multiprocessing lock (a named semaphore that a process stopped by
    its server never removes: the resource tracker then warns of a leaked semaphore at the server's stop;
    one process draws one job at a time)."""
    import threading

    from tqdm import tqdm

    tqdm.set_lock(threading.RLock())
    if memory is not None:
        limit_memory(memory)


def _set_threads(lp_threads: int) -> None:
    """Ready a server process for Blender: llvmpipe's thread count, and no Blender script folders
    inherited on ``sys.path`` (:func:`brainpainter.rendering.parallel.forget_blender_paths`)."""
    from brainpainter.rendering.parallel import forget_blender_paths

    os.environ["LP_NUM_THREADS"] = str(max(1, int(lp_threads)))
    forget_blender_paths()


# -- job worker -------------------------------------------------------------------------
def job_worker_main(data_dir: str, name: str, renderer: str, lp_threads: int, ttl_s: float,
                    time_limit_s: float, warm: bool = True, memory: int | None = None) -> None:
    """Entry point of a job worker process: take jobs until the parent process is gone; `memory`: the
    bytes of data memory it may use (None: no limit)."""
    _set_threads(lp_threads)
    die_with_parent()
    _rendering_process(memory)
    from brainpainter.web.store import Store

    parent = os.getppid()
    store = Store(data_dir)
    store.worker_state(name, os.getpid(), "starting")
    painters = PainterCache(renderer)
    if warm:
        painters.warm(320, 240)
    store.worker_state(name, os.getpid(), "ready")
    last_beat = time.monotonic()
    try:
        while not _orphaned(parent):
            job = store.claim(name)
            if job is None:
                time.sleep(POLL_S)
                if time.monotonic() - last_beat > HEARTBEAT_S:
                    store.worker_state(name, os.getpid(), "ready")
                    last_beat = time.monotonic()
                continue
            store.worker_state(name, os.getpid(), "busy")
            run_job(store, job, painters, ttl_s=ttl_s, time_limit_s=time_limit_s, parent=parent)
            store.worker_state(name, os.getpid(), "ready")
            last_beat = time.monotonic()
    finally:
        painters.close()


class _Stop(Exception):
    """The job was cancelled or given to another attempt, or the server is gone: stop quietly."""


def run_job(store: Any, job: dict[str, Any], painters: PainterCache, *, ttl_s: float, time_limit_s: float,
            parent: int | None = None) -> None:
    """Run one claimed job and record its end (done or failed) under its attempt number."""
    from brainpainter.errors import BrainPainterError

    job_id, attempt = job["id"], job["attempt"]
    started = time.time() if job.get("started") is None else job["started"]

    def tick(done: int, total: int | None = None) -> None:
        """After each image or frame: stop when the server is gone, the job was cancelled or given to
        another attempt, or it ran past its time limit."""
        if parent is not None and _orphaned(parent):
            raise _Stop
        if time.time() - started > time_limit_s:
            raise BrainPainterError(f"the job ran longer than this server's limit of {time_limit_s:g} s; "
                                    "choose fewer rows or views, or a smaller size.")
        if not store.progress(job_id, attempt, done, total):
            raise _Stop

    folder = store.job_dir(job_id)
    try:
        files = _KIND_RUNNERS[job["kind"]](folder, job, painters, tick)
    except _Stop:
        now = store.get(job_id)
        if now is not None and now["status"] == "cancelled":  # cancelled: what was made goes now
            discard_outputs(folder)
        return
    except (BrainPainterError, MemoryError) as exc:
        line = OUT_OF_MEMORY if isinstance(exc, MemoryError) else str(exc).splitlines()[0] if str(exc) else (
            type(exc).__name__)
        if store.fail(job_id, attempt, _no_paths(line, store), ttl_s):  # (a stale attempt touches nothing)
            discard_outputs(folder, published=False)
        return
    except Exception as exc:
        traceback.print_exc(file=sys.stderr)
        line = f"internal error: {type(exc).__name__}: {exc}".splitlines()[0]
        if store.fail(job_id, attempt, _no_paths(line, store), ttl_s):
            discard_outputs(folder, published=False)
        return
    store.finish(job_id, attempt, files, ttl_s)


def _no_paths(message: str, store: Any) -> str:
    """`message` without the server's own paths (clients see job errors): :func:`~brainpainter.web.config.
    no_paths`."""
    from brainpainter.web.config import no_paths

    return no_paths(message, Path(store.root))


def _prepared(folder: Path, job: dict[str, Any]) -> Any:
    from brainpainter.web.layer_uploads import LayerUploads
    from brainpainter.web.options import RenderOptions, prepare

    data = (folder / "input.bin").read_bytes()
    return data, prepare(data, job["input_name"], RenderOptions(**job["options"]),
                         data_dir=folder.parent.parent, **LayerUploads.read(folder).kwargs())


def _media_input(data: bytes, name: str, prep: Any) -> Any:
    """What figure, movie and export read: the table as a named stream, a map's maps, the bundle values of
    tracts alone, or None for a connectome or blobs alone (their files are in the run's keywords)."""
    from brainpainter.web.connectomes import is_connectome_bundle
    from brainpainter.web.maps import is_bundle, read_bundle
    from brainpainter.web.options import table_stream

    if prep.tract_table is not None or is_connectome_bundle(data) or prep.options.volume_surface:
        return None if prep.tract_table is None else str(prep.tract_table)
    return read_bundle(data) if is_bundle(data) else table_stream(data, name)


def _run_images(folder: Path, job: dict[str, Any], painters: PainterCache, tick: Any) -> list[str]:
    from brainpainter import __version__
    from brainpainter.io.output import PngWriter
    from brainpainter.io.transaction import MANIFEST
    from brainpainter.rendering.parallel import SerialRunner
    from brainpainter.rendering.run import layer_summaries, paint, png_metadata, run_settings
    from brainpainter.web.job_zip import zip_name

    data, prep = _prepared(folder, job)
    run = prep.run
    table = run.table
    painter = painters.get(table.atlas, prep.options.surface, prep.hidden, run.settings, prep.coloring,
                           **prep.painter_args())
    settings = run_settings(run, painter)
    plan = run.items(range(len(table.images)))
    names = [f"{prep.file_names[i]}_{view.name}.png" for i, view in plan]
    drawn = drawn_folder(folder)
    # written atomically: a file present is complete (a resumed job)
    todo = [(k, item) for k, item in enumerate(plan) if not (drawn / names[k]).exists()]
    done = len(plan) - len(todo)
    with PngWriter() as writer:
        # the painter stays in the cache: the runner is not closed
        painted = paint(run, SerialRunner(painter=painter), [item for _, item in todo])
        for (k, _), ((i, view), pixels) in zip(todo, painted, strict=True):
            writer.submit(drawn / names[k], pixels, png_metadata(table.images[i], view, settings))
            done += 1
            tick(done)
    entries = [{"file": name, "image": table.images[i], "row": i, "view": view.name}
               for name, (i, view) in zip(names, plan, strict=True)]
    manifest = {"software": {"brainpainter": __version__}, "input": table.summary(), "settings": settings,
                "files": entries}
    manifest.update(layer_summaries(painter))  # tracts and connectome drawn, as render's manifest
    manifest["reproduce"] = _reproduced(folder, job, data, prep)
    publish_drawn(folder, names, manifest, (run.settings.width, run.settings.height))
    # the zip is not stored (it would copy every PNG): it is made while it is downloaded
    return [*names, MANIFEST, zip_name(job["id"])]


# -- writing outputs: the command line's transaction ---------------------------------------------
DRAWN = "drawn"


def drawn_folder(folder: Path) -> Path:
    """``folder/drawn``, made if needed: an ``images`` job's PNGs until they are published.

    It outlives an attempt (a re-queued job resumes from it) and is never served.
    """
    path = folder / DRAWN
    path.mkdir(mode=0o700, exist_ok=True)
    return path


def publish_drawn(folder: Path, names: list[str], manifest: object, size: tuple[int, int]) -> None:
    """Publish the PNGs `names` of ``folder/drawn`` and `manifest` into ``folder/out``, all or nothing.

    Through :class:`~brainpainter.io.transaction.FolderTransaction`, as ``render --out``: the
    PNGs move (a rename, same file system) into its staging folder, every one is verified (a PNG
    of `size` (width, height)), then they are renamed into ``out`` with the manifest last while
    signals wait. ``drawn`` goes once they are published.
    """
    from brainpainter.io.transaction import FolderTransaction

    drawn = folder / DRAWN
    with FolderTransaction(folder / "out") as tx:
        for name in names:
            try:
                os.replace(drawn / name, tx.path(name))
            except OSError as exc:
                from brainpainter.io.folders import os_error

                raise os_error(exc, "cannot stage", drawn / name) from None
            tx.expect(name, size=size)
        tx.commit(manifest)
    shutil.rmtree(drawn, ignore_errors=True)


def discard_outputs(folder: Path, published: bool = True) -> None:
    """Remove what a job drew (``drawn``) and, when `published`, what it published (``out``)."""
    for sub in (DRAWN, "out") if published else (DRAWN,):
        shutil.rmtree(folder / sub, ignore_errors=True)


def _reproduced(folder: Path, job: dict[str, Any], data: bytes, prep: Any) -> dict[str, str]:
    """The command line and Python call that make a job's files again (its manifest's ``reproduce``)."""
    from brainpainter.web.layer_uploads import LayerUploads
    from brainpainter.web.reproduce import reproduce

    layers = LayerUploads.read(folder)
    params = dict(job["params"])
    if job["kind"] == "export":  # the command names the row by its image name
        params["image"] = prep.run.table.images[params.get("row", 0)]
    return reproduce(data, job["input_name"], prep.options, layers.tracts, job["kind"], params,
                     **{k: v for k, v in layers.kwargs().items() if k != "tracts"})


def _media_manifest(folder: Path, job: dict[str, Any], data: bytes, prep: Any, name: str) -> list[str]:
    """Write a figure's or movie's ``manifest.json`` beside it (what was made, and the command that makes it
    again); the job's files."""
    from brainpainter import __version__
    from brainpainter.io.output import write_json
    from brainpainter.io.transaction import MANIFEST

    write_json(folder / "out" / MANIFEST, {
        "software": {"brainpainter": __version__}, "input": job["input_name"], "file": name,
        "options": job["options"], job["kind"]: job["params"],
        "reproduce": _reproduced(folder, job, data, prep)})
    return [name, MANIFEST]


def _media_kwargs(prep: Any, renderer: str) -> dict[str, Any]:
    kwargs: dict[str, Any] = dict(prep.kwargs)  # the run's options (tract files included)
    kwargs.update(atlas=prep.run.table.atlas, hide=prep.hidden, surface=prep.options.surface,
                  renderer=renderer, progress=False)
    return kwargs


def _run_figure(folder: Path, job: dict[str, Any], painters: PainterCache, tick: Any) -> list[str]:
    from brainpainter.media.figure import make_figure, save_figure
    from brainpainter.rendering.kept import release
    from brainpainter.web.job_plan import check_figure_pixels
    from brainpainter.web.maps import figure_panels
    from brainpainter.web.options import FigureParams

    data, prep = _prepared(folder, job)
    p = dict(job["params"])
    max_pixels = p.pop("max_pixels", None)  # the server's limit when the job was queued (PNG only)
    name = f"figure.{p.get('format', 'pdf')}"
    tick(0)
    params = FigureParams(**p)  # the CLI's defaults for what the job did not give
    panels = figure_panels(params, data, prep.options.volume_surface)
    try:
        made = make_figure(_media_input(data, job["input_name"], prep), grid=params.grid,
                           title=params.title or None, label=params.label or None, dpi=params.dpi,
                           fig_width=params.fig_width, font_size=params.font_size, on_progress=tick,
                           **panels, **_media_kwargs(prep, painters.renderer))
    finally:
        release()  # the worker's painters are its cache's (bounded); a figure keeps none beside them
    if max_pixels is not None:  # composed now: its real size, before the PNG is drawn
        w, h = (round(x) for x in made.figure.get_size_inches() * params.dpi)
        check_figure_pixels(w, h, max_pixels)
    save_figure(made.figure, folder / "out" / name, params.dpi,
                transparent=prep.run.settings.background is None)
    return _media_manifest(folder, job, data, prep, name)


def _run_movie(folder: Path, job: dict[str, Any], painters: PainterCache, tick: Any) -> list[str]:
    from brainpainter.media.movie import make_movie
    from brainpainter.web.options import MovieParams

    data, prep = _prepared(folder, job)
    p = job["params"]
    name = f"movie.{p.get('format', 'mp4')}"
    tick(0)
    params = MovieParams(**p)  # the CLI's defaults for what the job did not give
    kwargs = _media_kwargs(prep, painters.renderer)  # progress: per frame (on_progress), not 0/1
    make_movie(_media_input(data, job["input_name"], prep), out=folder / "out" / name,
               frames_per_step=params.frames_per_step, easing=params.easing, hold=params.hold, fps=params.fps,
               clip_sweep=params.clip_sweep or None, title=params.title or None, label=params.label or None,
               on_progress=tick, **kwargs)
    return _media_manifest(folder, job, data, prep, name)


def _run_export(folder: Path, job: dict[str, Any], painters: PainterCache, tick: Any) -> list[str]:
    """One row as an interactive 3D page (``brainpainter export --format html``): no renderer."""
    from brainpainter.media.export import EXPORT_OPTIONS, export
    from brainpainter.web.options import ExportParams

    data, prep = _prepared(folder, job)
    params = ExportParams(**job["params"])
    name = f"{prep.file_names[params.row]}.html"
    tick(0)
    kwargs = {k: v for k, v in prep.kwargs.items() if k in EXPORT_OPTIONS}
    export(_media_input(data, job["input_name"], prep), folder / "out" / name, format="html", row=params.row,
           atlas=prep.run.table.atlas, title=params.title or None, **{**kwargs, "hide": prep.hidden})
    return _media_manifest(folder, job, data, prep, name)


_KIND_RUNNERS = {"images": _run_images, "figure": _run_figure, "movie": _run_movie, "export": _run_export}


# -- preview process ----------------------------------------------------------------------
def preview_main(conn: Any, renderer: str, lp_threads: int, warm_size: tuple[int, int],
                 memory: int | None = None) -> None:
    """Entry point of the preview process: answer render requests on `conn` until the parent is gone.

    A request is ``{"atlas", "surface", "hidden", "settings", "colors", "view", "coloring"}``
    (``colors`` a :class:`~brainpainter.rendering.geometry.VertexColors` when ``coloring`` is
    ``"vertices"``); the answer is
    ``("ok", png_bytes, milliseconds)`` or ``("error", one_line_message, 0)``; `memory`: the bytes of
    data memory the process may use (None: no limit).
    """
    _set_threads(lp_threads)
    die_with_parent()
    _rendering_process(memory)
    from brainpainter.atlas.registry import get_atlas
    from brainpainter.errors import BrainPainterError
    from brainpainter.io.output import png_bytes

    parent = os.getppid()
    painters = PainterCache(renderer)
    try:
        painters.warm(*warm_size)
        conn.send(("ready", b"", 0))
        while not _orphaned(parent):
            if not conn.poll(1.0):
                continue
            try:
                req = conn.recv()
            except EOFError:
                break
            t0 = time.perf_counter()
            try:
                atlas = get_atlas(req["atlas"])
                painter = painters.get(atlas, req["surface"], req["hidden"], req["settings"],
                                       req.get("coloring", "regions"),
                                       **{k: req[k] for k in SCENE_PARTS if k in req})
                pixels = painter.paint_colors(req["colors"], req["view"])
                conn.send(("ok", png_bytes(pixels), int((time.perf_counter() - t0) * 1000)))
            except BrainPainterError as exc:
                conn.send(("error", str(exc).splitlines()[0], 0))
            except Exception as exc:
                traceback.print_exc(file=sys.stderr)
                conn.send(("error", f"internal error: {type(exc).__name__}: {exc}", 0))
    finally:
        painters.close()
