"""XFeat vs SuperPoint vs ORB: extraction time and descriptor distances, in one run.

    SLSLAM_SUPERPOINT_MODEL=path/to/superpoint_v1.onnx python benchmarks/xfeat_frontend.py
        [--images 20] [--out benchmarks/results/xfeat_frontend.json]

Timing: the first ``--images`` left images of the real EuRoC excerpt (752 x 480); each image goes
through every front end in turn (so load from other processes hits all alike) and the medians
over the images are reported, for XFeat also split into network and post-processing. Front ends
as the tracker builds them from the default config (XFeat up to 4096 keypoints, SuperPoint all
above its threshold, ORB 1000), onnxruntime with its default threads.

Descriptor distances, for choosing ``tracking.max_distance_float`` (L2 between unit vectors):
each image against a copy shifted by SHIFT_PX (off the 8-px cell grid). A keypoint of A whose
shifted position has a keypoint of B within TRUE_PX has a true partner; the other keypoints of B
within SEARCH_PX of that position are the wrong candidates guided matching would also see.
Reported: percentiles of the true distance, of the nearest wrong distance, how often the true
partner is the nearest candidate and how often it also passes the tracker's ratio test (best <
RATIO x second best in the window); for XFeat also with a wider NMS (sparser keypoints).
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from slslam import _core
from slslam.features.orb import Orb, OrbOptions
from slslam.features.xfeat import XFeat, XFeatOptions

from common import SHARED_DATA, write_results

SHIFT_PX = 13
TRUE_PX = 1.5
SEARCH_PX = 15.0  # the tracker's default guided-matching window (tracking.search_radius_px)
RATIO = 0.9  # the tracker's ratio test inside the window (TrackerOptions::match_ratio)


def euroc_images(count: int) -> list[np.ndarray]:
    folder = SHARED_DATA / "euroc_v101_micro" / "mav0" / "cam0" / "data"
    if not folder.is_dir():
        raise SystemExit(f"real EuRoC images not available at {folder}")
    paths = sorted(folder.glob("*.png"))[:count]
    return [_core.read_gray_image(str(p)) for p in paths]


def front_ends() -> dict:
    out = {"xfeat": XFeat(), "orb": Orb(OrbOptions())}
    model = os.environ.get("SLSLAM_SUPERPOINT_MODEL")
    if model:
        from slslam.features.superpoint import SuperPoint, SuperPointOptions

        out["superpoint"] = SuperPoint(SuperPointOptions(model_path=model))
    else:
        print("SLSLAM_SUPERPOINT_MODEL not set: SuperPoint skipped")
    return out


def timing(nets: dict, images: list[np.ndarray]) -> dict:
    for net in nets.values():  # warm-up: session start, allocations
        net.detect(images[0])
    samples: dict[str, list[float]] = {name: [] for name in nets}
    samples["xfeat_network"] = []
    counts: dict[str, list[int]] = {name: [] for name in nets}
    for image in images:
        for name, net in nets.items():
            start = time.perf_counter()
            keypoints = net.detect(image)
            samples[name].append((time.perf_counter() - start) * 1e3)
            counts[name].append(len(keypoints))
        start = time.perf_counter()
        nets["xfeat"].infer(image)
        samples["xfeat_network"].append((time.perf_counter() - start) * 1e3)
    out = {
        name: {
            "median_ms": float(np.median(values)),
            "p90_ms": float(np.percentile(values, 90)),
            "min_ms": float(np.min(values)),
        }
        for name, values in samples.items()
    }
    for name, values in counts.items():
        out[name]["median_keypoints"] = float(np.median(values))
    out["xfeat_postprocess_median_ms"] = (
        out["xfeat"]["median_ms"] - out["xfeat_network"]["median_ms"]
    )
    out["images"] = len(images)
    out["load_average_1min"] = os.getloadavg()[0]
    return out


def distances(net, images: list[np.ndarray]) -> dict:
    true_d, wrong_d, nearest_is_true, passes_ratio = [], [], [], []
    for image in images:
        a = net.detect(image)
        b = net.detect(np.ascontiguousarray(image[:, SHIFT_PX:]))
        target = a.uv - np.array([SHIFT_PX, 0.0], dtype=np.float32)
        gap = np.linalg.norm(target[:, None, :] - b.uv[None, :, :], axis=2)
        d = np.linalg.norm(a.descriptors[:, None, :] - b.descriptors[None, :, :], axis=2)
        partner = gap.argmin(axis=1)
        has = gap[np.arange(len(a)), partner] <= TRUE_PX
        for i in np.nonzero(has)[0]:
            window = (gap[i] <= SEARCH_PX) & (gap[i] > TRUE_PX)
            true_d.append(d[i, partner[i]])
            wrong = d[i, window].min() if window.any() else np.inf
            if window.any():
                wrong_d.append(wrong)
            nearest_is_true.append(d[i, partner[i]] < wrong)
            passes_ratio.append(d[i, partner[i]] < RATIO * wrong)
    true_d, wrong_d = np.asarray(true_d), np.asarray(wrong_d)
    return {
        "pairs_with_true_partner": len(true_d),
        "true_L2_percentiles_50_90_95_99": np.percentile(true_d, [50, 90, 95, 99]).tolist(),
        "nearest_wrong_L2_percentiles_1_5_50": np.percentile(wrong_d, [1, 5, 50]).tolist(),
        "true_below": {t: float(np.mean(true_d < t)) for t in (0.6, 0.7, 0.8, 1.0)},
        "nearest_wrong_below": {t: float(np.mean(wrong_d < t)) for t in (0.6, 0.7, 0.8, 1.0)},
        "true_is_nearest_in_window": float(np.mean(nearest_is_true)),
        "true_passes_ratio_test": float(np.mean(passes_ratio)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--images", type=int, default=20)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    images = euroc_images(args.images)
    nets = front_ends()
    results = {"timing": timing(nets, images)}
    results["descriptor_distances"] = {
        name: distances(net, images[:5]) for name, net in nets.items() if name != "orb"
    }
    sparse = XFeat(XFeatOptions(nms_radius=4))
    results["descriptor_distances"]["xfeat_nms4"] = distances(sparse, images[:5])
    t = results["timing"]
    print(f"extraction per 752x480 image, median over {t['images']} EuRoC images [ms]:")
    for name in nets:
        print(f"  {name:12s} {t[name]['median_ms']:7.1f}  ({t[name]['median_keypoints']:.0f} kp)")
    print(
        f"  xfeat: network {t['xfeat_network']['median_ms']:.1f}, post-processing "
        f"{t['xfeat_postprocess_median_ms']:.1f}; load average {t['load_average_1min']:.1f}"
    )
    for name, stats in results["descriptor_distances"].items():
        print(f"{name}: {stats}")
    print(f"results in {write_results('xfeat_frontend', results, args.out)}")


if __name__ == "__main__":
    main()
