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
@click.option("--log-level", default="info", show_default=True,
              type=click.Choice(["debug", "info", "warning", "error"]))
def serve(host: str, port: int, data_dir: Path | None, workers: int, no_preview: bool, renderer: str,
          log_level: str, **limits: Any) -> None:
    """Serve the web page and JSON API: upload a table, check it, preview it, render it.

    \b
    Open http://127.0.0.1:8000/ in a browser. The API schema is at /openapi.json;
    /healthz and /readyz are for monitoring. Jobs survive a restart (they are
    kept in DATA_DIR/jobs.sqlite3 and re-queued).
    """
    import json
    import logging

    try:
        import uvicorn

        from brainpainter.web.app import create_app
        from brainpainter.web.config import ServerConfig, default_data_dir
    except ImportError as exc:  # pragma: no cover - core dependencies
        raise BrainPainterError(f"serve needs FastAPI and uvicorn ({exc}); "
                                "pip install fastapi uvicorn") from None
    for key in ("max_images", "max_jobs_per_client", "max_queued", "rate_per_minute"):
        if limits[key] < 1:
            raise BrainPainterError(f"--{key.replace('_', '-')} must be at least 1; {limits[key]} was given.")
    config = ServerConfig(data_dir=data_dir or default_data_dir(), workers=workers, preview=not no_preview,
                          renderer=renderer, **limits)
    from brainpainter.atlas import registry
    registry.renderers.get(renderer)  # an unknown renderer fails now, with the CLI's message
    try:
        config.data_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise BrainPainterError(f"--data-dir {str(config.data_dir)!r} cannot be created ({exc.strerror}); "
                                "choose a writable folder.") from None
    from brainpainter.web.store import lock_data_dir

    lock_data_dir(config.data_dir)  # one server per data folder (held until this process ends)
    level = getattr(logging, log_level.upper())
    handler = logging.StreamHandler()  # uvicorn configures its own loggers; ours log one line per record
    handler.setFormatter(logging.Formatter("%(message)s"))
    web_log = logging.getLogger("brainpainter.web")
    web_log.setLevel(level)
    web_log.addHandler(handler)
    web_log.propagate = False
    click.echo(json.dumps({"event": "start", "url": f"http://{host}:{port}/",
                           "data_dir": str(config.data_dir), "workers": workers,
                           "preview": not no_preview}), err=True)
    uvicorn.run(create_app(config), host=host, port=port, access_log=False, log_level=log_level,
                server_header=False, timeout_graceful_shutdown=10)
