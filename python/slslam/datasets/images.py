"""Reading camera images as the uint8 gray arrays the tracker takes, minding the bit depth.

OpenCV turns a 16-bit PNG into 8 bits by dropping the low byte (value / 256). Many machine-vision
cameras store 10- or 12-bit data in 16-bit PNGs without shifting it up, and 12-bit data (at most
4095) then becomes 0..15: an almost black image that tracks nothing, without a word. So a 16-bit
gray PNG is read here at full depth: when the first one of a sequence holds nothing above 4095,
the sequence is taken as 12-bit data and scaled by 1/16 (said once in the log); otherwise by 1/256
as OpenCV would. The choice is made once per reader so that every frame gets the same scale; a
later frame above 4095 in a 12-bit sequence saturates, with one warning.

Arrays (what ``cv2.imread`` or a ROS message gives) go through :meth:`GrayImageReader.convert`:
uint8 gray as is, 3- and 4-channel uint8 in OpenCV's BGR / BGRA order to gray with OpenCV's
weights (0.299 R + 0.587 G + 0.114 B), 16-bit gray by the rule above, 16-bit colour first to gray.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from slslam import _core

log = logging.getLogger(__name__)

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
PNG_GRAY = 0  # IHDR colour type of a single-channel PNG
MAX_12_BIT = 4095


def png_format(path: Path) -> tuple[int, int] | None:
    """(bit depth, colour type) from a PNG's IHDR header, or None when it is not a PNG."""
    with path.open("rb") as handle:
        head = handle.read(26)
    if len(head) < 26 or head[:8] != PNG_SIGNATURE or head[12:16] != b"IHDR":
        return None
    return head[24], head[25]


class GrayImageReader:
    """``reader(path)`` returns the image as a uint8 H x W array; ValueError names the file."""

    def __init__(self) -> None:
        self.shift: int | None = None  # right shift of 16-bit data: 4 (12-bit) or 8
        self._warned_saturation = False

    def __call__(self, path: str | Path) -> np.ndarray:
        path = Path(path)
        fmt = png_format(path) if path.is_file() else None
        if fmt != (16, PNG_GRAY):
            return _core.read_gray_image(str(path))
        return self._from_16_bit(path, self._read_16_bit(path))

    @staticmethod
    def _read_16_bit(path: Path) -> np.ndarray:
        from PIL import Image  # Pillow comes with matplotlib

        try:
            with Image.open(path) as image:
                data = np.asarray(image)
        except (OSError, ValueError) as exc:
            raise ValueError(f"{path}: unreadable 16-bit PNG ({exc})") from None
        if data.ndim != 2:
            raise ValueError(f"{path}: 16-bit PNG is not a single gray channel")
        return data.astype(np.uint16, copy=False)

    def convert(self, image: np.ndarray, where: str | Path = "image") -> np.ndarray:
        """``image`` as a C-contiguous uint8 H x W gray array (see the module docstring);
        ValueError naming ``where`` for any other shape or type."""
        if not isinstance(image, np.ndarray):
            raise ValueError(f"{where}: expected a numpy array, got {type(image).__name__}")
        if image.ndim == 3 and image.shape[2] == 1:
            image = image[:, :, 0]
        if image.ndim == 3:
            if image.shape[2] not in (3, 4) or image.dtype not in (np.uint8, np.uint16):
                raise ValueError(
                    f"{where}: expected gray, BGR or BGRA of uint8 or uint16, got shape "
                    f"{image.shape} {image.dtype}"
                )
            import cv2  # opencv-python-headless

            code = cv2.COLOR_BGR2GRAY if image.shape[2] == 3 else cv2.COLOR_BGRA2GRAY
            image = cv2.cvtColor(np.ascontiguousarray(image), code)
        if image.ndim != 2:
            raise ValueError(f"{where}: expected a H x W or H x W x C image, got {image.shape}")
        if image.dtype == np.uint16:
            return np.ascontiguousarray(self._from_16_bit(Path(str(where)), image))
        if image.dtype != np.uint8:
            raise ValueError(f"{where}: expected uint8 or uint16 pixels, got {image.dtype}")
        return np.ascontiguousarray(image)

    def _from_16_bit(self, path: Path, data: np.ndarray) -> np.ndarray:
        peak = int(data.max()) if data.size else 0
        if self.shift is None:
            self.shift = 4 if peak <= MAX_12_BIT else 8
            if self.shift == 4:
                log.info(
                    "%s: 16-bit PNG holding 12-bit data (max %d <= %d): scaling by 1/16 "
                    "to 8 bits for the whole sequence",
                    path,
                    peak,
                    MAX_12_BIT,
                )
        elif self.shift == 4 and peak > MAX_12_BIT and not self._warned_saturation:
            self._warned_saturation = True
            log.warning(
                "%s: value %d above 12 bits in a sequence read as 12-bit data: saturated",
                path,
                peak,
            )
        scaled = np.right_shift(data, self.shift)
        return np.minimum(scaled, 255).astype(np.uint8)
