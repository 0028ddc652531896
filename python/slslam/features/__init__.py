"""Point front ends: XFeat and SuperPoint (onnxruntime) and ORB (OpenCV) with one interface.

All have ``detect(image: uint8 H x W) -> Keypoints`` (uv, scores, descriptors) and declare what
else their ``detect`` takes (:class:`PointFrontEnd`, ``slslam.features.frontend``). The per-cell
limit, the dynamic-cell filter and the matchers run in the C++ core; ``slslam.features.matching``
exposes them (``grid_limit``, ``match_descriptors``, ``guided_match``, ``match_stereo_points``,
``DynamicCellFilter``, ``predict_with_robust_pose``), re-exported here.
"""

from slslam.features.frontend import FrontEndCapabilities, PointFrontEnd, frontend_capabilities
from slslam.features.keypoints import Keypoints
from slslam.features.matching import (
    DynamicCellFilter,
    DynamicCellOptions,
    GridLimitOptions,
    GuidedMatchOptions,
    MatchOptions,
    PinholeCamera,
    RobustPrediction,
    StereoMatchOptions,
    StereoRig,
    grid_limit,
    guided_match,
    match_descriptors,
    match_stereo_points,
    predict_with_robust_pose,
    stereo_rig,
)
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
    "DynamicCellFilter",
    "DynamicCellOptions",
    "FrontEndCapabilities",
    "GridLimitOptions",
    "GuidedMatchOptions",
    "Keypoints",
    "MatchOptions",
    "ModelError",
    "PinholeCamera",
    "PointFrontEnd",
    "RobustPrediction",
    "StereoMatchOptions",
    "StereoRig",
    "SuperPoint",
    "SuperPointOptions",
    "XFeat",
    "XFeatOptions",
    "frontend_capabilities",
    "grid_limit",
    "guided_match",
    "match_descriptors",
    "match_stereo_points",
    "predict_with_robust_pose",
    "resolve_model_path",
    "stereo_rig",
]
