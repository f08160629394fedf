#!/usr/bin/env sh
# Installs the Python peers used by cliffmap's benchmarks (never crate dependencies).
set -eu
python3 -m pip install --quiet pydelatin numpy pillow
