#include "slslam/mapping/triangulation.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include <Eigen/SVD>

#include "slslam/core/check.h"
#include "slslam/features/descriptor_matcher.h"
#include "slslam/features/image_patch.h"

namespace slslam {

namespace triangulation_detail {

EpipolarCandidates::EpipolarCandidates(
    const Eigen::Matrix<float, Eigen::Dynamic, 2, Eigen::RowMajor>& uv,
    const std::vector<int>& ids) {
  // (a keypoint at a non-finite position is never a candidate: no line passes near it)
  ids_.reserve(ids.size());
  for (int id : ids) {
    if (std::isfinite(uv(id, 0)) && std::isfinite(uv(id, 1))) ids_.push_back(id);
  }
  u_.resize(ids_.size());
  v_.resize(ids_.size());
  distance_.resize(ids_.size());
  for (size_t k = 0; k < ids_.size(); ++k) {
    u_[k] = uv(ids_[k], 0);
    v_[k] = uv(ids_[k], 1);
  }
}

void EpipolarCandidates::Collect(const Eigen::Vector3d& unit_line, double band_px,
                                 std::vector<int>* out) {
  out->clear();
  const double nx = unit_line.x(), ny = unit_line.y(), c = unit_line.z();
  const size_t n = ids_.size();
  const double* u = u_.data();
  const double* v = v_.data();
  double* distance = distance_.data();
  // Two passes: the distances in a loop without branches (the compiler vectorises it), then the
  // few within the band.
  for (size_t k = 0; k < n; ++k) distance[k] = std::abs(nx * u[k] + ny * v[k] + c);
  for (size_t k = 0; k < n; ++k) {
    if (distance[k] <= band_px) out->push_back(ids_[k]);
  }
}

}  // namespace triangulation_detail

namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return S;
}

// Fundamental matrix mapping pixels of view 1 to epipolar lines of view 2 (same intrinsics).
Eigen::Matrix3d Fundamental21(const PinholeCamera& camera, const Rigid3d& cam1_from_world,
                              const Rigid3d& cam2_from_world) {
  // cam2_from_cam1 (as RelativePose in optimization/pose_graph.h).
  const Eigen::Matrix3d R21 = cam2_from_world.rotation * cam1_from_world.rotation.transpose();
  const Eigen::Vector3d t21 = cam2_from_world.translation - R21 * cam1_from_world.translation;
  Eigen::Matrix3d K;
  K << camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0;
  const Eigen::Matrix3d K_inv = K.inverse();
  return K_inv.transpose() * Skew(t21) * R21 * K_inv;
}

struct View {
  const KeyFrame* keyframe;
  const StereoFrame* frame;
  Rigid3d cam_from_world;
  Eigen::Vector3d center;  ///< in the world [m]
};

View MakeView(const KeyFrame& kf) { return {&kf, kf.frame.get(), kf.cam_from_world, kf.Center()}; }

// Index pairs (i in view 1, j in view 2) of free keypoints matched along the epipolar lines.
std::vector<std::pair<int, int>> MatchAlongEpipolarLines(const View& a, const View& b,
                                                         const PinholeCamera& camera,
                                                         const TriangulationOptions& options) {
  const Keypoints& ka = a.frame->keypoints;
  const Keypoints& kb = b.frame->keypoints;
  std::vector<int> free_b;
  for (int j = 0; j < kb.size(); ++j) {
    if (b.keyframe->point_ids[j] < 0) free_b.push_back(j);
  }
  if (free_b.empty()) return {};
  const bool binary = ka.descriptors.type() == CV_8U;
  const float max_distance = binary ? options.max_distance_binary : options.max_distance_float;
  const Eigen::Matrix3d F = Fundamental21(camera, a.cam_from_world, b.cam_from_world);
  // The band narrows the candidates; the exact test below decides, over the candidates in
  // ascending order as the exhaustive scan did, so the matches are the same. The half pixel
  // beyond the bound covers rounding between the two tests.
  triangulation_detail::EpipolarCandidates band(kb.uv, free_b);
  std::vector<int> candidates;
  OneToOne one_to_one(kb.size());
  std::vector<int> match(ka.size(), -1);
  for (int i = 0; i < ka.size(); ++i) {
    if (a.keyframe->point_ids[i] >= 0) continue;
    const Eigen::Vector3d line = F * Eigen::Vector3d(ka.uv(i, 0), ka.uv(i, 1), 1.0);
    const double norm = std::hypot(line.x(), line.y());
    if (norm < 1e-12) continue;
    band.Collect(line / norm, options.epipolar_px + 0.5, &candidates);
    BestTwo best;
    for (int j : candidates) {
      const double distance =
          std::abs(line.x() * kb.uv(j, 0) + line.y() * kb.uv(j, 1) + line.z()) / norm;
      if (distance > options.epipolar_px) continue;
      best.Add(DescriptorDistance(ka.descriptors, i, kb.descriptors, j), j);
    }
    if (best.index < 0 || best.best > max_distance || best.best > options.ratio * best.second) {
      continue;
    }
    one_to_one.Offer(i, best.index, best.best, &match);
  }
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i < ka.size(); ++i) {
    if (match[i] >= 0) pairs.emplace_back(i, match[i]);
  }
  return pairs;
}

// Index pairs (a, b) of free segments that are each other's best LBD match, with a ratio test.
std::vector<std::pair<int, int>> MatchFreeSegments(const View& a, const View& b,
                                                   const TriangulationOptions& options) {
  const StereoFrame& fa = *a.frame;
  const StereoFrame& fb = *b.frame;
  std::vector<int> free_a, free_b;
  for (int i = 0; i < fa.NumLines(); ++i) {
    if (a.keyframe->line_ids[i] < 0) free_a.push_back(i);
  }
  for (int j = 0; j < fb.NumLines(); ++j) {
    if (b.keyframe->line_ids[j] < 0) free_b.push_back(j);
  }
  if (free_a.empty() || free_b.empty()) return {};
  const int na = static_cast<int>(free_a.size());
  const int nb = static_cast<int>(free_b.size());
  std::vector<float> distance(static_cast<size_t>(na) * nb);
  for (int x = 0; x < na; ++x) {
    for (int y = 0; y < nb; ++y) {
      distance[static_cast<size_t>(x) * nb + y] =
          DescriptorDistance(fa.line_descriptors, free_a[x], fb.line_descriptors, free_b[y]);
    }
  }
  std::vector<int> best_of_b(nb, -1);
  for (int y = 0; y < nb; ++y) {
    float best = std::numeric_limits<float>::max();
    for (int x = 0; x < na; ++x) {
      if (distance[static_cast<size_t>(x) * nb + y] < best) {
        best = distance[static_cast<size_t>(x) * nb + y];
        best_of_b[y] = x;
      }
    }
  }
  std::vector<std::pair<int, int>> pairs;
  for (int x = 0; x < na; ++x) {
    BestTwo best;
    for (int y = 0; y < nb; ++y) best.Add(distance[static_cast<size_t>(x) * nb + y], y);
    if (best.index < 0 || best.best > options.line_max_lbd ||
        best.best > options.line_ratio * best.second) {
      continue;
    }
    if (best_of_b[best.index] != x) continue;
    pairs.emplace_back(free_a[x], free_b[best.index]);
  }
  return pairs;
}

int TriangulatePoints(Map* map, const View& a, const View& b, const StereoRig& rig,
                      const TriangulationOptions& options) SLSLAM_REQUIRES(map->mutex()) {
  const PinholeCamera& camera = rig.camera;
  const double max_depth = options.max_depth_baselines * rig.baseline_m;
  const double cos_max = std::cos(options.min_parallax_deg * kDegToRad);
  const double bound = options.chi2 * options.sigma_px * options.sigma_px;
  int made = 0;
  for (const auto& [i, j] : MatchAlongEpipolarLines(a, b, camera, options)) {
    const Eigen::Vector2d uv_a = a.frame->keypoints.uv.row(i).cast<double>().transpose();
    const Eigen::Vector2d uv_b = b.frame->keypoints.uv.row(j).cast<double>().transpose();
    Eigen::Vector3d p;
    if (!TriangulatePoint(a.cam_from_world, camera.Unproject(uv_a), b.cam_from_world,
                          camera.Unproject(uv_b), &p)) {
      continue;
    }
    const Eigen::Vector3d ray_a = p - a.center;
    const Eigen::Vector3d ray_b = p - b.center;
    if (ray_a.dot(ray_b) / (ray_a.norm() * ray_b.norm()) > cos_max) continue;
    const double za = (a.cam_from_world.rotation * p + a.cam_from_world.translation).z();
    const double zb = (b.cam_from_world.rotation * p + b.cam_from_world.translation).z();
    if (!(za > 0.0 && zb > 0.0 && za < max_depth && zb < max_depth)) continue;
    Eigen::Vector2d ea, eb;
    if (!PointResidual(camera, a.cam_from_world, p, uv_a, &ea) ||
        !PointResidual(camera, b.cam_from_world, p, uv_b, &eb)) {
      continue;
    }
    if (ea.squaredNorm() > bound || eb.squaredNorm() > bound) continue;
    auto point = map->AddPoint(p, a.frame->keypoints.descriptors.row(i), a.keyframe->id);
    map->AddPointObservation(point->id, a.keyframe->id, i);
    map->AddPointObservation(point->id, b.keyframe->id, j);
    if (options.patch_window_px > 0 && !a.keyframe->left_image.empty()) {
      // (the new keyframe's image around its keypoint: matches in later frames are aligned to
      // it, Tracker::RefineTracks; empty where the patch leaves the image)
      point->patch =
          SamplePatch(a.keyframe->left_image, uv_a.x(), uv_a.y(), options.patch_window_px);
      if (!point->patch.empty()) point->patch_depth_m = za;
    }
    ++made;
  }
  return made;
}

int TriangulateLines(Map* map, const View& a, const View& b, const StereoRig& rig,
                     const TriangulationOptions& options) SLSLAM_REQUIRES(map->mutex()) {
  const PinholeCamera& camera = rig.camera;
  const double max_depth = options.max_depth_baselines * rig.baseline_m;
  const double cos_max = std::cos(options.min_plane_angle_deg * kDegToRad);
  const double line_bound = options.chi2 * options.line_sigma_px * options.line_sigma_px;
  int made = 0;
  for (const auto& [ia, ib] : MatchFreeSegments(a, b, options)) {
    const LineSegment& sa = a.frame->lines[ia];
    const LineSegment& sb = b.frame->lines[ib];
    const Eigen::Vector2d a0 = sa.start.cast<double>(), a1 = sa.end.cast<double>();
    const Eigen::Vector2d b0 = sb.start.cast<double>(), b1 = sb.end.cast<double>();
    PluckerLine line;
    try {
      const Eigen::Vector4d plane_a = BackProjectedPlane(camera, a.cam_from_world, a0, a1);
      const Eigen::Vector4d plane_b = BackProjectedPlane(camera, b.cam_from_world, b0, b1);
      const double cos_planes =
          std::abs(plane_a.head<3>().normalized().dot(plane_b.head<3>().normalized()));
      if (!(cos_planes < cos_max)) continue;
      line = PluckerLine::FromPlanes(plane_a, plane_b).Normalized();
    } catch (const std::invalid_argument&) {  // degenerate segment or parallel planes
      continue;
    }
    // Endpoints: where the rays of view a's segment endpoints pass the line, in both cameras.
    const PluckerLine in_a = line.Transformed(a.cam_from_world);
    const PluckerLine in_b = line.Transformed(b.cam_from_world);
    const Eigen::Vector3d s_a = in_a.ClosestPointToRay(camera.Unproject(a0));
    const Eigen::Vector3d e_a = in_a.ClosestPointToRay(camera.Unproject(a1));
    const Eigen::Vector3d s_b = in_b.ClosestPointToRay(camera.Unproject(b0));
    const Eigen::Vector3d e_b = in_b.ClosestPointToRay(camera.Unproject(b1));
    bool in_front = true;
    for (const Eigen::Vector3d& q : {s_a, e_a, s_b, e_b}) {
      in_front = in_front && q.z() > 0.0 && q.z() < max_depth;
    }
    if (!in_front) continue;
    Eigen::Vector3d ea, eb;
    if (!LineResidual(camera, a.cam_from_world, line, a0, a1, 0.0, &ea) ||
        !LineResidual(camera, b.cam_from_world, line, b0, b1, 0.0, &eb)) {
      continue;
    }
    if (ea.head<2>().squaredNorm() > line_bound || eb.head<2>().squaredNorm() > line_bound) {
      continue;
    }
    const Eigen::Matrix3d R_wa = a.cam_from_world.rotation.transpose();
    const Eigen::Vector3d start = R_wa * (s_a - a.cam_from_world.translation);
    const Eigen::Vector3d end = R_wa * (e_a - a.cam_from_world.translation);
    if ((end - start).norm() < 1e-3) continue;
    auto map_line =
        map->AddLine(line, start, end, a.frame->line_descriptors.row(ia), a.keyframe->id);
    map->AddLineObservation(map_line->id, a.keyframe->id, ia);
    map->AddLineObservation(map_line->id, b.keyframe->id, ib);
    ++made;
  }
  return made;
}

}  // namespace

bool TriangulatePoint(const Rigid3d& cam1_from_world, const Eigen::Vector3d& x1,
                      const Rigid3d& cam2_from_world, const Eigen::Vector3d& x2,
                      Eigen::Vector3d* p_w) {
  // x ~ P X with P = [R | t]: each view gives two rows of A X = 0.
  Eigen::Matrix4d A;
  Eigen::Matrix<double, 3, 4> P1, P2;
  P1 << cam1_from_world.rotation, cam1_from_world.translation;
  P2 << cam2_from_world.rotation, cam2_from_world.translation;
  A.row(0) = x1.x() * P1.row(2) - P1.row(0);
  A.row(1) = x1.y() * P1.row(2) - P1.row(1);
  A.row(2) = x2.x() * P2.row(2) - P2.row(0);
  A.row(3) = x2.y() * P2.row(2) - P2.row(1);
  const Eigen::JacobiSVD<Eigen::Matrix4d> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d X = svd.matrixV().col(3);
  if (std::abs(X.w()) < 1e-12 || !X.allFinite()) return false;
  *p_w = X.head<3>() / X.w();
  return true;
}

TriangulationStats CreateNewLandmarks(Map* map, int keyframe_id, const StereoRig& rig,
                                      const TriangulationOptions& options) {
  Require(map != nullptr, "triangulation needs a map");
  TriangulationStats stats;
  auto kf = map->keyframe(keyframe_id);
  if (!kf || kf->bad) return stats;
  const View a = MakeView(*kf);
  for (int other : map->BestCovisible(keyframe_id, options.neighbours)) {
    auto kf2 = map->keyframe(other);
    if (!kf2 || kf2->bad) continue;
    const View b = MakeView(*kf2);
    // A baseline shorter than the stereo pair's adds nothing stereo did not (ORB-SLAM3's rule).
    if ((b.center - a.center).norm() < rig.baseline_m) continue;
    if (options.points &&
        b.frame->keypoints.descriptors.type() == a.frame->keypoints.descriptors.type()) {
      stats.points += TriangulatePoints(map, a, b, rig, options);
    }
    if (options.lines && a.frame->NumLines() > 0 && b.frame->NumLines() > 0) {
      stats.lines += TriangulateLines(map, a, b, rig, options);
    }
  }
  return stats;
}

}  // namespace slslam
