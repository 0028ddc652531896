"""Point front ends: XFeat and SuperPoint (onnxruntime) and ORB (OpenCV) with one interface.

All have ``detect(image: uint8 H x W) -> Keypoints`` (uv, scores, descriptors) and declare what
else their ``detect`` takes (:class:`PointFrontEnd`, ``slslam.features.frontend``). The per-cell
limit, the dynamic-cell filter and the matchers are in the C++ core (``slslam._core``:
``grid_limit``, ``DynamicCellFilter``, ``match_descriptors``, ``guided_match``).
"""

from slslam.features.frontend import FrontEndCapabilities, PointFrontEnd, frontend_capabilities
from slslam.features.keypoints import Keypoints
from slslam.features.superpoint import (
    ENV_MODEL,
    ModelError,
    SuperPoint,
    SuperPointOptions,
    resolve_model_path,
)
from slslam.features.xfeat import XFeat, XFeatOptions

__all__ = [
    "ENV_MODEL",
    "FrontEndCapabilities",
    "Keypoints",
    "ModelError",
    "PointFrontEnd",
    "SuperPoint",
    "SuperPointOptions",
    "XFeat",
    "XFeatOptions",
    "frontend_capabilities",
    "resolve_model_path",
]
