#!/usr/bin/env sh
# Installs the Python peers used by cliffmap's benchmarks (never crate dependencies):
# pydelatin (TIN simplification), libigl (SLIM/ARAP/LSCM parameterization), numpy, scipy,
# pillow and matplotlib for the peer scripts and plots, OpenCV and pycolmap (camera fits).
set -eu
python3 -m pip install --quiet pydelatin libigl numpy scipy pillow matplotlib opencv-python-headless pycolmap
