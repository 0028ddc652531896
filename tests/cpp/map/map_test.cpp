#include "slslam/map/map.h"

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "slslam/core/time.h"

#include <vector>

namespace slslam {
namespace {

std::shared_ptr<StereoFrame> EmptyFrame() { return std::make_shared<StereoFrame>(); }

Eigen::Matrix3d Yaw(double deg) {
  return Eigen::AngleAxisd(deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

TEST(Map, CulledKeyFrameKeepsItsPoseThroughItsParent) {
  Map map;
  auto a = map.AddKeyFrame(Rigid3d(Yaw(10), Eigen::Vector3d(1, 2, 3)), EmptyFrame());
  auto b = map.AddKeyFrame(Rigid3d(Yaw(20), Eigen::Vector3d(2, 2, 3)), EmptyFrame());
  auto c = map.AddKeyFrame(Rigid3d(Yaw(35), Eigen::Vector3d(4, 1, 3)), EmptyFrame());
  b->parent = a->id;
  c->parent = b->id;
  const Eigen::Matrix3d R_b = b->cam_from_world.rotation;
  const Eigen::Vector3d t_b = b->cam_from_world.translation;
  map.EraseKeyFrame(b->id);
  EXPECT_EQ(c->parent, a->id);  // reparented
  Rigid3d pose;
  ASSERT_TRUE(map.KeyFramePose(b->id, &pose));
  EXPECT_TRUE(pose.rotation.isApprox(R_b, 1e-12));
  EXPECT_TRUE(pose.translation.isApprox(t_b, 1e-12));
  // The parent moves (a loop correction): the culled keyframe moves with it, rigidly.
  const Eigen::Matrix3d dR = Yaw(5);
  a->cam_from_world.rotation = a->cam_from_world.rotation * dR;
  ASSERT_TRUE(map.KeyFramePose(b->id, &pose));
  EXPECT_TRUE(pose.rotation.isApprox(R_b * dR, 1e-12));
  EXPECT_FALSE(map.KeyFramePose(99, &pose));
}

// Culling a keyframe of the IMU chain joins its samples to its successor's, which then starts at
// the culled one's predecessor.
TEST(Map, CulledKeyFrameJoinsTheImuChainAcrossIt) {
  Map map;
  std::vector<std::shared_ptr<KeyFrame>> kfs;
  for (int k = 0; k < 3; ++k) {
    kfs.push_back(map.AddKeyFrame(Rigid3d(), EmptyFrame()));
    KeyFrameInertial imu;
    imu.t_ns = NsFromSeconds(0.5 * k);
    imu.previous = k > 0 ? kfs[k - 1]->id : -1;
    for (int s = 0; k > 0 && s <= 10; ++s) {
      imu.samples_from_previous.Add(NsFromSeconds(0.5 * (k - 1) + 0.05 * s),
                                    Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
    }
    kfs.back()->inertial = imu;
  }
  map.EraseKeyFrame(kfs[1]->id);
  const KeyFrameInertial& last = *kfs[2]->inertial;
  EXPECT_EQ(last.previous, kfs[0]->id);
  EXPECT_EQ(last.samples_from_previous.size(), 21u);  // (the shared sample at 0.5 s once)
  ImuPreintegration pre;
  EXPECT_TRUE(last.samples_from_previous.Preintegrate(0, NsFromSeconds(1.0), 0.06, &pre));
  EXPECT_NEAR(pre.dt_s(), 1.0, 1e-12);
  // The chain's first keyframe culled: its successor starts a chain.
  map.EraseKeyFrame(kfs[0]->id);
  EXPECT_EQ(kfs[2]->inertial->previous, -1);
}

TEST(Map, PointsOfAscendingIdsAreTheLookedUpPoints) {
  // One walk along the ordered points (a few steps, else a search): every id as point(id) gives
  // it, missing and erased ids null, repeats, jumps beyond the walk's steps and ids past the end.
  Map map;
  auto kf = map.AddKeyFrame(Rigid3d(), EmptyFrame());
  const cv::Mat descriptor = cv::Mat::zeros(1, 32, CV_8U);
  std::vector<int> ids;
  for (int i = 0; i < 60; ++i) {
    ids.push_back(map.AddPoint(Eigen::Vector3d(i, 0, 1), descriptor, kf->id)->id);
  }
  for (int i = 0; i < 60; i += 7) map.ErasePoint(ids[i]);
  const std::vector<int> query = {ids[0] - 5, ids[1],  ids[1],  ids[2],      ids[7],       ids[8],
                                  ids[30],    ids[31], ids[59], ids[59] + 1, ids[59] + 100};
  const std::vector<MapPoint*> found = map.PointsOf(query);
  ASSERT_EQ(found.size(), query.size());
  for (size_t i = 0; i < query.size(); ++i) {
    EXPECT_EQ(found[i], map.point(query[i]).get()) << "id " << query[i];
  }
  EXPECT_NE(found[1], nullptr);
  EXPECT_EQ(found[4], nullptr);  // erased
  EXPECT_TRUE(map.PointsOf({}).empty());
  EXPECT_THROW(map.PointsOf({ids[2], ids[1]}), std::exception);
}

TEST(Map, AbsorbKeepsIdsUniqueAcrossMapsSharingIds) {
  auto ids = std::make_shared<MapIds>();
  Map first(ids), second(ids);
  auto a = first.AddKeyFrame(Rigid3d(), EmptyFrame());
  auto b = second.AddKeyFrame(Rigid3d(), EmptyFrame());
  auto p = second.AddPoint(Eigen::Vector3d(1, 0, 5), cv::Mat::zeros(1, 32, CV_8U), b->id);
  EXPECT_NE(a->id, b->id);
  const int epoch = first.correction_epoch();
  first.Absorb(&second);
  EXPECT_EQ(first.keyframes().size(), 2u);
  EXPECT_EQ(first.point(p->id), p);
  EXPECT_TRUE(second.keyframes().empty());
  EXPECT_GT(first.correction_epoch(), epoch);
  // New entries in either map continue after every id in use.
  auto c = first.AddKeyFrame(Rigid3d(), EmptyFrame());
  EXPECT_GT(c->id, b->id);
  EXPECT_THROW(first.Absorb(&first), std::invalid_argument);
  auto duplicate = std::make_shared<KeyFrame>();
  duplicate->id = a->id;
  EXPECT_THROW(first.RestoreKeyFrame(duplicate), std::invalid_argument);
}

}  // namespace
}  // namespace slslam
