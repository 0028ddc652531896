#!/usr/bin/env bash
# Sets up slslam and runs its main job, stereo point-line SLAM, on a sequence it makes itself:
# a dark (light 0.15) shaft-bottom loop from the simulator, then `slslam run` on it.
#
#   bash scripts/main.sh [OUT_DIR] [FRAMES]      # defaults: slslam_main, 300 frames (15 s)
#
# Uses slslam's default front end, ORB + lines (its preset python/slslam/presets/orb.yaml), and
# says so in one line. Writes OUT_DIR/sequence (EuRoC ASL layout) and OUT_DIR/run (trajectory.tum,
# frames.csv, map.ply, metrics.json with the ATE, ape.png, config.yaml).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
out="${1:-slslam_main}"
frames="${2:-300}"
bash scripts/setup.sh
source "$root/scripts/python_env.sh"
if "$PYTHON" - "$out/sequence/manifest.json" "$frames" <<'PY'
import json, sys
try:
    m = json.load(open(sys.argv[1]))
except OSError:
    sys.exit(1)
o = m["options"]
ok = m.get("status") == "complete" and o["frames"] == int(sys.argv[2]) and o["light"] == 0.15
sys.exit(0 if ok else 1)
PY
then
  echo "[slslam] reusing the simulated sequence in $out/sequence"
else
  "$PYTHON" -m slslam sim --preset loop --light 0.15 --frames "$frames" --no-lidar --out "$out/sequence"
fi
# The default front end: ORB + lines, with ORB's preset (the left image's keypoints searched along
# their rows of the right image); README.md says which front end to use when.
# `slslam run --xfeat` runs the learned XFeat instead.
echo "[slslam] front end: ORB + lines (the default; ORB's preset, python/slslam/presets/orb.yaml)"
"$PYTHON" -m slslam run "$out/sequence" --out "$out/run"
