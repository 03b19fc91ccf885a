#include "fullarm/arm/dynamics.hpp"

#include <cassert>
#include <numbers>
#include <stdexcept>
#include <string>

#include "fullarm/arm/kinematics.hpp"

namespace fullarm::arm {
namespace {

Eigen::Matrix3d skewSquare(const Eigen::Vector3d& c) noexcept {
  return c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose();
}

// The spatial kinematics of every link (R2 of reports/equations.md) from the frames of the last
// computeForwardKinematics in `data`: joint axes s = (z, o x z), masses and first moments m c
// about the world origin, and with `inertias` the rotational inertias about the origin; the
// ground accelerates at -g. Velocities at rest.
void bodiesAtKinematics(const ArmModel& model, ArmData& data, bool inertias) noexcept {
  RigidBodyData& b = data.bodies;
  b.ground_accel = {Eigen::Vector3d::Zero(), -model.gravity_W_mps2};
  for (int i = 0; i < data.tree.n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const LinkInertial& in = model.joints[k].inertial;
    b.R_WB[k] = data.X_WL[k].linear();
    b.o_W[k] = data.o_W[k];
    b.s[k] = {data.z_W[k], data.o_W[k].cross(data.z_W[k])};
    b.qd[k] = 0.0;
    b.V[k] = {};
    b.mass_kg[k] = in.mass_kg;
    b.first_moment_kgm[k] = in.mass_kg * data.com_W[k];
    if (inertias) {
      b.inertia_O_kgm2[k].noalias() = b.R_WB[k] * in.inertia_com_kgm2 * b.R_WB[k].transpose();
      b.inertia_O_kgm2[k] += in.mass_kg * skewSquare(data.com_W[k]);
    }
  }
}

// Body velocities V_b = V_p + s_b qd_b (R3), parents first (model order).
void setBodyVelocities(ArmData& data, const Eigen::Ref<const Eigen::VectorXd>& qd) noexcept {
  RigidBodyData& b = data.bodies;
  for (int i = 0; i < data.tree.n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    b.qd[k] = qd[i];
    b.V[k] = {b.s[k].top * qd[i], b.s[k].bottom * qd[i]};
    const int p = data.tree.parent[k];
    if (p >= 0) {
      b.V[k].top += b.V[static_cast<std::size_t>(p)].top;
      b.V[k].bottom += b.V[static_cast<std::size_t>(p)].bottom;
    }
  }
}

// Newton-Euler (R3-R4) at (q, qd, qdd) into `tau`, with `gravity` false for the ground at rest.
void inverseDynamics(const ArmModel& model, ArmData& data, const Eigen::Ref<const Eigen::VectorXd>& q,
                     const Eigen::Ref<const Eigen::VectorXd>& qd, const Eigen::Ref<const Eigen::VectorXd>& qdd,
                     bool gravity, Eigen::VectorXd& tau) noexcept {
  computeForwardKinematics(model, data, q);
  bodiesAtKinematics(model, data, true);
  if (!gravity) data.bodies.ground_accel = {};
  setBodyVelocities(data, qd);
  data.body_vector = qdd;  // fixed capacity: no allocation
  BodyVector result;       // fixed capacity, on the stack
  computeRigidBodyInverseDynamics(data.tree, data.bodies, data.body_vector, result);
  tau = result;
}

}  // namespace

// D2: gravity torques g(q) = ID(q, 0, 0) (reports/equations.md).
void computeGravityTorquesAtKinematics(const ArmModel& model, ArmData& data) noexcept {
  bodiesAtKinematics(model, data, false);
  computeRigidBodyGravity(data.tree, data.bodies, data.body_vector);
  data.tau_gravity = data.body_vector;
  ++data.gravity_passes;
}

// D2: gravity torques g(q) = ID(q, 0, 0) (reports/equations.md).
void computeGravityTorques(const ArmModel& model, ArmData& data, const Eigen::Ref<const Eigen::VectorXd>& q) noexcept {
  computeForwardKinematics(model, data, q);
  computeGravityTorquesAtKinematics(model, data);
}

// D1: inverse dynamics, Coriolis torques and mass matrix by the spatial algorithm (reports/equations.md).
void computeInverseDynamics(const ArmModel& model, ArmData& data, const Eigen::Ref<const Eigen::VectorXd>& q,
                            const Eigen::Ref<const Eigen::VectorXd>& qd,
                            const Eigen::Ref<const Eigen::VectorXd>& qdd) noexcept {
  assert(qd.size() == model.numJoints() && qdd.size() == model.numJoints());
  inverseDynamics(model, data, q, qd, qdd, true, data.tau);
}

// D1: inverse dynamics, Coriolis torques and mass matrix by the spatial algorithm (reports/equations.md).
void computeCoriolisTorques(const ArmModel& model, ArmData& data, const Eigen::Ref<const Eigen::VectorXd>& q,
                            const Eigen::Ref<const Eigen::VectorXd>& qd) noexcept {
  data.tau_coriolis.setZero();
  inverseDynamics(model, data, q, qd, data.tau_coriolis, false, data.tau_coriolis);
}

// D1: inverse dynamics, Coriolis torques and mass matrix by the spatial algorithm (reports/equations.md).
void computeMassMatrix(const ArmModel& model, ArmData& data, const Eigen::Ref<const Eigen::VectorXd>& q) noexcept {
  computeForwardKinematics(model, data, q);
  bodiesAtKinematics(model, data, true);
  computeRigidBodyMassMatrix(data.tree, data.bodies, data.body_matrix);
  data.mass_matrix = data.body_matrix;
}

// D2: gravity torques g(q) = ID(q, 0, 0) (reports/equations.md).
double computePotentialEnergy(const ArmModel& model, ArmData& data,
                              const Eigen::Ref<const Eigen::VectorXd>& q) noexcept {
  computeForwardKinematics(model, data, q);
  bodiesAtKinematics(model, data, false);
  double v = 0.0;
  for (int i = 0; i < data.tree.n; ++i) {
    v -= model.gravity_W_mps2.dot(data.bodies.first_moment_kgm[static_cast<std::size_t>(i)]);
  }
  return v;
}

// D3: kinetic energy (reports/equations.md).
double computeKineticEnergy(const ArmModel& model, ArmData& data, const Eigen::Ref<const Eigen::VectorXd>& q,
                            const Eigen::Ref<const Eigen::VectorXd>& qd) noexcept {
  computeForwardKinematics(model, data, q);
  bodiesAtKinematics(model, data, true);
  setBodyVelocities(data, qd);
  // 0.5 sum_b V_b . (I_b V_b) = 0.5 qd^T M qd.
  const RigidBodyData& b = data.bodies;
  double energy = 0.0;
  for (int i = 0; i < data.tree.n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const Eigen::Vector3d& w = b.V[k].top;
    const Eigen::Vector3d& v = b.V[k].bottom;
    const Eigen::Vector3d& h = b.first_moment_kgm[k];
    energy += w.dot(b.inertia_O_kgm2[k] * w + h.cross(v)) + v.dot(b.mass_kg[k] * v - h.cross(w));
  }
  return 0.5 * energy;
}

// D4: single-axis load of one joint (reports/equations.md).
SingleAxisLoad computeSingleAxisLoad(const ArmModel& model, int joint, const Eigen::VectorXd& posture) {
  if (joint < 0 || joint >= model.numJoints())
    throw std::invalid_argument("computeSingleAxisLoad: joint index " + std::to_string(joint) + " out of range");
  if (posture.size() != model.numJoints())
    throw std::invalid_argument("computeSingleAxisLoad: posture has " + std::to_string(posture.size()) +
                                " angles, expected " + std::to_string(model.numJoints()));
  ArmData data(model);
  Eigen::VectorXd q = posture;
  SingleAxisLoad load;
  computeMassMatrix(model, data, q);
  load.inertia_kgm2 = data.mass_matrix(joint, joint);
  q[joint] = 0.0;
  computeGravityTorques(model, data, q);
  load.gravity_cos_nm = data.tau_gravity[joint];
  q[joint] = std::numbers::pi / 2.0;
  computeGravityTorques(model, data, q);
  load.gravity_sin_nm = data.tau_gravity[joint];
  return load;
}

}  // namespace fullarm::arm
