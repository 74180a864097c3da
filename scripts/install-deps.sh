#!/bin/sh
# Installs the Debian 12 packages Stokesian needs to build, test and plot (see README).
# libopenblas0-openmp: an optimised BLAS for CHOLMOD's supernodal factorisation (the reference
# BLAS is ~10x slower on dense near-field blocks) and for the dense SD solver's LAPACK calls;
# liblapack-dev: the link-time liblapack.so (at run time liblapack.so.3 is OpenBLAS's).
# slurm-wlm, munge: a one-node Slurm started by tests/test_sweep_slurm for the sweep's job arrays
# (the test is skipped where the daemons cannot start).
set -eu
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
  ca-certificates git cmake make g++ pkg-config \
  libeigen3-dev libfftw3-dev libsuitesparse-dev liblapack-dev libopenblas0-openmp libhdf5-dev libtomlplusplus-dev doctest-dev libcli11-dev librandom123-dev \
  python3 python3-numpy python3-matplotlib python3-h5py python3-mdanalysis \
  slurm-wlm munge >/dev/null
