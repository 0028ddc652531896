"""Stereo point-line tracking and local mapping: ``Tracker`` (per frame) and ``run_sequence``
(a whole dataset with files written as it goes)."""

from slslam.tracking.run import RunSummary, open_dataset, run_sequence, write_ply
from slslam.tracking.tracker import (
    STATES,
    TRACKED_STATES,
    FrameCounts,
    LoopEvent,
    MapData,
    MapStats,
    StageTimings,
    Tracker,
    TrackResult,
)

__all__ = [
    "STATES",
    "TRACKED_STATES",
    "FrameCounts",
    "LoopEvent",
    "MapData",
    "MapStats",
    "RunSummary",
    "StageTimings",
    "TrackResult",
    "Tracker",
    "open_dataset",
    "run_sequence",
    "write_ply",
]
