"""Keypoints, line segments and their matches drawn on images with OpenCV, written as PNG."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

TITLE_PX = 22  # height of the title band above the images
GREEN, ORANGE = (0, 255, 0), (0, 140, 255)  # BGR


def _canvas(images: list[np.ndarray], title: str) -> np.ndarray:
    """The images side by side as BGR under a title band."""
    h = max(im.shape[0] for im in images)
    tiles = []
    for im in images:
        bgr = cv2.cvtColor(im, cv2.COLOR_GRAY2BGR) if im.ndim == 2 else im.copy()
        tiles.append(cv2.copyMakeBorder(bgr, 0, h - im.shape[0], 0, 0, cv2.BORDER_CONSTANT))
    canvas = cv2.copyMakeBorder(np.hstack(tiles), TITLE_PX, 0, 0, 0, cv2.BORDER_CONSTANT)
    if title:
        cv2.putText(canvas, title, (4, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 255), 1)
    return canvas


def _px(points: np.ndarray, shift: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
    """Points (N, 2) as integer pixels on the canvas (1/16 px sub-pixel precision)."""
    shifted = np.asarray(points, dtype=np.float64).reshape(-1, 2) + [shift[0], shift[1] + TITLE_PX]
    return np.round(shifted * 16).astype(np.int32)


def _segments(canvas, segments, colours, thickness: int, shift=(0.0, 0.0)) -> None:
    ends = _px(np.asarray(segments).reshape(-1, 2), shift).reshape(-1, 2, 2)
    for (a, b), colour in zip(ends, colours, strict=True):
        cv2.line(canvas, tuple(a), tuple(b), colour, thickness, cv2.LINE_AA, shift=4)


def draw_features(
    path: str | Path,
    image: np.ndarray,
    keypoints: np.ndarray | None = None,
    segments: np.ndarray | None = None,
    title: str = "",
) -> Path:
    """Keypoints (N, 2) as green dots and segments (M, 4: u0 v0 u1 v1) as orange lines."""
    canvas = _canvas([image], title)
    if segments is not None and len(segments):
        _segments(canvas, segments, [ORANGE] * len(segments), 1)
    if keypoints is not None and len(keypoints):
        for p in _px(keypoints):
            cv2.circle(canvas, tuple(p), 2 * 16, GREEN, -1, cv2.LINE_AA, shift=4)
    return _save(canvas, path)


def draw_matches(
    path: str | Path,
    image_a: np.ndarray,
    image_b: np.ndarray,
    points_a: np.ndarray,
    points_b: np.ndarray,
    point_pairs: np.ndarray,
    segments_a: np.ndarray | None = None,
    segments_b: np.ndarray | None = None,
    line_pairs: np.ndarray | None = None,
    title: str = "",
) -> Path:
    """Two images side by side: point matches in green, matched segments in matching colours."""
    canvas = _canvas([image_a, image_b], title)
    shift = (float(image_a.shape[1]), 0.0)
    if len(point_pairs):
        a = _px(points_a[point_pairs[:, 0]])
        b = _px(points_b[point_pairs[:, 1]], shift)
        for p, q in zip(a, b, strict=True):
            cv2.line(canvas, tuple(p), tuple(q), GREEN, 1, cv2.LINE_AA, shift=4)
    if line_pairs is not None and len(line_pairs):
        hues = (np.arange(len(line_pairs)) * 37 % 180).astype(np.uint8)
        hsv = np.stack([hues, np.full_like(hues, 255), np.full_like(hues, 255)], 1)[None]
        colours = [tuple(int(c) for c in bgr) for bgr in cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR)[0]]
        assert segments_a is not None and segments_b is not None  # line_pairs index them
        _segments(canvas, segments_a[line_pairs[:, 0]], colours, 2)
        _segments(canvas, segments_b[line_pairs[:, 1]], colours, 2, shift)
    return _save(canvas, path)


def _save(canvas: np.ndarray, path: str | Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        written = cv2.imwrite(str(path), canvas)
    except cv2.error:  # an unknown suffix
        written = False
    if not written:
        raise OSError(f"{path}: cannot write the image (is the suffix .png?)")
    return path
