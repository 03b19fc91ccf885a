#include "fullarm/design/scenario_analysis.hpp"

#include <algorithm>
#include <sstream>

namespace fullarm::design {
namespace {

LoopSetup setupFor(const JointScenario& sc, int delay) {
  LoopSetup s;
  s.control_period_s = sc.dt_s;
  s.delay_samples = delay;
  s.controller = sc.kind;
  return s;
}

VirtualWall wallOf(const JointScenario& sc) {
  return VirtualWall{sc.wall.stiffness_nm_per_rad, sc.wall.damping_nms_per_rad};
}

}  // namespace

JointPlantModel scenarioPlantModel(const JointScenario& sc) {
  JointPlantModel m;
  m.joint = sc.joint;
  m.load.inertia_kgm2 = sc.load.inertia_kgm2 - sc.user.inertia_kgm2;
  m.load.gravity_cos_nm = sc.load.gravity_cos_nm;
  m.load.gravity_sin_nm = sc.load.gravity_sin_nm;
  m.load.user_inertia_kgm2 = sc.user.inertia_kgm2;
  m.load.user_stiffness_nm_per_rad = sc.user.stiffness_nm_per_rad;
  m.load.user_damping_nms_per_rad = sc.user.damping_nms_per_rad;
  m.include_user = true;
  return m;
}

JointScenario scaleControllerGain(const JointScenario& scenario, double factor) {
  JointScenario sc = scenario;
  if (sc.kind == controllers::ControllerKind::kTorquePid) {
    sc.gains.torque_pid.kp_v_per_nm *= factor;
    sc.gains.torque_pid.ki_v_per_nms *= factor;
    sc.gains.torque_pid.kd_vs_per_nm *= factor;
  } else {
    sc.gains.sliding_mode.boundary_layer_radps /= factor;
  }
  return sc;
}

ScenarioLinearResult analyzeScenario(const JointScenario& sc, const LinearRequirements& req, int max_delay,
                                     const std::vector<double>& wall_dampings) {
  ScenarioLinearResult r;
  const JointPlantModel model = scenarioPlantModel(sc);
  const double q_free = sc.start_rad + sc.direction * sc.timing.free_move_rad;
  const OperatingPoint op_free = solveOperatingPoint(model, q_free);
  const OperatingPoint op_wall = solveOperatingPoint(model, wallPosition(sc));
  const PreparedJoint free_joint = prepareJoint(model, op_free, setupFor(sc, sc.delay_samples));
  const PreparedJoint wall_joint = prepareJoint(model, op_wall, setupFor(sc, sc.delay_samples));
  r.free = analyzePrepared(free_joint, sc.gains, VirtualWall{}, true);
  r.contact = analyzePrepared(wall_joint, sc.gains, wallOf(sc), true);
  r.predicted_gain_limit = std::min(r.free.gain_scale_upper, r.contact.gain_scale_upper);
  r.z_width = jointZWidth(wall_joint, sc.gains, wall_dampings);

  std::ostringstream why;
  bool stable_all = r.free.stable && r.contact.stable;
  if (!r.free.stable) why << "unstable in free motion (spectral radius " << r.free.spectral_radius << "); ";
  if (!r.contact.stable) why << "unstable against the wall (spectral radius " << r.contact.spectral_radius << "); ";
  for (int d = 1; d <= max_delay; ++d) {
    const double rf = closedLoopSpectralRadius(prepareJoint(model, op_free, setupFor(sc, d)), sc.gains, VirtualWall{});
    const double rc = closedLoopSpectralRadius(prepareJoint(model, op_wall, setupFor(sc, d)), sc.gains, wallOf(sc));
    r.delays.push_back(d);
    r.free_spectral_radius.push_back(rf);
    r.contact_spectral_radius.push_back(rc);
    // A free-position pole at z = 1 counts as stable (LinearChecks::stable).
    if (!(rf < 1.0 + kMarginalPoleTolerance) || !(rc < 1.0 + kMarginalPoleTolerance)) {
      stable_all = false;
      why << "unstable with " << d << " samples of delay (spectral radius free " << rf << ", wall " << rc << "); ";
    }
  }
  bool pass = stable_all;
  const double ms = std::max(r.free.margins.peak_sensitivity, r.contact.margins.peak_sensitivity);
  if (req.gate_peak_sensitivity && !(ms <= req.max_peak_sensitivity)) {
    pass = false;
    why << "peak sensitivity Ms " << ms << " > " << req.max_peak_sensitivity << "; ";
  }
  if (req.gate_sector && !(r.free.sector_ok && r.contact.sector_ok)) {
    pass = false;
    why << "sector condition Re L > -1 violated; ";
  }
  if (req.gate_passivity && !(r.free.passive && r.contact.passive)) {
    pass = false;
    why << "rendered impedance not passive (min Re Z "
        << std::min(r.free.min_real_impedance, r.contact.min_real_impedance) << " N m s/rad); ";
  }
  r.pass = pass;
  r.reason = why.str();
  if (r.reason.size() >= 2) r.reason.resize(r.reason.size() - 2);
  return r;
}

}  // namespace fullarm::design
