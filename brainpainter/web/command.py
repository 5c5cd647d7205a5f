"""The ``serve`` command (registered on the ``brainpainter`` group in cli.py). Only click loads here."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from brainpainter.errors import BrainPainterError

CONTEXT = {"help_option_names": ["-h", "--help"], "max_content_width": 100}


@click.command(context_settings=CONTEXT)
@click.option("--host", default="127.0.0.1", show_default=True, envvar="BRAINPAINTER_SERVE_HOST",
              show_envvar=True, help="Address to listen on (0.0.0.0: every interface, e.g. a lab server).")
@click.option("--port", default=8000, show_default=True, type=click.IntRange(0, 65535),
              envvar="BRAINPAINTER_SERVE_PORT", show_envvar=True)
@click.option("--data-dir", type=click.Path(path_type=Path, file_okay=False), default=None,
              envvar="BRAINPAINTER_SERVE_DATA_DIR", show_envvar=True,
              help="Where jobs, uploads and results are kept (default: the user data folder).")
@click.option("--workers", default=1, show_default=True, type=click.IntRange(0, 64),
              help="Rendering worker processes (each holds a warm renderer, ~0.6 GB).")
@click.option("--no-preview", is_flag=True, help="No live-preview process (saves one renderer's memory).")
@click.option("--renderer", default="blender", show_default=True)
@click.option("--max-upload-mb", type=float, default=10.0, show_default=True, help="Largest upload.")
@click.option("--max-images", type=int, default=600, show_default=True, help="Largest rows x views of a job.")
@click.option("--max-jobs-per-client", type=int, default=4, show_default=True,
              help="Queued or running jobs one client (IP address) may have.")
@click.option("--max-queued", type=int, default=100, show_default=True,
              help="Queued jobs in all; beyond it new jobs get 503 (try later).")
@click.option("--rate", "rate_per_minute", type=int, default=240, show_default=True,
              help="Uploads, previews and job requests per client and minute.")
@click.option("--job-time-limit", "job_time_limit_s", type=float, default=1800.0, show_default=True,
              help="Seconds a job may run.")
@click.option("--keep-results", "result_ttl_s", type=float, default=86400.0, show_default=True,
              help="Seconds results and uploads are kept.")
@click.option("--max-rows", type=int, default=20_000, show_default=True,
              help="Largest number of table rows in one upload.")
@click.option("--max-map-images", type=int, default=100, show_default=True,
              help="Largest number of images in one map upload (volumes of a 4-D NIfTI, GIfTI arrays).")
@click.option("--max-tract-streamlines", type=int, default=1_000_000, show_default=True,
              help="Largest number of streamlines in one tract upload (a hard cap; fewer are drawn).")
@click.option("--max-tract-files", type=int, default=100, show_default=True,
              help="Largest number of files (bundles) in one tract upload.")
@click.option("--max-pixels", type=int, default=2400 * 1800, show_default=True,
              help="Largest width x height of one rendered view.")
@click.option("--max-figure-pixels", type=int, default=40_000_000, show_default=True,
              help="Largest width x height of a figure job's PNG (refused before it is queued).")
@click.option("--worker-memory-gb", type=float, default=4.0, show_default=True,
              help="Data memory each rendering process may use; a job needing more fails (0: no limit).")
@click.option("--max-disk-gb", type=float, default=0.0, show_default=True,
              help="Disk the data folder may use; beyond it new uploads and jobs get 507 (0: no budget).")
@click.option("--max-connections", type=click.IntRange(1, 100_000), default=500, show_default=True,
              help="Open connections; beyond it new requests get 503.")
@click.option("--forwarded-allow-ips", default=None, metavar="IPS",
              help="Behind a reverse proxy: the proxy's address(es), comma-separated; only then is "
                   "X-Forwarded-For trusted to name the client. Without it the client is the connection's "
                   "address.")
@click.option("--log-level", default="info", show_default=True,
              type=click.Choice(["debug", "info", "warning", "error"]))
def serve(host: str, port: int, data_dir: Path | None, workers: int, no_preview: bool, renderer: str,
          log_level: str, max_connections: int, forwarded_allow_ips: str | None, **limits: Any) -> None:
    """Serve the web page and JSON API: upload a table, check it, preview it, render it.

    \b
    Open http://127.0.0.1:8000/ in a browser. The API schema is at /openapi.json;
    /healthz and /readyz are for monitoring. Jobs survive a restart (they are
    kept in DATA_DIR/jobs.sqlite3 and re-queued).
    """
    import json
    import logging
    import math
    import os

    try:
        import uvicorn  # noqa: F401 - fails here when missing

        from brainpainter.web.app import create_app
        from brainpainter.web.config import ServerConfig, default_data_dir
    except ImportError as exc:  # pragma: no cover - core dependencies
        raise BrainPainterError(f"serve needs FastAPI and uvicorn ({exc}); "
                                "pip install fastapi uvicorn") from None
    for key in ("max_images", "max_jobs_per_client", "max_queued", "rate_per_minute", "max_rows",
                "max_map_images", "max_tract_streamlines", "max_tract_files", "max_pixels",
                "max_figure_pixels"):
        if limits[key] < 1:
            raise BrainPainterError(f"--{key.replace('_', '-')} must be at least 1; {limits[key]} was given.")
    for key in ("max_upload_mb", "job_time_limit_s", "result_ttl_s", "max_disk_gb", "worker_memory_gb"):
        value = limits[key]
        if not math.isfinite(value) or value < 0 or (value == 0 and key not in ("max_disk_gb",
                                                                                "worker_memory_gb")):
            option = {"job_time_limit_s": "job-time-limit", "result_ttl_s": "keep-results"}.get(
                key, key.replace("_", "-"))
            raise BrainPainterError(f"--{option} must be a positive number; {value} was given.")
    config = ServerConfig(data_dir=data_dir or default_data_dir(), workers=workers, preview=not no_preview,
                          renderer=renderer, **limits)
    from brainpainter.atlas import registry
    registry.renderers.get(renderer)  # an unknown renderer fails now, with the CLI's message
    try:
        config.data_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise BrainPainterError(f"--data-dir {str(config.data_dir)!r} cannot be created ({exc.strerror}); "
                                "choose a writable folder.") from None
    from brainpainter.web.folder_lock import lock_data_dir

    lock_data_dir(config.data_dir)  # one server per data folder (held until this process ends)
    os.umask(0o077)  # uploads, results and the database: this user only (the workers inherit it)
    os.chmod(config.data_dir, 0o700)
    cache = config.data_dir / "cache"
    cache.mkdir(mode=0o700, exist_ok=True)
    # matplotlib's and other caches go under the data folder, not the user's home
    os.environ["MPLCONFIGDIR"] = str(cache / "matplotlib")
    os.environ["XDG_CACHE_HOME"] = str(cache)
    level = getattr(logging, log_level.upper())
    handler = logging.StreamHandler()  # uvicorn configures its own loggers; ours log one line per record
    handler.setFormatter(logging.Formatter("%(message)s"))
    web_log = logging.getLogger("brainpainter.web")
    web_log.setLevel(level)
    web_log.addHandler(handler)
    web_log.propagate = False
    shown_host = host if host not in ("0.0.0.0", "::", "") else "127.0.0.1"
    shown_host = f"[{shown_host}]" if ":" in shown_host else shown_host
    url = f"http://{shown_host}:{port}/"
    click.echo(json.dumps({"event": "start", "url": url, "listen": host,
                           "data_dir": str(config.data_dir), "workers": workers,
                           "preview": not no_preview}), err=True)
    if host not in ("127.0.0.1", "localhost", "::1"):
        click.echo(f"warning: listening on {host}: anyone who can reach this machine on port {port} can "
                   "use this server (it has no authentication); put it behind a proxy that "
                   "authenticates, or a firewall, when that is not intended.", err=True)
    from brainpainter.web.server import run

    def listening() -> None:  # the one line for a person, besides the JSON log
        click.echo(f"open {url} in a browser (Ctrl+C stops the server; data in {config.data_dir})", err=True)

    run(create_app(config), host=host, port=port, log_level=log_level, max_connections=max_connections,
        forwarded_allow_ips=forwarded_allow_ips, on_listening=listening)
