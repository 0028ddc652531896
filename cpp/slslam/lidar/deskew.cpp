#include "slslam/lidar/deskew.h"

#include <algorithm>
#include <cmath>

#include "slslam/core/check.h"
#include "slslam/geometry/rotation.h"

namespace slslam::lidar {

Eigen::Isometry3d SweepMotion::At(double t) const {
  if (time_s.empty()) return Eigen::Isometry3d::Identity();
  if (t <= time_s.front()) return T_start_t.front();
  if (t >= time_s.back()) return T_start_t.back();
  const size_t j = std::upper_bound(time_s.begin(), time_s.end(), t) - time_s.begin();
  const size_t i = j - 1;
  const double a = (t - time_s[i]) / (time_s[j] - time_s[i]);
  const Eigen::Quaterniond qi(T_start_t[i].linear()), qj(T_start_t[j].linear());
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = qi.slerp(a, qj).toRotationMatrix();
  T.translation() = (1.0 - a) * T_start_t[i].translation() + a * T_start_t[j].translation();
  return T;
}

SweepMotion SweepMotion::ConstantVelocity(const Eigen::Isometry3d& T_start_end, double period_s,
                                          int samples) {
  SLSLAM_CHECK(period_s > 0 && samples >= 2,
               "constant-velocity sweep needs period > 0 s and >= 2 "
               "samples");
  SweepMotion motion;
  const Eigen::Vector3d w = LogSO3(Eigen::Quaterniond(T_start_end.linear()));
  for (int k = 0; k < samples; ++k) {
    const double a = static_cast<double>(k) / (samples - 1);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = ExpSO3(a * w);
    T.translation() = a * T_start_end.translation();  // straight line at constant speed
    motion.time_s.push_back(a * period_s);
    motion.T_start_t.push_back(T);
  }
  return motion;
}

std::vector<Eigen::Vector3d> DeskewPoints(const std::vector<Eigen::Vector3d>& points,
                                          const std::vector<double>& time_s,
                                          const SweepMotion& motion) {
  SLSLAM_CHECK(points.size() == time_s.size(), "deskew: ", points.size(), " points but ",
               time_s.size(), " point times");
  SLSLAM_CHECK(motion.time_s.size() == motion.T_start_t.size(), "deskew: motion has ",
               motion.time_s.size(), " times but ", motion.T_start_t.size(), " poses");
  for (size_t k = 1; k < motion.time_s.size(); ++k) {
    SLSLAM_CHECK(motion.time_s[k] > motion.time_s[k - 1], "deskew: motion times must increase");
  }
  std::vector<Eigen::Vector3d> out(points.size());
  // Points of a spinning sensor come in runs of equal or close times: reuse the last pose.
  double last_t = std::nan("");
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (size_t i = 0; i < points.size(); ++i) {
    SLSLAM_CHECK(std::isfinite(time_s[i]), "deskew: point ", i, " has a non-finite time");
    if (time_s[i] != last_t) {
      T = motion.At(time_s[i]);
      last_t = time_s[i];
    }
    out[i] = T * points[i];
  }
  return out;
}

}  // namespace slslam::lidar
