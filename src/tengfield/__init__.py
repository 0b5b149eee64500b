"""tengfield: predict what a bouncing-ball triboelectric nanogenerator delivers.

Pipeline: scene -> impact dynamics -> field surrogate (dolfinx) -> circuit ->
V_OC, Q_SC, I_SC. Heavy dependencies (dolfinx, gmsh, pyvista) are imported
only by the stages that need them.
"""
__version__ = "0.1.0"

from .errors import DynamicsError, FieldError, SceneError, TengfieldError  # noqa: E402
from .scene import Scene, default_scene, load_scene, parse_scene  # noqa: E402

__all__ = ["Scene", "default_scene", "load_scene", "parse_scene", "SceneError",
           "TengfieldError", "DynamicsError", "FieldError", "__version__"]
