#!/usr/bin/env bash
# Installs what the PsychoPy window test (python/tests/test_psychopy_window.py) needs: Debian's
# Xvfb, and PsychoPy's `visual` module with pyglet into the venv given as $1. PsychoPy from PyPI
# without its full dependency tree (--no-deps: the wx GUI, audio and hardware packages are not
# needed to draw and read back a frame), plus the packages `from psychopy import visual`
# imports. About 45 s here. Exit 0 when `from psychopy import visual` works under Xvfb,
# 3 when something could not be installed (the caller then lets the test skip, saying why).
set -uo pipefail
venv=${1:?usage: .ci/psychopy.sh VENV}
py="$venv/bin/python"
if ! command -v Xvfb >/dev/null 2>&1; then
  if command -v apt-get >/dev/null 2>&1 && [[ $(id -u) == 0 ]]; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get install -y xvfb >/dev/null 2>&1 \
      || { apt-get update >/dev/null 2>&1 && apt-get install -y xvfb >/dev/null 2>&1; } \
      || { echo "Xvfb could not be installed"; exit 3; }
  else
    echo "no Xvfb, and no apt-get as root to install it"
    exit 3
  fi
fi
# pip's last line is shown when it fails.
pip() {
  local log
  log=$("$py" -m pip install --quiet --disable-pip-version-check "$@" 2>&1) || { echo "${log##*$'\n'}"; return 1; }
}
pip --no-deps "psychopy==2026.2.5" || { echo "pip could not install psychopy"; exit 3; }
pip pillow scipy "pyglet==1.5.27" packaging six json_tricks pyyaml i18next python-bidi pandas \
  arabic_reshaper freetype-py requests pyserial || { echo "pip could not install PsychoPy's imports"; exit 3; }
# The import needs a display. PsychoPy writes its preferences under the home folder
# (~/.psychopy3): the check runs with a home of its own, removed after.
home=$(mktemp -d)
trap 'rm -rf "$home"' EXIT
if ! HOME=$home PSYCHOPY_USERDIR=$home/.psychopy3 xvfb-run -a "$py" -c "from psychopy import visual" >/dev/null 2>&1; then
  echo "'from psychopy import visual' fails under Xvfb"
  exit 3
fi
echo "PsychoPy $(HOME=$home PSYCHOPY_USERDIR=$home/.psychopy3 "$py" -c 'import psychopy; print(psychopy.__version__)') and Xvfb ready"
