#!/usr/bin/env bash
# Clang's thread-safety analysis over the C++ core: every source under cpp/slslam is parsed by
# clang++ (syntax only, nothing is built) with -Wthread-safety as an error, so data marked
# SLSLAM_GUARDED_BY touched without its mutex, or a SLSLAM_REQUIRES function called without it,
# fails the run (cpp/slslam/core/thread_annotations.h). About a minute on two cores.
#
#   bash scripts/thread_safety.sh            # every source
#   bash scripts/thread_safety.sh FILE.cpp   # some sources
#
# Installs Debian's clang when missing (the product builds with GCC; clang is used for this check
# only). Called by .ci/run after scripts/test.sh.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
build_dir="build/thread_safety"

clang="$(command -v clang++ clang++-19 clang++-16 clang++-15 clang++-14 2>/dev/null | head -n1 || true)"
if [[ -z "$clang" ]]; then
  sudo=""
  [[ $(id -u) -eq 0 ]] || sudo="sudo"
  echo "[slslam] installing clang (for the thread-safety analysis only)"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends clang
  clang="$(command -v clang++)"
fi

# The compile commands of the core's libraries (configure only; no PCL, no Python module).
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DCMAKE_EXPORT_COMPILE_COMMANDS=ON \
  -DSLSLAM_BUILD_PYTHON=OFF -DSLSLAM_BUILD_TESTS=OFF -DSLSLAM_WITH_PCL=OFF >/dev/null

if [[ $# -gt 0 ]]; then
  sources=("$@")
else
  mapfile -t sources < <(find cpp/slslam -name '*.cpp' | sort)
fi
echo "[slslam] thread-safety analysis ($("$clang" --version | head -n1)): ${#sources[@]} sources"
PYTHONDONTWRITEBYTECODE=1 python3 - "$clang" "$build_dir/compile_commands.json" "${sources[@]}" <<'EOF'
import json
import os
import shlex
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

clang, db_path, *sources = sys.argv[1:]
db = {os.path.realpath(e["file"]): e for e in json.load(open(db_path))}
# GCC's own include directory (omp.h), after clang's.
GCC_INCLUDE = subprocess.run(["gcc", "-print-file-name=include"], capture_output=True,
                             text=True).stdout.strip()


def check(source: str) -> tuple[str, int, str]:
    entry = db.get(os.path.realpath(source))
    if entry is None:
        return source, -1, ""  # not in this build (the LiDAR sources need PCL)
    args = shlex.split(entry["command"]) if "command" in entry else entry["arguments"]
    # Keep includes, defines and the standard; drop GCC's code generation flags and -fopenmp
    # (its pragmas are ignored here; omp.h comes from GCC's own include directory).
    keep, i = [], 1
    while i < len(args):
        a = args[i]
        if a in ("-I", "-isystem", "-D") and i + 1 < len(args):
            keep += [a, args[i + 1]]
            i += 1
        elif a.startswith(("-I", "-isystem", "-D", "-std=")):
            keep.append(a)
        i += 1
    cmd = [clang, "-fsyntax-only", "-Wno-everything", "-Wthread-safety", "-Werror=thread-safety",
           "-ferror-limit=0", *keep, "-idirafter", GCC_INCLUDE, os.path.realpath(source)]
    run = subprocess.run(cmd, capture_output=True, text=True, cwd=entry["directory"])
    return source, run.returncode, run.stderr


# First a source that breaks the rule on purpose: the analysis must reject it, or it is not on.
probe = os.path.join(os.path.dirname(db_path), "thread_safety_probe.cpp")
with open(probe, "w") as f:
    f.write('#include "slslam/map/map.h"\n'
            "int Unlocked(const slslam::Map& map) { return map.correction_epoch(); }\n")
db[os.path.realpath(probe)] = dict(next(iter(db.values())), file=probe)
_, rc, err = check(probe)
if rc == 0 or "requires holding mutex" not in err:
    print(err, end="")
    sys.exit("[slslam] thread-safety analysis: a call without the map's lock was not rejected")

failed, skipped = 0, []
with ThreadPoolExecutor(max_workers=2) as pool:
    for source, rc, err in pool.map(check, sources):
        if rc < 0:
            skipped.append(os.path.basename(source))
            continue
        if rc != 0 or err.strip():
            print(err, end="")
        failed += rc != 0
checked = len(sources) - len(skipped)
if skipped:
    print(f"[slslam] not in this build (LiDAR needs PCL), skipped: {' '.join(skipped)}")
print(f"[slslam] thread-safety analysis: {checked - failed} of {checked} sources clean")
sys.exit(1 if failed else 0)
EOF
