#!/usr/bin/env bash
# Rebuilds the ORB vocabulary shipped with slslam (python/slslam/data/orb_vocabulary.slvoc) from
# frames of slslam's own simulator, so the file derives from nothing but this repository.
#
#   bash scripts/make_vocabulary.sh [WORK_FOLDER]
#
# WORK_FOLDER (default: a new temporary folder) keeps the simulated sequences; sequences already
# there are reused. Same slslam, same seeds: the same vocabulary, byte for byte.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
source "$root/scripts/python_env.sh"
work="${1:-$(mktemp -d -t slslam_vocab_XXXXXX)}"
mkdir -p "$work"

# Two roadways (the shaft-bottom loop and a junction), full onboard light and OIVIO's dim 0.15,
# with floating dust: 4 x 300 left images.
folders=()
for spec in "loop 1.0" "loop 0.15" "junction 1.0" "junction 0.15"; do
  read -r preset light <<<"$spec"
  dir="$work/${preset}_light${light}"
  if [[ ! -d "$dir/mav0/cam0/data" ]]; then
    "$PYTHON" -m slslam sim --preset "$preset" --frames 300 --light "$light" --dust --no-lidar \
      --seed 0 --out "$dir"
  fi
  folders+=("$dir/mav0/cam0/data")
done

"$PYTHON" -m slslam vocab train "${folders[@]}" --out python/slslam/data/orb_vocabulary.slvoc \
  --frontend orb --branching 10 --levels 4 --seed 0 --no-progress
"$PYTHON" -m slslam vocab info python/slslam/data/orb_vocabulary.slvoc
