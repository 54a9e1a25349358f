#!/bin/sh
# The virtual lab tests in demdesign and in LIGGGHTS side by side (bench/lab_side_by_side.py says
# what it runs and prints); installs LIGGGHTS when missing.
#   bench/lab_side_by_side.sh [--pair plain|rolling] [--packings N] [--tests ID,...] [--core K]
set -e
HERE=$(cd "$(dirname "$0")" && pwd)
. "$HERE/liggghts/ensure_installed.sh"
exec python3 "$HERE/lab_side_by_side.py" "$@"
