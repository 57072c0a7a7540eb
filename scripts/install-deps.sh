#!/usr/bin/env bash
# Installs pneumo's build and run dependencies from Debian packages.
# Idempotent; uses sudo when not run as root.
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
PACKAGES=(
  build-essential cmake ninja-build pkg-config
  libsundials-dev        # IDA, IDAS, SUNLinSol_KLU, SUNMatrix sparse (6.4)
  libsuitesparse-dev     # KLU
  libeigen3-dev
  libyaml-cpp-dev
  libcli11-dev
  libceres-dev           # pneumo fit: nonlinear least squares (2.1)
  libnlopt-cxx-dev       # pneumo optimize: DIRECT-L, COBYLA, BOBYQA
  libgtest-dev googletest
  gnuplot-nox            # pneumo plot
  libopenmpi-dev openmpi-bin   # pneumo sweep under mpirun (optional at build time)
  chromium               # headless check of the pneumo diagnose HTML report and the draw results view (tests)
  librsvg2-bin           # pneumo draw -o circuit.png (rsvg-convert)
  zip unzip              # pneumo export-fmu packs the FMU (zip); its test unpacks it (unzip)
  libxml2-utils          # xmllint: the FMU's modelDescription.xml checked in the tests
  pybind11-dev python3-dev python3-numpy   # the Python module (python/)
  python3-pytest         # its tests
  clang libclang-rt-14-dev     # libFuzzer targets (fuzz/, scripts/fuzz.sh)
)
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ "${#missing[@]}" -gt 0 ]; then
  echo "install-deps: installing ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
echo "install-deps: all dependencies present"
