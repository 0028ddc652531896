"""Trajectory error metrics on top of evo.

APE (absolute pose error, translation part, metres) after SE3 / Sim3 / no alignment (Umeyama), and
RPE (relative pose error over a fixed delta). The numbers are evo's own (``evo.main_ape.ape`` and
``evo.main_rpe.rpe``): slslam only associates the trajectories, checks the input and collects the
statistics, so a result here equals what ``evo_ape`` prints for the same files and options.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from evo import main_ape, main_rpe
from evo.core import sync
from evo.core.metrics import PoseRelation, Unit
from evo.core.trajectory import PosePath3D, PoseTrajectory3D

from slslam.errors import InputError

Alignment = Literal["se3", "sim3", "none"]
ALIGNMENTS = ("se3", "sim3", "none")
DeltaUnit = Literal["m", "frames", "deg", "rad"]
_DELTA_UNITS = {"m": Unit.meters, "frames": Unit.frames, "deg": Unit.degrees, "rad": Unit.radians}
STAT_KEYS = ("rmse", "mean", "median", "std", "min", "max", "sse")


@dataclass
class ErrorResult:
    """Statistics and per-pose errors of one metric.

    Attributes:
        name: ``ape`` or ``rpe``.
        stats: ``rmse, mean, median, std, min, max, sse`` in metres.
        errors: per-pose (APE) or per-pair (RPE) errors [m].
        timestamps: seconds for each error (None for untimed paths).
        estimate_aligned: the estimate after alignment (for plots).
        reference: the associated reference trajectory.
        options: what was used (alignment, max_diff, delta ...).
    """

    name: str
    stats: dict[str, float]
    errors: np.ndarray
    timestamps: np.ndarray | None
    estimate_aligned: PosePath3D
    reference: PosePath3D
    options: dict[str, object] = field(default_factory=dict)


def associate(
    reference: PosePath3D, estimate: PosePath3D, max_diff_s: float = 0.01
) -> tuple[PosePath3D, PosePath3D]:
    """Pair poses by nearest timestamp within ``max_diff_s`` (by index for untimed paths)."""
    if isinstance(reference, PoseTrajectory3D) and isinstance(estimate, PoseTrajectory3D):
        try:
            ref, est = sync.associate_trajectories(reference, estimate, max_diff=max_diff_s)
        except sync.SyncException as exc:
            raise InputError(
                None,
                f"the trajectories cannot be associated in time: {exc} "
                "(check that both files use the same time base, in seconds)",
            ) from None
    else:
        if reference.num_poses != estimate.num_poses:
            raise InputError(
                None,
                f"untimed trajectories must have equal length to be compared "
                f"by index ({reference.num_poses} vs {estimate.num_poses} poses)",
            )
        ref, est = copy.deepcopy(reference), copy.deepcopy(estimate)
    # evo stores trajectories in its Result under their names; fix them so _collect finds them.
    ref.name, est.name = "ref", "est"
    if ref.num_poses < 3:
        raise InputError(
            None,
            f"only {ref.num_poses} poses associate within {max_diff_s} s: "
            "check that both files use the same time base (seconds)",
        )
    return ref, est


def _first_line(exc: BaseException, limit: int = 200) -> str:
    """An exception's message on one line, at most ``limit`` characters."""
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _check_alignment(align: str) -> None:
    if align not in ALIGNMENTS:
        raise InputError(None, f"unknown alignment '{align}' (use one of {ALIGNMENTS})")


def _collect(name: str, result, ref: PosePath3D, options: dict[str, object]) -> ErrorResult:
    est_aligned = result.trajectories.get("est")
    stamps = result.np_arrays.get("timestamps")
    return ErrorResult(
        name=name,
        stats={k: float(result.stats[k]) for k in STAT_KEYS},
        errors=np.asarray(result.np_arrays["error_array"], dtype=float),
        timestamps=None if stamps is None else np.asarray(stamps, dtype=float),
        estimate_aligned=est_aligned,
        reference=ref,
        options=options,
    )


def compute_ape(
    reference: PosePath3D, estimate: PosePath3D, align: Alignment = "se3", max_diff_s: float = 0.01
) -> ErrorResult:
    """Absolute position error (translation part) after the chosen alignment."""
    _check_alignment(align)
    ref, est = associate(reference, estimate, max_diff_s)
    try:
        result = main_ape.ape(
            ref,
            est,
            PoseRelation.translation_part,
            align=align != "none",
            correct_scale=align == "sim3",
        )
    except Exception as exc:  # evo's own types, numpy's LinAlgError (e.g. a degenerate alignment)
        raise InputError(
            None,
            f"APE cannot be computed ({type(exc).__name__}: {_first_line(exc)}); a stationary or "
            "degenerate trajectory cannot be aligned",
        ) from None
    return _collect(
        "ape",
        result,
        ref,
        {
            "align": align,
            "max_diff_s": max_diff_s,
            "pose_relation": "translation_part",
            "num_poses": ref.num_poses,
        },
    )


def compute_rpe(
    reference: PosePath3D,
    estimate: PosePath3D,
    delta: float = 1.0,
    delta_unit: DeltaUnit = "m",
    align: Alignment = "se3",
    max_diff_s: float = 0.01,
) -> ErrorResult:
    """Relative translation error over pose pairs ``delta`` apart (metres travelled by default)."""
    _check_alignment(align)
    if delta_unit not in _DELTA_UNITS:
        raise InputError(None, f"unknown RPE delta unit '{delta_unit}' (use {list(_DELTA_UNITS)})")
    if not delta > 0:
        raise InputError(None, f"RPE delta must be > 0, got {delta}")
    ref, est = associate(reference, estimate, max_diff_s)
    unit = _DELTA_UNITS[delta_unit]
    if unit == Unit.frames and delta != int(delta):
        raise InputError(None, f"an RPE delta in frames must be an integer, got {delta}")
    try:
        result = main_rpe.rpe(
            ref,
            est,
            PoseRelation.translation_part,
            delta=int(delta) if unit == Unit.frames else delta,
            delta_unit=unit,
            align=align != "none",
            correct_scale=align == "sim3",
        )
    except Exception as exc:  # evo raises its own types when no pose pair spans delta
        raise InputError(
            None, f"RPE failed for delta {delta} {delta_unit}: {_first_line(exc)}"
        ) from None
    return _collect(
        "rpe",
        result,
        ref,
        {
            "align": align,
            "max_diff_s": max_diff_s,
            "delta": delta,
            "delta_unit": delta_unit,
            "pose_relation": "translation_part",
        },
    )
