# tengfield in a container: Debian bookworm's FEM stack (dolfinx 0.5.2, PETSc,
# OpenMPI) plus tengfield and its PyPI dependencies in a venv.
#
#   docker build -t tengfield .
#   docker run --rm -v "$PWD/out:/out" tengfield run -o /out
#   docker run --rm -v "$PWD/out:/out" --entrypoint mpirun tengfield \
#       -n 2 tengfield precompute          # surrogate into /out/cache
#
# docs/container.md has the details; scripts/test-container builds and tests
# this file with podman on a machine without a Docker daemon.
FROM debian:bookworm-slim

# System packages through the same script the Makefile uses (one source of
# truth). It installs with --no-install-recommends; the package lists and
# the .deb cache are dropped in the same layer.
COPY scripts/install-system.sh /tmp/install-system.sh
RUN DEBIAN_FRONTEND=noninteractive bash /tmp/install-system.sh \
 && apt-get clean \
 && rm -rf /var/lib/apt/lists/* /tmp/install-system.sh

# A venv that sees Debian's dolfinx, petsc4py, mpi4py, h5py and scipy
# (--system-site-packages, exactly as `make setup` does): those must come
# from Debian (built against its PETSc and OpenMPI), while the rest comes
# from PyPI. Debian's own python refuses `pip install` outside a venv
# (PEP 668, externally managed), which a venv respects without
# --break-system-packages.
ENV VIRTUAL_ENV=/opt/tengfield
ENV PATH=/opt/tengfield/bin:$PATH

# Behind a TLS-intercepting proxy, pass its CA bundle as a build secret:
#   docker build --secret id=ca-bundle,src=/etc/ssl/certs/ca-certificates.crt .
# Without the secret pip uses its own certificate store.
ARG PIP_DEFAULT_TIMEOUT=180
COPY . /tmp/tengfield-src
RUN --mount=type=secret,id=ca-bundle \
    if [ -s /run/secrets/ca-bundle ]; then export PIP_CERT=/run/secrets/ca-bundle; fi \
 && python3 -m venv --system-site-packages "$VIRTUAL_ENV" \
 && pip install --no-cache-dir --disable-pip-version-check \
        "numpy<2" "/tmp/tengfield-src[field]" \
 && rm -rf /tmp/tengfield-src \
 && tengfield --version

# MPI as root inside the container; mpirun -n 2 also on a 1-core host;
# OpenMPI's single-copy (CMA) transport needs ptrace rights that container
# runtimes usually withhold, so shared memory falls back to copy-in/out.
# Headless rendering: pyvista through VTK's EGL window (Mesa renders in
# software, no X server; VTK >= 9.4 reads VTK_DEFAULT_OPENGL_WINDOW) and
# matplotlib's Agg backend.
ENV OMPI_ALLOW_RUN_AS_ROOT=1 \
    OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 \
    OMPI_MCA_rmaps_base_oversubscribe=1 \
    OMPI_MCA_btl_vader_single_copy_mechanism=none \
    PYVISTA_OFF_SCREEN=true \
    VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow \
    MPLBACKEND=Agg \
    PYTHONUNBUFFERED=1

# Outputs go to /out: mount a host directory there. The caches go there too
# (/out/cache: field surrogates, dolfinx's compiled forms, numba's compiled
# kernels, matplotlib's font list), so later containers reuse them.
ENV XDG_CACHE_HOME=/out/cache \
    NUMBA_CACHE_DIR=/out/cache/numba
WORKDIR /out
VOLUME ["/out"]
ENTRYPOINT ["tengfield"]
CMD ["--help"]
