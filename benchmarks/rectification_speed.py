"""Time per stereo pair of loading (PNG decode) and rectifying (C++ remap) on real EuRoC images.

python benchmarks/rectification_speed.py [--repeats 50] [--out FILE]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from slslam.datasets import EurocSequence

from common import SHARED_DATA, time_calls, write_results


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=50)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    data = SHARED_DATA / "euroc_v101_micro"
    if not data.exists():
        print(f"skipped: real data not available at {data}")
        return 0
    raw = EurocSequence(data, rectify=False)
    rectified = EurocSequence(data)
    frame = raw[0]
    results = {
        "data": str(data),
        "image_size": list(frame.left.shape[::-1]),
        "load_pair_raw": time_calls(lambda: raw[0], args.repeats),
        "load_and_rectify_pair": time_calls(lambda: rectified[0], args.repeats),
        "rectify_pair_only": time_calls(
            lambda: rectified.rectifier.rectify(frame.left, frame.right), args.repeats
        ),
    }
    for key in ("load_pair_raw", "load_and_rectify_pair", "rectify_pair_only"):
        print(f"{key:24s} median {results[key]['median_ms']:7.3f} ms")
    print(f"wrote {write_results('rectification_speed', results, args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
