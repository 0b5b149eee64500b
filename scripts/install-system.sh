#!/usr/bin/env bash
# Installs the Debian packages tengfield needs: the FEM stack from Debian
# (dolfinx, PETSc, petsc4py, mpi4py, h5py, scipy), OpenMPI, and the system
# libraries the gmsh and VTK wheels load. One source of truth: the Makefile
# and the Dockerfile both call this script. It does nothing when every
# package is already installed.
#
# The release is read from /etc/os-release:
#   Debian 12 (bookworm): dolfinx 0.5.2, PETSc 3.18, OpenMPI 4.1, numpy 1.24
#   Debian 13 (trixie):   dolfinx 0.9.0, PETSc 3.22, OpenMPI 5.0, numpy 2.2
# Both releases use the same package names; the list below is shared and a
# release-specific difference would go in the `case` under it. Another Debian
# release (testing, sid) gets the Debian 13 list with a warning; anything that
# is not Debian stops here.
set -euo pipefail

OS_RELEASE="${TENGFIELD_OS_RELEASE:-/etc/os-release}"  # overridable for tests
[ -r "$OS_RELEASE" ] || { echo "install-system: cannot read $OS_RELEASE" >&2; exit 1; }
# shellcheck disable=SC1090
ID="" VERSION_ID="" VERSION_CODENAME="" PRETTY_NAME=""
. "$OS_RELEASE"

PACKAGES=(
  python3 python3-venv python3-pip python3-dev
  python3-dolfinx-real python3-petsc4py python3-mpi4py python3-h5py python3-scipy
  openmpi-bin libopenmpi-dev
  libglu1-mesa libgl1 libegl1 libosmesa6 libxrender1 libxcursor1 libxft2
  libxinerama1 libxext6 libx11-6 libxi6 libxrandr2
  ngspice   # the SPICE tests (tests/electrical/test_spice*.py) and examples/teng_load.cir
  # OpenBLAS, one thread, as the system BLAS and LAPACK (Debian's alternatives rank it
  # above the reference BLAS): CHOLMOD's and MUMPS's dense kernels; the 60-candidate
  # design ran 0.92x and the cold field stage 0.94x as long (docs/field.md). One thread:
  # tengfield is parallel by processes (MPI ranks, pools)
  libopenblas0-serial
  git make
)

if [ "$ID" != debian ]; then
  echo "install-system: ${PRETTY_NAME:-this system} is not Debian; tengfield's system" \
       "packages are known for Debian 12 (bookworm) and 13 (trixie) only" >&2
  exit 1
fi
case "$VERSION_ID:$VERSION_CODENAME" in
  12:*|*:bookworm) RELEASE="Debian 12 (bookworm)" ;;  # dolfinx 0.5.2
  13:*|*:trixie)   RELEASE="Debian 13 (trixie)" ;;    # dolfinx 0.9
  *) RELEASE="${PRETTY_NAME:-Debian $VERSION_ID}"
     echo "install-system: warning: $RELEASE is untested; installing the Debian 13 package list" >&2 ;;
esac

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-system: $RELEASE: all ${#PACKAGES[@]} Debian packages present"
  exit 0
fi
echo "install-system: $RELEASE: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
# one apt-get at a time on this machine (.ci/run builds the containers while this
# runs: scripts/test-container installs podman under the same lock); apt's own
# lock is waited for too, not failed on
APT=(apt-get -o DPkg::Lock::Timeout=600)
if [ -z "$SUDO" ] && [ -w /var/lock ] && command -v flock >/dev/null; then
  exec 9>/var/lock/tengfield-apt.lock
  flock 9
fi
$SUDO "${APT[@]}" update -q
$SUDO "${APT[@]}" install -y -q --no-install-recommends "${missing[@]}"
