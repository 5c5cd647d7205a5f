"""``brainpainter serve``: the web page and JSON API (FastAPI + uvicorn).

Modules
-------
config
    :class:`ServerConfig`: data folder, worker count and every limit.
options
    The render options as a pydantic model with the CLI's names and defaults,
    checked by the same :func:`brainpainter.rendering.run.prepare_run` as the CLI.
store
    Uploads and jobs in SQLite (WAL) under the data folder.
worker
    Worker processes: each keeps warm :class:`~brainpainter.rendering.painter.Painter`\\ s and
    runs queued jobs; the preview process renders one image at a time.
pool
    Starts, watches and restarts those processes; re-queues jobs of dead
    workers; removes expired results.
app
    The ASGI application (:func:`create_app`): routes and error answers.
guard
    Its middleware: security headers, body size limits, rate limit, access log.

Only the command's module is imported by ``brainpainter --help``; FastAPI,
uvicorn and bpy load when the server starts.
"""
