// The allocation guard proves the @rt arm functions never touch the heap.

#include <gtest/gtest.h>

#include <random>

#include "alloc_guard.hpp"
#include "arm_test_util.hpp"
#include "fullarm/arm/actuator.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/arm/sensors.hpp"

namespace fullarm::arm {
namespace {

class RealtimeAllocation : public ::testing::Test {
 protected:
  const ArmModel& model_ = test::defaultModel();
  ArmData data_{model_};
  std::mt19937 rng_{11};
  Eigen::VectorXd q_ = test::randomConfiguration(model_, rng_);
  Eigen::VectorXd qd_ = test::randomVector(model_.numJoints(), 1.0, rng_);
  Eigen::VectorXd qdd_ = test::randomVector(model_.numJoints(), 1.0, rng_);
  PointJacobian J_;
};

TEST_F(RealtimeAllocation, ForwardKinematics) {
  EXPECT_NO_HEAP_ALLOCATION(computeForwardKinematics(model_, data_, q_));
}

TEST_F(RealtimeAllocation, PointJacobianOnEveryLink) {
  computeForwardKinematics(model_, data_, q_);
  for (int link = 0; link < model_.numJoints(); ++link) {
    EXPECT_NO_HEAP_ALLOCATION(
        computePointJacobian(model_, data_, link, data_.com_W[static_cast<std::size_t>(link)], J_));
  }
}

TEST_F(RealtimeAllocation, GravityTorques) {
  EXPECT_NO_HEAP_ALLOCATION(computeGravityTorques(model_, data_, q_));
  computeForwardKinematics(model_, data_, q_);
  EXPECT_NO_HEAP_ALLOCATION(computeGravityTorquesAtKinematics(model_, data_));
}

TEST_F(RealtimeAllocation, InverseDynamics) {
  EXPECT_NO_HEAP_ALLOCATION(computeInverseDynamics(model_, data_, q_, qd_, qdd_));
}

TEST_F(RealtimeAllocation, MassMatrixCoriolisAndEnergies) {
  EXPECT_NO_HEAP_ALLOCATION(computeMassMatrix(model_, data_, q_));
  EXPECT_NO_HEAP_ALLOCATION(computeCoriolisTorques(model_, data_, q_, qd_));
  double e = 0.0;
  EXPECT_NO_HEAP_ALLOCATION(e = computeKineticEnergy(model_, data_, q_, qd_));
  EXPECT_NO_HEAP_ALLOCATION(e += computePotentialEnergy(model_, data_, q_));
  EXPECT_TRUE(std::isfinite(e));
}

TEST_F(RealtimeAllocation, SensorsAndActuators) {
  const Joint& j = model_.joints[0];
  double sum = 0.0;
  EXPECT_NO_HEAP_ALLOCATION({
    sum += potentiometerAngle(j.potentiometer, quantizeCode(potentiometerCounts(j.potentiometer, 0.1), 12));
    sum += torqueSensorTorque(j.torque_sensor, 2100.0) + torqueSensorCounts(j.torque_sensor, 3.0);
    sum += torqueCommandCode(j.torque_command, 3.0);
    sum += actuatorMomentArm(j.actuator, 0.2) + cylinderLength(j.actuator, 0.2);
  });
  EXPECT_TRUE(std::isfinite(sum));
}

// The guard itself must see Eigen's heap use in this very translation unit, or the tests above
// prove nothing.
TEST_F(RealtimeAllocation, GuardSeesDynamicEigenTemporaries) {
  fullarm::testing::AllocationGuard guard;
  const Eigen::VectorXd copy = q_ * 2.0;
  EXPECT_GE(guard.allocations(), 1u);
  EXPECT_EQ(copy.size(), q_.size());
}

}  // namespace
}  // namespace fullarm::arm
