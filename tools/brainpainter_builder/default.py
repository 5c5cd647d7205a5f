"""Build the bundled default template and atlas tables from ``../shared/data``.

One command, run from the repository root::

    python -m brainpainter_builder.default

reads FreeSurfer 7.3.2's fsaverage from ``../shared/data/freesurfer`` and
writes

- ``plugins/atlases/brainpainter_atlases/templates/fsaverage/`` (the template),
- ``plugins/atlases/brainpainter_atlases/data/{dk,destrieux,dkt}/regions.tsv``
  and ``data/aseg.tsv`` (the atlas look-up tables).

DKT is derived from FreeSurfer's DKT40 classifier atlas
(``average/?h.DKTaparc.atlas.acfb40.noaparc.i12.2016-08-02.gcs.gz``), since
FreeSurfer ships no DKT annotation for fsaverage. The build is deterministic:
running it twice gives byte-identical files.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

from brainpainter.errors import BrainPainterError

REPO = Path(__file__).resolve().parents[2]
DATA = REPO.parent / "shared" / "data"
ATLAS_PACKAGE = REPO / "plugins" / "atlases" / "brainpainter_atlases"
FREESURFER_VERSION = "freesurfer-7.3.2"
#: Cortical regions per hemisphere of the bundled atlases.
EXPECTED_REGIONS = {"dk": 34, "destrieux": 74, "dkt": 31}


def build_default(data: Path = DATA, out: Path = ATLAS_PACKAGE / "templates" / "fsaverage",
                  atlas_data: Path | None = ATLAS_PACKAGE / "data", *,
                  target_faces: int | None = None, progress: bool = True) -> dict[str, Any]:
    """Build the fsaverage template (and the atlas tables); return its report."""
    from brainpainter_builder.build import DEFAULT_TARGET_FACES, build_template
    from brainpainter_builder.report import template_report
    from brainpainter_builder.tables import write_atlas_tables

    fs = Path(data) / "freesurfer"
    subject = fs / "subjects" / "fsaverage"
    if not subject.is_dir():
        raise BrainPainterError(
            f"fsaverage not found at {subject}; pass --data with the folder that holds "
            "freesurfer/subjects/fsaverage (see ../shared/data/README.md)")
    t0 = time.perf_counter()
    path = build_template(
        subject, out, atlases=tuple(EXPECTED_REGIONS), name="fsaverage",
        target_faces=target_faces or DEFAULT_TARGET_FACES, gcs_dir=fs / "average",
        progress=progress, freesurfer_version=FREESURFER_VERSION,
        license_file=fs / "LICENSE.FreeSurfer.txt", expected_regions=EXPECTED_REGIONS)
    build_s = time.perf_counter() - t0
    if atlas_data is not None:
        write_atlas_tables(path, atlas_data, tuple(EXPECTED_REGIONS))
    info = template_report(path)
    info["build_s"] = round(build_s, 1)
    return info


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m brainpainter_builder.default",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=DATA,
                        help=f"shared data folder (default {DATA})")
    parser.add_argument("--out", type=Path, default=ATLAS_PACKAGE / "templates" / "fsaverage",
                        help="template folder to write")
    parser.add_argument("--atlas-data", type=Path, default=ATLAS_PACKAGE / "data",
                        help="atlas data folder for the regions.tsv tables")
    parser.add_argument("--no-tables", action="store_true", help="do not write the atlas tables")
    parser.add_argument("--target-faces", type=int, default=None,
                        help="faces per hemisphere and atlas (default: the builder's)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)
    try:
        info = build_default(args.data, args.out, None if args.no_tables else args.atlas_data,
                             target_faces=args.target_faces, progress=not args.quiet)
    except BrainPainterError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    m = info["manifest"]
    print(f"built {info['path']} in {info['build_s']} s: {info['size_mb']} MB, "
          f"load {info['load_s']} s")
    for labels, entry in m["labels"].items():
        c = entry["cortex"]
        print(f"  {labels}: {len(entry['regions'])} regions/hemisphere, faces lh {c['lh']['n_faces']} "
              f"rh {c['rh']['n_faces']}, open edges {c['lh']['open_edges']}/{c['rh']['open_edges']}")
    worst = max(m["subcortical"]["structures"], key=lambda s: abs(s["volume_error"]))
    print(f"  subcortical: {len(m['subcortical']['structures'])} structures, "
          f"{m['n_faces']['subcortical']} faces, worst volume error {worst['volume_error']:+.2%} "
          f"({worst['name']})")
    print(f"  glass: {m['n_faces']['glass']} faces")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
