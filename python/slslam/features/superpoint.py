"""SuperPoint keypoints and descriptors (DeTone et al. 2018) through onnxruntime.

The network gives, per 8 x 8 cell, 65 logits (64 pixel positions + a "no keypoint" dustbin) and a
256-d descriptor. Post-processing, all numpy-vectorised:

1. softmax over the 65 channels, drop the dustbin, pixel-shuffle to a full-resolution heatmap
   (channel c of a cell is the pixel at row c // 8, column c % 8 of that cell);
2. pixels reaching the threshold go through the reference implementation's greedy
   non-maximum suppression (strongest first; each kept point suppresses a (2r+1) x (2r+1) square),
   run in C++;
3. keypoints closer than ``border_px`` to the image edge are dropped, then the strongest
   ``max_keypoints`` are kept;
4. descriptors are sampled bilinearly from the coarse map at coarse position (x / 8 - 0.5,
   y / 8 - 0.5), the mapping of the reference implementation (grid_sample with x normalised by
   W / 2, align_corners=False), clamped at the map border, then L2-normalised.

Images whose sides are not multiples of 8 are padded (edge replication) on the right and bottom;
keypoints never come from the padding.

Weights are not redistributable: the model path comes from the options, else from the environment
variable ``SLSLAM_SUPERPOINT_MODEL``; ``slslam models`` explains how to obtain them.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from slslam import _core
from slslam.errors import InputError
from slslam.features.keypoints import Keypoints, check_gray_image

ENV_MODEL = "SLSLAM_SUPERPOINT_MODEL"
CELL = 8
DESCRIPTOR_DIM = 256
HOW_TO_OBTAIN = (
    "SuperPoint weights are not shipped with slslam (MagicLeap's licence forbids redistribution). "
    f"Set {ENV_MODEL} to a SuperPoint ONNX file, or give model_path; run `slslam models` for how "
    "to obtain and convert the official weights."
)


class ModelError(InputError):
    """The SuperPoint model file is missing or does not have SuperPoint's inputs and outputs."""


def check_detector_options(options) -> None:
    """ValueError unless a network detector's shared options (detection_threshold, nms_radius,
    border_px, max_keypoints, intra_op_threads) are in range; SuperPoint and XFeat use it."""
    if not 0.0 < options.detection_threshold < 1.0:
        raise ValueError(
            f"detection_threshold must be in (0, 1), got {options.detection_threshold}"
        )
    if options.nms_radius < 0 or options.border_px < 0:
        raise ValueError("nms_radius and border_px must be >= 0")
    if options.max_keypoints is not None and options.max_keypoints < 1:
        raise ValueError(f"max_keypoints must be >= 1 or None, got {options.max_keypoints}")
    if options.intra_op_threads < 0:
        raise ValueError(f"intra_op_threads must be >= 0, got {options.intra_op_threads}")


@dataclass(frozen=True)
class SuperPointOptions:
    """SuperPoint settings; the defaults are the paper's post-processing."""

    model_path: str | None = None  # ONNX file; None: $SLSLAM_SUPERPOINT_MODEL
    detection_threshold: float = 0.005  # softmax score a keypoint must reach [-]
    nms_radius: int = 4  # non-maximum suppression radius [px]
    border_px: int = 4  # no keypoints this close to the image edge [px]
    max_keypoints: int | None = None  # keep the strongest N (None: all)
    providers: str | tuple[str, ...] = "auto"  # onnxruntime providers; auto: CUDA if present
    intra_op_threads: int = 0  # onnxruntime threads (0: its default, all cores)
    # Run detect_batch() as one batched inference when the model's batch axis is dynamic. Off by
    # default: on a 2-core CPU two single 752x480 calls took 674 ms against 764 ms batched
    # (benchmark in the issue note); a GPU is where batching pays.
    batch_images: bool = False

    def check(self) -> None:
        check_detector_options(self)


def resolve_model_path(model_path: str | os.PathLike | None) -> Path:
    """The explicit path, else $SLSLAM_SUPERPOINT_MODEL; ModelError with the how-to otherwise."""
    chosen = model_path or os.environ.get(ENV_MODEL)
    if not chosen:
        raise ModelError(None, f"no SuperPoint model given. {HOW_TO_OBTAIN}")
    path = Path(chosen).expanduser()
    if not path.is_file():
        raise ModelError(path, f"SuperPoint model file not found. {HOW_TO_OBTAIN}")
    return path


def _providers(choice: str | tuple[str, ...]) -> list[str]:
    import onnxruntime as ort

    available = ort.get_available_providers()
    if choice == "auto":
        return [p for p in ("CUDAExecutionProvider", "CPUExecutionProvider") if p in available]
    wanted = [choice] if isinstance(choice, str) else list(choice)
    missing = [p for p in wanted if p not in available]
    if missing:
        raise ValueError(f"onnxruntime providers {missing} are not available (have {available})")
    return wanted


def open_session(
    path: Path, providers: str | tuple[str, ...], intra_op_threads: int, spinning: bool = True
):
    """An onnxruntime session on ``path`` (providers as in the options, 0 threads: all cores);
    a file onnxruntime cannot load is a ModelError naming it. Shared by every network. Where
    CUDA was asked for and onnxruntime could not start it, a warning says so (onnxruntime then
    runs on the CPU). ``spinning`` False: the session's worker threads sleep between tasks
    instead of spinning (onnxruntime's ``session.intra_op.allow_spinning``), which leaves the
    cores to the tracker's other threads."""
    import onnxruntime as ort

    chosen = _providers(providers)
    session_options = ort.SessionOptions()
    if intra_op_threads:
        session_options.intra_op_num_threads = intra_op_threads
    if not spinning:
        session_options.add_session_config_entry("session.intra_op.allow_spinning", "0")
    try:
        session = ort.InferenceSession(str(path), session_options, providers=chosen)
    except Exception as exc:  # onnxruntime raises its own types for corrupt files
        raise ModelError(path, f"onnxruntime cannot load it ({exc})") from None
    if "CUDAExecutionProvider" in chosen and "CUDAExecutionProvider" not in session.get_providers():
        import logging

        logging.getLogger("slslam").warning(
            "%s: onnxruntime has CUDA but could not start it (no GPU, or CUDA / cuDNN libraries "
            "missing: pip install onnxruntime-gpu[cuda,cudnn]); running on the CPU",
            path.name,
        )
    return session


def validate_session(session, path: Path) -> None:
    """Raise ModelError unless the session has SuperPoint's input and outputs."""
    inputs = session.get_inputs()
    if len(inputs) != 1 or inputs[0].name != "image" or len(inputs[0].shape) != 4:
        got = [(i.name, i.shape) for i in inputs]
        raise ModelError(path, f"expected one input 'image' of rank 4 [1, 1, H, W], got {got}")
    if inputs[0].shape[1] not in (1, "1") and isinstance(inputs[0].shape[1], int):
        raise ModelError(path, f"input 'image' must have 1 channel, got {inputs[0].shape[1]}")
    outputs = {o.name: o.shape for o in session.get_outputs()}
    for name, channels in (("semi", CELL * CELL + 1), ("desc", DESCRIPTOR_DIM)):
        if name not in outputs:
            raise ModelError(path, f"missing output '{name}' (outputs: {sorted(outputs)})")
        shape = outputs[name]
        if len(shape) != 4 or (isinstance(shape[1], int) and shape[1] != channels):
            raise ModelError(
                path, f"output '{name}' must be [1, {channels}, H/8, W/8], got {shape}"
            )


def heatmap_from_logits(semi: np.ndarray) -> np.ndarray:
    """(65, Hc, Wc) logits -> (8 Hc, 8 Wc) keypoint probability (softmax, dustbin dropped)."""
    e = np.exp(semi - semi.max(axis=0, keepdims=True))
    prob = e[:-1] / e.sum(axis=0, keepdims=True)
    hc, wc = semi.shape[1:]
    return prob.reshape(CELL, CELL, hc, wc).transpose(2, 0, 3, 1).reshape(hc * CELL, wc * CELL)


def nms_keypoints(heat: np.ndarray, threshold: float, radius: int, border: int) -> np.ndarray:
    """(N, 2) integer (u, v) kept by greedy NMS among pixels >= threshold, strongest first,
    without those closer than ``border`` to the image edge (C++: ``_core.suppress_non_maxima``)."""
    v, u = np.nonzero(heat >= threshold)
    uv = np.column_stack([u, v]).astype(np.int32)
    kept = _core.suppress_non_maxima(
        uv, heat[v, u].astype(np.float32), heat.shape[1], heat.shape[0], radius
    )
    uv = uv[np.asarray(kept, dtype=np.int64)]
    h, w = heat.shape
    inside = (
        (uv[:, 0] >= border)
        & (uv[:, 1] >= border)
        & (uv[:, 0] < w - border)
        & (uv[:, 1] < h - border)
    )
    return uv[inside]


def sample_descriptors(coarse: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Bilinear samples of a (D, Hc, Wc) map at pixel positions uv (N, 2); unit rows (N, D)."""
    d, hc, wc = coarse.shape
    x = np.clip(uv[:, 0] / CELL - 0.5, 0.0, wc - 1.0)
    y = np.clip(uv[:, 1] / CELL - 0.5, 0.0, hc - 1.0)
    x0 = np.minimum(np.floor(x).astype(int), wc - 1)
    y0 = np.minimum(np.floor(y).astype(int), hc - 1)
    x1, y1 = np.minimum(x0 + 1, wc - 1), np.minimum(y0 + 1, hc - 1)
    ax, ay = (x - x0)[:, None], (y - y0)[:, None]
    flat = coarse.reshape(d, -1).T
    out = (
        (1 - ax) * (1 - ay) * flat[y0 * wc + x0]
        + ax * (1 - ay) * flat[y0 * wc + x1]
        + (1 - ax) * ay * flat[y1 * wc + x0]
        + ax * ay * flat[y1 * wc + x1]
    )
    norm = np.linalg.norm(out, axis=1, keepdims=True)
    # A zero descriptor (a flat, black region through a network without bias) stays zero; the
    # caller drops such keypoints rather than match them.
    return (out / np.maximum(norm, 1e-12)).astype(np.float32)


def pad_to_cells(image: np.ndarray) -> np.ndarray:
    """Float image in [0, 1], padded right/bottom (edge replication) to multiples of 8."""
    h, w = image.shape
    pad_h, pad_w = (-h) % CELL, (-w) % CELL
    out = image.astype(np.float32) / 255.0
    return np.pad(out, ((0, pad_h), (0, pad_w)), mode="edge") if pad_h or pad_w else out


class SuperPoint:
    """SuperPoint on onnxruntime. ``detect(image)`` returns :class:`Keypoints`."""

    #: The tracker hands the network the image as it came, not the copy it smooths for lines and
    #: stereo matching when it is noisy (``tracking.denoise_above_noise``): on the dark simulated
    #: loop SuperPoint + lines drifted less on the raw images than on the smoothed ones
    #: (benchmarks/log/realtime.md). Bright frames are quiet, so the two are the same image there.
    smoothed_input = False
    # Its detect's keywords (slslam.features.PointFrontEnd): threshold (the low-texture fallback).
    detect_takes_threshold = True
    detect_takes_select = False
    detect_takes_denoised = False

    def __init__(self, options: SuperPointOptions = SuperPointOptions()):
        options.check()
        self.options = options
        self.model_path = resolve_model_path(options.model_path)
        self.session = open_session(self.model_path, options.providers, options.intra_op_threads)
        validate_session(self.session, self.model_path)
        self.providers = self.session.get_providers()

    @property
    def batch_is_dynamic(self) -> bool:
        """True when the model accepts several images per inference."""
        return not isinstance(self.session.get_inputs()[0].shape[0], int)

    def infer(self, image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Raw network outputs (65, Hc, Wc) logits and (256, Hc, Wc) descriptors."""
        padded = pad_to_cells(check_gray_image(image))
        semi, desc = self.session.run(["semi", "desc"], {"image": padded[None, None]})
        return semi[0], desc[0]

    def detect(self, image: np.ndarray, threshold: float | None = None) -> Keypoints:
        """Keypoints of one uint8 gray image; ``threshold`` overrides the options' detection
        threshold (the tracker's low-texture fallback detects at a lower one)."""
        return self._postprocess(image, *self.infer(image), threshold=threshold)

    def _postprocess(
        self,
        image: np.ndarray,
        semi: np.ndarray,
        coarse: np.ndarray,
        threshold: float | None = None,
    ) -> Keypoints:
        h, w = image.shape
        heat = heatmap_from_logits(semi)[:h, :w]
        o = self.options
        threshold = o.detection_threshold if threshold is None else threshold
        uv = nms_keypoints(heat, threshold, o.nms_radius, o.border_px)
        if o.max_keypoints is not None:
            uv = uv[: o.max_keypoints]
        scores = heat[uv[:, 1], uv[:, 0]].astype(np.float32)
        uv = uv.astype(np.float32)
        descriptors = sample_descriptors(coarse, uv)
        described = np.einsum("ij,ij->i", descriptors, descriptors) > 0.5
        return Keypoints(uv, scores, descriptors).select(described)

    def detect_batch(self, images: Sequence[np.ndarray]) -> list[Keypoints]:
        """Keypoints of several images (a stereo pair): one batched inference when
        ``options.batch_images`` is set, the model's batch axis is dynamic and the images share a
        size; one inference per image otherwise."""
        same_size = len({np.shape(image) for image in images}) == 1
        if not (self.options.batch_images and self.batch_is_dynamic and same_size and images):
            return [self.detect(image) for image in images]
        batch = np.stack([pad_to_cells(check_gray_image(image)) for image in images])[:, None]
        semi, desc = self.session.run(["semi", "desc"], {"image": batch})
        return [self._postprocess(image, semi[k], desc[k]) for k, image in enumerate(images)]
