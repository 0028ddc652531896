"""
slslam C++ core (camera geometry, rectification, features)
"""
from __future__ import annotations
import collections.abc
import numpy
import numpy.typing
import typing
__all__: list[str] = ['AssociationOptions', 'BundleAdjustmentOptions', 'DynamicCellFilter', 'DynamicCellOptions', 'FrameOutput', 'GridLimitOptions', 'GuidedMatchOptions', 'HeadLamp', 'ImuNoiseOptions', 'InertialOptions', 'KeyframeDatabase', 'LbdOptions', 'LeftLines', 'LidarOdometry', 'LidarOdometryOptions', 'LidarPoseGraphOptions', 'LineExtractorOptions', 'LineMatchOptions', 'LinePreprocessOptions', 'LioSmootherOptions', 'LocalMapperOptions', 'LoopClosingOptions', 'MatchOptions', 'Material', 'OdometryResult', 'OrbOptions', 'PinholeCamera', 'PlaceCandidate', 'PoseGraphOptions', 'PoseOptimizerOptions', 'PreparedFrame', 'RadTanCamera', 'RayCaster', 'RegistrationMethod', 'RegistrationOptions', 'RegistrationResult', 'RelocalisationOptions', 'ScanContextDatabase', 'ScanContextMatch', 'ScanContextOptions', 'ScanMatchOptions', 'SensorModel', 'ShadingCamera', 'StereoLineOptions', 'StereoMatchOptions', 'StereoRectifier', 'StereoRig', 'TrackerCore', 'TrackerOptions', 'TriangulationOptions', 'Vocabulary', 'VocabularyOptions', 'VoxelMapOptions', 'adapt_to_rig', 'associate_points_to_lines', 'detect_lsd_segments', 'estimate_noise_sigma', 'extract_lines', 'extract_orb', 'grid_limit', 'guided_match', 'local_maxima', 'match_descriptors', 'match_lines_by_points', 'match_scan_to_points', 'match_stereo_lines', 'match_stereo_points', 'optimize_lidar_pose_graph', 'predict_with_robust_pose', 'preprocess_lines', 'read_gray_image', 'read_map_file_header', 'read_point_cloud', 'register_clouds', 'relief_normals', 'sample_dense_map', 'shade_image', 'smooth_if_noisy', 'solid_texture', 'suppress_non_maxima', 'triangulate_stereo_lines', 'write_image']
class PinholeCamera:
    """
    Ideal pinhole intrinsics in pixels.
    """
    def K(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 3]"]:
        ...
    @typing.overload
    def __init__(self) -> None:
        ...
    @typing.overload
    def __init__(self, fx: typing.SupportsFloat | typing.SupportsIndex, fy: typing.SupportsFloat | typing.SupportsIndex, cx: typing.SupportsFloat | typing.SupportsIndex, cy: typing.SupportsFloat | typing.SupportsIndex, width: typing.SupportsInt | typing.SupportsIndex, height: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __repr__(self) -> str:
        ...
    def check(self) -> None:
        ...
    def project(self, point_in_cam: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"]) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[2, 1]"]:
        ...
    @property
    def cx(self) -> float:
        ...
    @cx.setter
    def cx(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def cy(self) -> float:
        ...
    @cy.setter
    def cy(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def fx(self) -> float:
        ...
    @fx.setter
    def fx(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def fy(self) -> float:
        ...
    @fy.setter
    def fy(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def height(self) -> int:
        ...
    @height.setter
    def height(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def width(self) -> int:
        ...
    @width.setter
    def width(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class RadTanCamera:
    """
    Pinhole with radial-tangential distortion.
    """
    def __init__(self, pinhole: PinholeCamera, distortion: typing.Annotated[collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex], "FixedSize(4)"]) -> None:
        ...
    @property
    def distortion(self) -> typing.Annotated[list[float], "FixedSize(4)"]:
        ...
    @property
    def pinhole(self) -> PinholeCamera:
        ...
class StereoRectifier:
    """
    Undistorts and rectifies a calibrated stereo pair (OpenCV).
    """
    def __init__(self, left: RadTanCamera, right: RadTanCamera, T_left_right: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[4, 4]"]) -> None:
        ...
    def rectify(self, left: numpy.ndarray, right: numpy.ndarray) -> tuple[numpy.ndarray, numpy.ndarray]:
        """
        Rectify a (left, right) pair of uint8 images; returns the rectified pair.
        """
    @property
    def R_rect_left(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 3]"]:
        ...
    @property
    def R_rectright_right(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 3]"]:
        ...
    @property
    def baseline_m(self) -> float:
        ...
    @property
    def rectified_camera(self) -> PinholeCamera:
        ...
class OrbOptions:
    """
    ORB extractor options (per-cell adaptive FAST, OpenCV descriptors).
    """
    adaptive: bool
    describe_smoothed: bool
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def cell_size_px(self) -> int:
        ...
    @cell_size_px.setter
    def cell_size_px(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def denoise_above_noise(self) -> float:
        ...
    @denoise_above_noise.setter
    def denoise_above_noise(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def edge_threshold(self) -> int:
        ...
    @edge_threshold.setter
    def edge_threshold(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def fast_threshold(self) -> int:
        ...
    @fast_threshold.setter
    def fast_threshold(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def max_features(self) -> int:
        ...
    @max_features.setter
    def max_features(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def min_fast_threshold(self) -> int:
        ...
    @min_fast_threshold.setter
    def min_fast_threshold(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def num_levels(self) -> int:
        ...
    @num_levels.setter
    def num_levels(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def scale_factor(self) -> float:
        ...
    @scale_factor.setter
    def scale_factor(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class MatchOptions:
    """
    Brute-force matcher options.
    """
    mutual: bool
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def max_distance(self) -> float:
        ...
    @max_distance.setter
    def max_distance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def ratio(self) -> float:
        ...
    @ratio.setter
    def ratio(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class GridLimitOptions:
    """
    Per-cell keypoint limit (the SL-SLAM paper's grid limitation).
    """
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def cell_size_px(self) -> int:
        """
        cell side P [px]
        """
    @cell_size_px.setter
    def cell_size_px(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def max_per_cell(self) -> int:
        """
        keypoints kept per cell
        """
    @max_per_cell.setter
    def max_per_cell(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def strong_score(self) -> float:
        """
        cells with a keypoint at this score keep only such keypoints; -inf: off
        """
    @strong_score.setter
    def strong_score(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class DynamicCellOptions:
    """
    Invalid-cell filter (the SL-SLAM paper's).
    """
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def alpha(self) -> float:
        """
        weight of the current frame
        """
    @alpha.setter
    def alpha(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def cell_size_px(self) -> int:
        """
        cell side [px]
        """
    @cell_size_px.setter
    def cell_size_px(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def min_matches(self) -> int:
        """
        matches a cell needs in a frame to count as evidence
        """
    @min_matches.setter
    def min_matches(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def sigma_median_ratio(self) -> float:
        """
        G's width is at least this many times the frame's median match residual
        """
    @sigma_median_ratio.setter
    def sigma_median_ratio(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def sigma_px(self) -> float:
        """
        Gaussian width of G(d) [px]
        """
    @sigma_px.setter
    def sigma_px(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def threshold(self) -> float:
        """
        l: invalid below this
        """
    @threshold.setter
    def threshold(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class DynamicCellFilter:
    """
    Per-cell motion-consistency weights; drops moving objects.
    """
    def __init__(self, width: typing.SupportsInt | typing.SupportsIndex, height: typing.SupportsInt | typing.SupportsIndex, options: DynamicCellOptions = ...) -> None:
        ...
    def keypoint_mask(self, uv: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 2]"]) -> list[bool]:
        ...
    def reset(self) -> None:
        ...
    def update(self, observed: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 2]"], predicted: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 2]"]) -> list[bool]:
        """
        Update from matched positions and their motion-predicted positions (M x 2 each); returns the validity of every cell (row-major).
        """
    @property
    def cells_x(self) -> int:
        ...
    @property
    def cells_y(self) -> int:
        ...
    @property
    def valid(self) -> list[bool]:
        ...
    @property
    def weights(self) -> list[float]:
        ...
class GuidedMatchOptions:
    """
    Window-guided descriptor matching.
    """
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def max_distance(self) -> float:
        """
        descriptor distance
        """
    @max_distance.setter
    def max_distance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def radius_px(self) -> float:
        """
        search radius [px]
        """
    @radius_px.setter
    def radius_px(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def ratio(self) -> float:
        """
        ratio test in the window
        """
    @ratio.setter
    def ratio(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class Material:
    """
    Surface material ids of the simulator's shading kernel.
    
    Members:
    
      ROCK
    
      COAL
    
      SHOTCRETE
    
      STEEL
    
      ROOF_MESH
    
      FLOOR
    
      PIPE
    
      CABLE
    
      WORKER
    
      CART
    
      NONE
    """
    CABLE: typing.ClassVar[Material]
    CART: typing.ClassVar[Material]
    COAL: typing.ClassVar[Material]
    FLOOR: typing.ClassVar[Material]
    NONE: typing.ClassVar[Material]
    PIPE: typing.ClassVar[Material]
    ROCK: typing.ClassVar[Material]
    ROOF_MESH: typing.ClassVar[Material]
    SHOTCRETE: typing.ClassVar[Material]
    STEEL: typing.ClassVar[Material]
    WORKER: typing.ClassVar[Material]
    __members__: typing.ClassVar[dict[str, Material]]
    @typing.overload
    def __eq__(self, other: Material) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: Material) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class ShadingCamera:
    """
    Pinhole intrinsics [px] and optical centre [m] for shading.
    """
    @typing.overload
    def __init__(self) -> None:
        ...
    @typing.overload
    def __init__(self, fx: typing.SupportsFloat | typing.SupportsIndex, fy: typing.SupportsFloat | typing.SupportsIndex, cx: typing.SupportsFloat | typing.SupportsIndex, cy: typing.SupportsFloat | typing.SupportsIndex, position: typing.Annotated[collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex], "FixedSize(3)"] = [0.0, 0.0, 0.0]) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def cx(self) -> float:
        ...
    @cx.setter
    def cx(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def cy(self) -> float:
        ...
    @cy.setter
    def cy(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def fx(self) -> float:
        ...
    @fx.setter
    def fx(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def fy(self) -> float:
        ...
    @fy.setter
    def fy(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def position(self) -> typing.Annotated[list[float], "FixedSize(3)"]:
        """
        optical centre in world [m]
        """
    @position.setter
    def position(self, arg1: typing.Annotated[collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex], "FixedSize(3)"]) -> None:
        ...
class HeadLamp:
    """
    Spot light: E = power * cos / d^2 inside half_angle_rad, falling smoothly to zero at falloff_ratio * half_angle_rad.
    """
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def direction(self) -> typing.Annotated[list[float], "FixedSize(3)"]:
        """
        unit forward axis in world
        """
    @direction.setter
    def direction(self, arg1: typing.Annotated[collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex], "FixedSize(3)"]) -> None:
        ...
    @property
    def falloff_ratio(self) -> float:
        """
        zero at this x half-angle
        """
    @falloff_ratio.setter
    def falloff_ratio(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def half_angle_rad(self) -> float:
        """
        fully lit half-angle [rad]
        """
    @half_angle_rad.setter
    def half_angle_rad(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def position(self) -> typing.Annotated[list[float], "FixedSize(3)"]:
        """
        in world [m]
        """
    @position.setter
    def position(self, arg1: typing.Annotated[collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex], "FixedSize(3)"]) -> None:
        ...
    @property
    def power(self) -> float:
        """
        intensity [irradiance units * m^2]
        """
    @power.setter
    def power(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class SensorModel:
    """
    s = radiance * cos^4 * exposure (full-well fraction); DN = gain * 255 * s + shot/read noise; out = 255 * (DN / 255)^gamma.
    """
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def exposure(self) -> float:
        """
        radiance -> full-well fraction
        """
    @exposure.setter
    def exposure(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def full_well_electrons(self) -> float:
        """
        [e-]
        """
    @full_well_electrons.setter
    def full_well_electrons(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def gain(self) -> float:
        """
        analog gain [-]
        """
    @gain.setter
    def gain(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def gamma(self) -> float:
        """
        encoding exponent (1/2.2; 1 = linear)
        """
    @gamma.setter
    def gamma(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def noise(self) -> bool:
        """
        shot + read noise on/off
        """
    @noise.setter
    def noise(self, arg0: bool) -> None:
        ...
    @property
    def read_noise_dn(self) -> float:
        """
        read noise sigma [DN]
        """
    @read_noise_dn.setter
    def read_noise_dn(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def seed(self) -> int:
        """
        noise seed
        """
    @seed.setter
    def seed(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def vignetting(self) -> bool:
        """
        cos^4 falloff on/off
        """
    @vignetting.setter
    def vignetting(self, arg0: bool) -> None:
        ...
class RayCaster:
    """
    A static triangle mesh prepared for ray casting (Embree, BVH built once).
    """
    def __init__(self, vertices: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 3]"], triangles: typing.Annotated[numpy.typing.ArrayLike, numpy.uint32, "[m, 3]"], material: typing.Annotated[numpy.typing.ArrayLike, numpy.uint8]) -> None:
        """
        vertices float (V, 3) [m], triangles uint32 (F, 3), material uint8 (F,) ids.
        """
    def cast(self, origin: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[3, 1]"], directions: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 3]"], dynamic: RayCaster = None) -> dict:
        """
        Cast rays from one origin along unit directions (N, 3). Returns a dict of numpy arrays: t (N,) [m] (inf: miss), normal (N, 3), point (N, 3), material (N,) uint8.
        """
    def cast_pinhole(self, R_world_cam: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 3]"], origin: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[3, 1]"], fx: typing.SupportsFloat | typing.SupportsIndex, fy: typing.SupportsFloat | typing.SupportsIndex, cx: typing.SupportsFloat | typing.SupportsIndex, cy: typing.SupportsFloat | typing.SupportsIndex, width: typing.SupportsInt | typing.SupportsIndex, height: typing.SupportsInt | typing.SupportsIndex, dynamic: RayCaster = None) -> dict:
        """
        One ray per pixel of a pinhole camera. Returns t, depth (H, W) [m], normal, point (H, W, 3) and material (H, W) uint8; pixel (u, v) looks along R_world_cam * normalize((u - cx) / fx, (v - cy) / fy, 1).
        """
    @property
    def num_triangles(self) -> int:
        ...
class LinePreprocessOptions:
    """
    Line preprocessing (the SL-SLAM paper's).
    """
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def length_ratio(self) -> float:
        """
        zeta
        """
    @length_ratio.setter
    def length_ratio(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_gap_px(self) -> float:
        """
        gap limit [px]
        """
    @max_gap_px.setter
    def max_gap_px(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def theta_min_rad(self) -> float:
        """
        angle unit [rad]
        """
    @theta_min_rad.setter
    def theta_min_rad(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def xi_d_px(self) -> float:
        """
        merge/delete distance [px]
        """
    @xi_d_px.setter
    def xi_d_px(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class AssociationOptions:
    """
    Point-line association (the SL-SLAM paper's).
    """
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def cell_size_px(self) -> int:
        ...
    @cell_size_px.setter
    def cell_size_px(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def layers(self) -> int:
        ...
    @layers.setter
    def layers(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def max_distance_px(self) -> float:
        ...
    @max_distance_px.setter
    def max_distance_px(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class LineMatchOptions:
    """
    Point-driven line matching.
    """
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def max_angle_rad(self) -> float:
        ...
    @max_angle_rad.setter
    def max_angle_rad(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_lbd_distance(self) -> float:
        ...
    @max_lbd_distance.setter
    def max_lbd_distance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def min_votes(self) -> int:
        ...
    @min_votes.setter
    def min_votes(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class StereoLineOptions:
    """
    Stereo line matching.
    """
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def max_angle_rad(self) -> float:
        ...
    @max_angle_rad.setter
    def max_angle_rad(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_lbd_distance(self) -> float:
        ...
    @max_lbd_distance.setter
    def max_lbd_distance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def min_angle_from_horizontal_rad(self) -> float:
        ...
    @min_angle_from_horizontal_rad.setter
    def min_angle_from_horizontal_rad(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def min_disparity_px(self) -> float:
        ...
    @min_disparity_px.setter
    def min_disparity_px(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def min_row_overlap(self) -> float:
        ...
    @min_row_overlap.setter
    def min_row_overlap(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class LbdOptions:
    """
    Our line band descriptor (features/lbd.h).
    """
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def band_width_px(self) -> int:
        ...
    @band_width_px.setter
    def band_width_px(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def max_samples_along(self) -> int:
        ...
    @max_samples_along.setter
    def max_samples_along(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def smoothing_sigma_px(self) -> float:
        ...
    @smoothing_sigma_px.setter
    def smoothing_sigma_px(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class LineExtractorOptions:
    """
    Line front end of the tracker: detector, scale, preprocessing, cap (tracking.line_* keys).
    """
    lbd: LbdOptions
    preprocess: LinePreprocessOptions
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def descriptor(self) -> str:
        """
        lbd (ours) or opencv_lbd (OpenCV's BinaryDescriptor's bytes)
        """
    @descriptor.setter
    def descriptor(self, arg1: str) -> None:
        ...
    @property
    def detection_scale(self) -> float:
        ...
    @detection_scale.setter
    def detection_scale(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def detector(self) -> str:
        """
        lsd (ours), lsd_opencv (OpenCV's) or fld
        """
    @detector.setter
    def detector(self, arg1: str) -> None:
        ...
    @property
    def max_lines(self) -> int:
        ...
    @max_lines.setter
    def max_lines(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class StereoRig:
    """
    Rectified stereo pair: left intrinsics and baseline.
    """
    camera: PinholeCamera
    @typing.overload
    def __init__(self) -> None:
        ...
    @typing.overload
    def __init__(self, camera: PinholeCamera, baseline_m: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def baseline_m(self) -> float:
        ...
    @baseline_m.setter
    def baseline_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class PoseOptimizerOptions:
    """
    Motion-only bundle adjustment.
    """
    own_solver: bool
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def iterations_per_round(self) -> int:
        ...
    @iterations_per_round.setter
    def iterations_per_round(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def line_angle_weight(self) -> float:
        ...
    @line_angle_weight.setter
    def line_angle_weight(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def line_weight(self) -> float:
        ...
    @line_weight.setter
    def line_weight(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def rounds(self) -> int:
        ...
    @rounds.setter
    def rounds(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class BundleAdjustmentOptions:
    """
    Local bundle adjustment.
    """
    dogleg_with_lines: bool
    own_solver: bool
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def line_angle_weight(self) -> float:
        ...
    @line_angle_weight.setter
    def line_angle_weight(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def line_min_information_per_rad2(self) -> float:
        ...
    @line_min_information_per_rad2.setter
    def line_min_information_per_rad2(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def line_prior_weight(self) -> float:
        ...
    @line_prior_weight.setter
    def line_prior_weight(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def line_weight(self) -> float:
        ...
    @line_weight.setter
    def line_weight(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def refine_iterations(self) -> int:
        ...
    @refine_iterations.setter
    def refine_iterations(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def robust_iterations(self) -> int:
        ...
    @robust_iterations.setter
    def robust_iterations(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class TriangulationOptions:
    """
    New landmarks from pairs of keyframes (local mapping).
    """
    lines: bool
    points: bool
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def min_parallax_deg(self) -> float:
        ...
    @min_parallax_deg.setter
    def min_parallax_deg(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def neighbours(self) -> int:
        ...
    @neighbours.setter
    def neighbours(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class LocalMapperOptions:
    """
    Local mapping.
    """
    ba: BundleAdjustmentOptions
    cull_keyframes: bool
    triangulate: bool
    triangulation: TriangulationOptions
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def local_keyframes(self) -> int:
        ...
    @local_keyframes.setter
    def local_keyframes(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def max_fixed_keyframes(self) -> int:
        ...
    @max_fixed_keyframes.setter
    def max_fixed_keyframes(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def redundant_ratio(self) -> float:
        ...
    @redundant_ratio.setter
    def redundant_ratio(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class StereoMatchOptions:
    """
    Stereo keypoint matching.
    """
    row_search: bool
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def max_depth_baselines(self) -> float:
        ...
    @max_depth_baselines.setter
    def max_depth_baselines(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_disparity_px(self) -> float:
        ...
    @max_disparity_px.setter
    def max_disparity_px(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_distance_binary(self) -> float:
        ...
    @max_distance_binary.setter
    def max_distance_binary(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_distance_float(self) -> float:
        ...
    @max_distance_float.setter
    def max_distance_float(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_row_offset_px(self) -> float:
        ...
    @max_row_offset_px.setter
    def max_row_offset_px(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def ratio(self) -> float:
        ...
    @ratio.setter
    def ratio(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def row_search_max_cost(self) -> float:
        ...
    @row_search_max_cost.setter
    def row_search_max_cost(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def row_search_min_texture(self) -> float:
        ...
    @row_search_min_texture.setter
    def row_search_min_texture(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def row_search_ratio(self) -> float:
        ...
    @row_search_ratio.setter
    def row_search_ratio(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def row_search_window(self) -> int:
        ...
    @row_search_window.setter
    def row_search_window(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def subpixel_search(self) -> int:
        ...
    @subpixel_search.setter
    def subpixel_search(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def subpixel_window(self) -> int:
        ...
    @subpixel_window.setter
    def subpixel_window(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class RelocalisationOptions:
    """
    Relocalisation by bag of words, PnP RANSAC and the local map.
    """
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def candidates(self) -> int:
        ...
    @candidates.setter
    def candidates(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def match_ratio(self) -> float:
        ...
    @match_ratio.setter
    def match_ratio(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def min_inliers(self) -> float:
        ...
    @min_inliers.setter
    def min_inliers(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def min_matches(self) -> int:
        ...
    @min_matches.setter
    def min_matches(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def min_pnp_inliers(self) -> int:
        ...
    @min_pnp_inliers.setter
    def min_pnp_inliers(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def ransac_error_px(self) -> float:
        ...
    @ransac_error_px.setter
    def ransac_error_px(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def ransac_iterations(self) -> int:
        ...
    @ransac_iterations.setter
    def ransac_iterations(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def vocabulary_levels_up(self) -> int:
        ...
    @vocabulary_levels_up.setter
    def vocabulary_levels_up(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class InertialOptions:
    """
    The IMU tightly coupled in tracking: initialisation, prediction, the pose prior, the propagated pose while the camera cannot track.
    """
    resume_map_after_lost: bool
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def T_body_cam(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[4, 4]"]:
        """
        4x4 pose of the rectified left camera in the IMU (body) frame.
        """
    @T_body_cam.setter
    def T_body_cam(self, arg1: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[4, 4]"]) -> None:
        ...
    @property
    def acc_bias_prior_mps2(self) -> float:
        ...
    @acc_bias_prior_mps2.setter
    def acc_bias_prior_mps2(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def acc_noise_density(self) -> float:
        ...
    @acc_noise_density.setter
    def acc_noise_density(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def acc_random_walk(self) -> float:
        ...
    @acc_random_walk.setter
    def acc_random_walk(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def flow_min_inliers(self) -> int:
        ...
    @flow_min_inliers.setter
    def flow_min_inliers(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def flow_sigma_mps(self) -> float:
        ...
    @flow_sigma_mps.setter
    def flow_sigma_mps(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def gravity_mps2(self) -> float:
        ...
    @gravity_mps2.setter
    def gravity_mps2(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def gravity_tolerance_mps2(self) -> float:
        ...
    @gravity_tolerance_mps2.setter
    def gravity_tolerance_mps2(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def gyro_bias_sigma_radps(self) -> float:
        ...
    @gyro_bias_sigma_radps.setter
    def gyro_bias_sigma_radps(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def gyro_noise_density(self) -> float:
        ...
    @gyro_noise_density.setter
    def gyro_noise_density(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def gyro_random_walk(self) -> float:
        ...
    @gyro_random_walk.setter
    def gyro_random_walk(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def keyframe_interval_s(self) -> float:
        ...
    @keyframe_interval_s.setter
    def keyframe_interval_s(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def keyframe_min_stereo_lines(self) -> int:
        ...
    @keyframe_min_stereo_lines.setter
    def keyframe_min_stereo_lines(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def local_ba_keyframes(self) -> int:
        ...
    @local_ba_keyframes.setter
    def local_ba_keyframes(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def lost_sigma_fraction(self) -> float:
        ...
    @lost_sigma_fraction.setter
    def lost_sigma_fraction(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def lost_sigma_min_m(self) -> float:
        ...
    @lost_sigma_min_m.setter
    def lost_sigma_min_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_gap_s(self) -> float:
        ...
    @max_gap_s.setter
    def max_gap_s(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_sample_gap_s(self) -> float:
        ...
    @max_sample_gap_s.setter
    def max_sample_gap_s(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def min_window_s(self) -> float:
        ...
    @min_window_s.setter
    def min_window_s(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def nonholonomic_max_side_ratio(self) -> float:
        ...
    @nonholonomic_max_side_ratio.setter
    def nonholonomic_max_side_ratio(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def nonholonomic_sigma_mps(self) -> float:
        ...
    @nonholonomic_sigma_mps.setter
    def nonholonomic_sigma_mps(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def refine_after_s(self) -> float:
        ...
    @refine_after_s.setter
    def refine_after_s(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def refine_min_path_m(self) -> float:
        ...
    @refine_min_path_m.setter
    def refine_min_path_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def time_offset_s(self) -> float:
        ...
    @time_offset_s.setter
    def time_offset_s(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def visual_information_scale(self) -> float:
        ...
    @visual_information_scale.setter
    def visual_information_scale(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def weak_update_min_inliers(self) -> int:
        ...
    @weak_update_min_inliers.setter
    def weak_update_min_inliers(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def weak_update_min_lines(self) -> int:
        ...
    @weak_update_min_lines.setter
    def weak_update_min_lines(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def window_s(self) -> float:
        ...
    @window_s.setter
    def window_s(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def zero_velocity_max_statistic(self) -> float:
        ...
    @zero_velocity_max_statistic.setter
    def zero_velocity_max_statistic(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def zero_velocity_sigma_mps(self) -> float:
        ...
    @zero_velocity_sigma_mps.setter
    def zero_velocity_sigma_mps(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class PoseGraphOptions:
    """
    Essential-graph optimisation.
    """
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def max_iterations(self) -> int:
        ...
    @max_iterations.setter
    def max_iterations(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def rotation_sigma_rad(self) -> float:
        ...
    @rotation_sigma_rad.setter
    def rotation_sigma_rad(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def translation_sigma_m(self) -> float:
        ...
    @translation_sigma_m.setter
    def translation_sigma_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class LoopClosingOptions:
    """
    Loop closing and map merging (bag of words, points and lines).
    """
    enabled: bool
    global_ba: bool
    merge_maps: bool
    pose_graph: PoseGraphOptions
    yaw_and_position_with_gravity: bool
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def agree_m(self) -> float:
        ...
    @agree_m.setter
    def agree_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def agree_rad(self) -> float:
        ...
    @agree_rad.setter
    def agree_rad(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def candidates(self) -> int:
        ...
    @candidates.setter
    def candidates(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def consistency(self) -> int:
        ...
    @consistency.setter
    def consistency(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def match_ratio(self) -> float:
        ...
    @match_ratio.setter
    def match_ratio(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_correction_floor_m(self) -> float:
        ...
    @max_correction_floor_m.setter
    def max_correction_floor_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_correction_rad(self) -> float:
        ...
    @max_correction_rad.setter
    def max_correction_rad(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_correction_ratio(self) -> float:
        ...
    @max_correction_ratio.setter
    def max_correction_ratio(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def min_inliers(self) -> float:
        ...
    @min_inliers.setter
    def min_inliers(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def min_keyframes(self) -> int:
        ...
    @min_keyframes.setter
    def min_keyframes(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def min_matches(self) -> int:
        ...
    @min_matches.setter
    def min_matches(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def min_pnp_inliers(self) -> int:
        ...
    @min_pnp_inliers.setter
    def min_pnp_inliers(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def ransac_error_px(self) -> float:
        ...
    @ransac_error_px.setter
    def ransac_error_px(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def ransac_iterations(self) -> int:
        ...
    @ransac_iterations.setter
    def ransac_iterations(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def strong_covisibility(self) -> int:
        ...
    @strong_covisibility.setter
    def strong_covisibility(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def welding_keyframes(self) -> int:
        ...
    @welding_keyframes.setter
    def welding_keyframes(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class TrackerOptions:
    """
    Tracking, mapping and front-end thresholds.
    """
    dynamic: DynamicCellOptions
    dynamic_cells: bool
    imu: InertialOptions
    lines_on_demand: bool
    localise_only: bool
    loop_closing: LoopClosingOptions
    mapping: LocalMapperOptions
    mapping_brake: bool
    mapping_overlap: bool
    pose: PoseOptimizerOptions
    relocalisation: RelocalisationOptions
    rig: StereoRig
    right_lines_on_keyframes: bool
    sequential: bool
    stereo: StereoMatchOptions
    triangulated_point_patches: bool
    use_imu: bool
    use_lines: bool
    vocabulary_path: str
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def close_depth_baselines(self) -> float:
        ...
    @close_depth_baselines.setter
    def close_depth_baselines(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def denoise_above_noise(self) -> float:
        ...
    @denoise_above_noise.setter
    def denoise_above_noise(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def frame_rate_hz(self) -> float:
        ...
    @frame_rate_hz.setter
    def frame_rate_hz(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def keyframe_max_frames(self) -> int:
        ...
    @keyframe_max_frames.setter
    def keyframe_max_frames(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def keyframe_min_frames(self) -> int:
        ...
    @keyframe_min_frames.setter
    def keyframe_min_frames(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def keyframe_min_frames_noisy(self) -> int:
        ...
    @keyframe_min_frames_noisy.setter
    def keyframe_min_frames_noisy(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def keyframe_min_inliers(self) -> int:
        ...
    @keyframe_min_inliers.setter
    def keyframe_min_inliers(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def keyframe_min_interval_s(self) -> float:
        ...
    @keyframe_min_interval_s.setter
    def keyframe_min_interval_s(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def keyframe_track_ratio(self) -> float:
        ...
    @keyframe_track_ratio.setter
    def keyframe_track_ratio(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def line_inlier_weight(self) -> float:
        ...
    @line_inlier_weight.setter
    def line_inlier_weight(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def line_max_angle_rad(self) -> float:
        ...
    @line_max_angle_rad.setter
    def line_max_angle_rad(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def line_max_lbd(self) -> float:
        ...
    @line_max_lbd.setter
    def line_max_lbd(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def line_search_px(self) -> float:
        ...
    @line_search_px.setter
    def line_search_px(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def line_sigma_px(self) -> float:
        ...
    @line_sigma_px.setter
    def line_sigma_px(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def lines_on_demand_inliers(self) -> int:
        ...
    @lines_on_demand_inliers.setter
    def lines_on_demand_inliers(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def lost_motion_frames(self) -> int:
        ...
    @lost_motion_frames.setter
    def lost_motion_frames(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def lost_reentry_confirm_m(self) -> float:
        ...
    @lost_reentry_confirm_m.setter
    def lost_reentry_confirm_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def lost_reentry_min_point_ratio(self) -> float:
        ...
    @lost_reentry_min_point_ratio.setter
    def lost_reentry_min_point_ratio(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def lost_search_scale(self) -> float:
        ...
    @lost_search_scale.setter
    def lost_search_scale(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def lost_velocity_decay(self) -> float:
        ...
    @lost_velocity_decay.setter
    def lost_velocity_decay(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def match_ratio(self) -> float:
        ...
    @match_ratio.setter
    def match_ratio(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_distance_binary(self) -> float:
        ...
    @max_distance_binary.setter
    def max_distance_binary(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_distance_float(self) -> float:
        ...
    @max_distance_float.setter
    def max_distance_float(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def min_init_points(self) -> int:
        ...
    @min_init_points.setter
    def min_init_points(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def min_inliers(self) -> int:
        ...
    @min_inliers.setter
    def min_inliers(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def new_map_after_lost_frames(self) -> int:
        ...
    @new_map_after_lost_frames.setter
    def new_map_after_lost_frames(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def point_sigma_px(self) -> float:
        ...
    @point_sigma_px.setter
    def point_sigma_px(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def projected_max_frames(self) -> int:
        ...
    @projected_max_frames.setter
    def projected_max_frames(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def projection_cell_px(self) -> int:
        ...
    @projection_cell_px.setter
    def projection_cell_px(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def projection_min_inliers(self) -> int:
        ...
    @projection_min_inliers.setter
    def projection_min_inliers(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def projection_search_px(self) -> int:
        ...
    @projection_search_px.setter
    def projection_search_px(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def recently_lost_frames(self) -> int:
        ...
    @recently_lost_frames.setter
    def recently_lost_frames(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def reference_focal_px(self) -> float:
        ...
    @reference_focal_px.setter
    def reference_focal_px(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def reference_rate_hz(self) -> float:
        ...
    @reference_rate_hz.setter
    def reference_rate_hz(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def search_radius_px(self) -> float:
        ...
    @search_radius_px.setter
    def search_radius_px(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def track_refine_max_px(self) -> float:
        ...
    @track_refine_max_px.setter
    def track_refine_max_px(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def track_refine_window_px(self) -> int:
        ...
    @track_refine_window_px.setter
    def track_refine_window_px(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def unaligned_max_turn_deg_per_frame(self) -> float:
        ...
    @unaligned_max_turn_deg_per_frame.setter
    def unaligned_max_turn_deg_per_frame(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def unaligned_min_aligned(self) -> int:
        ...
    @unaligned_min_aligned.setter
    def unaligned_min_aligned(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def unaligned_sigma_factor(self) -> float:
        ...
    @unaligned_sigma_factor.setter
    def unaligned_sigma_factor(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def weak_keyframe_frames(self) -> int:
        ...
    @weak_keyframe_frames.setter
    def weak_keyframe_frames(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def weak_keyframe_inliers(self) -> int:
        ...
    @weak_keyframe_inliers.setter
    def weak_keyframe_inliers(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class FrameOutput:
    """
    One frame's result from TrackerCore.track (slslam.Tracker wraps it into a TrackResult).
    """
    @property
    def acc_bias(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]:
        """
        the accelerometer bias estimated then, body frame [m/s^2] (0: no IMU)
        """
    @property
    def cam_from_world(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[4, 4]"]:
        """
        4x4 pose: x_cam = T x_world.
        """
    @property
    def gyro_bias(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]:
        """
        the gyroscope bias estimated then, body frame [rad/s] (0: no IMU)
        """
    @property
    def imu_initialised(self) -> bool:
        """
        the inertial state existed after this frame
        """
    @property
    def inlier_lines(self) -> int:
        ...
    @property
    def inlier_points(self) -> int:
        ...
    @property
    def keyframe(self) -> bool:
        ...
    @property
    def line_extraction_ms(self) -> float:
        ...
    @property
    def lines(self) -> int:
        """
        left-image line segments
        """
    @property
    def map_index(self) -> int:
        ...
    @property
    def mapping_ms(self) -> float:
        ...
    @property
    def masked_keypoints(self) -> int:
        ...
    @property
    def matched_lines(self) -> int:
        ...
    @property
    def matched_points(self) -> int:
        ...
    @property
    def matching_ms(self) -> float:
        ...
    @property
    def needs_keypoints(self) -> bool:
        """
        the frame came without keypoints and the tracker could not place the map's points in it: nothing changed, prepare it again with detected keypoints
        """
    @property
    def optimisation_ms(self) -> float:
        ...
    @property
    def position_sigma_m(self) -> float:
        """
        its position standard deviation then [m] (0: no IMU)
        """
    @property
    def projected_keypoints(self) -> int:
        """
        tracked on this many projected keypoints (0: on detected ones)
        """
    @property
    def relocalisation_ms(self) -> float:
        ...
    @property
    def state(self) -> str:
        ...
    @property
    def stereo_matching_ms(self) -> float:
        ...
    @property
    def v_world_body(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]:
        """
        the body's velocity in the world after this frame [m/s] (0: no IMU)
        """
    @property
    def weighted_inliers(self) -> float:
        ...
class PreparedFrame:
    """
    A frame whose stereo matching ran ahead (TrackerCore.prepare).
    """
    @property
    def stereo_matching_ms(self) -> float:
        ...
class LeftLines:
    """
    A left image's lines extracted ahead (TrackerCore.extract_left_lines).
    """
    @property
    def count(self) -> int:
        ...
    @property
    def extraction_ms(self) -> float:
        ...
class TrackerCore:
    """
    Stereo point-line tracker with local mapping (use slslam.Tracker).
    """
    def __init__(self, options: TrackerOptions, lines: LineExtractorOptions = ...) -> None:
        ...
    def add_imu(self, t_ns: typing.Annotated[numpy.typing.ArrayLike, numpy.int64, "[m, 1]"], gyro: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 3]"], acc: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 3]"]) -> None:
        """
        IMU samples (times [ns] int64, body frame, on the IMU's clock) for the visual-inertial tracking, before the frames they precede.
        """
    def extract_left_lines(self, left_image: numpy.ndarray, denoised: bool = False) -> LeftLines:
        """
        The left image's lines as track extracts them (smoothed when noisy), without the session's lock: for a thread beside the point front end. Needs use_lines and right_lines_on_keyframes. denoised: as track's.
        """
    def flush(self) -> None:
        ...
    def load_map(self, path: str) -> None:
        """
        Loads a saved atlas before the first frame; tracking starts by relocalising in it.
        """
    def map(self, settle: bool = True) -> dict:
        """
        Points and lines; settle: first waits for local mapping (and applies an overlapped local BA), else the map as it stands.
        """
    def prepare(self, index: typing.SupportsInt | typing.SupportsIndex, t_ns: typing.SupportsInt | typing.SupportsIndex, left_image: numpy.ndarray, right_image: numpy.ndarray, left_uv: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 2]"], left_descriptors: numpy.ndarray, right_uv: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 2]"], right_descriptors: numpy.ndarray, left_lines: LeftLines = None, keypoints_pending: bool = False, noisy: bool = False, denoised: bool = False) -> PreparedFrame:
        """
        track's first part without the session's lock: the frame's stereo matching (and its lines unless left_lines or lines on demand), for a thread ahead of the core. track(...) equals track_prepared(prepare(...)). keypoints_pending (no keypoints given; tracking.projected_max_frames): the tracker places the map's points in the frame, or returns needs_keypoints. noisy, denoised: as track's.
        """
    def save_map(self, path: str, version: str) -> None:
        """
        Writes every live map (versioned binary, checksummed); waits for mapping.
        """
    def track(self, index: typing.SupportsInt | typing.SupportsIndex, t_ns: typing.SupportsInt | typing.SupportsIndex, left_image: numpy.ndarray, right_image: numpy.ndarray, left_uv: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 2]"], left_descriptors: numpy.ndarray, right_uv: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 2]"], right_descriptors: numpy.ndarray, left_lines: LeftLines = None, noisy: bool = False, denoised: bool = False) -> FrameOutput:
        """
        Tracks one rectified stereo frame captured at t_ns [ns]; returns its FrameOutput. left_lines: the left image's lines from extract_left_lines on this left image (None: extracted here). noisy: the images were smoothed as noisy before (tracking.unaligned_sigma_factor). denoised: both images come from smooth_if_noisy at the options' denoise_above_noise (slslam.Tracker's own), so they are not checked again.
        """
    def track_prepared(self, frame: PreparedFrame) -> FrameOutput:
        """
        track's second part on a frame from prepare (once, in frame order): the tracker and local mapping; returns its FrameOutput.
        """
    def trajectory(self) -> dict:
        """
        Every estimated frame pose (index, t_ns, map_index, cam_from_world_rotation and _translation arrays) in the final map: after loop correction, merges and bundle adjustment.
        """
class VocabularyOptions:
    """
    Hierarchical k-means options.
    """
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def branching(self) -> int:
        """
        k of the k-means tree [-]
        """
    @branching.setter
    def branching(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def kmeans_iterations(self) -> int:
        """
        Lloyd iterations per node [-]
        """
    @kmeans_iterations.setter
    def kmeans_iterations(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def levels(self) -> int:
        """
        depth L of the tree [-]
        """
    @levels.setter
    def levels(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def seed(self) -> int:
        """
        k-means++ seed [-]
        """
    @seed.setter
    def seed(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class Vocabulary:
    """
    Bag-of-words vocabulary (hierarchical k-means, TF-IDF, L1 score).
    """
    @staticmethod
    def load(path: str) -> Vocabulary:
        """
        Read a .slvoc file; ValueError naming the path when it is not a valid one.
        """
    @staticmethod
    def score(a: collections.abc.Mapping[typing.SupportsInt | typing.SupportsIndex, typing.SupportsFloat | typing.SupportsIndex], b: collections.abc.Mapping[typing.SupportsInt | typing.SupportsIndex, typing.SupportsFloat | typing.SupportsIndex]) -> float:
        """
        L1 score 1 - 0.5 |a - b|_1 of two BoW vectors, in [0, 1].
        """
    @staticmethod
    def train(descriptors_per_image: collections.abc.Sequence[numpy.ndarray], options: VocabularyOptions = ...) -> Vocabulary:
        """
        Train on one (N, D) array per image: all uint8 (binary, D bytes) or all float32.
        """
    def __init__(self) -> None:
        ...
    def save(self, path: str) -> None:
        """
        Write a .slvoc file (through path + '.partial' and a rename).
        """
    def transform(self, descriptors: numpy.ndarray) -> dict[int, float]:
        """
        BoW vector {word: weight} (TF-IDF, L1-normalised).
        """
    def transform_with_features(self, descriptors: numpy.ndarray, levels_up: typing.SupportsInt | typing.SupportsIndex = 2) -> tuple[dict[int, float], dict[int, list[int]]]:
        """
        (BoW vector, {node: [feature rows]}) with nodes levels_up above the leaves.
        """
    def word_weight(self, word: typing.SupportsInt | typing.SupportsIndex) -> float:
        """
        IDF weight of a word.
        """
    @property
    def branching(self) -> int:
        ...
    @property
    def descriptor_cols(self) -> int:
        """
        bytes (binary) or floats per descriptor
        """
    @property
    def descriptor_type(self) -> typing.Any:
        """
        'binary' (uint8, Hamming) or 'float' (float32, L2); None when empty.
        """
    @property
    def empty(self) -> bool:
        ...
    @property
    def levels(self) -> int:
        ...
    @property
    def num_nodes(self) -> int:
        ...
    @property
    def num_words(self) -> int:
        ...
class PlaceCandidate:
    """
    A keyframe returned by KeyframeDatabase.query.
    """
    def __repr__(self) -> str:
        ...
    @property
    def keyframe_id(self) -> int:
        ...
    @property
    def score(self) -> float:
        ...
    @property
    def shared_words(self) -> int:
        ...
class KeyframeDatabase:
    """
    Inverted index of keyframe BoW vectors (thread-safe).
    """
    def __contains__(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> bool:
        ...
    def __init__(self) -> None:
        ...
    def __len__(self) -> int:
        ...
    def add(self, keyframe_id: typing.SupportsInt | typing.SupportsIndex, bow: collections.abc.Mapping[typing.SupportsInt | typing.SupportsIndex, typing.SupportsFloat | typing.SupportsIndex]) -> None:
        ...
    def clear(self) -> None:
        ...
    def query(self, bow: collections.abc.Mapping[typing.SupportsInt | typing.SupportsIndex, typing.SupportsFloat | typing.SupportsIndex], max_results: typing.SupportsInt | typing.SupportsIndex = 10, min_score: typing.SupportsFloat | typing.SupportsIndex = 0.0, min_shared_ratio: typing.SupportsFloat | typing.SupportsIndex = 0.8, accept: collections.abc.Callable[[int], bool] = None) -> list[PlaceCandidate]:
        """
        Keyframes sharing words with bow, best score first; accept(id) -> bool filters ids.
        """
    def remove(self, keyframe_id: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class ImuNoiseOptions:
    """
    Continuous-time IMU noise (Kalibr units).
    """
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def acc_noise_density(self) -> float:
        ...
    @acc_noise_density.setter
    def acc_noise_density(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def acc_random_walk(self) -> float:
        ...
    @acc_random_walk.setter
    def acc_random_walk(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def gravity_mps2(self) -> float:
        ...
    @gravity_mps2.setter
    def gravity_mps2(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def gyro_noise_density(self) -> float:
        ...
    @gyro_noise_density.setter
    def gyro_noise_density(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def gyro_random_walk(self) -> float:
        ...
    @gyro_random_walk.setter
    def gyro_random_walk(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class VoxelMapOptions:
    """
    Local map of LiDAR odometry.
    """
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def max_distance_m(self) -> float:
        ...
    @max_distance_m.setter
    def max_distance_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_points_per_voxel(self) -> int:
        ...
    @max_points_per_voxel.setter
    def max_points_per_voxel(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def min_point_spacing_m(self) -> float:
        ...
    @min_point_spacing_m.setter
    def min_point_spacing_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def voxel_m(self) -> float:
        ...
    @voxel_m.setter
    def voxel_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class ScanMatchOptions:
    """
    Scan-to-map point-to-plane registration.
    """
    point_to_plane: bool
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def convergence_rotation_rad(self) -> float:
        ...
    @convergence_rotation_rad.setter
    def convergence_rotation_rad(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def convergence_translation_m(self) -> float:
        ...
    @convergence_translation_m.setter
    def convergence_translation_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def inlier_m(self) -> float:
        ...
    @inlier_m.setter
    def inlier_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_correspondence_m(self) -> float:
        ...
    @max_correspondence_m.setter
    def max_correspondence_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_iterations(self) -> int:
        ...
    @max_iterations.setter
    def max_iterations(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def num_threads(self) -> int:
        ...
    @num_threads.setter
    def num_threads(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def plane_max_thickness_m(self) -> float:
        ...
    @plane_max_thickness_m.setter
    def plane_max_thickness_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def plane_neighbours(self) -> int:
        ...
    @plane_neighbours.setter
    def plane_neighbours(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def prior_rotation_sigma_rad(self) -> float:
        ...
    @prior_rotation_sigma_rad.setter
    def prior_rotation_sigma_rad(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def prior_translation_sigma_m(self) -> float:
        ...
    @prior_translation_sigma_m.setter
    def prior_translation_sigma_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def robust_scale_m(self) -> float:
        ...
    @robust_scale_m.setter
    def robust_scale_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class LioSmootherOptions:
    """
    Fixed-lag LiDAR-inertial smoother.
    """
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def initial_acc_bias_sigma(self) -> float:
        ...
    @initial_acc_bias_sigma.setter
    def initial_acc_bias_sigma(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def initial_gyro_bias_sigma(self) -> float:
        ...
    @initial_gyro_bias_sigma.setter
    def initial_gyro_bias_sigma(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def initial_tilt_sigma_rad(self) -> float:
        ...
    @initial_tilt_sigma_rad.setter
    def initial_tilt_sigma_rad(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def initial_velocity_sigma_mps(self) -> float:
        ...
    @initial_velocity_sigma_mps.setter
    def initial_velocity_sigma_mps(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_iterations(self) -> int:
        ...
    @max_iterations.setter
    def max_iterations(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def window(self) -> int:
        ...
    @window.setter
    def window(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class LidarOdometryOptions:
    """
    LiDAR(-inertial) odometry; nested option groups by name.
    """
    deskew: bool
    imu: ImuNoiseOptions
    map: VoxelMapOptions
    match: ScanMatchOptions
    smoother: LioSmootherOptions
    use_imu: bool
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def T_body_sensor(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[4, 4]"]:
        """
        4x4 pose of the LiDAR in the IMU (body) frame (body_from_sensor).
        """
    @T_body_sensor.setter
    def T_body_sensor(self, arg1: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[4, 4]"]) -> None:
        ...
    @property
    def gravity_window_s(self) -> float:
        ...
    @gravity_window_s.setter
    def gravity_window_s(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def map_voxel_m(self) -> float:
        ...
    @map_voxel_m.setter
    def map_voxel_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_range_m(self) -> float:
        ...
    @max_range_m.setter
    def max_range_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def min_range_m(self) -> float:
        ...
    @min_range_m.setter
    def min_range_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def scan_information_scale(self) -> float:
        ...
    @scan_information_scale.setter
    def scan_information_scale(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def scan_period_s(self) -> float:
        ...
    @scan_period_s.setter
    def scan_period_s(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def source_voxel_m(self) -> float:
        ...
    @source_voxel_m.setter
    def source_voxel_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class OdometryResult:
    """
    One sweep's pose, state, quality and timing.
    """
    @property
    def T_world_body(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[4, 4]"]:
        """
        4x4 pose of the IMU (body) in the world at the sweep start.
        """
    @property
    def T_world_sensor(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[4, 4]"]:
        """
        4x4 pose of the LiDAR in the world at the sweep start.
        """
    @property
    def acc_bias(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]:
        ...
    @property
    def correspondences(self) -> int:
        ...
    @property
    def degeneracy(self) -> float:
        ...
    @property
    def deskew_ms(self) -> float:
        ...
    @property
    def fitness(self) -> float:
        ...
    @property
    def gyro_bias(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]:
        ...
    @property
    def inlier_rmse_m(self) -> float:
        ...
    @property
    def map_ms(self) -> float:
        ...
    @property
    def map_points(self) -> int:
        ...
    @property
    def match_ms(self) -> float:
        ...
    @property
    def matched(self) -> bool:
        ...
    @property
    def smoother_ms(self) -> float:
        ...
    @property
    def source_points(self) -> int:
        ...
    @property
    def t_ns(self) -> int:
        ...
    @property
    def total_ms(self) -> float:
        ...
    @property
    def velocity_world(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[3, 1]"]:
        ...
class LidarOdometry:
    """
    LiDAR(-inertial) odometry, one sweep at a time.
    """
    def __init__(self, options: LidarOdometryOptions = ...) -> None:
        ...
    def add_imu(self, t_ns: collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex], gyro: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 3]"], acc: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 3]"]) -> None:
        """
        Append IMU samples: t_ns (N,) int64 increasing, gyro (N, 3) [rad/s], acc (N, 3) [m/s^2], body frame.
        """
    def last_scan(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 3]"]:
        """
        The last sweep deskewed to its start, voxelised, sensor frame (N, 3) [m].
        """
    def map_points(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 3]"]:
        """
        Points of the local map (N, 3), world frame [m].
        """
    def process_scan(self, t_ns: typing.SupportsInt | typing.SupportsIndex, points: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, n]"], point_time_s: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex] = []) -> OdometryResult:
        """
        One sweep: points float32 (N, 3|4) in the sensor frame, per-point time after t_ns [s] (empty: no deskewing). Returns an OdometryResult.
        """
class ScanContextOptions:
    """
    Scan Context descriptor and search.
    """
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def candidates(self) -> int:
        ...
    @candidates.setter
    def candidates(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def exclude_recent(self) -> int:
        ...
    @exclude_recent.setter
    def exclude_recent(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def height_offset_m(self) -> float:
        ...
    @height_offset_m.setter
    def height_offset_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_distance(self) -> float:
        ...
    @max_distance.setter
    def max_distance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_radius_m(self) -> float:
        ...
    @max_radius_m.setter
    def max_radius_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def rings(self) -> int:
        ...
    @rings.setter
    def rings(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def sectors(self) -> int:
        ...
    @sectors.setter
    def sectors(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class ScanContextMatch:
    """
    Best loop candidate of a query.
    """
    @property
    def distance(self) -> float:
        ...
    @property
    def index(self) -> int:
        ...
    @property
    def shift(self) -> int:
        ...
    @property
    def yaw_rad(self) -> float:
        ...
class ScanContextDatabase:
    """
    Scan Context keyframe database.
    """
    def __init__(self, options: ScanContextOptions = ...) -> None:
        ...
    def __len__(self) -> int:
        ...
    def add(self, points_sensor: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 3]"]) -> int:
        """
        Add a keyframe's points (N, 3), sensor frame; its index.
        """
    def context(self, index: typing.SupportsInt | typing.SupportsIndex) -> typing.Annotated[numpy.typing.NDArray[numpy.float32], "[m, n]"]:
        ...
    def query(self, index: typing.SupportsInt | typing.SupportsIndex) -> ScanContextMatch:
        """
        Best older keyframe for keyframe `index` (index -1: none below max_distance).
        """
class LidarPoseGraphOptions:
    """
    Keyframe pose graph solver.
    """
    def __init__(self) -> None:
        ...
    @property
    def loop_cauchy_scale(self) -> float:
        ...
    @loop_cauchy_scale.setter
    def loop_cauchy_scale(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_iterations(self) -> int:
        ...
    @max_iterations.setter
    def max_iterations(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class RegistrationMethod:
    """
    LiDAR registration method.
    
    Members:
    
      FPFH_SAC_IA_ICP
    
      NDT
    
      PFH_SAC_IA_ICP
    
      ICP
    """
    FPFH_SAC_IA_ICP: typing.ClassVar[RegistrationMethod]
    ICP: typing.ClassVar[RegistrationMethod]
    NDT: typing.ClassVar[RegistrationMethod]
    PFH_SAC_IA_ICP: typing.ClassVar[RegistrationMethod]
    __members__: typing.ClassVar[dict[str, RegistrationMethod]]
    @typing.overload
    def __eq__(self, other: RegistrationMethod) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: RegistrationMethod) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class RegistrationOptions:
    """
    Parameters of register_clouds (units: m, counts).
    """
    icp_reject_one_to_one: bool
    point_to_plane: bool
    sac_ia_try_identity: bool
    def __init__(self) -> None:
        ...
    def check(self) -> None:
        ...
    @property
    def coarse_voxel_m(self) -> float:
        ...
    @coarse_voxel_m.setter
    def coarse_voxel_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def feature_radius_m(self) -> float:
        ...
    @feature_radius_m.setter
    def feature_radius_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def fine_voxel_m(self) -> float:
        ...
    @fine_voxel_m.setter
    def fine_voxel_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def icp_fitness_epsilon(self) -> float:
        ...
    @icp_fitness_epsilon.setter
    def icp_fitness_epsilon(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def icp_iterations_coarse(self) -> int:
        ...
    @icp_iterations_coarse.setter
    def icp_iterations_coarse(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def icp_iterations_fine(self) -> int:
        ...
    @icp_iterations_fine.setter
    def icp_iterations_fine(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def icp_max_corr_coarse_m(self) -> float:
        ...
    @icp_max_corr_coarse_m.setter
    def icp_max_corr_coarse_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def icp_max_corr_fine_m(self) -> float:
        ...
    @icp_max_corr_fine_m.setter
    def icp_max_corr_fine_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def icp_source_points_coarse(self) -> int:
        ...
    @icp_source_points_coarse.setter
    def icp_source_points_coarse(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def icp_source_points_fine(self) -> int:
        ...
    @icp_source_points_fine.setter
    def icp_source_points_fine(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def icp_transformation_epsilon(self) -> float:
        ...
    @icp_transformation_epsilon.setter
    def icp_transformation_epsilon(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def max_range_m(self) -> float:
        ...
    @max_range_m.setter
    def max_range_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def min_range_m(self) -> float:
        ...
    @min_range_m.setter
    def min_range_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def ndt_iterations(self) -> int:
        ...
    @ndt_iterations.setter
    def ndt_iterations(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def ndt_resolution_m(self) -> float:
        ...
    @ndt_resolution_m.setter
    def ndt_resolution_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def ndt_step_m(self) -> float:
        ...
    @ndt_step_m.setter
    def ndt_step_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def normal_k(self) -> int:
        ...
    @normal_k.setter
    def normal_k(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def num_threads(self) -> int:
        ...
    @num_threads.setter
    def num_threads(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def outlier_k(self) -> int:
        ...
    @outlier_k.setter
    def outlier_k(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def outlier_std_mul(self) -> float:
        ...
    @outlier_std_mul.setter
    def outlier_std_mul(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def sac_ia_confidence(self) -> float:
        ...
    @sac_ia_confidence.setter
    def sac_ia_confidence(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def sac_ia_edge_similarity(self) -> float:
        ...
    @sac_ia_edge_similarity.setter
    def sac_ia_edge_similarity(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def sac_ia_iterations(self) -> int:
        ...
    @sac_ia_iterations.setter
    def sac_ia_iterations(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def sac_ia_max_corr_m(self) -> float:
        ...
    @sac_ia_max_corr_m.setter
    def sac_ia_max_corr_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def sac_ia_min_sample_m(self) -> float:
        ...
    @sac_ia_min_sample_m.setter
    def sac_ia_min_sample_m(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def sac_ia_randomness(self) -> int:
        ...
    @sac_ia_randomness.setter
    def sac_ia_randomness(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def sac_ia_samples(self) -> int:
        ...
    @sac_ia_samples.setter
    def sac_ia_samples(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    @property
    def sac_ia_source_keypoints(self) -> int:
        ...
    @sac_ia_source_keypoints.setter
    def sac_ia_source_keypoints(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
class RegistrationResult:
    """
    T_target_source, quality and per-stage times [ms].
    """
    @property
    def coarse_ms(self) -> float:
        ...
    @property
    def converged(self) -> bool:
        ...
    @property
    def features_ms(self) -> float:
        ...
    @property
    def fine_ms(self) -> float:
        ...
    @property
    def fitness(self) -> float:
        ...
    @property
    def inlier_rmse(self) -> float:
        ...
    @property
    def iterations(self) -> int:
        ...
    @property
    def preprocess_ms(self) -> float:
        ...
    @property
    def source_keypoints(self) -> int:
        ...
    @property
    def source_points(self) -> int:
        ...
    @property
    def target_keypoints(self) -> int:
        ...
    @property
    def target_points(self) -> int:
        ...
    @property
    def total_ms(self) -> float:
        ...
    @property
    def transform(self) -> typing.Annotated[numpy.typing.NDArray[numpy.float64], "[4, 4]"]:
        """
        4x4 T_target_source (target_from_source): maps source points into the target frame.
        """
def adapt_to_rig(options: TrackerOptions) -> TrackerOptions:
    """
    The options the tracker runs with: counts in frames turned to frame_rate_hz against reference_rate_hz, pixel windows to the rig's fx against reference_focal_px.
    """
def associate_points_to_lines(keypoints: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 2]"], segments: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 4]"], width: typing.SupportsInt | typing.SupportsIndex, height: typing.SupportsInt | typing.SupportsIndex, options: AssociationOptions = ..., valid_cells: collections.abc.Sequence[bool] = []) -> list[list[int]]:
    """
    For every segment, the indices of its associated keypoints.
    """
def detect_lsd_segments(image: numpy.ndarray) -> typing.Annotated[numpy.typing.NDArray[numpy.float32], "[m, 4]"]:
    """
    LSD's raw segments (x1, y1, x2, y2) of an 8-bit gray image, with LSD's default settings (features/lsd.h): before preprocessing, at the image's resolution.
    """
def estimate_noise_sigma(image: numpy.ndarray) -> float:
    """
    Standard deviation of white noise in a uint8 gray image [gray levels] (Immerkaer 1996: the 3 x 3 mask [1 -2 1]^T [1 -2 1], the L1 norm of its response over the inner pixels).
    """
def extract_lines(image: numpy.ndarray, options: LineExtractorOptions = ...) -> tuple[typing.Annotated[numpy.typing.NDArray[numpy.float32], "[m, 4]"], numpy.ndarray, int]:
    """
    Segments + preprocessing + LBD with the tracker's line options (detector, detection scale, cap): (segments float32 (N, 4) as u0 v0 u1 v1, LBD uint8 (N, 32), number of raw segments).
    """
def extract_orb(image: numpy.ndarray, options: OrbOptions = ...) -> tuple[typing.Annotated[numpy.typing.NDArray[numpy.float32], "[m, 2]"], typing.Annotated[numpy.typing.NDArray[numpy.float32], "[m, 1]"], numpy.ndarray]:
    """
    ORB keypoints of a uint8 image: (uv float32 N x 2, score float32 N, descriptors uint8 N x 32).
    """
def grid_limit(uv: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 2]"], score: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 1]"], width: typing.SupportsInt | typing.SupportsIndex, height: typing.SupportsInt | typing.SupportsIndex, options: GridLimitOptions = ...) -> list[int]:
    """
    Indices (ascending) of the keypoints kept: the best max_per_cell by score in every cell.
    """
def guided_match(predicted: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 2]"], query: numpy.ndarray, keypoints: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 2]"], train: numpy.ndarray, options: GuidedMatchOptions = ...) -> typing.Annotated[numpy.typing.NDArray[numpy.int32], "[m, 1]"]:
    """
    For each predicted position (M x 2) with descriptor, the index of the best keypoint within the radius, or -1.
    """
def local_maxima(heat: typing.Annotated[numpy.typing.NDArray[numpy.float32], "[m, n]", "flags.c_contiguous"], threshold: typing.SupportsFloat | typing.SupportsIndex, radius_px: typing.SupportsInt | typing.SupportsIndex, border_px: typing.SupportsInt | typing.SupportsIndex) -> typing.Annotated[numpy.typing.NDArray[numpy.int32], "[m, 2]"]:
    """
    Max-filter NMS of a float32 heatmap (H x W): (u, v) int32 of the pixels above the threshold that are the maximum of their (2r+1)^2 window (ties kept), row-major order.
    """
def match_descriptors(query: numpy.ndarray, train: numpy.ndarray, options: MatchOptions = ...) -> typing.Annotated[numpy.typing.NDArray[numpy.int32], "[m, 2]"]:
    """
    Mutual nearest-neighbour + ratio matching; returns (query index, train index) pairs N x 2.
    """
def match_lines_by_points(lines_a: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 4]"], points_a: collections.abc.Sequence[collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex]], lbd_a: numpy.ndarray, lines_b: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 4]"], points_b: collections.abc.Sequence[collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex]], lbd_b: numpy.ndarray, point_matches: typing.Annotated[numpy.typing.ArrayLike, numpy.int32, "[m, 2]"], options: LineMatchOptions = ...) -> typing.Annotated[numpy.typing.NDArray[numpy.int32], "[m, 2]"]:
    ...
def match_scan_to_points(source: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 3]"], target: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 3]"], T_target_source: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[4, 4]"], options: ScanMatchOptions = ..., voxel_m: typing.SupportsFloat | typing.SupportsIndex = 0.5) -> tuple[typing.Annotated[numpy.typing.NDArray[numpy.float64], "[4, 4]"], float, float, typing.Annotated[numpy.typing.NDArray[numpy.float64], "[6, 6]"]]:
    """
    Point-to-plane registration of source (N, 3) onto target (M, 3) from an initial T_target_source; returns (T_target_source, fitness, inlier_rmse_m, information 6x6).
    """
def match_stereo_lines(left: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 4]"], lbd_left: numpy.ndarray, right: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 4]"], lbd_right: numpy.ndarray, options: StereoLineOptions = ...) -> typing.Annotated[numpy.typing.NDArray[numpy.int32], "[m, 2]"]:
    ...
def match_stereo_points(left_image: numpy.ndarray, right_image: numpy.ndarray, left_uv: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 2]"], left_descriptors: numpy.ndarray, right_uv: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 2]"], right_descriptors: numpy.ndarray, rig: StereoRig, options: StereoMatchOptions = ..., denoise_above_noise: typing.SupportsFloat | typing.SupportsIndex = 6.0) -> tuple[typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"], typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 1]"]]:
    """
    The tracker's stereo matching of keypoints on the pair smoothed as the tracker smooths it (noisier than denoise_above_noise; 0: never): descriptors along the row band, then the row search with options.row_search, then subpixel refinement. (u_right, depth) per left keypoint, -1 where unmatched.
    """
def optimize_lidar_pose_graph(T_world_keyframe: collections.abc.Sequence[typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[4, 4]"]], a: collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex], b: collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex], T_a_b: collections.abc.Sequence[typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[4, 4]"]], information: collections.abc.Sequence[typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[6, 6]"]], loop: collections.abc.Sequence[bool], options: LidarPoseGraphOptions = ...) -> list[typing.Annotated[numpy.typing.NDArray[numpy.float64], "[4, 4]"]]:
    """
    Optimise keyframe poses (list of 4x4) under relative-pose edges a -> b (T_a_b, 6x6 information on translation then rotation, loop flag for the Cauchy loss); the first keyframe is held. Returns the poses.
    """
def predict_with_robust_pose(points_prev: typing.Annotated[numpy.typing.ArrayLike, numpy.float64, "[m, 3]"], observed: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 2]"], camera: PinholeCamera, threshold_px: typing.SupportsFloat | typing.SupportsIndex = 2.0) -> tuple[bool, typing.Annotated[numpy.typing.NDArray[numpy.float32], "[m, 2]"], typing.Annotated[numpy.typing.NDArray[numpy.float64], "[4, 4]"], list[bool]]:
    """
    RANSAC PnP pose from 3-D points (previous camera frame) and their current pixels; returns (ok, predicted uv N x 2, T_cur_prev 4 x 4, inlier flags).
    """
def preprocess_lines(segments: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 4]"], width: typing.SupportsInt | typing.SupportsIndex, height: typing.SupportsInt | typing.SupportsIndex, options: LinePreprocessOptions = ...) -> typing.Annotated[numpy.typing.NDArray[numpy.float32], "[m, 4]"]:
    ...
def read_gray_image(path: str) -> numpy.ndarray:
    """
    Read an image file as a uint8 gray array; ValueError names the file.
    """
def read_map_file_header(path: str) -> dict:
    """
    Header of a map file (.slmap) as a dict: format_version, slslam_version, descriptor_type ('binary', 'float' or None), descriptor_cols, vocabulary, line_descriptor ('opencv_lbd' or 'lbd'; format 1 files: 'opencv_lbd'), camera {fx, fy, cx, cy, width, height} [px], baseline_m, next_ids {keyframe, point, line}, and per map {keyframes, culled_keyframes, points, lines}. Checks magic, version, size and checksum (the whole file is read) but builds no map; a foreign, damaged or newer file raises ValueError naming it.
    """
def read_point_cloud(path: str) -> typing.Annotated[numpy.typing.NDArray[numpy.float32], "[m, n]"]:
    """
    Read a KITTI .bin, PCD or PLY point cloud (by extension) as float32 (N, 4): x, y, z [m], intensity (0 when the file has none). Raises ValueError naming the file.
    """
def register_clouds(source: numpy.ndarray, target: numpy.ndarray, options: RegistrationOptions = ..., method: RegistrationMethod = RegistrationMethod.RegistrationMethod.FPFH_SAC_IA_ICP) -> RegistrationResult:
    """
    Register source onto target (float32 (N, 3|4) arrays [m]). Returns a RegistrationResult whose transform (4x4) is T_target_source: it maps source points into the target frame.
    """
def relief_normals(points: numpy.ndarray, normals: numpy.ndarray, height_m: typing.SupportsFloat | typing.SupportsIndex, wavelength_m: typing.SupportsFloat | typing.SupportsIndex, footprint_m: typing.Any = None, octaves: typing.SupportsInt | typing.SupportsIndex = 3) -> numpy.typing.NDArray[numpy.float32]:
    """
    Unit normals (float32 (N, 3)) of world points (float32 (N, 3) [m]) on surfaces with unit normals once a relief h = height_m * fBm(p / wavelength_m, octaves) is added along them; footprint_m (float32 (N,), [m]) fades octaves below a few pixel footprints.
    """
def sample_dense_map(map: typing.Annotated[numpy.typing.NDArray[numpy.float32], "[m, n]", "flags.c_contiguous"], map_height: typing.SupportsInt | typing.SupportsIndex, map_width: typing.SupportsInt | typing.SupportsIndex, uv: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 2]"], input_height: typing.SupportsInt | typing.SupportsIndex, input_width: typing.SupportsInt | typing.SupportsIndex, cubic: bool) -> typing.Annotated[numpy.typing.NDArray[numpy.float32], "[m, n]"]:
    """
    Samples of a C x (Hc Wc) float32 map at input pixels uv (N x 2), as grid_sample (align_corners=False, zero padding), bilinear or bicubic: N x C.
    """
def shade_image(points: numpy.ndarray, normals: numpy.ndarray, material: numpy.ndarray, height: typing.SupportsInt | typing.SupportsIndex, width: typing.SupportsInt | typing.SupportsIndex, camera: ShadingCamera, headlamp: HeadLamp, roof_lamp_positions: numpy.ndarray, roof_lamp_power: typing.SupportsFloat | typing.SupportsIndex, light_level: typing.SupportsFloat | typing.SupportsIndex, ambient: typing.SupportsFloat | typing.SupportsIndex, sensor: SensorModel, frame_index: typing.SupportsInt | typing.SupportsIndex) -> numpy.typing.NDArray[numpy.uint8]:
    """
    Shade one image from per-pixel hits (row-major, N = height * width): points and normals float32 (N, 3) or (H, W, 3) in world [m], material uint8 ids (255 = no hit). Returns a uint8 (height, width) image; deterministic for a given sensor.seed and frame_index.
    """
def smooth_if_noisy(image: numpy.ndarray, above_noise: typing.SupportsFloat | typing.SupportsIndex) -> numpy.ndarray:
    """
    The uint8 image smoothed by a Gaussian of sigma = noise / 7 px when its estimated noise (Immerkaer) exceeds above_noise (> 0): a new array; otherwise the image itself.
    """
def solid_texture(points: numpy.ndarray, material: numpy.ndarray, normals: typing.Any = None) -> numpy.typing.NDArray[numpy.float32]:
    """
    Albedo in [0, 1] (float32, N) of world points (float32 (N, 3) [m]) with uint8 material ids; bolt plates are drawn only when normals are given.
    """
def suppress_non_maxima(uv: typing.Annotated[numpy.typing.ArrayLike, numpy.int32, "[m, 2]"], score: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 1]"], width: typing.SupportsInt | typing.SupportsIndex, height: typing.SupportsInt | typing.SupportsIndex, radius_px: typing.SupportsInt | typing.SupportsIndex) -> list[int]:
    """
    Greedy NMS of integer (u, v) candidates (N x 2 int32): kept indices, strongest first.
    """
def triangulate_stereo_lines(left: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 4]"], right: typing.Annotated[numpy.typing.ArrayLike, numpy.float32, "[m, 4]"], camera: PinholeCamera, baseline_m: typing.SupportsFloat | typing.SupportsIndex) -> tuple[typing.Annotated[numpy.typing.NDArray[numpy.float64], "[m, 6]"], list[bool]]:
    """
    3-D endpoints (N, 6: start xyz, end xyz in the left camera [m]) and success flags.
    """
def write_image(path: str, image: numpy.ndarray) -> None:
    """
    Write a uint8 gray image (format from the extension).
    """
__git_commit__: str
__version__: str = '0.1.0'
