#!/usr/bin/env bash
# Create (or reuse) the project-local test environment .venvs/bpy-<VERSION> for one Blender.
#
#   tools/setup_venv.sh 5.0.1     ->  .venvs/bpy-5.0.1  from tools/requirements-bpy-5.0.1.txt
#   tools/setup_venv.sh 4.2       ->  .venvs/bpy-4.2    from tools/requirements-bpy-4.2.txt
#
# Idempotent: a stamp file inside the venv holds a hash of the requirement files and of the
# interpreter; while it matches, nothing is installed.  Any change rebuilds the venv from
# scratch, so an interrupted install never leaves a half-working environment in use.
# Needs only python3.11 on PATH (bpy on PyPI is built for CPython 3.11 only); override with
# PYTHON=/path/to/python3.11.
set -euo pipefail

version="${1:?usage: tools/setup_venv.sh BLENDER_VERSION (5.0.1, 4.5 or 4.2)}"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
requirements="$root/tools/requirements-bpy-$version.txt"
venv="$root/.venvs/bpy-$version"
stamp="$venv/.monoskel-requirements.sha256"
python="${PYTHON:-python3.11}"

if [[ ! -f "$requirements" ]]; then
    echo "error: no requirements file $requirements (known: $(cd "$root/tools" && ls requirements-bpy-*.txt | tr '\n' ' '))" >&2
    exit 2
fi
if ! command -v "$python" >/dev/null 2>&1; then
    echo "error: $python not found on PATH. MonoSkel's tests run Blender as the PyPI 'bpy' module," >&2
    echo "       which exists only for CPython 3.11: install Python 3.11 (e.g. apt install python3.11-venv," >&2
    echo "       pyenv install 3.11, or python.org) or set PYTHON=/path/to/python3.11." >&2
    exit 2
fi
if ! "$python" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))'; then
    echo "error: $python is Python $("$python" -c 'import platform; print(platform.python_version())'), but bpy needs 3.11" >&2
    exit 2
fi

wanted="$("$python" - "$requirements" "$root/tools/requirements-common.txt" <<'PY'
import hashlib, sys
digest = hashlib.sha256(sys.version.encode())
for path in sys.argv[1:]:
    with open(path, "rb") as fh:
        digest.update(fh.read())
print(digest.hexdigest())
PY
)"

if [[ -f "$stamp" && "$(cat "$stamp")" == "$wanted" && -x "$venv/bin/python" ]]; then
    echo "venv $venv is up to date"
    exit 0
fi

echo "creating $venv (bpy $version) ..."
start=$(date +%s)
rm -rf "$venv"
mkdir -p "$root/.venvs"
"$python" -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check --no-input -r "$requirements"
"$venv/bin/python" -c 'import bpy, numpy, scipy; print("installed Blender", bpy.app.version_string, "numpy", numpy.__version__, "scipy", scipy.__version__)'
echo "$wanted" > "$stamp"
echo "venv $venv ready in $(( $(date +%s) - start )) s"
