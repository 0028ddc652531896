#!/usr/bin/env bash
# Sets up (Debian packages, slslam with test extras, GoogleTest binaries) and runs every test:
# the C++ suite through ctest, the lint and type checks, then the Python suite through pytest.
# Fails when any part fails. The ThreadSanitizer build and clang's thread-safety analysis are
# separate scripts (scripts/tsan.sh, scripts/thread_safety.sh) that .ci/run calls after this.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
build_dir="build/test"

# One build serves both: the pip build also compiles the GoogleTest binary into $build_dir.
bash scripts/setup.sh test -C cmake.define.SLSLAM_BUILD_TESTS=ON -C "build-dir=$build_dir"
source "$root/scripts/python_env.sh"

echo "[slslam] C++ tests"
ctest --test-dir "$build_dir" --output-on-failure -j2

# ruff, clang-format and mypy (scripts/lint.sh)
bash scripts/lint.sh

echo "[slslam] Python tests"
"$PYTHON" -m pytest tests/python "$@"
