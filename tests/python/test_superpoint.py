"""SuperPoint front end: post-processing by hand, model loading and validation on a tiny random
network built here, and the real weights when they are present."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from slslam import _core
from slslam.features import ModelError, SuperPoint, SuperPointOptions
from slslam.features.orb import Orb
from slslam.features.superpoint import (
    ENV_MODEL,
    heatmap_from_logits,
    nms_keypoints,
    pad_to_cells,
    sample_descriptors,
)

from conftest import SHARED_DATA

REAL_MODEL = SHARED_DATA.parent / "models" / "superpoint_v1" / "superpoint_v1.onnx"


def tiny_model(
    path: Path, semi_channels: int = 65, desc_channels: int = 256, input_name: str = "image"
) -> Path:
    """A random SuperPoint-shaped network: 8x8 stride-8 convolutions, dynamic H and W."""
    onnx = pytest.importorskip("onnx", reason="the onnx package builds the test model")
    from onnx import TensorProto, helper, numpy_helper

    rng = np.random.default_rng(0)
    w_semi = numpy_helper.from_array(
        rng.normal(0, 1, (semi_channels, 1, 8, 8)).astype(np.float32), "w_semi"
    )
    w_desc = numpy_helper.from_array(
        rng.normal(0, 1, (desc_channels, 1, 8, 8)).astype(np.float32), "w_desc"
    )
    nodes = [
        helper.make_node("Conv", [input_name, "w_semi"], ["semi"], strides=[8, 8]),
        helper.make_node("Conv", [input_name, "w_desc"], ["desc"], strides=[8, 8]),
    ]
    graph = helper.make_graph(
        nodes,
        "tiny_superpoint",
        [helper.make_tensor_value_info(input_name, TensorProto.FLOAT, ["N", 1, "H", "W"])],
        [
            helper.make_tensor_value_info(
                "semi", TensorProto.FLOAT, ["N", semi_channels, "Hc", "Wc"]
            ),
            helper.make_tensor_value_info(
                "desc", TensorProto.FLOAT, ["N", desc_channels, "Hc", "Wc"]
            ),
        ],
        initializer=[w_semi, w_desc],
    )
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    onnx.save(model, path)
    return path


def test_heatmap_pixel_shuffle_puts_channel_c_at_row_c_div_8_column_c_mod_8():
    semi = np.full((65, 2, 3), -20.0, dtype=np.float32)
    semi[64] = 5.0  # dustbin everywhere ...
    semi[8 * 2 + 5, 1, 2] = 30.0  # ... except one cell: channel 21 (row 2, column 5)
    heat = heatmap_from_logits(semi)
    assert heat.shape == (16, 24)
    v, u = np.unravel_index(np.argmax(heat), heat.shape)
    assert (v, u) == (8 + 2, 16 + 5)
    assert heat[v, u] == pytest.approx(1.0, abs=1e-6)


def test_nms_keeps_cluster_peak_and_distant_peaks_and_drops_the_border():
    heat = np.zeros((40, 40), dtype=np.float32)
    heat[10, 10], heat[10, 12], heat[12, 11] = 0.9, 0.5, 0.4  # one cluster
    heat[10, 20] = 0.6  # 10 px away: a peak of its own
    heat[2, 20] = 0.95  # within the 4 px border
    heat[30, 30] = 0.001  # under the threshold
    uv = nms_keypoints(heat, threshold=0.005, radius=4, border=4)
    assert uv.tolist() == [[10, 10], [20, 10]]


def test_descriptor_sampling_at_cell_centre_and_halfway():
    coarse = np.zeros((4, 2, 3), dtype=np.float32)
    coarse[:, 0, 0] = [1, 0, 0, 0]
    coarse[:, 0, 1] = [0, 1, 0, 0]
    # Cell (row 0, column 0) is sampled exactly at pixel (4, 4): x / 8 - 0.5 = 0.
    at_centre = sample_descriptors(coarse, np.array([[4.0, 4.0]]))
    np.testing.assert_allclose(at_centre[0], [1, 0, 0, 0], atol=1e-6)
    # Halfway to the next cell (pixel 8): the normalised average.
    halfway = sample_descriptors(coarse, np.array([[8.0, 4.0]]))
    np.testing.assert_allclose(halfway[0], np.array([1, 1, 0, 0]) / np.sqrt(2), atol=1e-6)


def test_padding_to_multiples_of_eight():
    image = np.arange(60 * 90, dtype=np.uint32).reshape(60, 90).astype(np.uint8)
    padded = pad_to_cells(image)
    assert padded.shape == (64, 96) and padded.dtype == np.float32
    np.testing.assert_allclose(padded[:60, :90], image / 255.0)
    np.testing.assert_allclose(padded[63, :90], image[59] / 255.0)  # edge replicated


def test_tiny_model_runs_on_odd_sizes_and_black_images(tmp_path):
    model = tiny_model(tmp_path / "tiny.onnx")
    net = SuperPoint(SuperPointOptions(model_path=str(model), max_keypoints=50))
    image = np.random.default_rng(1).integers(0, 255, (60, 90), dtype=np.uint8)
    kp = net.detect(image)
    assert 0 < len(kp) <= 50
    assert kp.descriptors.shape == (len(kp), 256) and kp.descriptors.dtype == np.float32
    np.testing.assert_allclose(np.linalg.norm(kp.descriptors, axis=1), 1.0, atol=1e-5)
    assert np.all((kp.uv[:, 0] >= 4) & (kp.uv[:, 0] < 86) & (kp.uv[:, 1] >= 4) & (kp.uv[:, 1] < 56))
    assert np.all(np.diff(kp.scores) <= 0)  # strongest first
    # A black frame through this bias-free network gives zero descriptors: such keypoints are
    # dropped, not returned with meaningless descriptors.
    assert len(net.detect(np.zeros((48, 64), dtype=np.uint8))) == 0
    assert len(net.detect_batch([image, image])) == 2
    # A batched inference of a stereo pair gives exactly what two single calls give.
    batched = SuperPoint(
        SuperPointOptions(model_path=str(model), max_keypoints=50, batch_images=True)
    )
    assert batched.batch_is_dynamic
    other = np.ascontiguousarray(image[:, ::-1])
    for a, b in zip(
        batched.detect_batch([image, other]), [net.detect(image), net.detect(other)], strict=True
    ):
        np.testing.assert_array_equal(a.uv, b.uv)
        np.testing.assert_allclose(a.descriptors, b.descriptors, atol=1e-6)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"semi_channels": 64}, "output 'semi' must be"),
        ({"desc_channels": 128}, "output 'desc'"),
        ({"input_name": "img"}, "expected one input 'image'"),
    ],
)
def test_models_that_do_not_fit_are_rejected_with_the_file_name(tmp_path, kwargs, message):
    model = tiny_model(tmp_path / "bad.onnx", **kwargs)
    with pytest.raises(ModelError, match=message) as info:
        SuperPoint(SuperPointOptions(model_path=str(model)))
    assert str(model) in str(info.value)


def test_model_path_resolution(tmp_path, monkeypatch):
    monkeypatch.delenv(ENV_MODEL, raising=False)
    with pytest.raises(ModelError, match="slslam models"):
        SuperPoint()
    with pytest.raises(ModelError, match="file not found"):
        SuperPoint(SuperPointOptions(model_path=str(tmp_path / "missing.onnx")))
    corrupt = tmp_path / "corrupt.onnx"
    corrupt.write_bytes(b"not a model")
    with pytest.raises(ModelError, match="cannot load"):
        SuperPoint(SuperPointOptions(model_path=str(corrupt)))
    monkeypatch.setenv(ENV_MODEL, str(tiny_model(tmp_path / "env.onnx")))
    assert SuperPoint().model_path == tmp_path / "env.onnx"


def test_bad_images_are_rejected(tmp_path):
    net = SuperPoint(SuperPointOptions(model_path=str(tiny_model(tmp_path / "t.onnx"))))
    for bad, message in (
        (np.zeros((8, 8), np.uint8), "smaller than"),
        (np.zeros((64, 64), np.float32), "uint8"),
        (np.zeros((64, 64, 3), np.uint8), "2-D"),
    ):
        with pytest.raises(ValueError, match=message):
            net.detect(bad)
    with pytest.raises(ValueError, match="detection_threshold"):
        SuperPointOptions(detection_threshold=0.0).check()


@pytest.fixture
def real_model() -> str:
    if not REAL_MODEL.is_file():
        pytest.skip(f"real SuperPoint weights not available at {REAL_MODEL}")
    return str(REAL_MODEL)


def _euroc_image() -> np.ndarray:
    folder = SHARED_DATA / "euroc_v101_micro" / "mav0" / "cam0" / "data"
    if not folder.is_dir():
        pytest.skip(f"real EuRoC images not available at {folder}")
    return _core.read_gray_image(str(sorted(folder.glob("*.png"))[0]))


def test_real_weights_find_spread_keypoints_that_match_under_a_shift(real_model):
    image = _euroc_image()
    net = SuperPoint(SuperPointOptions(model_path=real_model))
    kp = net.detect(image)
    assert len(kp) > 300
    # Spread over the image: keypoints in at least 3 of 4 quadrants.
    quadrants = {(u > 376, v > 240) for u, v in kp.uv}
    assert len(quadrants) >= 3
    np.testing.assert_allclose(np.linalg.norm(kp.descriptors, axis=1), 1.0, atol=1e-5)
    assert len(net.detect(np.zeros_like(image))) == 0  # a black frame: no keypoints, no crash
    shifted = np.ascontiguousarray(image[:, 16:])  # content moves 16 px left
    kp2 = net.detect(shifted)
    options = _core.MatchOptions()
    options.max_distance, options.ratio = 1.0, 1.0
    pairs = _core.match_descriptors(kp.descriptors, kp2.descriptors, options)
    assert len(pairs) > 200
    delta = kp.uv[pairs[:, 0]] - kp2.uv[pairs[:, 1]] - np.array([16.0, 0.0])
    assert np.mean(np.linalg.norm(delta, axis=1) < 2.0) > 0.8


def test_orb_has_the_same_interface():
    image = _euroc_image()
    kp = Orb().detect(image)
    assert len(kp) > 300 and kp.descriptors.shape[1] == 32 and kp.descriptors.dtype == np.uint8
    assert kp.uv.dtype == np.float32 and kp.scores.shape == (len(kp),)


def test_models_command_explains_checks_and_reports_errors(tmp_path, capsys):
    from slslam.cli import main

    assert main(["models", "guide"]) == 0
    assert ENV_MODEL in capsys.readouterr().out
    good = tiny_model(tmp_path / "good.onnx")
    assert main(["models", "check", str(good)]) == 0
    assert "SuperPoint model OK" in capsys.readouterr().out
    bad = tiny_model(tmp_path / "bad.onnx", desc_channels=64)
    assert main(["models", "check", str(bad)]) == 2
    assert "output 'desc'" in capsys.readouterr().err
    assert main(["models", "convert", str(tmp_path / "none.pth"), str(tmp_path / "o.onnx")]) == 2


def test_convert_pth_reproduces_the_reference_onnx(real_model, tmp_path):
    """Our PyTorch SuperPoint definition + export gives the same network as the reference ONNX
    (weights from the workplace's fp16 numpy copy, written as a MagicLeap-style .pth)."""
    torch = pytest.importorskip("torch", reason="converting .pth weights needs PyTorch")
    npz = REAL_MODEL.parent / "superpoint_v1_fp16.npz"
    if not npz.is_file():
        pytest.skip(f"numpy copy of the weights not available at {npz}")
    from slslam.features.models import convert_pth

    weights = np.load(npz)
    pth = tmp_path / "superpoint_v1.pth"
    torch.save({k: torch.from_numpy(weights[k].astype(np.float32)) for k in weights}, pth)
    converted = SuperPoint(SuperPointOptions(model_path=str(convert_pth(pth, tmp_path / "c.onnx"))))
    reference = SuperPoint(SuperPointOptions(model_path=real_model))
    image = _euroc_image()
    for ours, theirs in zip(converted.infer(image), reference.infer(image), strict=True):
        np.testing.assert_allclose(ours, theirs, atol=1e-3)
    assert converted.batch_is_dynamic  # our export allows batched stereo inference
