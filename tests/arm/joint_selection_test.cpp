// JointSelection: gather and scatter between configuration vectors (model order) and subset
// vectors (selection order), against index-by-index loops written out here.

#include "fullarm/arm/joint_selection.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

#include "alloc_guard.hpp"

namespace fullarm::arm {
namespace {

using FixedCapacityVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxJoints, 1>;

TEST(JointSelection, GatherAndScatterFollowTheListedOrder) {
  const JointSelection s(10, {5, 0, 3});
  ASSERT_EQ(s.size(), 3);
  EXPECT_EQ(s.numModelJoints(), 10);
  Eigen::VectorXd config(10);
  for (int i = 0; i < 10; ++i) config[i] = 100.0 + i;
  Eigen::VectorXd subset(3);
  s.gather(config, subset);
  EXPECT_EQ(subset, Eigen::Vector3d(105.0, 100.0, 103.0));
  Eigen::VectorXd back = Eigen::VectorXd::Constant(10, -1.0);
  s.scatter(Eigen::Vector3d(1.0, 2.0, 3.0), back);
  for (int i = 0; i < 10; ++i) {
    const double expected = i == 5 ? 1.0 : (i == 0 ? 2.0 : (i == 3 ? 3.0 : -1.0));  // others untouched
    EXPECT_EQ(back[i], expected) << i;
  }
  EXPECT_EQ(s.position(5), 0);
  EXPECT_EQ(s.position(3), 2);
  EXPECT_EQ(s.position(4), -1);
  EXPECT_EQ(s.modelIndices(), (std::vector<int>{5, 0, 3}));
}

TEST(JointSelection, AllIsTheIdentity) {
  const JointSelection s = JointSelection::all(4);
  ASSERT_EQ(s.size(), 4);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(s.modelIndex(k), k);
  const Eigen::Vector4d config(1.0, 2.0, 3.0, 4.0);
  Eigen::VectorXd subset(4);
  s.gather(config, subset);
  EXPECT_EQ(subset, config);
}

TEST(JointSelection, RejectsBadLists) {
  EXPECT_THROW(JointSelection(3, {0, 3}), std::invalid_argument);
  EXPECT_THROW(JointSelection(3, {-1}), std::invalid_argument);
  EXPECT_THROW(JointSelection(3, {1, 1}), std::invalid_argument);
  EXPECT_THROW(JointSelection(20, std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10}), std::invalid_argument);
  EXPECT_EQ(JointSelection().size(), 0);
}

TEST(JointSelection, GatherAndScatterDoNotAllocateOnFixedCapacityVectors) {
  const JointSelection s(10, {6, 2, 1, 9});
  Eigen::VectorXd config = Eigen::VectorXd::LinSpaced(10, 0.0, 9.0);
  FixedCapacityVector subset(4);
  EXPECT_NO_HEAP_ALLOCATION(s.gather(config, subset));
  EXPECT_EQ(subset[0], 6.0);
  EXPECT_EQ(subset[3], 9.0);
  subset *= 2.0;
  EXPECT_NO_HEAP_ALLOCATION(s.scatter(subset, config));
  EXPECT_EQ(config[6], 12.0);
  EXPECT_EQ(config[9], 18.0);
  EXPECT_EQ(config[0], 0.0);
}

}  // namespace
}  // namespace fullarm::arm
