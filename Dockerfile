# tengfield in a container: Debian's FEM stack (dolfinx, PETSc, OpenMPI)
# plus tengfield and its PyPI dependencies in a venv. One recipe, two Debian
# releases, chosen by the build argument DEBIAN_RELEASE:
#
#   docker build -t tengfield .                                      # Debian 12, dolfinx 0.5.2
#   docker build --build-arg DEBIAN_RELEASE=trixie -t tengfield:trixie .   # Debian 13, dolfinx 0.9
#   docker run --rm -v "$PWD/out:/out" tengfield run -o /out
#   docker run --rm -v "$PWD/out:/out" --entrypoint mpirun tengfield \
#       -n 2 tengfield precompute          # surrogate into /out/cache
#
# docs/container.md has the details; scripts/test-container builds and tests
# this file for both releases with podman on a machine without a Docker daemon.
ARG DEBIAN_RELEASE=bookworm
FROM debian:${DEBIAN_RELEASE}-slim

# System packages through the same script the Makefile uses (one source of
# truth; it reads /etc/os-release, so the same line serves both releases).
# It installs with --no-install-recommends; the package lists and the .deb
# cache are dropped in the same layer.
COPY scripts/install-system.sh /tmp/install-system.sh
RUN DEBIAN_FRONTEND=noninteractive bash /tmp/install-system.sh \
 && apt-get clean \
 && rm -rf /var/lib/apt/lists/* /tmp/install-system.sh

# A venv that sees Debian's dolfinx, petsc4py, mpi4py, h5py, numpy and scipy
# (--system-site-packages, exactly as `make setup` does): those must come
# from Debian (built against its PETSc, OpenMPI and numpy), while the rest
# comes from PyPI; scripts/numpy-requirement keeps numpy on the system's
# major version (numpy<2 on bookworm, numpy 2 on trixie). Debian's own
# python refuses `pip install` outside a venv (PEP 668, externally managed),
# which a venv respects without --break-system-packages.
ENV VIRTUAL_ENV=/opt/tengfield
ENV PATH=/opt/tengfield/bin:$PATH

# Behind a TLS-intercepting proxy, pass its CA bundle as a build secret:
#   docker build --secret id=ca-bundle,src=/etc/ssl/certs/ca-certificates.crt .
# Without the secret pip uses its own certificate store.
# numba's compiled kernels live in the image (not in the /out volume, which
# is empty in a new container): `python -m tengfield._warmup` compiles every
# kernel at build time, so the first `tengfield run` loads them instead of
# spending about 10 s compiling. numba keys an entry on the CPU: on a CPU
# other than the build machine's a kernel is compiled once more (as root,
# into the same directory; a user that cannot write there gets numba's
# fallback, a cache of its own).
ENV NUMBA_CACHE_DIR=/opt/tengfield/numba-cache
ARG PIP_DEFAULT_TIMEOUT=180
COPY . /tmp/tengfield-src
RUN --mount=type=secret,id=ca-bundle \
    if [ -s /run/secrets/ca-bundle ]; then export PIP_CERT=/run/secrets/ca-bundle; fi \
 && python3 -m venv --system-site-packages "$VIRTUAL_ENV" \
 && pip install --no-cache-dir --disable-pip-version-check \
        "$(sh /tmp/tengfield-src/scripts/numpy-requirement)" "/tmp/tengfield-src[field]" \
 && rm -rf /tmp/tengfield-src \
 && tengfield --version \
 && python -m tengfield._warmup

# MPI as root inside the container; mpirun -n 2 also on a 1-core host
# (OpenMPI 4.1 on bookworm reads OMPI_MCA_rmaps_base_oversubscribe, OpenMPI 5
# on trixie, whose launcher is PRRTE, reads PRTE_MCA_rmaps_default_mapping_policy);
# OpenMPI's single-copy (CMA) transport needs ptrace rights that container
# runtimes usually withhold, so shared memory falls back to copy-in/out
# (btl_vader_single_copy_mechanism on 4.1, the smsc framework on 5).
# Headless rendering: pyvista through VTK's EGL window (Mesa renders in
# software, no X server; VTK >= 9.4 reads VTK_DEFAULT_OPENGL_WINDOW) and
# matplotlib's Agg backend.
ENV OMPI_ALLOW_RUN_AS_ROOT=1 \
    OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 \
    OMPI_MCA_rmaps_base_oversubscribe=1 \
    PRTE_MCA_rmaps_default_mapping_policy=:oversubscribe \
    OMPI_MCA_btl_vader_single_copy_mechanism=none \
    OMPI_MCA_smsc=^cma \
    PYVISTA_OFF_SCREEN=true \
    VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow \
    MPLBACKEND=Agg \
    PYTHONUNBUFFERED=1

# Outputs go to /out: mount a host directory there. The caches made at run
# time go there too (/out/cache: field surrogates, dolfinx's compiled forms,
# matplotlib's font list), so later containers reuse them; numba's kernels
# are in the image (NUMBA_CACHE_DIR above).
ENV XDG_CACHE_HOME=/out/cache
WORKDIR /out
VOLUME ["/out"]
ENTRYPOINT ["tengfield"]
CMD ["--help"]
