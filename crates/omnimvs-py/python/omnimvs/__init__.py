"""omnimvs: 360-degree depth from a rig of 220-degree fisheye cameras (OmniMVS, ICCV 2019).

Python bindings of the Rust library: every function computes exactly what the ``omnimvs``
command computes, returns numpy arrays, releases the GIL while it works and raises
``ValueError``, ``FileNotFoundError`` or ``OSError`` with the library's message.

>>> import omnimvs
>>> ds = omnimvs.Dataset("itbt_sample")          # a folder with config.yaml and the images
>>> ds.frames, ds.num_cameras, ds.min_depth
>>> inv_depth = omnimvs.sgm(ds, 1)               # ZNCC + SGM, float32 (160, 640), 1/m
>>> net = omnimvs.infer(ds, 1)                   # the bundled cascade, float32 (160, 640)
>>> rig = omnimvs.Rig.from_config("itbt_sample/config.yaml")
>>> live = omnimvs.sgm(ds.images(1), rig=rig)    # images from anywhere, as uint8 arrays
"""

from ._omnimvs import (
    Dataset,
    Rig,
    __version__,
    evaluate,
    infer,
    lookup_table,
    photometric_difference,
    sgm,
    synth,
)

__all__ = [
    "Dataset",
    "Rig",
    "__version__",
    "evaluate",
    "infer",
    "lookup_table",
    "photometric_difference",
    "sgm",
    "synth",
]
