"""fathom: navigation sensor simulation and estimators (Rust), from Python.

- ``run`` / ``check``: scenario files through the same driver as ``fathom run`` /
  ``fathom check``; the summary as Python objects, the CSV series as numpy arrays.
- ``KalmanFilter``: FilterPy's interface on fathom's Kalman core.
- ``World``: a triangle mesh (OBJ / STL / arrays) and batch-parallel ray casting.
"""

import os
from typing import Any, Dict, List, Mapping, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

ArrayLike = npt.ArrayLike
FloatArray = npt.NDArray[np.float64]
Scenario = Union[str, "os.PathLike[str]"]

MATERIAL_MISS: int
"""Material code of a miss (-1)."""
MATERIAL_OPAQUE: int
"""Material code of an opaque surface (0)."""
MATERIAL_GLASS: int
"""Material code of glass (1)."""
MATERIAL_OTHER_BASE: int
"""``Other(id)`` has the code ``MATERIAL_OTHER_BASE + id`` (2 + id)."""
MAX_FIXED_DIM_X: int
"""Largest ``dim_x`` served by a fixed-size filter (12); larger sizes use the dynamic core."""
MAX_FIXED_DIM_Z: int
"""Largest measurement size served by a fixed-size update (6); larger ones use the stacked update."""

def run(
    scenario: Scenario,
    runs: Optional[int] = None,
    seed: Optional[int] = None,
    threads: Optional[int] = None,
    out: Optional[Union[str, "os.PathLike[str]"]] = None,
) -> "RunResult":
    """Run a scenario (a path, or TOML text: a str with a newline or '=') like ``fathom run``.

    ``runs`` and ``seed`` override the scenario's ``runs`` and ``base_seed``; ``threads``
    is the number of worker threads (default all cores; the numbers do not depend on
    it). Without ``out`` nothing is written; with ``out`` every file ``fathom run``
    writes is written there by the same writer. The GIL is released while running.

    Raises ``ValueError`` for an invalid scenario or bad arguments (the message is the
    line ``fathom check`` prints), ``OSError`` for an unreadable file and
    ``RuntimeError`` for a failure while running.
    """

def check(scenario: Scenario, /) -> str:
    """Validate a scenario without running it (``fathom check``).

    Returns the resolved scenario (defaults filled in) as TOML text; raises
    ``ValueError`` with the one line ``fathom check`` prints when it is invalid.
    """

def preset(name: str, /) -> str:
    """The TOML text of a registered experiment's preset (``scenarios/<name>.toml``)."""

def experiments() -> Dict[str, str]:
    """The registered experiments: name -> one-line description."""

class RunResult:
    """The outcome of :func:`run`."""

    experiment: str
    """Experiment name."""
    seed_doc: str
    """The seed paper's file name."""
    runs: int
    """Monte Carlo runs of the main batch."""
    base_seed: int
    """Base seed of the runs."""
    summary: Dict[str, Any]
    """The whole ``summary.json`` (equal to ``json.load`` of the file ``fathom run`` writes)."""
    rows: List[Dict[str, Any]]
    """``summary["rows"]``: ``method``, ``metric``, ``paper`` (float or None), ``value``, ``ci95`` ([lo, hi] or None)."""
    claims: List[Dict[str, Any]]
    """``summary["claims"]``: ``id``, ``text``, ``holds``, ``detail``."""
    extra: Dict[str, Any]
    """The extra keys of ``summary.json``."""
    series: Dict[str, Dict[str, Union[FloatArray, List[str]]]]
    """CSV file name -> column name -> float64 array (text columns: list of str)."""
    figures: Dict[str, str]
    """SVG file name -> SVG text."""
    resolved_toml: str
    """The resolved scenario (defaults filled in, overrides folded in)."""
    out_dir: Optional[str]
    """The output folder when ``out`` was given."""

class KalmanFilter:
    """A linear Kalman filter with FilterPy's interface on fathom's Kalman core.

    ``dim_x <= 12`` uses the fixed-size core (measurement sizes up to 6 through its
    fixed-size update, larger ones through its stacked update); larger ``dim_x`` the
    dynamic core. Update: Joseph form. ``F``, ``Q``, ``H``, ``R``, ``B`` are arrays held
    by the filter (in-place edits take effect); ``x`` and ``P`` live in the core (every
    assignment and step is checked there; in-place edits of the returned arrays are
    checked and loaded at the next step). Bad input raises ``ValueError`` with the
    core's message and leaves the filter unchanged. Each ``predict()`` advances the
    core's time ``t`` by ``dt`` (default 1); error messages carry it.
    """

    def __init__(self, dim_x: int, dim_z: int, dim_u: int = 0) -> None: ...
    @property
    def dim_x(self) -> int: ...
    @property
    def dim_z(self) -> int: ...
    @property
    def dim_u(self) -> int: ...
    @property
    def core(self) -> str:
        """``"fixed<N>"`` or ``"dynamic"``."""
    x: FloatArray
    """State, shape ``(dim_x, 1)`` (or ``(dim_x,)`` after assigning a 1-D array)."""
    P: FloatArray
    """State covariance ``(dim_x, dim_x)``."""
    F: FloatArray
    """State transition ``(dim_x, dim_x)``."""
    Q: FloatArray
    """Process noise ``(dim_x, dim_x)``."""
    H: FloatArray
    """Measurement matrix ``(dim_z, dim_x)``."""
    R: FloatArray
    """Measurement noise ``(dim_z, dim_z)``, checked on assignment."""
    B: Optional[FloatArray]
    """Control matrix ``(dim_x, dim_u)`` or None."""
    dt: float
    """Time added to ``t`` by each ``predict()``."""
    alpha: float
    """Always 1 (no fading memory)."""
    @property
    def t(self) -> float: ...
    def predict(
        self,
        u: Optional[ArrayLike] = None,
        B: Optional[ArrayLike] = None,
        F: Optional[ArrayLike] = None,
        Q: Optional[Union[ArrayLike, float]] = None,
    ) -> None:
        """``x = F x (+ B u)``, ``P = F P F^T + Q``; arguments override the filter's for this call."""
    def update(
        self,
        z: Optional[ArrayLike],
        R: Optional[Union[ArrayLike, float]] = None,
        H: Optional[ArrayLike] = None,
    ) -> None:
        """Joseph-form update with ``z``; ``z=None`` skips it (FilterPy)."""
    @property
    def y(self) -> FloatArray:
        """Innovation ``z - H x`` of the last update."""
    @property
    def S(self) -> FloatArray:
        """Innovation covariance ``H P H^T + R`` of the last update."""
    @property
    def SI(self) -> FloatArray:
        """``S^-1``."""
    @property
    def K(self) -> FloatArray:
        """Kalman gain of the last update."""
    @property
    def z(self) -> Optional[FloatArray]:
        """The last measurement."""
    @property
    def nis(self) -> Optional[float]:
        """Normalized innovation squared ``y^T S^-1 y`` of the last update."""
    @property
    def mahalanobis(self) -> Optional[float]:
        """``sqrt(nis)``."""
    @property
    def log_likelihood(self) -> Optional[float]: ...
    @property
    def likelihood(self) -> Optional[float]: ...
    @property
    def x_prior(self) -> FloatArray: ...
    @property
    def P_prior(self) -> FloatArray: ...
    @property
    def x_post(self) -> FloatArray: ...
    @property
    def P_post(self) -> FloatArray: ...

class RayHits:
    """Hits of :meth:`World.cast`, one entry per ray. Misses: range inf, normal NaN,
    material ``MATERIAL_MISS``, triangle -1, hit False."""

    ranges: FloatArray
    """``(N,)`` range along the unit direction, m."""
    normals: FloatArray
    """``(N, 3)`` unit normal of the hit triangle facing the ray (NED)."""
    materials: npt.NDArray[np.int32]
    """``(N,)`` material codes."""
    triangles: npt.NDArray[np.int64]
    """``(N,)`` index of the hit triangle in ``World.triangles``."""
    hit: npt.NDArray[np.bool_]
    """``(N,)`` whether the ray hit."""
    def __len__(self) -> int: ...

class World:
    """A triangle mesh in local NED metres (x north, y east, z down) with a BVH ray caster."""

    @staticmethod
    def from_obj(
        path: Union[str, "os.PathLike[str]"],
        axes: str = "enu_z_up",
        scale: float = 1.0,
        origin_offset: Tuple[float, float, float] = (0.0, 0.0, 0.0),
        materials: Optional[Mapping[str, Union[str, int]]] = None,
        default_material: Optional[str] = "opaque",
    ) -> "World":
        """Read an OBJ file. ``axes``: the file's axes as a scenario's ``world.axes``
        names them, ``"enu_z_up"`` (default), ``"ned"``, ``"y_up_right_handed"`` or
        ``"y_up_left_handed"`` (short forms ``"enu"``, ``"y_up_rh"``, ``"y_up_lh"``); ``scale``: metres per file unit;
        ``origin_offset``: subtracted first (file axes and units); ``materials``:
        ``usemtl`` name -> ``"opaque"``, ``"glass"`` or a code."""
    @staticmethod
    def from_stl(
        path: Union[str, "os.PathLike[str]"],
        axes: str = "enu_z_up",
        scale: float = 1.0,
        origin_offset: Tuple[float, float, float] = (0.0, 0.0, 0.0),
        material: Union[str, int, None] = None,
    ) -> "World":
        """Read a binary or ASCII STL file (every face ``material``, default opaque)."""
    @staticmethod
    def from_arrays(
        vertices: ArrayLike, triangles: ArrayLike, materials: Optional[List[int]] = None
    ) -> "World":
        """A world from ``(V, 3)`` vertices (NED m), ``(T, 3)`` indices and ``(T,)`` material codes."""
    def __len__(self) -> int: ...
    @property
    def vertices(self) -> FloatArray: ...
    @property
    def triangles(self) -> npt.NDArray[np.int64]: ...
    @property
    def materials(self) -> npt.NDArray[np.int32]: ...
    @property
    def bounds(self) -> Optional[Tuple[FloatArray, FloatArray]]: ...
    @property
    def report(self) -> Optional[Dict[str, int]]: ...
    def cast(
        self,
        origins: ArrayLike,
        directions: ArrayLike,
        max_range: Union[float, ArrayLike, None] = None,
        threads: Optional[int] = None,
    ) -> RayHits:
        """Closest hits of ``(N, 3)`` rays with ``1e-9 < t <= max_range`` (default inf),
        cast in parallel (``threads``: default all cores; the result does not depend on it)."""
    def cast_one(
        self,
        origin: Tuple[float, float, float],
        direction: Tuple[float, float, float],
        max_range: float = ...,
    ) -> Optional[Tuple[float, FloatArray, int, int]]:
        """One ray through the caster's scalar call: ``(range, normal, material, triangle)`` or None."""
