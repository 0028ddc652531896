"""Coal-mine roadway simulator: stereo camera, 16-beam LiDAR and IMU with exact ground truth.

    from slslam.sim import SimOptions, Simulator
    Simulator(SimOptions(preset="loop", light=0.15, dust=True, frames=400)).write("out/")

Modules: ``centrelines`` (preset paths), ``roadway`` (meshes and materials), ``raycast``
(Open3D/Embree), ``sensors`` (stereo camera, LiDAR), ``trajectory`` (robot motion and IMU),
``movers`` and ``dust`` (dynamic content), ``asl_writer`` (EuRoC layout), ``sequence`` (all of it).
Image formation (textures, lights, sensor noise) runs in the C++ core (``_core.shade_image``).
"""

from slslam.sim.sequence import PRESETS, SimOptions, Simulator

__all__ = ["PRESETS", "SimOptions", "Simulator"]
