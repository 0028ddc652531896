# Sourced by the other scripts: picks the Python that slslam is installed into.
# Order: $PYTHON if set; the project's .venv if it exists; python3. On a Python that is
# "externally managed" (PEP 668, e.g. Debian's /usr/bin/python3) a .venv is created instead of
# installing into the system.
_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [[ -z "${PYTHON:-}" ]]; then
  if [[ -x "$_root/.venv/bin/python" ]]; then
    PYTHON="$_root/.venv/bin/python"
  elif python3 -c 'import sys, sysconfig, pathlib; sys.exit(0 if (pathlib.Path(sysconfig.get_path("stdlib")) / "EXTERNALLY-MANAGED").exists() and sys.prefix == sys.base_prefix else 1)'; then
    echo "[slslam] python3 is externally managed: creating $_root/.venv" >&2
    python3 -m venv "$_root/.venv"
    PYTHON="$_root/.venv/bin/python"
  else
    PYTHON="python3"
  fi
fi
export PYTHON
