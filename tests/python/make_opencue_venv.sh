#!/bin/sh
# Creates (once) a virtual environment holding OpenCue's pyoutline from PyPI, for the OpenCue
# example's test. pyoutline 1.37.0 imports 'packaging' without declaring it, so it is named here.
set -eu
python=$1
venv=$2
if [ -x "$venv/bin/python" ] && "$venv/bin/python" -c "import outline.backend.cue" 2>/dev/null; then
  exit 0
fi
"$python" -m venv "$venv"
"$venv/bin/pip" install --quiet --disable-pip-version-check "opencue-pyoutline==1.37.0" "packaging"
"$venv/bin/python" -c "import outline.backend.cue"
