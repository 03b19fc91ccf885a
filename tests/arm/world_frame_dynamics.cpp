#include "world_frame_dynamics.hpp"

#include <vector>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/kinematics.hpp"

namespace fullarm::arm::test {
namespace {

// Per-link scratch, world frame.
struct Scratch {
  std::vector<Eigen::Vector3d> omega, omega_dot, accel_origin, force, moment;
  std::vector<Eigen::Matrix3d> inertia_W;  // link inertia about its COM in the world
  explicit Scratch(std::size_t n) : omega(n), omega_dot(n), accel_origin(n), force(n), moment(n), inertia_W(n) {}
};

// Recursive Newton-Euler on the link tree, in world coordinates, after forward kinematics.
// Outward pass (Craig, Eq. 6.45-6.48, world-frame form):
//   omega_i     = omega_p + z_i qd_i
//   omega_dot_i = omega_dot_p + omega_p x z_i qd_i + z_i qdd_i
//   a_o_i       = a_o_p + omega_dot_p x (o_i - o_p) + omega_p x (omega_p x (o_i - o_p))
//   a_c_i       = a_o_i + omega_dot_i x (c_i - o_i) + omega_i x (omega_i x (c_i - o_i))
// with the base accelerating at -gravity_scale * g, so gravity enters as an inertial force.
// Inward pass (Eq. 6.51-6.53): f_i = m a_c + sum f_child,
//   n_i (about o_i) = I omega_dot + omega x I omega + (c_i - o_i) x m a_c
//                     + sum (n_child + (o_child - o_i) x f_child),  tau_i = z_i . n_i.
Eigen::VectorXd newtonEuler(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                            const Eigen::VectorXd& qdd, double gravity_scale) {
  ArmData fk(model);
  computeForwardKinematics(model, fk, q);
  const int n = model.numJoints();
  Scratch d(static_cast<std::size_t>(n));
  for (std::size_t k = 0; k < model.joints.size(); ++k) {
    const Eigen::Matrix3d& R = fk.X_WL[k].linear();
    d.inertia_W[k] = R * model.joints[k].inertial.inertia_com_kgm2 * R.transpose();
  }
  const Eigen::Vector3d base_accel = -gravity_scale * model.gravity_W_mps2;
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const Joint& joint = model.joints[k];
    Eigen::Vector3d omega_p = Eigen::Vector3d::Zero();
    Eigen::Vector3d omega_dot_p = Eigen::Vector3d::Zero();
    Eigen::Vector3d a_p = base_accel;
    Eigen::Vector3d o_p = fk.o_W[k];  // base: any point works, its motion is pure translation
    if (joint.parent >= 0) {
      const auto p = static_cast<std::size_t>(joint.parent);
      omega_p = d.omega[p];
      omega_dot_p = d.omega_dot[p];
      a_p = d.accel_origin[p];
      o_p = fk.o_W[p];
    }
    const Eigen::Vector3d& z = fk.z_W[k];
    d.omega[k] = omega_p + z * qd[i];
    d.omega_dot[k] = omega_dot_p + omega_p.cross(z * qd[i]) + z * qdd[i];
    const Eigen::Vector3d r_po = fk.o_W[k] - o_p;
    d.accel_origin[k] = a_p + omega_dot_p.cross(r_po) + omega_p.cross(omega_p.cross(r_po));
    const Eigen::Vector3d r_oc = fk.com_W[k] - fk.o_W[k];
    const Eigen::Vector3d& w = d.omega[k];
    const Eigen::Vector3d a_c = d.accel_origin[k] + d.omega_dot[k].cross(r_oc) + w.cross(w.cross(r_oc));
    const Eigen::Vector3d f_inertial = joint.inertial.mass_kg * a_c;
    d.force[k] = f_inertial;
    d.moment[k] = d.inertia_W[k] * d.omega_dot[k] + w.cross(d.inertia_W[k] * w) + r_oc.cross(f_inertial);
  }
  Eigen::VectorXd tau(n);
  for (int i = n - 1; i >= 0; --i) {
    const auto k = static_cast<std::size_t>(i);
    tau[i] = fk.z_W[k].dot(d.moment[k]);
    const int parent = model.joints[k].parent;
    if (parent >= 0) {
      const auto p = static_cast<std::size_t>(parent);
      d.force[p] += d.force[k];
      d.moment[p] += d.moment[k] + (fk.o_W[k] - fk.o_W[p]).cross(d.force[k]);
    }
  }
  return tau;
}

}  // namespace

// D5: world-frame Newton-Euler (test oracle) (reports/equations.md).
Eigen::VectorXd worldFrameInverseDynamics(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                          const Eigen::VectorXd& qdd) {
  return newtonEuler(model, q, qd, qdd, 1.0);
}

Eigen::VectorXd worldFrameCoriolisTorques(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  return newtonEuler(model, q, qd, Eigen::VectorXd::Zero(model.numJoints()), 0.0);
}

Eigen::MatrixXd worldFrameMassMatrix(const ArmModel& model, const Eigen::VectorXd& q) {
  const int n = model.numJoints();
  Eigen::MatrixXd mass(n, n);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
  for (int j = 0; j < n; ++j) mass.col(j) = newtonEuler(model, q, zero, Eigen::VectorXd::Unit(n, j), 0.0);
  return mass;
}

Eigen::VectorXd worldFrameGravityTorques(const ArmModel& model, const Eigen::VectorXd& q) {
  ArmData fk(model);
  computeForwardKinematics(model, fk, q);
  const int n = model.numJoints();
  // Subtree mass and first moment, leaves to root.
  std::vector<double> mass(static_cast<std::size_t>(n));
  std::vector<Eigen::Vector3d> moment(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    mass[k] = model.joints[k].inertial.mass_kg;
    moment[k] = model.joints[k].inertial.mass_kg * fk.com_W[k];
  }
  for (int i = n - 1; i >= 0; --i) {
    const auto k = static_cast<std::size_t>(i);
    const int parent = model.joints[k].parent;
    if (parent >= 0) {
      mass[static_cast<std::size_t>(parent)] += mass[k];
      moment[static_cast<std::size_t>(parent)] += moment[k];
    }
  }
  Eigen::VectorXd g(n);
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const Eigen::Vector3d lever = moment[k] - mass[k] * fk.o_W[k];
    g[i] = -fk.z_W[k].dot(lever.cross(model.gravity_W_mps2));
  }
  return g;
}

}  // namespace fullarm::arm::test
