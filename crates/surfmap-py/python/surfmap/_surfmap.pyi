# Type stubs of the Rust extension surfmap._surfmap (docstrings: help(surfmap.flatten), …).
# tests/test_docs.py checks that every function here has the runtime's parameters.

import os
from typing import Any, Callable, Dict, List, Literal, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

PathLike = Union[str, os.PathLike[str]]
FloatArray = npt.NDArray[np.floating[Any]]
IndexArray = npt.NDArray[np.integer[Any]]
Alpha = Tuple[float, float, float]
Report = Dict[str, Any]
Row = Dict[str, Any]

# The columns of the batch table (summary.csv, the rows of flatten_file / flatten_many).
BATCH_COLUMNS: List[str]
# The columns of the registration table (summary.csv of register / register_file rows).
REGISTER_COLUMNS: List[str]

class MeshError(ValueError):
    """The mesh cannot be used as given; ``defects`` lists why (dicts as in inspect())."""

    defects: List[Dict[str, Any]]

class MatchNotTrusted(RuntimeError):
    correspondence: FloatArray
    report: Report

class SolverError(RuntimeError):
    """The computation failed on a valid mesh; the message says what to try."""

def inspect(V: FloatArray, F: IndexArray) -> Report: ...
def measure(
    V: FloatArray,
    F: IndexArray,
    UV: FloatArray,
    FUV: Optional[IndexArray] = None,
    *,
    normalize: bool = True,
    overlap: bool = True,
) -> Report: ...
def flatten(
    V: FloatArray,
    F: IndexArray,
    *,
    preset: Literal["conformal", "balanced", "area", "length"] = "balanced",
    alpha: Optional[Alpha] = None,
    energy: Literal["litke", "sd", "mips", "arap"] = "litke",
    from_alpha: Optional[Alpha] = None,
    start: Literal["auto", "lscm", "mean_value"] = "auto",
    multilevel: Literal["auto", "on", "off"] = "auto",
    coarse_vertices: Optional[int] = None,
    fill_holes: Optional[bool] = None,
    cut: Optional[Literal["never", "auto", "holes"]] = None,
    seams: Optional[IndexArray] = None,
    max_distortion: Optional[float] = None,
    max_cut_rounds: int = 30,
    max_iters: int = 200,
    tolerance: float = 1e-12,
    armijo_c: float = 0.5,
    normalize: bool = False,
) -> Union[
    # Without cut, seams or max_distortion: (UV, report), one UV per vertex.
    Tuple[npt.NDArray[np.float64], Report],
    # With them: (UV, FUV, report), per-corner UVs (UV[FUV[t, j]] for corner j of F[t]).
    Tuple[npt.NDArray[np.float64], npt.NDArray[np.int64], Report],
]: ...
def geometry_images(
    V: FloatArray,
    F: IndexArray,
    *,
    size: int = 257,
    UV: Optional[FloatArray] = None,
    pyramid: bool = True,
    features: Optional[Sequence[Dict[str, Any]]] = None,
    fill_holes: bool = False,
) -> Dict[str, Any]: ...
def read_mesh(path: PathLike) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]: ...
def write_obj(
    path: PathLike,
    V: FloatArray,
    F: IndexArray,
    UV: Optional[FloatArray] = None,
    FUV: Optional[IndexArray] = None,
) -> None: ...
def repair(
    V: FloatArray,
    F: IndexArray,
    *,
    weld: Optional[float] = None,
    drop_degenerate: bool = False,
    reorient: bool = False,
    keep_largest: bool = False,
    component: Optional[int] = None,
    drop_unreferenced: bool = False,
    fix_non_manifold: bool = False,
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.int64], Dict[str, int]]: ...
def crop(
    V: FloatArray,
    F: IndexArray,
    *,
    center: Sequence[float],
    radius: float,
    geodesic: bool = False,
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.int64], npt.NDArray[np.int64]]: ...

# flatten_file and flatten_many take the keywords of flatten() (preset, alpha, energy,
# from_alpha, start, multilevel, coarse_vertices, fill_holes, cut, seams, max_distortion,
# max_cut_rounds, max_iters, tolerance, armijo_c, normalize) as **options.
def flatten_file(
    path: PathLike, outdir: PathLike, name: Optional[str] = None, **options: Any
) -> Row: ...
def output_names(paths: Sequence[PathLike]) -> List[str]: ...
def _check_flatten_options(**options: Any) -> None: ...
def _flatten_many(
    paths: Sequence[PathLike],
    outdir: PathLike,
    workers: int = 0,
    callback: Optional[Callable[[Row], None]] = None,
    **options: Any,
) -> List[Row]: ...

def register_file(
    template: PathLike,
    scan: PathLike,
    outdir: PathLike,
    name: Optional[str] = None,
    landmarks_dir: Optional[PathLike] = None,
    keep_matches: bool = False,
    size: Optional[int] = None,
    budget: Optional[int] = None,
) -> Row: ...
def _check_register(template: PathLike, size: Optional[int] = None, budget: Optional[int] = None) -> float: ...
def _register_many(
    template: PathLike,
    scans: Sequence[PathLike],
    outdir: PathLike,
    workers: int = 0,
    callback: Optional[Callable[[Row], None]] = None,
    landmarks_dir: Optional[PathLike] = None,
    keep_matches: bool = False,
    resume: bool = False,
    size: Optional[int] = None,
    budget: Optional[int] = None,
) -> List[Row]: ...

def match(
    VA: FloatArray,
    FA: IndexArray,
    VB: FloatArray,
    FB: IndexArray,
    *,
    landmarks: Optional[Dict[str, Any]] = None,
    features_a: Optional[Union[Dict[str, Any], Sequence[Dict[str, Any]]]] = None,
    features_b: Optional[Union[Dict[str, Any], Sequence[Dict[str, Any]]]] = None,
    size: Optional[int] = None,
    align: Optional[Literal["auto", "features", "shape", "none"]] = None,
    features_start: Optional[Literal["both", "plane"]] = None,
    keep_folds: Optional[bool] = None,
    rim_fit_rings: Optional[int] = None,
    complete_rings: Optional[int] = None,
    pin_landmarks: Optional[bool] = None,
    scale_b: Optional[float] = None,
    budget: Optional[int] = None,
    hole_features: Optional[Literal["auto", "on", "off"]] = None,
    whole_hole_rims: Optional[bool] = None,
    fill_holes: Optional[bool] = None,
    beta: Optional[Sequence[float]] = None,
    position_weight: Optional[float] = None,
    similarity_search: Optional[Literal["shape", "off", "always"]] = None,
    search_candidates: Optional[Sequence[float]] = None,
    search_level: Optional[int] = None,
    rim_tolerance: Optional[float] = None,
    relief: Optional[float] = None,
    crop_overlap: Optional[Literal["auto", "off"]] = None,
    strict: Optional[bool] = None,
    recover: Optional[bool] = None,
    open_mouth: Optional[bool] = None,
) -> Tuple[FloatArray, Report]: ...
