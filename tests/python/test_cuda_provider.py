"""onnxruntime's CUDA provider: chosen by ``providers: auto`` when present, and the networks give
the same keypoints and descriptors on it as on the CPU (within a tolerance: cuDNN's convolutions
sum in another order). The comparison skips where onnxruntime has no CUDAExecutionProvider."""

from __future__ import annotations

import numpy as np
import pytest

from slslam.features.superpoint import SuperPoint, SuperPointOptions, _providers
from slslam.features.xfeat import XFeat, XFeatOptions

from conftest import SHARED_DATA

ort = pytest.importorskip("onnxruntime")
HAS_CUDA = "CUDAExecutionProvider" in ort.get_available_providers()
SUPERPOINT = SHARED_DATA.parent / "models" / "superpoint_v1" / "superpoint_v1.onnx"
needs_cuda = pytest.mark.skipif(
    not HAS_CUDA, reason="onnxruntime has no CUDAExecutionProvider here (no GPU or a CPU build)"
)


def textured_image(seed: int = 3) -> np.ndarray:
    """Blobs and edges at several scales, 480 x 752 (a rock wall's statistics, roughly)."""
    rng = np.random.default_rng(seed)
    from scipy.ndimage import gaussian_filter

    image = sum(gaussian_filter(rng.normal(0, 1, (480, 752)), s) * s for s in (1.0, 3.0, 8.0))
    image = (image - image.min()) / np.ptp(image) * 255
    return image.astype(np.uint8)


def test_auto_puts_cuda_first_exactly_when_onnxruntime_has_it():
    chosen = _providers("auto")
    assert chosen[-1] == "CPUExecutionProvider"
    assert (chosen[0] == "CUDAExecutionProvider") == HAS_CUDA


def assert_same_features(cpu, gpu, max_px: float = 1.0, min_shared: float = 0.95) -> None:
    """Most CPU keypoints have a GPU keypoint within max_px, with nearly the same descriptor."""
    assert len(cpu) > 100
    assert abs(len(gpu) - len(cpu)) <= 0.05 * len(cpu)
    d = np.linalg.norm(cpu.uv[:, None, :] - gpu.uv[None, :, :], axis=2)
    nearest = d.argmin(axis=1)
    close = d[np.arange(len(cpu)), nearest] <= max_px
    assert close.mean() >= min_shared
    a = cpu.descriptors[close].astype(np.float64)
    b = gpu.descriptors[nearest[close]].astype(np.float64)
    assert np.median(np.einsum("ij,ij->i", a, b)) > 0.999


@needs_cuda
def test_xfeat_on_cuda_matches_the_cpu():
    image = textured_image()
    cpu = XFeat(XFeatOptions(providers="CPUExecutionProvider")).detect(image)
    cuda = XFeat(XFeatOptions(providers=("CUDAExecutionProvider", "CPUExecutionProvider")))
    assert cuda.providers[0] == "CUDAExecutionProvider"
    assert_same_features(cpu, cuda.detect(image))


@needs_cuda
@pytest.mark.skipif(not SUPERPOINT.is_file(), reason=f"no SuperPoint weights at {SUPERPOINT}")
def test_superpoint_on_cuda_matches_the_cpu():
    image = textured_image()
    path = str(SUPERPOINT)
    cpu = SuperPoint(SuperPointOptions(model_path=path, providers="CPUExecutionProvider"))
    cuda = SuperPoint(
        SuperPointOptions(
            model_path=path, providers=("CUDAExecutionProvider", "CPUExecutionProvider")
        )
    )
    assert cuda.providers[0] == "CUDAExecutionProvider"
    assert_same_features(cpu.detect(image), cuda.detect(image))


@pytest.mark.skipif(HAS_CUDA, reason="CUDA starts here: the fallback cannot be seen")
def test_cuda_asked_for_but_not_started_is_a_warning_not_a_silent_cpu_run(monkeypatch, caplog):
    """onnxruntime-gpu lists CUDA on a machine without a GPU and quietly runs on the CPU: the
    session is made anyway, and slslam says in the log that CUDA did not start."""
    import slslam.features.superpoint as sp
    from slslam.features.xfeat import SHIPPED_MODEL

    monkeypatch.setattr(
        sp, "_providers", lambda _: ["CUDAExecutionProvider", "CPUExecutionProvider"]
    )
    with caplog.at_level("WARNING", logger="slslam"):
        session = sp.open_session(SHIPPED_MODEL, "auto", 1)
    assert session.get_providers() == ["CPUExecutionProvider"]
    assert "could not start" in caplog.text and SHIPPED_MODEL.name in caplog.text
