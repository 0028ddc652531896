"""Point front ends side by side: SuperPoint (onnxruntime) vs ORB (OpenCV), in one run.

    SLSLAM_SUPERPOINT_MODEL=path/to/superpoint_v1.onnx python benchmarks/point_frontend.py

Measures, on the same images and with the same number of keypoints:
  * repeatability and matching precision on Oxford "churchill" (real images, ground-truth
    homographies H_1_k) and on simulated mine frames at light 1.0 / 0.5 / 0.15, where the ground
    truth correspondence of a pixel comes from the ray-cast depth and the true relative pose;
  * extraction time per 752 x 480 frame on the CPU: SuperPoint fp32 at full and half
    resolution, SuperPoint int8 (onnxruntime dynamic quantisation) and ORB.

Definitions (the usual ones, e.g. DeTone et al. 2018):
  repeatability  fraction of keypoints of image A, visible in B, with a keypoint of B within
                 EPS_PX of their true position (averaged A->B and B->A);
  precision      fraction of mutual-nearest-neighbour descriptor matches whose B keypoint is
                 within EPS_PX of the A keypoint's true position.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

from slslam import _core
from slslam.sim import SimOptions, Simulator

from common import (
    SHARED_DATA,
    sim_cam_b_from_cam_a,
    time_calls,
    transfer_pixels,
    write_results,
)

EPS_PX = 3.0
NUM_KEYPOINTS = 1000


class OrbFrontEnd:
    name = "orb"

    def __init__(self, n: int):
        self.options = _core.OrbOptions()
        self.options.max_features = n

    def detect(self, image: np.ndarray):
        uv, _score_unused, desc = _core.extract_orb(image, self.options)
        return uv, desc


class SuperPointFrontEnd:
    def __init__(self, model: str, n: int, name: str = "superpoint"):
        from slslam.features.superpoint import SuperPoint, SuperPointOptions

        self.name = name
        self.model = model
        self.net = SuperPoint(SuperPointOptions(model_path=model, max_keypoints=n))

    def detect(self, image: np.ndarray):
        kp = self.net.detect(image)
        return kp.uv, kp.descriptors


def _match(desc_a: np.ndarray, desc_b: np.ndarray) -> np.ndarray:
    options = _core.MatchOptions()
    if desc_a.dtype == np.uint8:
        options.max_distance = 80.0
    else:
        options.max_distance = 1.2
    options.ratio = 1.0  # mutual nearest neighbour only: precision of the raw descriptors
    return _core.match_descriptors(desc_a, desc_b, options)


def _evaluate_pair(fe, img_a, img_b, warp_a, warp_b, label: str) -> dict:
    """Detect in both images, match, and score against the ground-truth warps."""
    uv_a, d_a = fe.detect(img_a)
    uv_b, d_b = fe.detect(img_b)
    rep, prec, correct = _score(uv_a, uv_b, warp_a, warp_b, _match(d_a, d_b))
    return {
        "pair": label,
        "repeatability": rep,
        "precision": prec,
        "correct": correct,
        "keypoints": [len(uv_a), len(uv_b)],
    }


def _score(uv_a, uv_b, warp_a, warp_b, match_pairs):
    """Repeatability (symmetric) and precision given warps that map points to the other image
    (returning NaN where the point is not visible there)."""
    rep = []
    for src, dst, warp in ((uv_a, uv_b, warp_a), (uv_b, uv_a, warp_b)):
        projected = warp(src)
        visible = np.all(np.isfinite(projected), axis=1)
        if visible.sum() == 0 or len(dst) == 0:
            rep.append(0.0)
            continue
        d = np.linalg.norm(projected[visible, None, :] - dst[None, :, :], axis=2).min(axis=1)
        rep.append(float(np.mean(d < EPS_PX)))
    if len(match_pairs) == 0:
        return float(np.mean(rep)), 0.0, 0
    projected = warp_a(uv_a[match_pairs[:, 0]])
    error = np.linalg.norm(projected - uv_b[match_pairs[:, 1]], axis=1)
    valid = np.isfinite(error)
    correct = int(np.sum(error[valid] < EPS_PX))
    return float(np.mean(rep)), correct / max(int(valid.sum()), 1), correct


def _homography_warp(H: np.ndarray, shape: tuple[int, int]):
    def warp(uv: np.ndarray) -> np.ndarray:
        p = np.column_stack([uv, np.ones(len(uv))]) @ H.T
        out = p[:, :2] / p[:, 2:]
        inside = (
            (out[:, 0] >= 0) & (out[:, 1] >= 0) & (out[:, 0] < shape[1]) & (out[:, 1] < shape[0])
        )
        out[~inside] = np.nan
        return out

    return warp


def churchill(front_ends) -> dict:
    folder = SHARED_DATA / "images" / "churchill"
    if not folder.exists():
        return {"skipped": f"{folder} not available"}
    ref = _core.read_gray_image(str(folder / "1.ppm"))
    results = {}
    for k in range(2, 7):
        img = _core.read_gray_image(str(folder / f"{k}.ppm"))
        H = np.loadtxt(folder / f"H_1_{k}")
        warp_a = _homography_warp(H, img.shape)
        warp_b = _homography_warp(np.linalg.inv(H), ref.shape)
        for fe in front_ends:
            results.setdefault(fe.name, []).append(
                _evaluate_pair(fe, ref, img, warp_a, warp_b, f"1-{k}")
            )
    return results


def _depth_warp(depth_a, T_b_a, cam, depth_b):
    """Map pixels of A into B through A's depth and the relative pose; NaN where occluded."""

    def warp(uv: np.ndarray) -> np.ndarray:
        out, z_a, z_b = transfer_pixels(uv, depth_a, T_b_a, cam)
        ub = np.clip(np.round(out[:, 0]).astype(int), 0, cam.width - 1)
        vb = np.clip(np.round(out[:, 1]).astype(int), 0, cam.height - 1)
        visible = (
            np.isfinite(z_a)
            & (z_b > 0.1)
            & (out[:, 0] >= 0)
            & (out[:, 1] >= 0)
            & (out[:, 0] < cam.width)
            & (out[:, 1] < cam.height)
        )
        visible &= np.abs(depth_b[vb, ub] - z_b) < 0.05 * z_b  # not occluded in B
        out[~visible] = np.nan
        return out

    return warp


def simulated(front_ends, lights=(1.0, 0.5, 0.15), pairs=((20, 30), (60, 75), (100, 110))) -> dict:
    results = {}
    for light in lights:
        sim = Simulator(SimOptions(preset="loop", frames=200, light=light, seed=3))
        cam = sim.camera
        for a, b in pairs:
            img_a, _, depth_a = sim.render_stereo(a)
            img_b, _, depth_b = sim.render_stereo(b)
            T_b_a = sim_cam_b_from_cam_a(sim, a, b)
            warp_a = _depth_warp(depth_a, T_b_a, cam, depth_b)
            warp_b = _depth_warp(depth_b, np.linalg.inv(T_b_a), cam, depth_a)
            for fe in front_ends:
                results.setdefault(f"light{light}", {}).setdefault(fe.name, []).append(
                    _evaluate_pair(fe, img_a, img_b, warp_a, warp_b, f"{a}-{b}")
                )
    return results


def timing(model: str | None, image: np.ndarray) -> dict:
    out = {
        "orb": time_calls(lambda: _core.extract_orb(image, OrbFrontEnd(NUM_KEYPOINTS).options), 20)
    }
    if not model:
        return out
    from slslam.features.superpoint import SuperPoint, SuperPointOptions

    half = np.ascontiguousarray(image[::2, ::2])
    net = SuperPoint(SuperPointOptions(model_path=model, max_keypoints=NUM_KEYPOINTS))
    out["superpoint_fp32_full"] = time_calls(lambda: net.detect(image), 10)
    out["superpoint_fp32_half"] = time_calls(lambda: net.detect(half), 10)
    return out


def quantised(model: str) -> str:
    from onnxruntime.quantization import QuantType, quantize_dynamic

    out = Path(tempfile.mkdtemp()) / "superpoint_int8.onnx"
    quantize_dynamic(model, str(out), weight_type=QuantType.QUInt8)
    return str(out)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--no-int8", action="store_true", help="skip the quantised model")
    parser.add_argument("--orb-only", action="store_true", help="skip SuperPoint")
    args = parser.parse_args()
    default = SHARED_DATA.parent / "models" / "superpoint_v1" / "superpoint_v1.onnx"
    model = os.environ.get("SLSLAM_SUPERPOINT_MODEL") or (
        str(default) if default.exists() else None
    )
    if args.orb_only:
        model = None
    front_ends = [OrbFrontEnd(NUM_KEYPOINTS)]
    if model:
        front_ends.insert(0, SuperPointFrontEnd(model, NUM_KEYPOINTS))
        if not args.no_int8:
            front_ends.insert(
                1, SuperPointFrontEnd(quantised(model), NUM_KEYPOINTS, name="superpoint_int8")
            )
    else:
        print("SuperPoint weights not found (set SLSLAM_SUPERPOINT_MODEL): ORB only")
    sim_image = Simulator(SimOptions(preset="loop", frames=40)).render_stereo(20)[0]
    results = {
        "eps_px": EPS_PX,
        "num_keypoints": NUM_KEYPOINTS,
        "model": model,
        "churchill": churchill(front_ends),
        "simulated": simulated(front_ends),
        "timing_ms": timing(model, sim_image),
    }
    if model and not args.no_int8:
        from slslam.features.superpoint import SuperPoint, SuperPointOptions

        int8 = SuperPoint(
            SuperPointOptions(model_path=front_ends[1].model, max_keypoints=NUM_KEYPOINTS)
        )
        results["timing_ms"]["superpoint_int8_full"] = time_calls(
            lambda: int8.detect(sim_image), 10
        )
    _print(results)
    print(f"wrote {write_results('point_frontend', results, args.out)}")
    return 0


def _print(results: dict) -> None:
    def row(name, entries):
        rep = np.mean([e["repeatability"] for e in entries])
        prec = np.mean([e["precision"] for e in entries])
        correct = np.mean([e["correct"] for e in entries])
        print(
            f"  {name:18s} repeatability {rep:5.3f}  precision {prec:5.3f}  correct {correct:6.1f}"
        )

    if "skipped" not in results["churchill"]:
        print("churchill (pairs 1-2 .. 1-6, mean)")
        for name, entries in results["churchill"].items():
            row(name, entries)
    for light, per in results["simulated"].items():
        print(f"simulated loop, {light} (3 pairs, mean)")
        for name, entries in per.items():
            row(name, entries)
    print("extraction time per 752x480 frame (median)")
    for name, t in results["timing_ms"].items():
        print(f"  {name:22s} {t['median_ms']:7.1f} ms")


if __name__ == "__main__":
    sys.exit(main())
