#!/bin/sh
# Installs the Python peers for benches/peers/param_libigl.py (never crate dependencies).
set -e
pip install libigl numpy scipy matplotlib
