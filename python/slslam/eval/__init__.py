"""Trajectory evaluation: APE / RPE through evo, metrics JSON and PNG plots."""

from slslam.eval.metrics import ErrorResult, compute_ape, compute_rpe
from slslam.eval.report import Evaluation, evaluate, load_groundtruth

__all__ = [
    "ErrorResult",
    "Evaluation",
    "compute_ape",
    "compute_rpe",
    "evaluate",
    "load_groundtruth",
]
