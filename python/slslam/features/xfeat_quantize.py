"""XFeat in 8-bit integers: static quantisation of the shipped ONNX file with onnxruntime.

    slslam models quantize xfeat --out third_party/xfeat/xfeat_int8.onnx

Convolutions run with int8 weights (per output channel) and uint8 activations (QDQ format, the
layout onnxruntime's x86 kernels execute in integers, with VNNI where the processor has it). The
weights use 7 of the 8 bits (``reduce_range``): on an x86 processor without VNNI (AVX2 only, e.g.
AMD EPYC before Zen 4) onnxruntime multiplies uint8 by int8 with an instruction that saturates
pairs of products at 16 bits, and full-range weights overflowed it: fewer of the float network's
keypoints came back within 1 px there than on a VNNI processor, while with 7 bits the outputs are
the same on either processor (benchmarks/log/realtime.md).
Activation ranges come from calibration images (min / max over them): by default frames the
simulator renders of the shaft-bottom loop at full light and at light 0.15 (seed 0), so the file
is reproducible from slslam alone and no data set is needed. On a CPU with VNNI the network
takes about half the time of the float file, on one with AVX2 only about the same; the tracker's
accuracy was the same within the run-to-run spread (benchmarks/log/realtime.md). Needs only
onnxruntime (its ``quantization`` package).
"""

from __future__ import annotations

import logging
import tempfile
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

from slslam.features.superpoint import ModelError
from slslam.features.xfeat import INPUT, SHIPPED_MODEL, pad_to_multiple, validate_session
from slslam.features.xfeat_export import sha256

#: Calibration of the shipped file: the simulated loop at these light levels, these frames.
CALIBRATION_LIGHTS = (1.0, 0.15)
CALIBRATION_FRAMES = tuple(range(0, 84, 7))
#: Nodes left in float. The input's instance normalisation: quantising its input (the image)
#: clipped gray levels above the calibration frames' brightest (176 on the simulated loop) before
#: the network saw them. The keypoint head (four 1 x 1 convolutions on the 8 x 8 pixel blocks of
#: the image, at an eighth of its rows and columns): its logits place the keypoints, to sub-pixel
#: precision on their heatmap; with the head in float the keypoints stay about twice as close to
#: the float network's as with it in 8 bits, in the same time (benchmarks/log/realtime.md).
FLOAT_NODES = ("/net/norm/InstanceNormalization",) + tuple(
    f"/net/keypoint_head/keypoint_head.{i}/{'Conv' if i == 3 else 'layer/layer.0/Conv'}"
    for i in range(4)
)


class _DropMessages(logging.Filter):
    """Drops log records whose message contains ``text``."""

    def __init__(self, text: str) -> None:
        super().__init__()
        self.text = text

    def filter(self, record: logging.LogRecord) -> bool:
        return self.text not in record.getMessage()


def simulated_calibration_images(
    lights: Sequence[float] = CALIBRATION_LIGHTS, frames: Sequence[int] = CALIBRATION_FRAMES
) -> list[np.ndarray]:
    """Left images of the simulated loop (seed 0, no dust, no LiDAR) at each light level."""
    from slslam.sim import SimOptions, Simulator

    images: list[np.ndarray] = []
    for light in lights:
        sim = Simulator(SimOptions(preset="loop", light=light, frames=max(frames) + 1, lidar=False))
        images.extend(sim.render_stereo(i)[0] for i in frames)
    return images


def _float_nodes(path: Path, source: Path) -> list[str]:
    """FLOAT_NODES, all of which the graph must have (another export's names: ModelError)."""
    import onnx

    names = {node.name for node in onnx.load(str(path)).graph.node}
    missing = [name for name in FLOAT_NODES if name not in names]
    if missing:
        raise ModelError(source, f"no node {missing[0]} to keep in float: not XFeat's export")
    return list(FLOAT_NODES)


def quantize_xfeat(
    out: str | Path, images: Iterable[np.ndarray] | None = None, source: str | Path | None = None
) -> dict[str, str]:
    """Writes the int8 file ``out`` from the float file ``source`` (default: the shipped one),
    calibrated on ``images`` (uint8 gray, any size; default: the simulated frames above).
    Returns the facts PROVENANCE.md records."""
    import onnxruntime as ort

    try:
        from onnxruntime.quantization import (
            CalibrationDataReader,
            QuantFormat,
            QuantType,
            quantize_static,
        )
        from onnxruntime.quantization.shape_inference import quant_pre_process
    except ImportError as exc:  # onnxruntime's quantisation needs the onnx package
        raise ModelError(None, f"quantising XFeat needs onnx: pip install onnx ({exc})") from None

    source = Path(source) if source else SHIPPED_MODEL
    if not source.is_file():
        raise ModelError(source, "XFeat model file not found")
    batches = [
        {INPUT: pad_to_multiple(image)[None, None]}
        for image in (simulated_calibration_images() if images is None else images)
    ]
    if not batches:
        raise ValueError("quantising XFeat needs at least one calibration image")

    class Reader(CalibrationDataReader):
        def __init__(self) -> None:
            self._it = iter(batches)

        def get_next(self):
            return next(self._it, None)

    from slslam.files import copy_atomic

    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        prepared = Path(tmp) / "prepared.onnx"
        quant_pre_process(str(source), str(prepared), skip_symbolic_shape=True)
        partial = Path(tmp) / "int8.onnx"
        # onnxruntime warns through the root logger that the instance normalisation's 1-d
        # constant has no channel axis to quantise per channel; it stays in float, as it should.
        quiet = _DropMessages("out-of-range for weight")
        logging.getLogger().addFilter(quiet)
        try:
            quantize_static(
                str(prepared),
                str(partial),
                Reader(),
                quant_format=QuantFormat.QDQ,
                per_channel=True,
                reduce_range=True,  # 7-bit weights: no 16-bit saturation without VNNI (above)
                activation_type=QuantType.QUInt8,
                weight_type=QuantType.QInt8,
                nodes_to_exclude=_float_nodes(prepared, source),
            )
        finally:
            logging.getLogger().removeFilter(quiet)
        session = ort.InferenceSession(str(partial), providers=["CPUExecutionProvider"])
        validate_session(session, partial)
        copy_atomic(partial, out)  # the temporary folder may be on another file system
    return {
        "onnxruntime": ort.__version__,
        "source": f"{source.name} sha256 {sha256(source)}",
        "calibration images": str(len(batches)),
        "sha256": sha256(out),
        "bytes": str(out.stat().st_size),
    }
