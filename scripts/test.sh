#!/usr/bin/env bash
# Sets up (Debian packages, slslam with test extras, GoogleTest binaries) and runs every test:
# the C++ suite through ctest, then the Python suite through pytest. Fails when either fails.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
build_dir="build/test"

# One build serves both: the pip build also compiles the GoogleTest binary into $build_dir.
bash scripts/setup.sh test -C cmake.define.SLSLAM_BUILD_TESTS=ON -C "build-dir=$build_dir"
source "$root/scripts/python_env.sh"

echo "[slslam] C++ tests"
ctest --test-dir "$build_dir" --output-on-failure -j2

# The threaded tracker under ThreadSanitizer (its own build in build/tsan, about 6 minutes on two
# cores the first time); SLSLAM_SKIP_TSAN=1 skips it.
if [[ "${SLSLAM_SKIP_TSAN:-0}" != "1" ]]; then
  bash scripts/tsan.sh
fi

# Clang's thread-safety analysis of the core's locking (syntax only, about a minute);
# SLSLAM_SKIP_THREAD_SAFETY=1 skips it.
if [[ "${SLSLAM_SKIP_THREAD_SAFETY:-0}" != "1" ]]; then
  bash scripts/thread_safety.sh
fi

# ruff, clang-format and mypy (scripts/lint.sh)
bash scripts/lint.sh

echo "[slslam] Python tests"
"$PYTHON" -m pytest tests/python "$@"
