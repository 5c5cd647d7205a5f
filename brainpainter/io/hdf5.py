"""HDF5 files (MINC-2 volumes) checked before nibabel reads them: :func:`check_hdf5`.

HDF5 can take a dataset's data from other files: *external storage* (raw
bytes of any file, ``/etc/passwd`` included), *external links* (an object of
another HDF5 file) and *virtual datasets* (pieces of other files). nibabel
reads MINC-2 through h5py, which follows all three. A volume is read only
from its own file, so an HDF5 file using any of them is refused.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from brainpainter.errors import BrainPainterError


def check_hdf5(path: str | Path, what: str) -> None:
    """Refuse an HDF5 file that takes data from another file; other files pass unchecked.

    Parameters
    ----------
    path : path-like
    what : str
        What the file is, for messages (``"volume"``).

    Raises
    ------
    BrainPainterError
        A dataset with external storage or virtual, or an external link.
    """
    path = Path(path)
    try:
        import h5py
    except ImportError:
        return  # nibabel cannot read MINC-2 either: it says so
    if not h5py.is_hdf5(str(path)):  # its superblock may follow a user block: h5py looks where HDF5 does
        return
    found: list[str] = []

    def visit(name: str, link: Any) -> None:
        if isinstance(link, h5py.ExternalLink):
            found.append(f"{name}: an external link to {link.filename!r}")
        elif isinstance(link, h5py.HardLink) and isinstance(obj := f5.get(name), h5py.Dataset):
            if obj.is_virtual:
                found.append(f"{name}: a virtual dataset")
            elif obj.id.get_create_plist().get_external_count():
                name_0 = obj.id.get_create_plist().get_external(0)[0].decode(errors="replace")
                found.append(f"{name}: external storage in {name_0!r}")

    try:
        with h5py.File(path, "r") as f5:
            if not hasattr(f5, "visititems_links"):
                raise BrainPainterError(f"checking the HDF5 {what} {str(path)!r} needs h5py 3.11 or newer; "
                                        "pip install -U h5py, or convert the file to NIfTI.")
            f5.visititems_links(visit)
    except OSError as exc:
        raise BrainPainterError(f"cannot read {what} {str(path)!r} as HDF5 ({exc}); give the file your "
                                "software wrote.") from None
    if found:
        raise BrainPainterError(
            f"{what} {str(path)!r} takes data from another file ({found[0][:160]}); brainpainter reads a "
            "volume only from its own file. Save it with its data inside (e.g. convert it with mnc2nii).")
