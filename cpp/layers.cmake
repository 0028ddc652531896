# The layers of the C++ core, lowest first, and the layers each one builds on directly. One
# table for two readers: cpp/CMakeLists.txt makes one static library per layer
# (slslam_<layer>, every .cpp under cpp/slslam/<layer>/) linking only these, and
# cpp/check_layers.cmake fails the build when a file of a layer includes a header of a layer that
# is not below it (the transitive closure of this table).
#
#   core          cameras, the stereo rig, images, checks
#   features      keypoints, lines, descriptors, the stereo frame's data
#   geometry      rotations, Pluecker lines, reprojection residuals
#   inertial      IMU preintegration, the inertial state and its covariance, inertial initialisation
#   place         bag-of-words vocabulary and keyframe database
#   map           keyframes (with their IMU states), points, lines, covisibility, map files
#   optimization  Ceres problems: pose, bundle adjustment, pose graph
#   mapping       local mapping, triangulation, loop closing, the atlas
#   tracking      stereo matching, the stereo front end, the tracker, the inertial estimator
#   pipeline      the per-frame session over the tracker (what slslam._core's TrackerCore binds)
#   sim           the roadway simulator's renderer (beside the SLAM layers)
#   lidar         LiDAR registration and LiDAR-inertial SLAM (beside; needs PCL; its loops go to
#                 optimization's pose graph)
set(SLSLAM_LAYERS core features geometry inertial place map optimization mapping tracking pipeline sim
                  lidar)
set(SLSLAM_LAYER_DEPS_core "")
set(SLSLAM_LAYER_DEPS_features core)
set(SLSLAM_LAYER_DEPS_geometry core)
set(SLSLAM_LAYER_DEPS_inertial core geometry)
set(SLSLAM_LAYER_DEPS_place core)
set(SLSLAM_LAYER_DEPS_map core features geometry inertial place)
set(SLSLAM_LAYER_DEPS_optimization core geometry inertial)
set(SLSLAM_LAYER_DEPS_mapping map optimization)
set(SLSLAM_LAYER_DEPS_tracking mapping)
set(SLSLAM_LAYER_DEPS_pipeline tracking)
set(SLSLAM_LAYER_DEPS_sim core)
set(SLSLAM_LAYER_DEPS_lidar core geometry inertial optimization)

# SLSLAM_LAYER_BELOW_<layer>: every layer it may include (transitive closure of the table).
foreach(layer IN LISTS SLSLAM_LAYERS)
  set(below "")
  set(todo ${SLSLAM_LAYER_DEPS_${layer}})
  while(todo)
    list(POP_FRONT todo next)
    if(NOT next IN_LIST below)
      list(APPEND below ${next})
      list(APPEND todo ${SLSLAM_LAYER_DEPS_${next}})
    endif()
  endwhile()
  set(SLSLAM_LAYER_BELOW_${layer} ${below})
endforeach()
