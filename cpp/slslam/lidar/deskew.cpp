#include "slslam/lidar/deskew.h"

#include <algorithm>
#include <cmath>

#include "slslam/core/check.h"
#include "slslam/geometry/rotation.h"

namespace slslam::lidar {

Rigid3d SweepMotion::At(double t) const {
  if (time_s.empty()) return Rigid3d();
  if (t <= time_s.front()) return start_from_t.front();
  if (t >= time_s.back()) return start_from_t.back();
  const size_t j = std::upper_bound(time_s.begin(), time_s.end(), t) - time_s.begin();
  const size_t i = j - 1;
  const double a = (t - time_s[i]) / (time_s[j] - time_s[i]);
  const Eigen::Quaterniond qi(start_from_t[i].rotation), qj(start_from_t[j].rotation);
  return Rigid3d(qi.slerp(a, qj).toRotationMatrix(),
                 (1.0 - a) * start_from_t[i].translation + a * start_from_t[j].translation);
}

SweepMotion SweepMotion::ConstantVelocity(const Rigid3d& start_from_end, double period_s,
                                          int samples) {
  SLSLAM_CHECK(period_s > 0 && samples >= 2,
               "constant-velocity sweep needs period > 0 s and >= 2 "
               "samples");
  SweepMotion motion;
  const Eigen::Vector3d w = LogSO3(Eigen::Quaterniond(start_from_end.rotation));
  for (int k = 0; k < samples; ++k) {
    const double a = static_cast<double>(k) / (samples - 1);
    // (a straight line at constant speed)
    motion.time_s.push_back(a * period_s);
    motion.start_from_t.emplace_back(ExpSO3(a * w), a * start_from_end.translation);
  }
  return motion;
}

std::vector<Eigen::Vector3d> DeskewPoints(const std::vector<Eigen::Vector3d>& points,
                                          const std::vector<double>& time_s,
                                          const SweepMotion& motion) {
  SLSLAM_CHECK(points.size() == time_s.size(), "deskew: ", points.size(), " points but ",
               time_s.size(), " point times");
  SLSLAM_CHECK(motion.time_s.size() == motion.start_from_t.size(), "deskew: motion has ",
               motion.time_s.size(), " times but ", motion.start_from_t.size(), " poses");
  for (size_t k = 1; k < motion.time_s.size(); ++k) {
    SLSLAM_CHECK(motion.time_s[k] > motion.time_s[k - 1], "deskew: motion times must increase");
  }
  std::vector<Eigen::Vector3d> out(points.size());
  // Points of a spinning sensor come in runs of equal or close times: reuse the last pose.
  double last_t = std::nan("");
  Rigid3d start_from_t;
  for (size_t i = 0; i < points.size(); ++i) {
    SLSLAM_CHECK(std::isfinite(time_s[i]), "deskew: point ", i, " has a non-finite time");
    if (time_s[i] != last_t) {
      start_from_t = motion.At(time_s[i]);
      last_t = time_s[i];
    }
    out[i] = start_from_t * points[i];
  }
  return out;
}

}  // namespace slslam::lidar
