#!/usr/bin/env bash
# Installs what slslam needs on a Debian/Ubuntu machine, then slslam itself. Idempotent.
#
#   bash scripts/setup.sh            # Debian packages + slslam
#   bash scripts/setup.sh test       # ... with the test extras (pytest)
#   bash scripts/setup.sh dev        # ... with the developer tools (ruff, pre-commit)
#
# Extra arguments after the extras are passed to pip (for example -C cmake.define.X=Y).
# Runs apt-get as root, or through sudo when not root.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
extras="${1:-}"
shift || true

APT_PACKAGES=(
  build-essential pkg-config ccache python3-venv
  libeigen3-dev libopencv-dev libopencv-contrib-dev libceres-dev libembree-dev libgtest-dev libpcl-dev
)
missing=()
for pkg in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
done
if ((${#missing[@]})); then
  sudo=""
  [[ $(id -u) -eq 0 ]] || sudo="sudo"
  echo "[slslam] installing Debian packages: ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "[slslam] Debian packages already installed"
fi

source "$root/scripts/python_env.sh"
spec="."
[[ -n "$extras" ]] && spec=".[$extras]"
echo "[slslam] installing slslam into $("$PYTHON" -c 'import sys; print(sys.prefix)')"
"$PYTHON" -m pip install --disable-pip-version-check -q "$spec" "$@"
"$PYTHON" -m slslam version
