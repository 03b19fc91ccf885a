#include "fullarm/arm/dynamics.hpp"

#include <cassert>
#include <numbers>
#include <stdexcept>
#include <string>

#include "fullarm/arm/kinematics.hpp"

namespace fullarm::arm {
namespace {

// Recursive Newton-Euler on the link tree, in world coordinates, after forward kinematics.
// Outward pass (Craig, Introduction to Robotics, Eq. 6.45-6.48, world-frame form):
//   omega_i     = omega_p + z_i qd_i
//   omega_dot_i = omega_dot_p + omega_p x z_i qd_i + z_i qdd_i
//   a_o_i       = a_o_p + omega_dot_p x (o_i - o_p) + omega_p x (omega_p x (o_i - o_p))
//   a_c_i       = a_o_i + omega_dot_i x (c_i - o_i) + omega_i x (omega_i x (c_i - o_i))
// with the base accelerating at -gravity_scale * g, so gravity enters as an inertial force.
// Inward pass (Eq. 6.51-6.53): f_i = m a_c + sum f_child,
//   n_i (about o_i) = I omega_dot + omega x I omega + (c_i - o_i) x m a_c
//                     + sum (n_child + (o_child - o_i) x f_child),  tau_i = z_i . n_i.
void newtonEuler(const ArmModel& model, ArmData& data, const Eigen::Ref<const Eigen::VectorXd>& qd,
                 const Eigen::Ref<const Eigen::VectorXd>& qdd, double gravity_scale,
                 Eigen::Ref<Eigen::VectorXd> tau) noexcept {
  const int n = model.numJoints();
  const Eigen::Vector3d base_accel = -gravity_scale * model.gravity_W_mps2;
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const Joint& joint = model.joints[k];
    Eigen::Vector3d omega_p = Eigen::Vector3d::Zero();
    Eigen::Vector3d omega_dot_p = Eigen::Vector3d::Zero();
    Eigen::Vector3d a_p = base_accel;
    Eigen::Vector3d o_p = data.o_W[k];  // base: any point works, its motion is pure translation
    if (joint.parent >= 0) {
      const auto p = static_cast<std::size_t>(joint.parent);
      omega_p = data.omega[p];
      omega_dot_p = data.omega_dot[p];
      a_p = data.accel_origin[p];
      o_p = data.o_W[p];
    }
    const Eigen::Vector3d& z = data.z_W[k];
    data.omega[k] = omega_p + z * qd[i];
    data.omega_dot[k] = omega_dot_p + omega_p.cross(z * qd[i]) + z * qdd[i];
    const Eigen::Vector3d r_po = data.o_W[k] - o_p;
    data.accel_origin[k] = a_p + omega_dot_p.cross(r_po) + omega_p.cross(omega_p.cross(r_po));

    const LinkInertial& in = joint.inertial;  // data.inertia_W[k] set by updateWorldInertias
    const Eigen::Vector3d r_oc = data.com_W[k] - data.o_W[k];
    const Eigen::Vector3d& w = data.omega[k];
    const Eigen::Vector3d a_c = data.accel_origin[k] + data.omega_dot[k].cross(r_oc) + w.cross(w.cross(r_oc));
    const Eigen::Vector3d f_inertial = in.mass_kg * a_c;
    data.force[k] = f_inertial;
    data.moment[k] = data.inertia_W[k] * data.omega_dot[k] + w.cross(data.inertia_W[k] * w) + r_oc.cross(f_inertial);
  }
  for (int i = n - 1; i >= 0; --i) {
    const auto k = static_cast<std::size_t>(i);
    tau[i] = data.z_W[k].dot(data.moment[k]);
    const int parent = model.joints[k].parent;
    if (parent >= 0) {
      const auto p = static_cast<std::size_t>(parent);
      data.force[p] += data.force[k];
      data.moment[p] += data.moment[k] + (data.o_W[k] - data.o_W[p]).cross(data.force[k]);
    }
  }
}

// Link inertias about their COM rotated into the world, once per configuration.
void updateWorldInertias(const ArmModel& model, ArmData& data) noexcept {
  for (std::size_t k = 0; k < model.joints.size(); ++k) {
    const Eigen::Matrix3d& R = data.X_WL[k].linear();
    data.inertia_W[k].noalias() = R * model.joints[k].inertial.inertia_com_kgm2 * R.transpose();
  }
}

}  // namespace

void computeGravityTorquesAtKinematics(const ArmModel& model, ArmData& data) noexcept {
  const int n = model.numJoints();
  // Subtree mass and first moment, leaves to root.
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    data.subtree_mass_kg[k] = model.joints[k].inertial.mass_kg;
    data.mass_moment[k] = model.joints[k].inertial.mass_kg * data.com_W[k];
  }
  for (int i = n - 1; i >= 0; --i) {
    const auto k = static_cast<std::size_t>(i);
    const int parent = model.joints[k].parent;
    if (parent >= 0) {
      const auto p = static_cast<std::size_t>(parent);
      data.subtree_mass_kg[p] += data.subtree_mass_kg[k];
      data.mass_moment[p] += data.mass_moment[k];
    }
  }
  // g_i = dV/dq_i = -z_i . sum_k (c_k - o_i) x m_k g over the links joint i moves.
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const Eigen::Vector3d lever = data.mass_moment[k] - data.subtree_mass_kg[k] * data.o_W[k];
    data.tau_gravity[i] = -data.z_W[k].dot(lever.cross(model.gravity_W_mps2));
  }
  ++data.gravity_passes;
}

void computeGravityTorques(const ArmModel& model, ArmData& data, const Eigen::Ref<const Eigen::VectorXd>& q) noexcept {
  computeForwardKinematics(model, data, q);
  computeGravityTorquesAtKinematics(model, data);
}

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

void computeInverseDynamics(const ArmModel& model, ArmData& data, const Eigen::Ref<const Eigen::VectorXd>& q,
                            const Eigen::Ref<const Eigen::VectorXd>& qd,
                            const Eigen::Ref<const Eigen::VectorXd>& qdd) noexcept {
  assert(qd.size() == model.numJoints() && qdd.size() == model.numJoints());
  computeForwardKinematics(model, data, q);
  updateWorldInertias(model, data);
  newtonEuler(model, data, qd, qdd, 1.0, data.tau);
}

void computeCoriolisTorques(const ArmModel& model, ArmData& data, const Eigen::Ref<const Eigen::VectorXd>& q,
                            const Eigen::Ref<const Eigen::VectorXd>& qd) noexcept {
  computeForwardKinematics(model, data, q);
  updateWorldInertias(model, data);
  data.qdd_unit.setZero();
  newtonEuler(model, data, qd, data.qdd_unit, 0.0, data.tau_coriolis);
}

void computeMassMatrix(const ArmModel& model, ArmData& data, const Eigen::Ref<const Eigen::VectorXd>& q) noexcept {
  computeForwardKinematics(model, data, q);
  updateWorldInertias(model, data);
  const int n = model.numJoints();
  // Column j of M is the Newton-Euler torque for qdd = e_j with qd = 0 and no gravity.
  // data.tau_coriolis is free scratch here (qd = 0 holds it at zero).
  data.tau_coriolis.setZero();
  for (int j = 0; j < n; ++j) {
    data.qdd_unit.setZero();
    data.qdd_unit[j] = 1.0;
    newtonEuler(model, data, data.tau_coriolis, data.qdd_unit, 0.0, data.mass_matrix.col(j));
  }
  data.tau_coriolis.setZero();
  data.qdd_unit.setZero();
}

double computePotentialEnergy(const ArmModel& model, ArmData& data,
                              const Eigen::Ref<const Eigen::VectorXd>& q) noexcept {
  computeForwardKinematics(model, data, q);
  double v = 0.0;
  for (std::size_t k = 0; k < model.joints.size(); ++k) {
    v -= model.joints[k].inertial.mass_kg * model.gravity_W_mps2.dot(data.com_W[k]);
  }
  return v;
}

double computeKineticEnergy(const ArmModel& model, ArmData& data, const Eigen::Ref<const Eigen::VectorXd>& q,
                            const Eigen::Ref<const Eigen::VectorXd>& qd) noexcept {
  computeMassMatrix(model, data, q);
  data.qdd_unit.noalias() = data.mass_matrix * qd;  // preallocated: no temporary
  const double energy = 0.5 * qd.dot(data.qdd_unit);
  data.qdd_unit.setZero();
  return energy;
}

}  // namespace fullarm::arm
