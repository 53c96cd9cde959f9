"""Type stubs of the compiled module (re-exported by ``omnimvs``)."""

import os
from pathlib import Path
from typing import Literal, Optional, Sequence, Tuple, TypedDict, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str

PathLike = Union[str, os.PathLike[str]]
Image = npt.NDArray[np.uint8]
FloatMap = npt.NDArray[np.float32]

class Maps(TypedDict):
    """Every map of an estimate (``infer(..., maps=True)``), each ``(height, width)``."""

    inv_depth: FloatMap
    index: FloatMap
    entropy: Optional[FloatMap]
    spread: Optional[FloatMap]

class Metrics(TypedDict):
    """The paper's metrics of one frame (``E = |n_hat - n*| / N * 100``)."""

    over1_pct: float
    over3_pct: float
    over5_pct: float
    mae: float
    rms: float
    valid_pixels: int

class Rig:
    """The geometry of a rig (cameras, poses, minimum depth, validity masks), for images that
    do not come from a dataset folder: ``sgm(images, rig=rig)``."""

    @staticmethod
    def from_config(path: PathLike) -> "Rig":
        """Reads the rig of a reference ``config.yaml`` (or of the folder holding it); the
        same as ``from_file(path)``.

        Raises FileNotFoundError for a missing file, ValueError for a wrong field."""
    @staticmethod
    def from_file(
        path: PathLike,
        rig_frame: Optional[Literal["calibration", "fitted"]] = None,
        min_depth: Optional[float] = None,
    ) -> "Rig":
        """Reads the rig of any calibration file omnimvs reads (``config.yaml``, Basalt's
        ``calibration.json``, Kalibr's ``camchain.yaml``, or a folder holding one or the
        released ``ocamN.txt`` + ``poses.txt``), in ``rig_frame``, with the sweep's minimum depth
        ``min_depth`` in metres (default: the file's, else 0.55). Images need not exist.

        Raises FileNotFoundError for a missing file, ValueError for a wrong field (the message
        names the file and the field)."""
    @property
    def num_cameras(self) -> int:
        """Number of cameras."""
    @property
    def models(self) -> list[str]:
        """Each camera's model: ``"ocam"``, ``"ds"``, ``"eucm"``, ``"ucm"``, ``"kb4"`` or
        ``"pinhole-radtan"``."""
    @property
    def rig_from_cam(self) -> list[list[list[float]]]:
        """Each camera's pose, camera to rig, as a 4x4 nested list (metres)."""
    @property
    def min_depth(self) -> float:
        """Minimum depth of the sweep, metres."""
    @property
    def image_sizes(self) -> list[Tuple[int, int]]:
        """``(height, width)`` of each camera's images."""

class Dataset:
    """A dataset folder in the reference layout (``config.yaml`` + images), read as the
    ``omnimvs`` command reads it; never written to.

    A folder in the released datasets' layout (``ocam1.txt``.. and ``poses.txt``) opens too;
    ``pose_unit`` (``"m"``, ``"cm"``, the default, or ``"mm"``) is the unit of its
    ``poses.txt`` translations. So does a folder with a Basalt ``calibration.json`` or a
    Kalibr ``camchain.yaml`` and one image folder per camera (``cam0/``.. or ``cam1/``..).
    ``rig_frame`` is ``"calibration"`` (the default) or ``"fitted"`` (origin at the cameras'
    mean, vertical axis normal to their plane); ``min_depth`` replaces the minimum depth.

    Raises FileNotFoundError when there is no ``config.yaml``, ValueError for a wrong field or
    an unknown or inapplicable ``pose_unit``."""

    def __init__(
        self,
        path: PathLike,
        pose_unit: Optional[str] = None,
        rig_frame: Optional[Literal["calibration", "fitted"]] = None,
        min_depth: Optional[float] = None,
    ) -> None: ...
    @property
    def rig_frame(self) -> str:
        """The frame the rig and the outputs are expressed in, in words."""
    @property
    def root(self) -> Path:
        """The dataset folder."""
    @property
    def frames(self) -> list[int]:
        """The frames of the configured range whose images all exist."""
    @property
    def num_cameras(self) -> int:
        """Number of cameras of the rig."""
    @property
    def min_depth(self) -> float:
        """Minimum depth of the sweep (``config.omnimvs_sweep_min_depth``), metres."""
    @property
    def rig(self) -> Rig:
        """The rig of the dataset."""
    def images(self, frame: int, colour: bool = False) -> list[Image]:
        """The images of every camera at ``frame``: gray, ``uint8`` ``(height, width)`` (a
        colour image as its channels' mean); with ``colour=True`` as decoded, a colour image
        as ``uint8`` ``(height, width, 3)`` (RGB), a gray one as ``(height, width)``.

        Raises FileNotFoundError when an image is missing."""
    def ground_truth(self, frame: int) -> Optional[FloatMap]:
        """The stored ground-truth inverse depth (1/m) of ``frame``, or None."""

def lookup_table(
    source: Union[Dataset, Rig],
    height: int = 160,
    width: int = 640,
    ndepth: int = 192,
    phi_deg: float = 45.0,
) -> npt.NDArray[np.float32]:
    """The lookup table in the ``.hwd`` layout: ``[cameras, ndepth/2, height, width, 2]``
    sampling positions normalised for ``grid_sample(align_corners=True)``."""

@overload
def sgm(
    source: Dataset,
    frame: int,
    height: int = 160,
    width: int = 640,
    ndepth: Optional[int] = None,
    phi_deg: float = 45.0,
    *,
    cost: Literal["zncc", "mccnn", "sweepnet"] = "zncc",
    # None, or "fast" (32 spheres), "balanced" (64), "accurate" (192): instead of ndepth.
    speed: Optional[Literal["fast", "balanced", "accurate"]] = None,
) -> FloatMap: ...
@overload
def sgm(
    source: Sequence[Image],
    frame: None = None,
    height: int = 160,
    width: int = 640,
    ndepth: Optional[int] = None,
    phi_deg: float = 45.0,
    *,
    rig: Rig,
    cost: Literal["zncc", "mccnn", "sweepnet"] = "zncc",
    speed: Optional[Literal["fast", "balanced", "accurate"]] = None,
) -> FloatMap: ...
@overload
def infer(
    source: Dataset,
    frame: int,
    # None: the default bundled model, the cascade (160x640); "cascade" or "tiny" (32x128) by
    # name; or a weights file.
    weights: Optional[PathLike] = None,
    *,
    preset: str = "paper",
    backend: str = "cpu",
    # None, or a percentage of the hypotheses: answers between two surfaces move to one.
    snap_edges: Optional[float] = None,
    # None, or nats: pixels whose uncertainty is above it are NaN.
    max_entropy: Optional[float] = None,
    # None, or index units of N: the same by the spread (standard deviation).
    max_spread: Optional[float] = None,
    # "auto": the bundled cascade's learnt picks after it (its two, as "chain");
    # "off"; "single": its first pick alone; "chain": its two picks, the second trained on the
    # first's answers; or a pick's .safetensors (several, comma-separated, run in turn).
    pick: str = "auto",
    # True: a dict of every map (Maps) instead of the inverse depth alone.
    maps: Literal[False] = False,
    # None, or "fast" (half input size, no pick), "balanced" (no pick), "accurate": instead of pick.
    speed: Optional[Literal["fast", "balanced", "accurate"]] = None,
) -> FloatMap: ...
@overload
def infer(
    source: Dataset,
    frame: int,
    weights: Optional[PathLike] = None,
    *,
    preset: str = "paper",
    backend: str = "cpu",
    snap_edges: Optional[float] = None,
    max_entropy: Optional[float] = None,
    max_spread: Optional[float] = None,
    pick: str = "auto",
    maps: Literal[True],
    speed: Optional[Literal["fast", "balanced", "accurate"]] = None,
) -> Maps: ...
@overload
def infer(
    source: Sequence[Image],
    frame: None = None,
    # None: the default bundled model, the cascade (160x640); "cascade" or "tiny" (32x128) by
    # name; or a weights file.
    weights: Optional[PathLike] = None,
    *,
    preset: str = "paper",
    backend: str = "cpu",
    rig: Rig,
    snap_edges: Optional[float] = None,
    max_entropy: Optional[float] = None,
    max_spread: Optional[float] = None,
    pick: str = "auto",
    maps: Literal[False] = False,
    speed: Optional[Literal["fast", "balanced", "accurate"]] = None,
) -> FloatMap: ...
@overload
def infer(
    source: Sequence[Image],
    frame: None = None,
    weights: Optional[PathLike] = None,
    *,
    preset: str = "paper",
    backend: str = "cpu",
    rig: Rig,
    snap_edges: Optional[float] = None,
    max_entropy: Optional[float] = None,
    max_spread: Optional[float] = None,
    pick: str = "auto",
    maps: Literal[True],
    speed: Optional[Literal["fast", "balanced", "accurate"]] = None,
) -> Maps: ...
def evaluate(
    prediction: Union[npt.NDArray[np.float32], npt.NDArray[np.float64]],
    dataset: Dataset,
    frame: int,
    height: int = 160,
    width: int = 640,
    ndepth: int = 192,
    phi_deg: float = 45.0,
    protocol: str = "reference",
) -> Metrics:
    """The paper's metrics of a predicted inverse-depth map (on its own grid, resampled to the
    ``height x width`` evaluation grid, indices of ``ndepth`` spheres) against the frame's
    ground truth, as ``omnimvs eval`` scores a method; ``protocol`` is ``"reference"`` (the
    paper's: sky not scored) or ``"with-sky"``."""

def photometric_difference(
    prediction: Union[npt.NDArray[np.float32], npt.NDArray[np.float64]],
    dataset: Dataset,
    frame: int,
    phi_deg: float = 45.0,
) -> Optional[float]:
    """How well a predicted inverse-depth map (on its own grid over ``+-phi_deg``) explains the
    frame's images, without ground truth, as ``omnimvs eval`` scores real recordings: the
    median gray difference over camera pairs seeing each point, divided by the gray values'
    standard deviation (lower is better); ``None`` when no two cameras share enough points."""

def synth(
    kind: str,
    out: PathLike,
    frames: Union[Tuple[int, int], int, None] = (1, 10),
    seed: int = 0,
    rig: Union[Rig, PathLike, None] = None,
    size: Optional[Tuple[int, int]] = None,
    spp: int = 1,
) -> Dataset:
    """Renders a synthetic dataset (``"things"`` or ``"house"``) with exact ground truth into
    ``out`` (frames 1..10 by default) and returns it. ``rig``: ``None`` (the published rig), a
    ``Rig``, a rig file, or ``"random:SEED"`` (a rig drawn from the seed)."""
