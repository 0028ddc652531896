#!/usr/bin/env bash
# Rebuilds the vocabularies shipped with slslam (python/slslam/data/orb_vocabulary.slvoc for ORB,
# python/slslam/data/xfeat_vocabulary.slvoc for XFeat) from frames of slslam's own simulator, so
# the files derive from nothing but this repository (and, for XFeat, its shipped weights).
#
#   bash scripts/make_vocabulary.sh [WORK_FOLDER [FRONTEND...]]
#
# WORK_FOLDER (default: a new temporary folder) keeps the simulated sequences; sequences already
# there are reused. FRONTEND: orb and/or xfeat (default both). Same slslam, same seeds: the same
# vocabulary, byte for byte.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
source "$root/scripts/python_env.sh"
work="${1:-$(mktemp -d -t slslam_vocab_XXXXXX)}"
frontends=("${@:2}")
((${#frontends[@]})) || frontends=(orb xfeat)
# k and L per front end. XFeat's float words cost 256 bytes each (ORB's 32), so its tree is
# smaller: 8^4 = 4,096 words keep the file near 1.2 MB.
declare -A tree=([orb]="10 4" [xfeat]="8 4")
for frontend in "${frontends[@]}"; do
  [[ -n "${tree[$frontend]:-}" ]] || { echo "unknown front end: $frontend (orb, xfeat)" >&2; exit 2; }
done
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

for frontend in "${frontends[@]}"; do
  read -r branching levels <<<"${tree[$frontend]}"
  out="python/slslam/data/${frontend}_vocabulary.slvoc"
  "$PYTHON" -m slslam vocab train "${folders[@]}" --out "$out" --frontend "$frontend" \
    --branching "$branching" --levels "$levels" --seed 0 --no-progress
  "$PYTHON" -m slslam vocab info "$out"
done
