#!/usr/bin/env bash
# Lint and type checks, as CI runs them: ruff (check and format), clang-format on the C++ sources
# (Debian's, installed when missing), mypy on python/slslam (pyproject.toml [tool.mypy]).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
source "$root/scripts/python_env.sh"

echo "[slslam] lint: ruff check, ruff format --check"
"$PYTHON" -m ruff check python tests benchmarks
"$PYTHON" -m ruff format --check python tests benchmarks

echo "[slslam] lint: clang-format --dry-run -Werror"
if ! command -v clang-format >/dev/null; then
  sudo=""
  [[ $(id -u) -eq 0 ]] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends clang-format
fi
git ls-files 'cpp/*.h' 'cpp/*.cpp' 'tests/cpp/*.h' 'tests/cpp/*.cpp' 'benchmarks/*.cpp' |
  xargs clang-format --dry-run -Werror

echo "[slslam] types: mypy python/slslam"
"$PYTHON" -m mypy
