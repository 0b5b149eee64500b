"""A discretisation nobody keeps is destroyed when its solve is done (issue #40's design
study grew to 3.4 GB per process): collecting the Python objects does not free the
matrices dolfinx assembled, and petsc4py defers the destruction of what it collects to
``garbage_cleanup`` on the mesh's own communicator."""
import pytest
from mpi4py import MPI

from tengfield.scene import default_scene

field = pytest.mark.field


def _discretised(scene, moving):
    from tengfield.field import _dolfinx as dx
    from tengfield.field import axisymmetric as ax

    eps = ax.permittivities(scene.device, ax.geometry.layout(scene, 1e-3))
    return ax.discretised(dx, scene, 1e-3, MPI.COMM_SELF, eps, moving=moving)[1]


@field
def test_a_remeshed_discretisation_is_destroyed_and_a_kept_reference_is_not():
    from tengfield.field import _dolfinx as dx
    from tengfield.field import axisymmetric as ax
    from tengfield.field import moving

    scene = default_scene().with_values(field={"mesh_size_mm": 2.0})
    disc = _discretised(scene, moving=False)
    A, P = disc.A, disc.P
    ax.solve_discretisation(dx, disc, -8e-6, scene.device.ball_diameter, source_solve=False)
    moving.done_with(dx, disc, moving=False)
    assert A.handle == 0 and P.handle == 0 and disc.A is None and disc.P is None

    moving.clear()
    kept = _discretised(scene.with_values(field={"mesh_motion": "move"}), moving=True)
    assert kept.placement in ("reference", "moved")
    ax.solve_discretisation(dx, kept, -8e-6, scene.device.ball_diameter, source_solve=False)
    A = kept.A
    moving.done_with(dx, kept, moving=True)
    assert A.handle != 0 and kept.solver        # the reference keeps its operator and solver
    moving.clear()                              # ... until the references are forgotten
    assert A.handle == 0
