"""Settings of a ``brainpainter serve`` instance: where it keeps data, how many workers, every limit."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import platformdirs


def default_data_dir() -> Path:
    """``$XDG_DATA_HOME/brainpainter/serve`` (platform equivalent elsewhere)."""
    return Path(platformdirs.user_data_dir("brainpainter")) / "serve"


@dataclass(frozen=True)
class ServerConfig:
    """One server's settings (the ``serve`` options; limits have safe defaults for a public lab server).

    Attributes
    ----------
    data_dir : Path
        Holds ``jobs.sqlite3`` and one folder per upload and per job (named by their random ids).
    workers : int
        Job worker processes (each holds warm painters). 0 runs no jobs (API tests).
    preview : bool
        Start the preview process (one warm painter for the live preview).
    renderer : str
        Renderer name in the ``brainpainter.renderers`` registry.
    max_upload_mb : float
        Largest accepted upload.
    max_images : int
        Largest rows x views of one job.
    max_pixels : int
        Largest width x height of one rendered view.
    max_figure_pixels : int
        Largest width x height of a figure job's PNG (checked before it is queued, and again when composed).
    worker_memory_gb : float
        Data memory each rendering process (job worker, preview) may use; a job needing more fails with one
        line. 0 = no limit.
    max_jobs_per_client : int
        Queued or running jobs one client (IP address) may have at once.
    max_uploads_per_client : int
        Uploads kept per client; older ones are deleted (jobs keep their own copy).
    max_queued : int
        Queued jobs of all clients; beyond it submissions get 503.
    rate_per_minute : int
        Requests that change state (uploads, jobs, previews) per client and minute.
    job_time_limit_s : float
        A job running longer fails and its worker is restarted.
    result_ttl_s : float
        Finished jobs and uploads are deleted this long after they finish / arrive.
    max_attempts : int
        A job whose worker died this many times fails instead of being re-queued.
    threads_per_worker : int
        ``LP_NUM_THREADS`` (Mesa llvmpipe threads) of each rendering process;
        0 = CPU cores divided among the workers and the preview process.
    max_rows : int
        Largest number of table rows in one upload (like the readers' column limit: every request
        that reads the table stays bounded).
    max_map_images : int
        Largest number of images in one map upload (volumes of a 4-D NIfTI, data arrays of a GIfTI);
        each costs about 1.3 MB on fsaverage.
    max_tract_streamlines : int
        Largest number of streamlines the tractograms of one tract upload may hold together (a hard
        cap: the files are refused; fewer are drawn, ``max_streamlines``).
    max_tract_files : int
        Largest number of files (bundles, a values table; a zip's members counted) of one tract upload.
    max_disk_gb : float
        Disk the data folder may use (uploads and results); beyond it new uploads and jobs get 507.
        0 = no budget.
    work_threads : int
        Threads that read tables for requests (check, preview, submit); status reads never wait for them.
    max_waiting_work : int
        Requests that may wait for a work thread; beyond it they get 503 + Retry-After.
    parse_time_limit_s : float
        Seconds a spreadsheet (``.xlsx``) upload may take to read (in its own process, killed after).
    work_time_limit_s : float
        Seconds the work of one check, preview or job submission may take (reading the upload into a run,
        laying out a figure), in a request process killed after (:mod:`brainpainter.web.work_processes`).
    work_processes : int
        Request processes: calls run at once (3: two clients' slowest requests leave one for the others).
    upload_time_limit_s : float
        Seconds a request may take to send its body (uploads); slower ones get 408.
    max_uploads_in_flight : int
        Uploads one client may be sending at once (more get 429 without being read).
    """

    data_dir: Path = field(default_factory=default_data_dir)
    workers: int = 1
    preview: bool = True
    renderer: str = "blender"
    max_upload_mb: float = 10.0
    max_images: int = 600
    max_pixels: int = 2400 * 1800
    max_figure_pixels: int = 40_000_000
    worker_memory_gb: float = 4.0
    max_jobs_per_client: int = 4
    max_uploads_per_client: int = 100
    max_queued: int = 100
    rate_per_minute: int = 240
    job_time_limit_s: float = 1800.0
    result_ttl_s: float = 24 * 3600.0
    max_attempts: int = 3
    threads_per_worker: int = 0
    preview_max_width: int = 480
    max_rows: int = 20_000
    max_map_images: int = 100
    max_tract_streamlines: int = 1_000_000
    max_tract_files: int = 100
    max_disk_gb: float = 0.0
    work_threads: int = 2
    max_waiting_work: int = 16
    parse_time_limit_s: float = 20.0
    work_time_limit_s: float = 30.0
    work_processes: int = 3
    upload_time_limit_s: float = 60.0
    max_uploads_in_flight: int = 4

    @property
    def max_disk_bytes(self) -> int:
        return int(self.max_disk_gb * 1024**3)

    @property
    def worker_memory_bytes(self) -> int | None:
        return int(self.worker_memory_gb * 1024**3) if self.worker_memory_gb > 0 else None

    @property
    def max_upload_bytes(self) -> int:
        return int(self.max_upload_mb * 1024 * 1024)

    def lp_threads(self) -> int:
        """Mesa threads per rendering process, so that processes do not oversubscribe the cores."""
        if self.threads_per_worker > 0:
            return self.threads_per_worker
        procs = max(1, self.workers) + (1 if self.preview else 0)
        return max(1, (os.cpu_count() or 1) // procs)


def no_paths(message: str, root: Path) -> str:
    """`message` without the server's own paths (clients see it): a file in the data folder `root` by its
    name only, the folder itself as ``DATA_DIR``."""
    import re

    for folder in {str(root.resolve()), str(root)}:
        message = re.sub(re.escape(folder) + r"/(?:[^\s'\"/]+/)*", "", message).replace(folder, "DATA_DIR")
    return message
