"""Pictures for inspection and the docs (PNG files, matplotlib without a screen)."""

from slslam.viz.features import draw_features, draw_matches

__all__ = ["draw_features", "draw_matches"]
