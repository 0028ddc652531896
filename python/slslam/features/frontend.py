"""What a point front end is to the tracker: ``PointFrontEnd``, and the capabilities it declares.

A point front end is any object with ``detect(image) -> Keypoints`` (``image``: uint8 H x W
gray). Optional keywords of ``detect`` are declared by class attributes, not found by probing
its signature:

=============================  ========  =========================================================
attribute                      default   when True
=============================  ========  =========================================================
``smoothed_input``             True      ``detect`` sees the pair the tracker smoothed when noisy
                                         (``tracking.denoise_above_noise``); False: the image as it
                                         came (SuperPoint)
``detect_takes_threshold``     False     ``detect(image, threshold=t)`` detects at ``t`` instead of
                                         ``options.detection_threshold`` (the low-texture fallback,
                                         ``features.low_texture_fallback``)
``detect_takes_select``        False     ``detect(image, select=f)`` calls ``f(uv, scores)`` and
                                         keeps (and describes) only the returned indices, in their
                                         order (the grid limit before descriptors, XFeat)
``detect_takes_denoised``      False     ``detect(image, denoised_above_noise=t)``: the image came
                                         through the tracker's smoothing at threshold ``t``, so the
                                         front end need not check the noise again (ORB, XFeat)
=============================  ========  =========================================================

Every built-in front end (:class:`~slslam.features.orb.Orb`, :class:`~slslam.features.XFeat`,
:class:`~slslam.features.SuperPoint`) sets all four. A front end of your own may leave any of
them out: it then gets the default above (a plain ``detect(image)``). A front end without a
callable ``detect``, or with a capability that is not a bool, is refused with a ``TypeError``
naming it (:func:`frontend_capabilities`). Type checkers ask for all four attributes; subclass
:class:`PointFrontEnd` to inherit the defaults.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from slslam.features.keypoints import Keypoints

__all__ = ["CAPABILITIES", "FrontEndCapabilities", "PointFrontEnd", "frontend_capabilities"]


class PointFrontEnd(Protocol):
    """A point front end: ``detect(image) -> Keypoints`` and its declared capabilities (the
    module's table). Subclassing it inherits the defaults of the capabilities."""

    smoothed_input: bool = True
    detect_takes_threshold: bool = False
    detect_takes_select: bool = False
    detect_takes_denoised: bool = False

    def detect(self, image: np.ndarray) -> Keypoints:
        """Keypoints of one uint8 gray image (H x W)."""
        ...


#: The capability attributes and their defaults for a front end that does not set them.
CAPABILITIES: dict[str, bool] = {
    "smoothed_input": True,
    "detect_takes_threshold": False,
    "detect_takes_select": False,
    "detect_takes_denoised": False,
}


@dataclass(frozen=True)
class FrontEndCapabilities:
    """The capabilities of one front end, defaults filled in (see the module's table)."""

    smoothed_input: bool = True
    detect_takes_threshold: bool = False
    detect_takes_select: bool = False
    detect_takes_denoised: bool = False
    #: ``options.detection_threshold`` when the front end has one (learned detectors), else None
    detection_threshold: float | None = None


def frontend_capabilities(frontend: Any) -> FrontEndCapabilities:
    """The declared capabilities of ``frontend`` (a missing attribute: its default).

    Raises:
        TypeError: ``frontend`` has no callable ``detect``, or a capability attribute that is
            not a bool (named, with the front end's class).
    """
    name = type(frontend).__name__
    if not callable(getattr(frontend, "detect", None)):
        raise TypeError(
            f"point front end {name} has no detect(image) -> Keypoints method "
            "(slslam.features.PointFrontEnd)"
        )
    declared: dict[str, bool] = {}
    for attribute, default in CAPABILITIES.items():
        value = getattr(frontend, attribute, default)
        if not isinstance(value, (bool, np.bool_)):
            raise TypeError(
                f"point front end {name}: {attribute} must be True or False, got {value!r} "
                "(slslam.features.PointFrontEnd)"
            )
        declared[attribute] = bool(value)
    threshold = getattr(getattr(frontend, "options", None), "detection_threshold", None)
    return FrontEndCapabilities(**declared, detection_threshold=threshold)
