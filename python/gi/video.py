"""Video output: 8-bit sRGB frames encoded to H.264 by the ffmpeg that ships inside the
``imageio-ffmpeg`` wheel (no system ffmpeg needed)."""

from __future__ import annotations

import os
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from gi._checks import OutputError, named_error

#: File suffixes written as video.
VIDEO_FORMATS = {".mp4", ".mov", ".mkv"}


def _encoder(path: Path) -> Any:
    """The ``imageio_ffmpeg`` module, or an :class:`OutputError` naming the missing package
    (an install without gi's dependency ``imageio-ffmpeg``)."""
    try:
        import imageio_ffmpeg  # type: ignore[import-untyped]
    except ImportError as e:
        raise OutputError(
            path, f"video needs the imageio-ffmpeg package ({e}); pip install imageio-ffmpeg"
        ) from e
    return imageio_ffmpeg


class VideoWriter:
    """Writes frames (``(height, width, 3)`` uint8 sRGB) to ``path`` at ``fps`` frames a
    second, H.264 in yuv420p (what players expect). Odd sizes are padded to even ones by
    repeating the last row or column (yuv420p needs even sizes). The video is encoded into a
    hidden file next to ``path`` and renamed when :meth:`close` succeeds; :meth:`abort` (or an
    error) deletes it, so a failed or interrupted encode leaves no half file.

    ``quality`` is imageio-ffmpeg's 1–10 scale (8: x264 constant rate factor 10, visually
    lossless for renders).
    """

    def __init__(self, path: str | Path, fps: float, quality: float = 8) -> None:
        self.path = Path(path)
        if self.path.suffix.lower() not in VIDEO_FORMATS:
            formats = ", ".join(sorted(VIDEO_FORMATS))
            raise named_error(
                "output", f"unsupported video format {self.path.suffix!r} (use {formats})"
            )
        self.fps = Fraction(fps).limit_denominator(1001)
        self.quality = quality
        self.tmp = self.path.with_name(f".{self.path.stem}.partial{self.path.suffix}")
        self._gen: Any = None
        self._size: tuple[int, int] | None = None
        self.frames = 0

    def write(self, rgb8: np.ndarray) -> None:
        """Appends one frame."""
        frame = np.asarray(rgb8)
        if frame.dtype != np.uint8 or frame.ndim != 3 or frame.shape[2] != 3:
            raise named_error(
                "frame", f"frames must be (H, W, 3) uint8, got {frame.shape} {frame.dtype}"
            )
        h, w = frame.shape[:2]
        if self._gen is not None and (w, h) != self._size:
            raise named_error("frame", f"frame size {w}x{h} differs from the video's {self._size}")
        if w % 2 or h % 2:
            frame = np.pad(frame, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge")
        try:
            if self._gen is None:
                imageio_ffmpeg = _encoder(self.path)
                self.path.parent.mkdir(parents=True, exist_ok=True)
                self._size = (w, h)
                self._gen = imageio_ffmpeg.write_frames(
                    str(self.tmp),
                    self.padded_size(w, h),
                    fps=self.fps,
                    codec="libx264",
                    quality=self.quality,
                    macro_block_size=2,
                    ffmpeg_log_level="error",
                )
                self._gen.send(None)
            self._gen.send(np.ascontiguousarray(frame))
        except (OSError, RuntimeError) as e:  # ffmpeg could not start or write
            raise OutputError(self.path, f"encoding failed ({e})") from e
        self.frames += 1

    @staticmethod
    def padded_size(width: int, height: int) -> tuple[int, int]:
        """The size of the video of ``width``×``height`` frames (even, for yuv420p)."""
        return width + width % 2, height + height % 2

    def close(self) -> None:
        """Finishes the video and moves it to ``path``."""
        if self._gen is None:
            raise named_error("frame", f"{self.path}: no frames were written")
        gen, self._gen = self._gen, None
        try:
            gen.close()
            os.replace(self.tmp, self.path)
        except (OSError, RuntimeError) as e:
            self.tmp.unlink(missing_ok=True)
            raise OutputError(self.path, f"encoding failed ({e})") from e
        except BaseException:
            self.tmp.unlink(missing_ok=True)
            raise

    def abort(self) -> None:
        """Stops encoding and deletes the partial file."""
        gen, self._gen = self._gen, None
        try:
            if gen is not None:
                gen.close()
        finally:
            self.tmp.unlink(missing_ok=True)
