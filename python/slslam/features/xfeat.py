"""XFeat keypoints and descriptors (Potje et al., CVPR 2024) through onnxruntime.

XFeat is a small network made for CPUs. Its weights are Apache-2.0 and ship with slslam
(third_party/xfeat: licence, provenance and the export command ``slslam models export xfeat``),
so this front end works with no download. The network gives, on the 1/8 grid, 65 keypoint logits
per cell (64 pixel positions + a dustbin, as SuperPoint), a reliability map and 64-d dense
descriptors. Post-processing follows the reference ``detectAndCompute``, all numpy-vectorised:

1. softmax over the 65 channels, dustbin dropped, pixel-shuffled to a full-resolution heatmap;
2. non-maximum suppression: a pixel is a keypoint when it is the maximum of the
   (2r+1) x (2r+1) window around it (the reference's 5 x 5 max-pool, r = 2) and its heatmap value
   exceeds the detection threshold;
3. rank = heatmap at the keypoint x reliability sampled bilinearly at it (the reference's score);
   the ``max_keypoints`` of highest rank are kept, highest first;
4. descriptors are sampled bicubically from the dense map (already unit length) and normalised.

Sampling uses the reference's mapping from a pixel x of a W-wide network input to the coarse map
(``grid_sample`` with x normalised by W - 1, align_corners=False): x * Wc / (W - 1) - 0.5, with
zero padding outside the map, and PyTorch's cubic convolution kernel (A = -0.75).

The network needs sides that are multiples of 32. The reference resizes the image to the nearest
smaller multiple and scales the keypoints back; here the image is padded (edge replication) on the
right and bottom instead, so keypoints are measured on the image's own pixel grid (a rectified
stereo pair keeps its geometry exactly) and never come from the padding. On images whose sides are
multiples of 32 both give the same keypoints.

``Keypoints.scores`` holds the heatmap value, not the rank: it is on the scale of
``detection_threshold``, which the tracker's low-texture fallback compares scores with (a cell
holding a keypoint above the threshold keeps only those). With the rank as the score, 86 % of the
keypoints above the threshold scored below it on a EuRoC image and the fallback thinned the cells
that had any; on 100 frames of the dark simulated loop (XFeat + lines) that gave 0.073 m ATE
against 0.039 m with the heatmap value (benchmarks/log/xfeat_frontend.md).

Keypoints are whole pixels. The keypoint head sees one 8 x 8 cell at a time, so a keypoint repeats
exactly under shifts by whole cells and within about 1.3 px rms along a shift that moves the
content off the cell grid (EuRoC image, 3-13 px shifts; tests/python/test_xfeat.py). With
``subpixel`` (set by XFeat's preset) each is moved to the vertex of a Gaussian fitted to the
heatmap around it, per axis (``refine_subpixel``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from slslam import _core
from slslam.features.keypoints import Keypoints, check_gray_image, smoothed_already
from slslam.features.superpoint import (
    ModelError,
    check_detector_options,
    heatmap_from_logits,
    open_session,
)

CELL = 8  # the coarse maps are 1/8 of the input [px]
MULTIPLE = 32  # the network's input sides must be multiples of this [px]
DESCRIPTOR_DIM = 64
INPUT = "image"
OUTPUTS = ("descriptors", "keypoint_logits", "reliability")
OUTPUT_CHANNELS = {
    "descriptors": DESCRIPTOR_DIM,
    "keypoint_logits": CELL * CELL + 1,
    "reliability": 1,
}
#: The ONNX file installed with slslam (CMake copies third_party/xfeat into slslam/data/xfeat).
SHIPPED_MODEL = Path(__file__).resolve().parent.parent / "data" / "xfeat" / "xfeat.onnx"
#: The same network quantised to 8 bits (``slslam models quantize xfeat``), shipped beside it.
SHIPPED_INT8_MODEL = SHIPPED_MODEL.with_name("xfeat_int8.onnx")
PRECISIONS = ("fp32", "int8")


@dataclass(frozen=True)
class XFeatOptions:
    """XFeat settings; the defaults are the reference detectAndCompute's post-processing, and the
    smoothing of noisy frames that the reference does not do."""

    model_path: str | None = None  # ONNX file; None: the one shipped with slslam
    # the shipped file used when model_path is None: fp32, or int8 (quantised, about half the
    # network's time on a CPU, the same tracking accuracy on the simulated loop)
    precision: Literal["fp32", "int8"] = "fp32"
    detection_threshold: float = 0.05  # heatmap value a keypoint must exceed [-]
    nms_radius: int = 2  # keypoints are maxima of a (2r+1) x (2r+1) window [px]
    border_px: int = 0  # no keypoints this close to the image edge [px]
    max_keypoints: int | None = 4096  # keep the strongest N (None: all)
    providers: str | tuple[str, ...] = "auto"  # onnxruntime providers; auto: CUDA if present
    intra_op_threads: int = 0  # onnxruntime threads (0: its default, all cores)
    # onnxruntime's worker threads spin while waiting for work (its default); False: they sleep,
    # and leave the cores to the tracker's other threads
    intra_op_spinning: bool = True
    # keypoints to subpixel positions: a Gaussian (parabola through the log heatmap) fitted to
    # the maximum and its two neighbours along each axis (the reference keeps whole pixels)
    subpixel: bool = False
    # Dark frames are noisy (gain): above this estimated noise (Immerkaer's estimator, as ORB's
    # denoise_above_noise) the network sees a Gaussian-smoothed image, sigma = noise / 7 px
    # [gray levels]; 0: never smooth
    denoise_above_noise: float = 6.0

    def check(self) -> None:
        check_detector_options(self)
        if self.precision not in PRECISIONS:
            raise ValueError(f"precision must be one of {PRECISIONS}, got {self.precision!r}")
        if not 0.0 <= self.denoise_above_noise <= 255.0:
            raise ValueError(
                f"denoise_above_noise must be in [0, 255], got {self.denoise_above_noise}"
            )


def resolve_model_path(model_path: str | None, precision: str = "fp32") -> Path:
    """The explicit path, else the shipped model of that precision; ModelError naming the file
    when it is missing."""
    if model_path:
        path = Path(model_path).expanduser()
        if not path.is_file():
            raise ModelError(path, "XFeat model file not found")
        return path
    shipped = SHIPPED_INT8_MODEL if precision == "int8" else SHIPPED_MODEL
    if not shipped.is_file():
        raise ModelError(
            shipped,
            "the XFeat model shipped with slslam is missing from this installation "
            "(reinstall slslam, or export one with `slslam models export xfeat --out FILE` and "
            "set features.xfeat.model_path)",
        )
    return shipped


def validate_session(session, path: Path) -> None:
    """Raise ModelError unless the session has XFeat's input and outputs (see xfeat_export)."""
    inputs = session.get_inputs()
    if len(inputs) != 1 or inputs[0].name != INPUT or len(inputs[0].shape) != 4:
        got = [(i.name, i.shape) for i in inputs]
        raise ModelError(path, f"expected one input '{INPUT}' of rank 4 [1, 1, H, W], got {got}")
    if isinstance(inputs[0].shape[1], int) and inputs[0].shape[1] != 1:
        raise ModelError(path, f"input '{INPUT}' must have 1 channel, got {inputs[0].shape[1]}")
    outputs = {o.name: o.shape for o in session.get_outputs()}
    for name, channels in OUTPUT_CHANNELS.items():
        if name not in outputs:
            raise ModelError(path, f"missing output '{name}' (outputs: {sorted(outputs)})")
        shape = outputs[name]
        if len(shape) != 4 or (isinstance(shape[1], int) and shape[1] != channels):
            raise ModelError(
                path, f"output '{name}' must be [1, {channels}, H/8, W/8], got {shape}"
            )


def estimate_noise(image: np.ndarray) -> float:
    """Standard deviation of white noise in an 8-bit gray image [gray levels] (Immerkaer 1996),
    in C++ (``_core.estimate_noise_sigma``, the tracker's and ORB's estimate): the mask's
    response summed exactly in integers, one pass (a float32 ``cv2.filter2D`` and its sum took
    1.5-2 ms an image, on every detected frame)."""
    return float(_core.estimate_noise_sigma(image))


def denoise(image: np.ndarray, above_noise: float) -> np.ndarray:
    """The image smoothed by a Gaussian of sigma noise / 7 (clamped to 0.5-2.5 px) when its
    noise exceeds ``above_noise`` (> 0), else the image itself: ``_core.smooth_if_noisy``, the
    smoothing the tracker applies to noisy frames (so on a frame the tracker smoothed already it
    only estimates the noise)."""
    if above_noise <= 0.0:
        return image
    return _core.smooth_if_noisy(image, float(above_noise))


def pad_to_multiple(image: np.ndarray) -> np.ndarray:
    """Float32 gray levels, padded right/bottom (edge replication) to multiples of 32."""
    h, w = image.shape
    pad_h, pad_w = (-h) % MULTIPLE, (-w) % MULTIPLE
    out = image.astype(np.float32)
    return np.pad(out, ((0, pad_h), (0, pad_w)), mode="edge") if pad_h or pad_w else out


def local_maxima(heat: np.ndarray, threshold: float, radius: int, border: int) -> np.ndarray:
    """(N, 2) integer (u, v) of pixels above ``threshold`` that are the maximum of their
    (2r+1)^2 window (ties all kept, as the reference's max-pool), at least ``border`` px inside
    the image, in row-major order. In C++ (``_core.local_maxima``): the numpy version (24 shifted
    comparisons over every candidate) took 10-20 ms an image, a fifth of XFeat's time with int8."""
    heat = np.ascontiguousarray(heat, dtype=np.float32)
    return np.asarray(_core.local_maxima(heat, float(threshold), int(radius), int(border)))


def refine_subpixel(heat: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(N, 2) float32 subpixel positions of the integer maxima ``uv`` of ``heat``: per axis the
    vertex of the parabola through the log heatmap at the maximum and its two neighbours (a
    Gaussian peak), within half a pixel; maxima on the image's edge keep their pixel."""
    h, w = heat.shape
    out = uv.astype(np.float32)
    if len(uv) == 0:
        return out
    u, v = uv[:, 0], uv[:, 1]
    log = lambda a: np.log(np.maximum(a, 1e-12))  # noqa: E731
    for axis, (size, du, dv) in enumerate(((w, 1, 0), (h, 0, 1))):
        pos = uv[:, axis]
        inside = (pos > 0) & (pos < size - 1)
        ui, vi = u[inside], v[inside]
        c = log(heat[vi, ui])
        lo = log(heat[vi - dv, ui - du])
        hi = log(heat[vi + dv, ui + du])
        curvature = lo - 2.0 * c + hi
        with np.errstate(divide="ignore", invalid="ignore"):
            offset = np.where(curvature < 0.0, 0.5 * (lo - hi) / curvature, 0.0)
        out[inside, axis] += np.clip(offset, -0.5, 0.5).astype(np.float32)
    return out


def sample_map(
    coarse: np.ndarray, uv: np.ndarray, input_hw: tuple[int, int], cubic: bool
) -> np.ndarray:
    """(N, C) float32 samples of a (C, Hc, Wc) map at pixels uv (N, 2) of the network input
    (H, W), as the reference's ``grid_sample`` (align_corners=False, zero padding): bilinear or
    bicubic (PyTorch's kernel, A = -0.75). In C++ (``_core.sample_dense_map``): the scipy sparse
    product it replaces took 3-8 ms an image."""
    c, hc, wc = coarse.shape
    flat = np.ascontiguousarray(coarse.reshape(c, hc * wc), dtype=np.float32)
    points = np.ascontiguousarray(uv, dtype=np.float32).reshape(-1, 2)
    h, w = input_hw
    return np.asarray(_core.sample_dense_map(flat, hc, wc, points, h, w, bool(cubic)))


class XFeat:
    """XFeat on onnxruntime. ``detect(image)`` returns :class:`Keypoints` (64-d float)."""

    #: The tracker hands the network the pair it smoothed for lines and stereo matching when
    #: noisy (``tracking.denoise_above_noise``); on the raw dark images XFeat never initialised.
    smoothed_input = True
    # Its detect's keywords (slslam.features.PointFrontEnd): threshold, select (the grid limit
    # before descriptors are sampled) and denoised_above_noise.
    detect_takes_threshold = True
    detect_takes_select = True
    detect_takes_denoised = True

    def __init__(self, options: XFeatOptions = XFeatOptions()):
        options.check()
        self.options = options
        self.model_path = resolve_model_path(options.model_path, options.precision)
        self.session = open_session(
            self.model_path, options.providers, options.intra_op_threads, options.intra_op_spinning
        )
        validate_session(self.session, self.model_path)
        self.providers = self.session.get_providers()

    def infer(self, image: np.ndarray) -> dict[str, np.ndarray]:
        """Raw network outputs of one uint8 image (padded to multiples of 32), batch dropped:
        descriptors (64, Hc, Wc), keypoint_logits (65, Hc, Wc), reliability (1, Hc, Wc)."""
        padded = pad_to_multiple(check_gray_image(image))
        outputs = self.session.run(list(OUTPUTS), {INPUT: padded[None, None]})
        return {name: out[0] for name, out in zip(OUTPUTS, outputs, strict=True)}

    def detect(
        self,
        image: np.ndarray,
        threshold: float | None = None,
        select: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
        denoised_above_noise: float | None = None,
    ) -> Keypoints:
        """Keypoints of one uint8 gray image; ``threshold`` overrides the options' detection
        threshold (the tracker's low-texture fallback detects at a lower one). ``select``, given
        the (N, 2) float32 positions and (N,) scores, returns the indices of the keypoints to
        keep (the tracker's grid limit): only those are described, and returned in that order
        (descriptor sampling is the costliest step after the network). ``denoised_above_noise``:
        the image came through ``_core.smooth_if_noisy`` at this threshold (the tracker's
        smoothing); the network's own smoothing check is then skipped when its threshold is at
        least this one (as :meth:`slslam.features.orb.Orb.detect`, with the same caveat)."""
        image = check_gray_image(image)
        o = self.options
        checked = smoothed_already(denoised_above_noise, o.denoise_above_noise)
        net = self.infer(image if checked else denoise(image, o.denoise_above_noise))
        threshold = o.detection_threshold if threshold is None else threshold
        hc, wc = net["keypoint_logits"].shape[1:]
        input_hw = (hc * CELL, wc * CELL)
        h, w = image.shape
        heat = heatmap_from_logits(net["keypoint_logits"])[:h, :w]
        uv = local_maxima(heat, threshold, o.nms_radius, o.border_px)
        reliability = sample_map(net["reliability"], uv, input_hw, cubic=False)[:, 0]
        scores = heat[uv[:, 1], uv[:, 0]]
        rank = scores * reliability
        order = np.argsort(-rank, kind="stable")[: o.max_keypoints]
        order = order[rank[order] > 0]
        uv, scores = uv[order], scores[order].astype(np.float32)
        uv = refine_subpixel(heat, uv) if o.subpixel else uv.astype(np.float32)
        if select is not None and len(uv) > 0:
            keep = np.asarray(select(uv, scores), dtype=np.int64)
            uv, scores = uv[keep], scores[keep]
        descriptors = sample_map(net["descriptors"], uv, input_hw, cubic=True)
        norm = np.linalg.norm(descriptors, axis=1, keepdims=True)
        descriptors = (descriptors / np.maximum(norm, 1e-12)).astype(np.float32)
        return Keypoints(uv, scores, descriptors.reshape(-1, DESCRIPTOR_DIM))
