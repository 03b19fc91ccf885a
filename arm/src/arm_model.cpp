#include "fullarm/arm/arm_model.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <set>
#include <sstream>

#include "fullarm/arm/sensors.hpp"
#include "fullarm/core/config_error.hpp"

namespace fullarm::arm {
namespace {

// Relative tolerance of the inertia checks: symmetry and the triangle inequality are tested
// against this fraction of the largest principal moment, so exact cylinders and spheres
// written with six decimals pass and the reference's identified set (margins of -100 %) fails.
constexpr double kInertiaRelTol = 1e-6;

std::string jointKey(const ArmModel& model, std::size_t i) {
  const int n_arm = model.numArmJoints();
  if (model.joints[i].is_hand) {
    return "hand_joints[" + std::to_string(static_cast<int>(i) - n_arm) + "]";
  }
  return "joints[" + std::to_string(i) + "]";
}

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

}  // namespace

int ArmModel::numArmJoints() const noexcept {
  int n = 0;
  for (const Joint& j : joints) n += j.is_hand ? 0 : 1;
  return n;
}

int ArmModel::jointIndex(std::string_view joint_name) const noexcept {
  for (std::size_t i = 0; i < joints.size(); ++i) {
    if (joints[i].name == joint_name) return static_cast<int>(i);
  }
  return -1;
}

Eigen::VectorXd ArmModel::defaultPosture() const {
  Eigen::VectorXd q(numJoints());
  for (int i = 0; i < numJoints(); ++i) q[i] = joints[static_cast<std::size_t>(i)].default_rad;
  return q;
}

Eigen::VectorXd ArmModel::lowerLimits() const {
  Eigen::VectorXd q(numJoints());
  for (int i = 0; i < numJoints(); ++i) q[i] = joints[static_cast<std::size_t>(i)].limits.min_rad;
  return q;
}

Eigen::VectorXd ArmModel::upperLimits() const {
  Eigen::VectorXd q(numJoints());
  for (int i = 0; i < numJoints(); ++i) q[i] = joints[static_cast<std::size_t>(i)].limits.max_rad;
  return q;
}

double ArmModel::totalMass() const noexcept {
  double m = 0.0;
  for (const Joint& j : joints) m += j.inertial.mass_kg;
  return m;
}

// K1: modified DH link transforms (reports/equations.md).
Eigen::Isometry3d dhTransform(const DhParameters& dh) {
  // Modified DH (Craig): Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_offset) Tz(d_i). Rz(q) follows.
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.rotate(Eigen::AngleAxisd(dh.alpha_rad, Eigen::Vector3d::UnitX()));
  X.translate(Eigen::Vector3d(dh.a_m, 0.0, 0.0));
  X.rotate(Eigen::AngleAxisd(dh.theta_offset_rad, Eigen::Vector3d::UnitZ()));
  X.translate(Eigen::Vector3d(0.0, 0.0, dh.d_m));
  return X;
}

// K2: roll-pitch-yaw rotation (reports/equations.md).
Eigen::Matrix3d rotationFromRpy(double roll_rad, double pitch_rad, double yaw_rad) {
  return (Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// D6: physical consistency of an inertia (reports/equations.md).
std::string checkInertia(double mass_kg, const Eigen::Matrix3d& I) {
  if (!std::isfinite(mass_kg) || !I.allFinite()) return "mass and inertia must be finite numbers";
  if (mass_kg < 0.0) return "mass must be >= 0 kg, got " + fmt(mass_kg);
  const double scale = I.cwiseAbs().maxCoeff();
  if (mass_kg == 0.0) {
    if (scale != 0.0) return "a massless link (mass_kg: 0) must have zero inertia";
    return {};
  }
  if ((I - I.transpose()).cwiseAbs().maxCoeff() > kInertiaRelTol * scale) {
    return "inertia matrix must be symmetric";
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(I);
  const Eigen::Vector3d& lambda = eig.eigenvalues();  // ascending
  if (lambda[0] <= 0.0) {
    return "inertia about the centre of mass must be positive definite; smallest principal moment is " +
           fmt(lambda[0]) + " kg m^2";
  }
  // Triangle inequality: no principal moment exceeds the sum of the other two.
  const double margin = lambda[0] + lambda[1] - lambda[2];
  if (margin < -kInertiaRelTol * lambda[2]) {
    return "principal moments (" + fmt(lambda[0]) + ", " + fmt(lambda[1]) + ", " + fmt(lambda[2]) +
           ") kg m^2 violate the triangle inequality (no rigid body has them)";
  }
  return {};
}

void validateArmModel(const ArmModel& model) {
  const auto fail = [&](const std::string& key, const std::string& message) {
    throw core::ConfigError(model.source, key, message);
  };
  const std::size_t n = model.joints.size();
  if (n == 0) fail("joints", "expected at least one joint");
  if (n > static_cast<std::size_t>(kMaxJoints)) {
    fail("joints", "at most " + std::to_string(kMaxJoints) + " joints are supported, got " + std::to_string(n));
  }
  if (!(model.gravity_W_mps2.allFinite())) fail("gravity_mps2", "expected finite numbers");

  std::set<std::string, std::less<>> names;
  bool seen_hand = false;
  for (std::size_t i = 0; i < n; ++i) {
    const Joint& j = model.joints[i];
    const std::string key = jointKey(model, i);
    if (j.name.empty()) fail(key + ".name", "expected a non-empty joint name");
    if (!names.insert(j.name).second) fail(key + ".name", "duplicate joint name '" + j.name + "'");
    if (j.is_hand) {
      seen_hand = true;
    } else if (seen_hand) {
      fail(key, "arm-chain joints must come before hand joints");
    }
    if (j.parent >= static_cast<int>(i) || j.parent < -1) {
      fail(key + ".parent", "the parent must be an earlier joint");
    }
    if (!j.is_hand && j.parent != static_cast<int>(i) - 1) fail(key, "arm joints must form a chain");
    if (!j.is_hand && !j.dh) fail(key + ".dh", "an arm-chain joint needs its DH parameters");
    if (j.dh && !j.X_PL0.isApprox(dhTransform(*j.dh), 1e-12)) {
      fail(key + ".dh", "X_PL0 does not equal the transform of the DH parameters");
    }

    const JointLimits& lim = j.limits;
    if (!(lim.min_rad < lim.max_rad)) {
      fail(key + ".limits",
           "expected min_rad < max_rad, got min_rad " + fmt(lim.min_rad) + " and max_rad " + fmt(lim.max_rad));
    }
    if (!(lim.velocity_radps > 0.0)) fail(key + ".limits.velocity_radps", "expected a value > 0 rad/s");
    if (!(lim.torque_nm > 0.0)) fail(key + ".limits.torque_nm", "expected a value > 0 N m");
    if (j.default_rad < lim.min_rad || j.default_rad > lim.max_rad) {
      fail(key + ".default_rad", "expected a value within [min_rad, max_rad] = [" + fmt(lim.min_rad) + ", " +
                                     fmt(lim.max_rad) + "], got " + fmt(j.default_rad));
    }

    if (j.inertial.mass_kg < 0.0) {
      fail(key + ".link.mass_kg", "expected a mass >= 0 kg, got " + fmt(j.inertial.mass_kg));
    }
    if (const std::string why = checkInertia(j.inertial.mass_kg, j.inertial.inertia_com_kgm2); !why.empty()) {
      fail(key + ".link.inertia_kgm2", why);
    }

    const LinkGeometry& g = j.geometry;
    if (g.type == LinkGeometry::Type::kCapsule && !(g.radius_m > 0.0)) {
      fail(key + ".link.geometry.radius_m", "expected a capsule radius > 0 m");
    }
    if (g.type == LinkGeometry::Type::kMesh && !(g.mesh_scale > 0.0)) {
      fail(key + ".link.geometry.scale", "expected a mesh scale > 0");
    }

    const ActuatorGeometry& act = j.actuator;
    if (act.type == ActuatorGeometry::Type::kLinear &&
        !(act.moment_arm_m > 0.0 && act.mount_distance_m > act.moment_arm_m)) {
      fail(key + ".actuator", "expected 0 < moment_arm_m < mount_distance_m for a cylinder on a lever, got " +
                                  fmt(act.moment_arm_m) + " and " + fmt(act.mount_distance_m));
    }

    const PotentiometerCalibration& pot = j.potentiometer;
    if (pot.bits < 8 || pot.bits > 24) fail(key + ".sensors.potentiometer.bits", "expected 8 .. 24 bits");
    if (pot.polarity != 1 && pot.polarity != -1) fail(key + ".sensors.potentiometer.polarity", "expected 1 or -1");
    if (pot.slope_rad_per_count == 0.0)
      fail(key + ".sensors.potentiometer.slope_rad_per_count", "expected a non-zero slope");
    const auto [pot_lo, pot_hi] = potentiometerSpan(pot);
    if (lim.min_rad < pot_lo || lim.max_rad > pot_hi) {
      fail(key + ".limits", "the joint range [" + fmt(lim.min_rad) + ", " + fmt(lim.max_rad) +
                                "] rad is outside what the potentiometer can read, [" + fmt(pot_lo) + ", " +
                                fmt(pot_hi) + "] rad");
    }
    const TorqueSensorCalibration& ts = j.torque_sensor;
    if (ts.bits < 8 || ts.bits > 24) fail(key + ".sensors.torque.bits", "expected 8 .. 24 bits");
    if (ts.slope_nm_per_count == 0.0) fail(key + ".sensors.torque.slope_nm_per_count", "expected a non-zero slope");
    const TorqueCommandCalibration& tc = j.torque_command;
    if (tc.bits < 8 || tc.bits > 24) fail(key + ".sensors.torque_command.bits", "expected 8 .. 24 bits");
    if (tc.slope_nm_per_count == 0.0) {
      fail(key + ".sensors.torque_command.slope_nm_per_count", "expected a non-zero slope");
    }
    const auto [ts_lo, ts_hi] = torqueSensorSpan(ts);
    if (-lim.torque_nm < ts_lo || lim.torque_nm > ts_hi) {
      fail(key + ".limits.torque_nm", "the torque limit " + fmt(lim.torque_nm) +
                                          " N m exceeds what the torque sensor can read, [" + fmt(ts_lo) + ", " +
                                          fmt(ts_hi) + "] N m");
    }
  }
  if (model.tool_link < 0 || model.tool_link >= static_cast<int>(n)) fail("tool.link", "expected a joint name");
  const auto check_segment = [&](int joint, const char* key) {
    if (joint < -1 || joint >= static_cast<int>(n) ||
        (joint >= 0 && model.joints[static_cast<std::size_t>(joint)].is_hand)) {
      fail(std::string("segments.") + key, "expected the name of an arm-chain joint");
    }
  };
  check_segment(model.upper_arm_joint, "upper_arm_joint");
  check_segment(model.forearm_joint, "forearm_joint");
}

bool jointMovesLink(const ArmModel& model, int joint, int link) noexcept {
  for (int j = link; j >= 0; j = model.joints[static_cast<std::size_t>(j)].parent) {
    if (j == joint) return true;
  }
  return false;
}

}  // namespace fullarm::arm
