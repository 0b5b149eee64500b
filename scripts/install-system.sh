#!/usr/bin/env bash
# Installs the Debian (bookworm) packages tengfield needs: the FEM stack from
# Debian, OpenMPI, and the system libraries the gmsh and VTK wheels load.
# One source of truth: the Makefile and the Dockerfile both call this script.
# It does nothing when every package is already installed.
set -euo pipefail
PACKAGES=(
  python3 python3-venv python3-pip python3-dev
  python3-dolfinx-real python3-petsc4py python3-mpi4py python3-h5py python3-scipy
  openmpi-bin libopenmpi-dev
  libglu1-mesa libgl1 libegl1 libosmesa6 libxrender1 libxcursor1 libxft2
  libxinerama1 libxext6 libx11-6 libxi6 libxrandr2
  git make
)
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-system: all ${#PACKAGES[@]} Debian packages present"
  exit 0
fi
echo "install-system: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
