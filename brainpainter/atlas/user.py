"""User atlases: atlases added by ``brainpainter atlas add``, kept in the user's data folder.

Each one is a folder ``{user_data_dir}/atlases/NAME/`` (``platformdirs``;
``~/.local/share/brainpainter/atlases`` on Linux) holding either

* a **label-map atlas**: ``atlas.json`` + ``regions.tsv`` + a label-set
  overlay (``labels.json``, ``cortex-{hemi}-NAME.npz``) made from an
  annotation by :mod:`brainpainter.atlas.labelset` — the same folder layout an atlas
  plugin ships; or
* a **group atlas**: ``atlas.toml``, a copy of the region-group config
  (:mod:`brainpainter.atlas.config`), built from its base atlas when loaded.

The folders are discovered by the ``brainpainter.atlases`` registry next to
the entry points (distribution ``"user"``). Everything is written into a
hidden temporary folder beside the target and renamed into place, so a
failed ``add`` leaves nothing behind.
"""

from __future__ import annotations

import re
import shutil
import tempfile
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import TypeVar

from brainpainter.atlas import labelset, registry
from brainpainter.atlas.model import load_atlas_dir
from brainpainter.atlas.registry import CONFIG_FILE, atlases_dir, load_atlas_config, user_folders
from brainpainter.atlas.template import load_template
from brainpainter.errors import BrainPainterError, choice_error
from brainpainter.io.files import read_input
from brainpainter.io.output import RESERVED_NAMES
from brainpainter.io.transaction import check_replaceable, replace_folder

NAME_RE = re.compile(r"^[A-Za-z][A-Za-z0-9_.-]{0,63}$")
RESERVED = RESERVED_NAMES


def check_name(name: str, *, replace: bool = False) -> str:
    """Validate a new atlas name: allowed characters, no clash with an installed atlas."""
    check_syntax(name)
    registry.atlases.reset()
    for entry in registry.atlases.entries():
        names = (entry.name, *entry.aliases)
        if any(n.lower() == name.lower() for n in names):
            if entry.distribution == "user":
                if replace and entry.name == name:
                    return name
                raise BrainPainterError(
                    f"you already have an atlas named {entry.name!r} ({entry.target}); choose another "
                    f"name, pass --replace, or remove it first (brainpainter atlas remove {entry.name})"
                )
            raise BrainPainterError(
                f"an atlas named {entry.name!r} is already installed (from {entry.distribution}); "
                f"choose another name for yours"
            )
    return name


def check_syntax(name: str) -> str:
    """Atlas names are used as folder and file names: a letter, then letters, digits, ``_ - .``."""
    if not NAME_RE.match(str(name)):
        raise BrainPainterError(
            f"atlas name {name!r} is not allowed; use a letter followed by letters, digits, '_', '-' or "
            "'.' (at most 64), e.g. yeo7"
        )
    if str(name).split(".")[0].upper() in RESERVED:
        raise BrainPainterError(
            f"atlas name {name!r} is not allowed: Windows reserves {str(name).split('.')[0].upper()!r} for a "
            "device (with any extension), so its folder could not be copied there; choose another name"
        )
    if str(name).endswith("."):
        raise BrainPainterError(
            f"atlas name {name!r} is not allowed: Windows drops a final '.', so it would be another name "
            "there; remove the final '.'"
        )
    return name


def _is_user_atlas(folder: Path) -> bool:
    return (folder / "atlas.json").is_file() or (folder / CONFIG_FILE).is_file()


@contextmanager
def staged_folder(name: str, out: Path | None = None) -> Iterator[Path]:
    """Yield a hidden temporary folder; on success it replaces ``atlases_dir()/name`` (or `out`).

    `out` must be new or empty; in the user's atlas folder only an atlas
    folder is replaced (``--replace``). The parent folder is locked meanwhile.
    """
    if out is not None:
        with replace_folder(out, lambda p: False, "output folder", "Give a new or empty folder.") as stage:
            yield stage
        return
    with replace_folder(atlases_dir() / name, _is_user_atlas, "atlas folder",
                        f"Remove it by hand or choose another name than {name!r}.") as stage:
        yield stage


def parse_annot_options(values: list[str] | tuple[str, ...]) -> dict[str, Path]:
    """``["lh=FILE", "rh=FILE"]`` (or two files named ``lh.*``/``rh.*``) -> ``{"lh": FILE, "rh": FILE}``."""
    out: dict[str, Path] = {}
    for v in values:
        hemi, sep, file = str(v).partition("=")
        if not sep:
            hemi, file = labelset.hemi_of(v) or "", str(v)
            if not hemi:
                raise BrainPainterError(
                    f"cannot tell the hemisphere of {v!r}; write --annot lh={v} or --annot rh={v}")
        hemi = hemi.strip().lower()
        hemi = {"left": "lh", "l": "lh", "right": "rh", "r": "rh"}.get(hemi, hemi)
        if hemi not in ("lh", "rh"):
            raise BrainPainterError(f"--annot must be lh=FILE or rh=FILE; {v!r} was given")
        if hemi in out:
            raise BrainPainterError(f"--annot gives two {hemi} files ({out[hemi]}, {file}); give one per "
                                    "hemisphere")
        out[hemi] = Path(file).expanduser()
    missing = [h for h in ("lh", "rh") if h not in out]
    if missing:
        raise BrainPainterError(f"--annot needs a file for each hemisphere; {missing[0]} is missing "
                                f"(add --annot {missing[0]}=FILE)")
    return out


def add_label_map(name: str, annots: Mapping[str, str | Path | labelset.LabelMap], *,
                  template: str = "fsaverage", title: str = "", description: str = "", citation: str = "",
                  region_aliases: Mapping[str, tuple[str, ...]] | None = None, replace: bool = False,
                  out: str | Path | None = None) -> Path:
    """Add an atlas made from one label map per hemisphere (``.annot`` / ``.label.gii``).

    Parameters
    ----------
    name : str
        Atlas name (and label-set name).
    annots : mapping of {"lh", "rh"} to path or LabelMap
        A file, or a label map already read (a CIFTI dlabel's, :mod:`brainpainter.maps.dlabel`).
    template : str
        Template the label maps were made for (registry name or folder).
    title, description, citation : str
    region_aliases : mapping of str to tuple of str, optional
        Other names of regions (hemisphere-free), e.g. ``{"7Networks_1": ("Visual",)}``.
    replace : bool
        Replace a user atlas of the same name.
    out : path, optional
        Write the atlas folder there (for an atlas plugin) instead of adding it.

    Returns
    -------
    Path
        The atlas folder.
    """
    if out is None:
        check_name(name, replace=replace)
    else:
        check_syntax(name)
        check_replaceable(Path(out).expanduser(), lambda p: False, "output folder",
                          "Give a new or empty folder.")
    tpl = load_template(template)
    maps = {h: a if isinstance(a, labelset.LabelMap) else labelset.read_label_map(a, h)
            for h, a in annots.items() if h in ("lh", "rh")}
    label_set = labelset.build_label_set(name, tpl, maps)
    with staged_folder(name, Path(out) if out is not None else None) as stage:
        labelset.write_atlas_folder(stage, label_set, tpl, title=title, description=description,
                                    citation=citation, region_aliases=dict(region_aliases or {}))
        load_atlas_dir(stage)  # validates what was written
    registry.atlases.reset()
    return Path(out) if out is not None else atlases_dir() / name


T = TypeVar("T")


def store_built(name: str, build: Callable[[Path], T], *, replace: bool = False,
                out: str | Path | None = None) -> tuple[Path, T]:
    """Check `name`, run ``build(folder)`` into a staged folder, validate it and publish it.

    The folder replaces ``atlases_dir()/name`` (the user's atlas), or becomes `out`
    (an atlas plugin's data). Returns the atlas folder and what `build` returned.
    """
    if out is None:
        check_name(name, replace=replace)
    else:
        check_syntax(name)
    with staged_folder(name, Path(out) if out is not None else None) as stage:
        result = build(stage)
        load_atlas_dir(stage)  # validates what was written
    registry.atlases.reset()
    return (Path(out) if out is not None else atlases_dir() / name), result


def add_config(name: str, config: str | Path, *, replace: bool = False) -> Path:
    """Add a region-group atlas from a TOML config (validated first); returns its folder."""
    check_name(name, replace=replace)
    config = Path(config).expanduser()
    load_atlas_config(config, name=name)  # every error before anything is written
    text = read_input(config, "atlas config")
    with staged_folder(name) as stage:
        (stage / CONFIG_FILE).write_bytes(text)
        load_atlas_config(stage / CONFIG_FILE, name=name)
    registry.atlases.reset()
    return atlases_dir() / name


def remove(name: str) -> Path:
    """Remove the user atlas `name`; returns the folder (or symbolic link) that was removed.

    A folder that is a symbolic link (to an atlas kept elsewhere) is removed
    as a link: the files it points to are left as they are
    (:func:`removal_message` says so).
    """
    folders = user_folders()
    hit = next((n for n in folders if n.lower() == str(name).lower()), None)
    if hit is None:
        registry.atlases.reset()
        installed = {e.name: e.distribution for e in registry.atlases.entries() if e.distribution != "user"}
        low = {n.lower(): n for n in installed}
        if str(name).lower() in low:
            dist = installed[low[str(name).lower()]]
            raise BrainPainterError(f"atlas {name!r} is installed from {dist}, not added by you; "
                                    f"uninstall it with: pip uninstall {dist}")
        raise choice_error("'atlas'", name, list(folders),
                           "Only atlases added with 'brainpainter atlas add' can be removed.")
    folder = folders[hit]
    if folder.is_symlink():
        folder.unlink()  # the link only: rmtree would refuse it, and the target is not ours to delete
        registry.atlases.reset()
        return folder
    trash = Path(tempfile.mkdtemp(prefix=f".{hit}.removing-", dir=folder.parent))
    trash.rmdir()
    folder.rename(trash)  # atomic: the atlas is gone at once, then the files
    shutil.rmtree(trash, ignore_errors=True)
    registry.atlases.reset()
    return folder


def removal_message(name: str, folder: Path, link_target: str | None) -> str:
    """What ``atlas remove`` did: a folder deleted, or a symbolic link removed and its target kept."""
    if link_target is not None:
        return (f"atlas {name!r} removed: {folder} was a symbolic link to {link_target}; the link was "
                f"removed, the files in {link_target} were left as they are")
    return f"atlas {name!r} removed ({folder} deleted)"


def link_target(name: str) -> str | None:
    """Where the folder of user atlas `name` points, if it is a symbolic link (None otherwise)."""
    import os

    folder = next((p for n, p in user_folders().items() if n.lower() == str(name).lower()), None)
    return os.readlink(folder) if folder is not None and folder.is_symlink() else None
