"""Movie files: MP4 (H.264 through the ffmpeg binary of ``imageio-ffmpeg``) and GIF (pillow).

MP4 is H.264 (yuv420p, BT.709, ``+faststart``); a GIF has one palette for
the whole movie, Floyd-Steinberg dithered. Both write frames as they come, so
memory does not grow with the number of frames.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from brainpainter.errors import BrainPainterError

MAX_GIF_FRAMES = 2_000  # a GIF is for slides and web pages; longer movies: MP4
GIF_PALETTE_FRAMES = 12  # frames sampled for a GIF's palette


class _Mp4Writer:
    def __init__(self, path: Path, size: tuple[int, int], fps: float) -> None:
        import imageio_ffmpeg

        self.path = path

        self._gen = imageio_ffmpeg.write_frames(
            str(path), size, fps=fps, codec="libx264", pix_fmt_in="rgb24", pix_fmt_out="yuv420p",
            quality=None, macro_block_size=2, ffmpeg_log_level="quiet",  # failures: verified after
            # sRGB frames -> BT.709 YUV, tagged as such so players convert back the same way
            output_params=["-crf", "18", "-preset", "medium", "-vf", "scale=out_color_matrix=bt709",
                           "-x264-params", "colorprim=bt709:transfer=bt709:colormatrix=bt709",
                           "-movflags", "+faststart"],
        )
        self._gen.send(None)

    def write(self, frame: NDArray[Any]) -> None:
        try:
            self._gen.send(np.ascontiguousarray(frame))
        except (OSError, RuntimeError, StopIteration) as exc:
            raise self._failed(exc) from None

    def close(self) -> None:
        try:
            self._gen.close()
        except (OSError, RuntimeError) as exc:
            raise self._failed(exc) from None

    def _failed(self, exc: BaseException) -> BrainPainterError:
        from brainpainter.io.verify import _broken

        return _broken(self.path, f"the video encoder (ffmpeg) stopped: {type(exc).__name__}")

    def abort(self) -> None:
        self._gen.close()  # ffmpeg finishes the temporary file, which is then deleted


class _GifWriter:
    """GIF written frame by frame: one palette for the whole movie, Floyd-Steinberg dithered.

    A shared palette keeps still parts (colour bar, unchanged regions) identical
    from frame to frame, so dithering does not flicker. The palette comes from
    a mosaic of up to 12 frames spread over the movie (given up front), and each
    frame is quantised and appended to the file as it comes, so memory does
    not grow with the number of frames.
    """

    def __init__(self, path: Path, size: tuple[int, int], fps: float,
                 background: tuple[int, int, int] = (255, 255, 255),
                 samples: Sequence[NDArray[Any]] = ()) -> None:
        self.path, self.fps, self.background = path, fps, tuple(int(c) for c in background)
        self.size = size
        self.n_frames = 0
        self._palette = self.palette(samples)
        self._fh = path.open("wb")
        colors = bytes(self._palette.getpalette()[: 3 * 256])
        colors += bytes(self.background) * ((768 - len(colors)) // 3)
        self._fh.write(b"GIF89a" + struct.pack("<HHBBB", size[0], size[1], 0xF7, 255, 0) + colors)
        # loop forever (NETSCAPE2.0 application extension)
        self._fh.write(b"!\xff\x0bNETSCAPE2.0\x03\x01" + struct.pack("<H", 0) + b"\x00")

    def palette(self, samples: Sequence[NDArray[Any]]) -> Any:
        """255 colours from a mosaic of the sample frames, plus the exact background colour."""
        from PIL import Image

        colors = np.array([self.background], np.uint8)
        if len(samples):
            mosaic = np.concatenate([f[::2, ::2] for f in samples], axis=0)
            sampled = Image.fromarray(np.ascontiguousarray(mosaic)).quantize(
                colors=255, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
            colors = np.array((sampled.getpalette() or [])[: 3 * 255], dtype=np.uint8).reshape(-1, 3)[:255]
        colors = np.vstack([colors, np.array([self.background] * (256 - len(colors)), np.uint8)])
        palette = Image.new("P", (1, 1))
        palette.putpalette(colors.ravel().tolist())
        return palette

    def write(self, frame: NDArray[Any]) -> None:
        from PIL import GifImagePlugin, Image

        im = Image.fromarray(np.ascontiguousarray(frame)).quantize(palette=self._palette,
                                                                 dither=Image.Dither.FLOYDSTEINBERG)
        # pillow's palette look-up is approximate: put the background back exactly (index 255)
        bg = Image.fromarray(((frame == self.background).all(axis=-1) * 255).astype(np.uint8))
        im.paste(255, mask=bg)
        params = {"duration": max(20, round(1000 / self.fps / 10) * 10), "disposal": 1}
        write_frame = getattr(GifImagePlugin, "_write_frame_data", None)
        if write_frame is not None:  # straight into the file
            write_frame(self._fh, im, (0, 0), params)
        else:  # pragma: no cover - older/newer pillow: the public (but leakier) frame encoder
            for part in GifImagePlugin.getdata(im, **params):  # type: ignore[arg-type]
                self._fh.write(part)
        self.n_frames += 1

    def abort(self) -> None:
        self._fh.close()

    def close(self) -> None:
        self._fh.write(b";")
        self._fh.close()
