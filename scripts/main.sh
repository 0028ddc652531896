#!/usr/bin/env bash
# Sets up slslam and runs its main job on data it makes itself.
# Until the tracker exists (issue "slslam run"), the main job is the evaluation demo: a generated
# mine-loop ground truth, a synthetic drifting estimate, APE/RPE, metrics.json and ape.png.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
out="${1:-slslam_demo}"
bash scripts/setup.sh
source "$root/scripts/python_env.sh"
"$PYTHON" -m slslam demo --out "$out"
