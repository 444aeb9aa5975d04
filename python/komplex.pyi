"""Komplex: quadric-CSG geometry and rendering from Python, in numpy batches.

A scene is a union of blocks (intersections of quadric solids and
half-spaces); where blocks overlap, the priority rule decides the owner
(the first opaque block, else the first transparent one). Blocks are
numbered from 1 in priority order, as in the EXR ``id.block`` channel;
``0`` means no block. See docs/python.md.
"""

from os import PathLike
from typing import Dict, List, Optional, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt

__version__: str

ArrayLike = npt.ArrayLike

class SceneError(ValueError):
    """A scene that cannot be loaded; the message names the place (JSON
    path, line and column), as the command line does."""

class BlockInfo(TypedDict):
    index: int
    """1-based, as ``classify`` and ``id.block``."""
    name: str
    material: str
    transparent: bool
    box: Optional[Tuple[Tuple[float, float, float], Tuple[float, float, float]]]
    """``(min, max)`` corners, ``±inf`` on unbounded axes; ``None`` for an empty block."""

class Hits:
    """The first hits of a batch of rays; ``N`` entries each."""

    t: npt.NDArray[np.float64]
    """Distance along the normalised ray, ``inf`` where nothing is hit."""
    block: npt.NDArray[np.uint32]
    """1-based block hit, ``0`` where nothing is hit."""
    solid: npt.NDArray[np.uint32]
    """1-based solid of that block, ``0`` where nothing is hit."""
    point: npt.NDArray[np.float64]
    """``(N, 3)`` hit points, ``nan`` where nothing is hit."""
    normal: npt.NDArray[np.float64]
    """``(N, 3)`` outward unit normals of the hit block's surface, ``nan`` where nothing is hit."""
    entering: npt.NDArray[np.bool_]
    """Whether the ray enters the hit block there (else it leaves it)."""
    def __len__(self) -> int: ...

class Traces:
    """Every ray's partition into segments, ragged: ray ``i``'s segments are
    ``start[offsets[i]:offsets[i + 1]]`` (and the same slice of ``end`` and ``block``)."""

    offsets: npt.NDArray[np.int64]
    """``(N + 1,)``."""
    start: npt.NDArray[np.float64]
    end: npt.NDArray[np.float64]
    """``inf`` for each ray's last segment."""
    block: npt.NDArray[np.uint32]
    """1-based owner, ``0`` for empty space."""
    def __len__(self) -> int: ...

class Scene:
    """A loaded scene. Queries release the GIL and run on every core."""

    @property
    def blocks(self) -> List[BlockInfo]:
        """The blocks in priority order."""
    def classify(self, points: ArrayLike) -> npt.NDArray[np.uint32]:
        """The owner of each point of an ``(N, 3)`` array: 1-based block
        indices, ``0`` outside every block. Non-finite points raise ``ValueError``."""
    def cast(self, origins: ArrayLike, directions: ArrayLike, max_t: float = ...) -> Hits:
        """The first hit of each ray within ``max_t`` (directions are
        normalised, so ``t`` is a distance). A zero direction raises ``ValueError``."""
    def trace(self, origins: ArrayLike, directions: ArrayLike) -> Traces:
        """Each ray's partition into segments owned by one block or none,
        from ``t = 0`` to ``inf``."""
    def volumes(
        self, tolerance: float = 1e-3, seed: int = 0, box: Optional[Tuple[float, float, float, float, float, float]] = None
    ) -> dict:
        """Every block's volume as the complex owns it, its own volume and
        the union's, with standard errors: ``komplex volume --json`` as
        Python data (docs/geometry.md)."""
    def overlaps(
        self, tolerance: float = 1e-3, seed: int = 0, box: Optional[Tuple[float, float, float, float, float, float]] = None
    ) -> dict:
        """Every pair of blocks whose own regions share a positive volume,
        with the volume, its error and a point inside both: ``komplex
        overlaps --json`` as Python data."""
    def render(
        self,
        width: Optional[int] = None,
        height: Optional[int] = None,
        spp: Optional[int] = None,
        threads: Optional[int] = None,
        precision: Optional[str] = None,
        samples: Optional[int] = None,
        noise: Optional[float] = None,
        seed: Optional[int] = None,
    ) -> Dict[str, np.ndarray]:
        """Renders the scene's camera view (as ``komplex render``, with the
        scene's integrator): the EXR channels ``R G B A Z N.X N.Y N.Z``
        (float32) and ``id.block id.object`` (uint32) as ``(height, width)``
        arrays, and under adaptive sampling (``noise``) ``spp`` (uint32) and
        ``error`` (float32). ``width`` or ``height`` alone keeps the aspect
        ratio; ``spp`` is samples per pixel (``--spp``), ``samples`` an n×n
        grid per pixel, ``noise`` the bound of adaptive sampling
        (``--noise``), ``seed`` the seed of the random samples;
        ``precision`` is ``"fast"``, ``"accurate"`` or ``"certified"``."""
    def __len__(self) -> int: ...

def load(path: Union[str, PathLike]) -> Scene:
    """Reads a scene file (JSON). Raises ``SceneError`` for a bad scene,
    ``FileNotFoundError`` or ``OSError`` when it cannot be read."""

def loads(json: str) -> Scene:
    """Reads a scene from JSON text. Raises ``SceneError`` for a bad scene."""

def import_openmc(path: Union[str, PathLike]) -> Scene:
    """Imports an OpenMC geometry (``geometry.xml`` or a ``model.xml``) as
    ``komplex import-openmc`` does; each block is named ``cell <id>`` after
    its OpenMC cell. Raises ``ValueError`` naming the line and column of bad
    input, ``FileNotFoundError`` or ``OSError`` when it cannot be read."""
