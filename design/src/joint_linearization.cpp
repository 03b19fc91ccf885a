#include "fullarm/design/joint_linearization.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/plant/hydraulics.hpp"

namespace fullarm::design {

namespace {

constexpr int kNewtonIterations = 60;

// Rigid-body terms about one axis with the rest of the arm locked at `posture`: the diagonal
// mass-matrix entry and g(q) = a cos q + b sin q (exact for a rigid body about a fixed axis).
struct AxisLoad {
  double inertia = 0.0;
  double a = 0.0;
  double b = 0.0;
};

AxisLoad axisLoad(const arm::ArmModel& model, int i, const Eigen::VectorXd& posture) {
  const arm::SingleAxisLoad axis = arm::computeSingleAxisLoad(model, i, posture);
  return {axis.inertia_kgm2, axis.gravity_cos_nm, axis.gravity_sin_nm};
}

// Point mass merged into a link, keeping the inertia about the new centre of mass (parallel
// axis theorem), as plant::ArmPlant does with the user's arm.
void mergePointMass(arm::LinkInertial& link, double mass_kg, const Eigen::Vector3d& p_L) {
  if (mass_kg <= 0.0) return;
  const double m0 = link.mass_kg;
  const double m = m0 + mass_kg;
  const Eigen::Vector3d com = (m0 * link.com_m + mass_kg * p_L) / m;
  const auto shift = [](double mass, const Eigen::Vector3d& d) {
    return Eigen::Matrix3d(mass * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose()));
  };
  link.inertia_com_kgm2 += shift(m0, link.com_m - com) + shift(mass_kg, p_L - com);
  link.com_m = com;
  link.mass_kg = m;
}

// Everything the RHS and its Jacobian need at one state.
struct Evaluation {
  JointStateVector xdot = JointStateVector::Zero();
  Eigen::Matrix<double, kJointStates, kJointStates> A = Eigen::Matrix<double, kJointStates, kJointStates>::Zero();
  Eigen::Matrix<double, kJointStates, 2> B = Eigen::Matrix<double, kJointStates, 2>::Zero();
  double tau_cell = 0.0;
  Eigen::Matrix<double, 1, kJointStates> dcell_dx = Eigen::Matrix<double, 1, kJointStates>::Zero();
  double dcell_dtau_user = 0.0;
};

Evaluation evaluate(const JointPlantModel& model, const OperatingPoint& op, const JointStateVector& x, double command,
                    double tau_user, FrictionLinearization friction_mode) {
  const plant::JointParams& p = model.joint;
  const JointLoad& load = model.load;
  const bool user = model.include_user;
  const double q = x[kAngle];
  const double w = x[kVelocity];
  Evaluation e;

  // Mechanics (H14, H15): M q'' = tau_act + tau_user + tau_cuff - g(q).
  const double mass = load.inertia_kgm2 + p.actuator.inertia_kgm2 + (user ? load.user_inertia_kgm2 : 0.0);
  const double ga = load.gravity_cos_nm + (user ? load.user_gravity_cos_nm : 0.0);
  const double gb = load.gravity_sin_nm + (user ? load.user_gravity_sin_nm : 0.0);
  const double k_user = user ? load.user_stiffness_nm_per_rad : 0.0;
  const double b_user = user ? load.user_damping_nms_per_rad : 0.0;
  const double g = ga * std::cos(q) + gb * std::sin(q);
  const double dg = -ga * std::sin(q) + gb * std::cos(q);
  const double tau_cuff = -k_user * (q - op.q_rad) - b_user * w;

  Eigen::Matrix<double, 1, kJointStates> dact = Eigen::Matrix<double, 1, kJointStates>::Zero();
  double tau_act = 0.0;
  const bool ideal = p.actuator.kind == plant::ActuatorKind::kIdealTorque;
  const plant::StrokeRange range = plant::strokeRange(p);
  const plant::ChamberVolumes v = plant::chamberVolumes(p, range, q);
  if (ideal) {
    tau_act = command;
  } else {
    const plant::ValueSlope f = plant::frictionTorque(p.friction, w);
    const plant::StopTorque st = plant::hardStopTorque(p, q, w);
    tau_act = x[kPressureA] * v.dva_dq + x[kPressureB] * v.dvb_dq - f.value + st.torque_nm;
    double friction_slope = p.friction.viscous_nms_per_rad;
    if (friction_mode == FrictionLinearization::kTangent) friction_slope = f.slope;
    if (friction_mode == FrictionLinearization::kStribeckWorst) friction_slope += stribeckWorstSlope(p.friction);
    dact[kPressureA] = v.dva_dq;
    dact[kPressureB] = v.dvb_dq;
    dact[kAngle] = x[kPressureA] * v.d2va_dq2 + x[kPressureB] * v.d2vb_dq2 + st.d_dq;
    dact[kVelocity] = -friction_slope + st.d_dqd;
  }
  const double qdd = (tau_act + tau_user + tau_cuff - g) / mass;
  Eigen::Matrix<double, 1, kJointStates> dqdd = dact;
  dqdd[kAngle] += -k_user - dg;
  dqdd[kVelocity] += -b_user;
  dqdd /= mass;
  const double dqdd_dtau = 1.0 / mass;
  const double dqdd_du = ideal ? 1.0 / mass : 0.0;

  e.xdot[kAngle] = w;
  e.xdot[kVelocity] = qdd;
  e.A(kAngle, kVelocity) = 1.0;
  e.A.row(kVelocity) = dqdd;
  e.B(kVelocity, kInUserTorque) = dqdd_dtau;
  e.B(kVelocity, kInCommand) = dqdd_du;
  // Load cell (H15): tau_cell = tau_act - J_act q''.
  const double j_act = p.actuator.inertia_kgm2;
  e.tau_cell = tau_act - j_act * qdd;
  e.dcell_dx = dact - j_act * dqdd;
  e.dcell_dtau_user = -j_act * dqdd_dtau;
  if (ideal) return e;

  // Spool (H12): x'' = w_v^2 (K_amp V - x) - 2 zeta w_v x'; V = u, or K_t (u - tau_cell).
  const double wv = 2.0 * std::numbers::pi * p.valve.natural_frequency_hz;
  const double kamp = p.valve.amplifier_gain_per_v;
  const bool torque_loop = p.input_mode == plant::InputMode::kTorqueLoop;
  const double kt = p.torque_loop.gain_v_per_nm;
  const double volts = torque_loop ? kt * (command - e.tau_cell) : command;
  e.xdot[kSpool] = x[kSpoolRate];
  e.xdot[kSpoolRate] = wv * wv * (kamp * volts - x[kSpool]) - 2.0 * p.valve.damping_ratio * wv * x[kSpoolRate];
  e.A(kSpool, kSpoolRate) = 1.0;
  e.A(kSpoolRate, kSpool) = -wv * wv;
  e.A(kSpoolRate, kSpoolRate) = -2.0 * p.valve.damping_ratio * wv;
  if (torque_loop) {
    e.B(kSpoolRate, kInCommand) = wv * wv * kamp * kt;
    e.A.row(kSpoolRate) -= wv * wv * kamp * kt * e.dcell_dx;
    e.B(kSpoolRate, kInUserTorque) = -wv * wv * kamp * kt * e.dcell_dtau_user;
  } else {
    e.B(kSpoolRate, kInCommand) = wv * wv * kamp;
  }

  // Chambers (H13): p' = beta(p)/V (Q_valve + Q_check - Q_leak - dV/dq qd).
  const double pa = x[kPressureA];
  const double pb = x[kPressureB];
  const plant::ValveFlows f = plant::valveFlows(p, x[kSpool], pa, pb);
  const double ci = p.chambers.internal_leakage_m3ps_per_pa;
  const double ce = p.chambers.external_leakage_m3ps_per_pa;
  const plant::ValueSlope ba = plant::effectiveBulkModulus(p.fluid, pa);
  const plant::ValueSlope bb = plant::effectiveBulkModulus(p.fluid, pb);
  const plant::ValueSlope cva = plant::checkValveFlow(p, pa);
  const plant::ValueSlope cvb = plant::checkValveFlow(p, pb);
  const double fa = f.q_a_m3ps + cva.value - ci * (pa - pb) - ce * pa - v.dva_dq * w;
  const double fb = f.q_b_m3ps + cvb.value + ci * (pa - pb) - ce * pb - v.dvb_dq * w;
  const double ka = ba.value / v.v_a_m3;
  const double kb = bb.value / v.v_b_m3;
  e.xdot[kPressureA] = ka * fa;
  e.xdot[kPressureB] = kb * fb;
  e.A(kPressureA, kSpool) = ka * f.dqa_dx;
  e.A(kPressureA, kPressureA) = ba.slope / v.v_a_m3 * fa + ka * (f.dqa_dpa + cva.slope - ci - ce);
  e.A(kPressureA, kPressureB) = ka * ci;
  e.A(kPressureA, kAngle) = -ka * fa * v.dva_dq / v.v_a_m3 - ka * v.d2va_dq2 * w;
  e.A(kPressureA, kVelocity) = -ka * v.dva_dq;
  e.A(kPressureB, kSpool) = kb * f.dqb_dx;
  e.A(kPressureB, kPressureB) = bb.slope / v.v_b_m3 * fb + kb * (f.dqb_dpb + cvb.slope - ci - ce);
  e.A(kPressureB, kPressureA) = kb * ci;
  e.A(kPressureB, kAngle) = -kb * fb * v.dvb_dq / v.v_b_m3 - kb * v.d2vb_dq2 * w;
  e.A(kPressureB, kVelocity) = -kb * v.dvb_dq;
  return e;
}

}  // namespace

double stribeckWorstSlope(const plant::FrictionParams& f) noexcept {
  const double drop = f.static_nm - f.coulomb_nm;
  if (!(drop > 0.0) || !(f.stribeck_velocity_radps > 0.0)) return 0.0;
  // d/dw [drop exp(-(w/ws)^2)] = -2 drop w/ws^2 exp(-(w/ws)^2), steepest at w = ws/sqrt(2).
  return -drop * std::sqrt(2.0) / f.stribeck_velocity_radps * std::exp(-0.5);
}

JointLoad jointLoadFromArm(const arm::ArmModel& model, const plant::UserArmParams& user, int joint_index,
                           const Eigen::VectorXd& posture) {
  if (joint_index < 0 || joint_index >= model.numJoints()) {
    throw core::ConfigError(model.source, "joint", "joint index " + std::to_string(joint_index) + " out of range");
  }
  if (posture.size() != model.numJoints()) {
    throw core::ConfigError(model.source, "posture", "expected " + std::to_string(model.numJoints()) + " joint angles");
  }
  const AxisLoad device = axisLoad(model, joint_index, posture);
  JointLoad load;
  load.inertia_kgm2 = device.inertia;
  load.gravity_cos_nm = device.a;
  load.gravity_sin_nm = device.b;
  if (!user.enabled || !arm::jointMovesLink(model, joint_index, user.link)) return load;
  // The user's arm: merged into a copy of the model exactly as the plant does, so the
  // difference to the bare device is the user's share of inertia and gravity.
  arm::ArmModel with_user = model;
  mergePointMass(with_user.joints[static_cast<std::size_t>(user.link)].inertial, user.mass_kg, user.point_L);
  const AxisLoad total = axisLoad(with_user, joint_index, posture);
  load.user_inertia_kgm2 = total.inertia - device.inertia;
  load.user_gravity_cos_nm = total.a - device.a;
  load.user_gravity_sin_nm = total.b - device.b;
  // Cuff spring and damper through the cuff point's velocity Jacobian z x (p - o).
  arm::ArmData data(model);
  arm::computeForwardKinematics(model, data, posture);
  const Eigen::Vector3d p = arm::pointInWorld(data, user.link, user.point_L);
  const auto i = static_cast<std::size_t>(joint_index);
  const double r2 = data.z_W[i].cross(p - data.o_W[i]).squaredNorm();
  load.user_stiffness_nm_per_rad = user.stiffness_n_per_m * r2;
  load.user_damping_nms_per_rad = user.damping_ns_per_m * r2;
  return load;
}

JointStateVector jointRhs(const JointPlantModel& model, const OperatingPoint& op, const JointStateVector& x,
                          double command, double tau_user_nm, double* tau_cell_nm) {
  const Evaluation e = evaluate(model, op, x, command, tau_user_nm, FrictionLinearization::kTangent);
  if (tau_cell_nm != nullptr) *tau_cell_nm = e.tau_cell;
  return e.xdot;
}

OperatingPoint solveOperatingPoint(const JointPlantModel& model, double q_rad, double qd_radps, double tau_user_nm) {
  const plant::JointParams& p = model.joint;
  if (q_rad < p.min_rad || q_rad > p.max_rad) {
    throw std::runtime_error("solveOperatingPoint: q = " + std::to_string(q_rad) +
                             " rad is outside the joint range of " + p.name);
  }
  OperatingPoint op;
  op.q_rad = q_rad;
  op.qd_radps = qd_radps;
  op.tau_user_nm = tau_user_nm;
  JointStateVector& x = op.state;
  x.setZero();
  x[kAngle] = q_rad;
  x[kVelocity] = qd_radps;
  const bool ideal = p.actuator.kind == plant::ActuatorKind::kIdealTorque;
  const bool torque_loop = p.input_mode == plant::InputMode::kTorqueLoop;
  const double kamp = p.valve.amplifier_gain_per_v;
  const double kt = p.torque_loop.gain_v_per_nm;
  // Command that puts the spool at rest at x[kSpool].
  const auto holdingCommand = [&](const Evaluation& e) {
    if (ideal) return 0.0;
    return torque_loop ? x[kSpool] / (kamp * kt) + e.tau_cell : x[kSpool] / kamp;
  };
  if (ideal) {
    // The ideal torque source just holds the load.
    Evaluation e = evaluate(model, op, x, 0.0, tau_user_nm, FrictionLinearization::kTangent);
    const double mass = e.B(kVelocity, kInCommand) > 0.0 ? 1.0 / e.B(kVelocity, kInCommand) : 1.0;
    op.command = -e.xdot[kVelocity] * mass;
    e = evaluate(model, op, x, op.command, tau_user_nm, FrictionLinearization::kTangent);
    op.tau_cell_nm = e.tau_cell;
    return op;
  }
  // Initial guess: mean pressure, load pressure from the static torque balance, spool centred.
  const double pm = 0.5 * (p.supply_pressure_pa + p.return_pressure_pa);
  x[kPressureA] = x[kPressureB] = pm;
  {
    const Evaluation e = evaluate(model, op, x, 0.0, tau_user_nm, FrictionLinearization::kTangent);
    const double dva = e.A(kVelocity, kPressureA);
    const double dvb = e.A(kVelocity, kPressureB);
    const double delta = -e.xdot[kVelocity] / (dva - dvb);
    x[kPressureA] += delta;
    x[kPressureB] -= delta;
  }
  // Newton on r = (p_a', p_b', q'') over z = (spool, p_a, p_b), the spool held by its command.
  const int idx[3] = {kSpool, kPressureA, kPressureB};
  const int rows[3] = {kPressureA, kPressureB, kVelocity};
  const auto residual = [&](const Evaluation& e) {
    Eigen::Vector3d r;
    for (int i = 0; i < 3; ++i) r[i] = e.xdot[rows[i]];
    return r;
  };
  const auto scaled = [&](const Eigen::Vector3d& r) {
    const double pressure_scale = p.fluid.oil_bulk_modulus_pa;  // p' of one second of unit strain
    return std::hypot(r[0] / pressure_scale, r[1] / pressure_scale, r[2]);
  };
  // The spool row: with the command chosen to hold the spool, spool' = spool'' = 0 exactly;
  // in torque-loop mode the command also depends on tau_cell, which the Newton step sees
  // through the full Jacobian only via the other rows (the spool itself is a free unknown).
  Evaluation e = evaluate(model, op, x, 0.0, tau_user_nm, FrictionLinearization::kTangent);
  double norm = scaled(residual(e));
  bool converged = false;
  for (int it = 0; it < kNewtonIterations; ++it) {
    if (norm < 1e-12) {
      converged = true;
      break;
    }
    Eigen::Matrix3d J;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) J(i, j) = e.A(rows[i], idx[j]);
    }
    const Eigen::Vector3d dz = -J.fullPivLu().solve(residual(e));
    // Backtracking line search on the scaled residual.
    double step = 1.0;
    JointStateVector trial = x;
    Evaluation et;
    double trial_norm = norm;
    for (int ls = 0; ls < 30; ++ls) {
      trial = x;
      for (int j = 0; j < 3; ++j) trial[idx[j]] += step * dz[j];
      et = evaluate(model, op, trial, 0.0, tau_user_nm, FrictionLinearization::kTangent);
      trial_norm = scaled(residual(et));
      if (trial_norm < norm) break;
      step *= 0.5;
    }
    if (!(trial_norm < norm)) break;
    x = trial;
    e = et;
    norm = trial_norm;
  }
  if (!converged && !(norm < 1e-9)) {
    throw std::runtime_error("solveOperatingPoint: no trim found for joint " + p.name + " at q = " +
                             std::to_string(q_rad) + " rad (scaled residual " + std::to_string(norm) + ")");
  }
  if (std::abs(x[kSpool]) >= 1.0) {
    throw std::runtime_error("solveOperatingPoint: joint " + p.name +
                             " needs a saturated valve to hold q = " + std::to_string(q_rad) + " rad");
  }
  op.tau_cell_nm = e.tau_cell;
  op.command = holdingCommand(e);
  return op;
}

JointLinearModel linearizeJoint(const JointPlantModel& model, const OperatingPoint& op,
                                FrictionLinearization friction) {
  const Evaluation e = evaluate(model, op, op.state, op.command, op.tau_user_nm, friction);
  JointLinearModel lin;
  lin.op = op;
  lin.plant.A = e.A;
  lin.plant.B = e.B;
  lin.plant.C = Eigen::MatrixXd::Zero(3, kJointStates);
  lin.plant.D = Eigen::MatrixXd::Zero(3, 2);
  lin.plant.C(kOutAngle, kAngle) = 1.0;
  lin.plant.C(kOutVelocity, kVelocity) = 1.0;
  lin.plant.C.row(kOutTorqueCell) = e.dcell_dx;
  lin.plant.D(kOutTorqueCell, kInUserTorque) = e.dcell_dtau_user;
  if (model.joint.actuator.kind == plant::ActuatorKind::kIdealTorque) {
    lin.plant.D(kOutTorqueCell, kInCommand) = 1.0 - model.joint.actuator.inertia_kgm2 * e.B(kVelocity, kInCommand);
  }
  lin.plant.sample_time_s = 0.0;
  const double q = op.q_rad;
  lin.device_gravity_slope_nm_per_rad =
      -model.load.gravity_cos_nm * std::sin(q) + model.load.gravity_sin_nm * std::cos(q);
  return lin;
}

}  // namespace fullarm::design
