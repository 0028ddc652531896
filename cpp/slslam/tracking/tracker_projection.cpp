// Tracker: frames tracked on projected keypoints (TrackerOptions::projected_max_frames). The local
// map's points are projected with the predicted pose and aligned to their patches in the left
// image, as semi-direct odometry tracks between keyframes; the front end's detector runs only on
// the frames the tracker hands back (keyframes, weak tracking, every projected_max_frames + 1-th).
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "slslam/tracking/tracker.h"
#include "slslam/tracking/tracker_internal.h"

namespace slslam {

namespace tracker_detail {

double SearchPatch(const cv::Mat& image, const cv::Mat& patch, double scale, int radius_px,
                   double* u, double* v) {
  // Every other patch pixel (the coarse step only has to land within AlignPatch's reach): a
  // (2 * (w / 2) + 1)^2 grid of samples 2 * scale image pixels apart, zero-mean NCC.
  const int w = patch.rows / 2, half = w / 2;
  if (half < 1 || radius_px < 0) return -1.0;
  const int side = 2 * half + 1, n = side * side;
  std::vector<float> t(n), values(n);
  double t_mean = 0.0;
  for (int r = 0, k = 0; r < side; ++r) {
    const float* row = patch.ptr<float>(w + 2 * (r - half));
    for (int c = 0; c < side; ++c, ++k) {
      t[k] = row[w + 2 * (c - half)];
      t_mean += t[k];
    }
  }
  t_mean /= n;
  double t_ss = 0.0;
  for (float& x : t) {
    x = static_cast<float>(x - t_mean);
    t_ss += static_cast<double>(x) * x;
  }
  if (t_ss <= 1e-6) return -1.0;
  const double reach = 2.0 * half * scale + 1.0;
  double best = -1.0, best_u = *u, best_v = *v;
  // Offsets 2 px apart (AlignPatch converges from within a pixel or two of the alignment).
  for (int dy = -radius_px; dy <= radius_px; dy += 2) {
    for (int dx = -radius_px; dx <= radius_px; dx += 2) {
      const double x = *u + dx, y = *v + dy;
      if (x - reach < 0.0 || y - reach < 0.0 || x + reach > image.cols - 1.0 ||
          y + reach > image.rows - 1.0) {
        continue;
      }
      const double mean = SampleGrid(image, x, y, half, 2.0 * scale, values.data()) / n;
      double i_ss = 0.0, i_t = 0.0;
      for (int k = 0; k < n; ++k) {
        const double i = values[k] - mean;
        i_ss += i * i;
        i_t += i * t[k];
      }
      const double ncc = i_t / std::sqrt(std::max(1e-12, i_ss * t_ss));
      if (ncc > best) {
        best = ncc;
        best_u = x;
        best_v = y;
      }
    }
  }
  *u = best_u;
  *v = best_v;
  return best;
}

}  // namespace tracker_detail

bool Tracker::CanProject(const StereoFrame& frame) const {
  // (the frame after a keyframe is detected: its inliers are the keyframe rule's reference, see
  // AcceptTracking; on projected keypoints, one per cell, they understated it)
  return options_.projected_max_frames > 0 && atlas_.size() > 0 && mode_ == Mode::kTracking &&
         have_pose_ && projected_run_ < options_.projected_max_frames &&
         last_point_inliers_ >= options_.projection_min_inliers &&
         frame.index - last_keyframe_frame_ > 1;
}

std::shared_ptr<const StereoFrame> Tracker::WithProjectedKeypoints(
    std::shared_ptr<const StereoFrame> frame, const LocalMapSnapshot& local,
    const Rigid3d& pred_cam_from_world) const {
  auto out = std::make_shared<StereoFrame>(*frame);
  out->keypoints_pending = false;
  out->keypoints = Keypoints{};
  out->u_right.clear();
  out->depth.clear();
  const cv::Mat* image = current_left_;
  const int n_local = static_cast<int>(local.point_ids.size());
  if (image == nullptr || image->empty() || options_.track_refine_window_px <= 0 || n_local == 0) {
    return out;
  }
  // Candidates: points with a patch, in front, at a scale the patch can be aligned at.
  struct Candidate {
    int row;
    double scale, depth;
  };
  std::vector<Candidate> candidates;
  for (int r = 0; r < n_local; ++r) {
    if (local.point_patches[r].empty()) continue;
    const double depth = (pred_cam_from_world * local.point_w[r]).z();
    if (depth <= 0.05) continue;
    const double scale = local.point_patch_depth_m[r] / depth;
    if (scale < 0.5 || scale > 2.0) continue;
    candidates.push_back({r, scale, depth});
  }
  // The prediction's error is mostly a rotation, a shift common to the image: found on up to 40
  // points spread over the candidates (a coarse search, then the alignment), as their median.
  constexpr int kShiftPoints = 40;
  constexpr double kMinNcc = 0.8;
  std::vector<double> shift_u, shift_v;
  const size_t stride = std::max<size_t>(1, candidates.size() / kShiftPoints);
  for (size_t i = 0; i < candidates.size(); i += stride) {
    const Candidate& c = candidates[i];
    const double u0 = local.point_uv(c.row, 0), v0 = local.point_uv(c.row, 1);
    double u = u0, v = v0;
    const cv::Mat& patch = local.point_patches[c.row];
    if (tracker_detail::SearchPatch(*image, patch, c.scale, options_.projection_search_px, &u, &v) <
        0.7) {
      continue;
    }
    if (!tracker_detail::AlignPatch(*image, patch, c.scale, kMinNcc, &u, &v)) continue;
    shift_u.push_back(u - u0);
    shift_v.push_back(v - v0);
  }
  double du = 0.0, dv = 0.0;
  if (shift_u.size() >= 5) {
    const auto median = [](std::vector<double>* x) {
      std::nth_element(x->begin(), x->begin() + x->size() / 2, x->end());
      return (*x)[x->size() / 2];
    };
    du = median(&shift_u);
    dv = median(&shift_v);
  }
  // The candidates aligned from their predicted positions moved by the shift, one point per
  // projection_cell_px square cell (the first of at most two tries in map order that aligns:
  // older points first): points spread over the image, at a fraction of the cost of all.
  const int kCellPx = options_.projection_cell_px;
  const int cells_x = image->cols / kCellPx + 1, cells_y = image->rows / kCellPx + 1;
  std::vector<char> taken(static_cast<size_t>(cells_x) * cells_y, 0);
  const float max_sq = options_.track_refine_max_px * options_.track_refine_max_px;
  std::vector<int> rows;
  std::vector<Eigen::Vector2f> uv;
  std::vector<double> depths;
  for (const Candidate& c : candidates) {
    const double u0 = local.point_uv(c.row, 0) + du, v0 = local.point_uv(c.row, 1) + dv;
    const int cx = static_cast<int>(u0) / kCellPx, cy = static_cast<int>(v0) / kCellPx;
    if (u0 < 0.0 || v0 < 0.0 || cx >= cells_x || cy >= cells_y) continue;
    char& cell = taken[static_cast<size_t>(cy) * cells_x + cx];
    if (cell >= 2) continue;  // aligned one, or tried two
    ++cell;
    double u = u0, v = v0;
    if (!tracker_detail::AlignPatch(*image, local.point_patches[c.row], c.scale, kMinNcc, &u, &v)) {
      continue;
    }
    if ((u - u0) * (u - u0) + (v - v0) * (v - v0) > max_sq) continue;
    cell = 2;
    rows.push_back(c.row);
    uv.emplace_back(static_cast<float>(u), static_cast<float>(v));
    depths.push_back(c.depth);
  }
  const int n = static_cast<int>(rows.size());
  Keypoints& kp = out->keypoints;
  kp.uv.resize(n, 2);
  kp.score = Eigen::VectorXf::Ones(n);
  kp.octave = Eigen::VectorXi::Zero(n);
  kp.descriptors = cv::Mat(n, local.point_descriptors.cols, local.point_descriptors.type());
  out->u_right.assign(n, -1.0);
  out->depth.assign(n, -1.0);
  // Stereo: the column the predicted depth gives, refined as a descriptor match is (only where
  // the refinement's window fits; elsewhere the keypoint stays monocular).
  const cv::Mat* right = current_right_;
  const bool stereo = right != nullptr && !right->empty() && options_.stereo.subpixel_window > 0;
  const PinholeCamera& cam = options_.rig.camera;
  for (int i = 0; i < n; ++i) {
    kp.uv.row(i) = uv[i].transpose();
    local.point_descriptors.row(rows[i]).copyTo(kp.descriptors.row(i));
    if (!stereo) continue;
    const double u_r = uv[i].x() - cam.fx * options_.rig.baseline_m / depths[i];
    if (!SubpixelWindowFits(
            *image, *right, options_.stereo, static_cast<int>(std::lround(uv[i].x())),
            static_cast<int>(std::lround(uv[i].y())), static_cast<int>(std::lround(u_r)))) {
      continue;
    }
    out->u_right[i] = u_r;
    out->depth[i] = depths[i];
  }
  if (stereo && n > 0) {
    RefineStereoSubpixel(*image, *right, options_.rig, options_.stereo, out.get());
  }
  return out;
}

}  // namespace slslam
