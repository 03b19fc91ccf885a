#include "fullarm/identification/identified_plant.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "fullarm/identification/joint_groups.hpp"
#include "fullarm/plant/hydraulics.hpp"

namespace fullarm::identification {
namespace {

constexpr double kStructureTolerance = 1.0e-3;

std::string text(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

[[noreturn]] void refuse(const plant::JointParams& joint, const std::string& what) {
  throw std::invalid_argument("identified model of " + joint.name + ": " + what);
}

// The fixed structure must be the start joint's: otherwise the groups were identified on
// another valve or actuator and cannot be carried by this joint's parameters. It is compared to
// 0.1 %: a fit started from the joint at a slightly different angle (a cylinder's moment arm
// changes with it) has the same valve.
void checkStructure(const plant::JointParams& start, const GreyModel& groups, const GreyModel& own) {
  const auto same = [](double a, double b) {
    return std::abs(a - b) <= kStructureTolerance * std::max({std::abs(a), std::abs(b), 1e-12});
  };
  const struct {
    const char* name;
    double identified, plant;
  } items[] = {{"stall torque [N m]", groups.stall_torque_nm, own.stall_torque_nm},
               {"underlap [V]", groups.underlap_v, own.underlap_v},
               {"edge rounding [V]", groups.edge_rounding_v, own.edge_rounding_v},
               {"spool natural frequency [Hz]", groups.spool_hz, own.spool_hz},
               {"spool damping ratio", groups.spool_damping, own.spool_damping},
               {"load-cell filter [Hz]", groups.torque_filter_hz, own.torque_filter_hz}};
  for (const auto& item : items) {
    if (!same(item.identified, item.plant)) {
      refuse(start, std::string("its ") + item.name + " is " + text(item.identified) + " but the plant joint's is " +
                        text(item.plant) + ": expected a model identified on this joint's valve and actuator");
    }
  }
}

}  // namespace

IdentifiedPlantJoint plantJointWithGroups(const plant::JointParams& start, const GreyModel& groups, double q_rad,
                                          double link_inertia_kgm2) {
  if (start.actuator.kind == plant::ActuatorKind::kIdealTorque) refuse(start, "the plant joint has no hydraulics");
  const auto& v = groups.value;
  for (const int i : {kFlowGain, kStiffness, kInertia}) {
    const double x = v[static_cast<std::size_t>(i)];
    if (!(std::isfinite(x) && x > 0.0))
      refuse(start, std::string(greyParamName(i)) + " is " + text(x) + ": expected > 0");
  }
  for (const int i : {kLeakage, kViscous, kCoulomb, kStribeck}) {
    const double x = v[static_cast<std::size_t>(i)];
    if (!(std::isfinite(x) && x >= 0.0))
      refuse(start, std::string(greyParamName(i)) + " is " + text(x) + ": expected >= 0");
  }
  const GreyModel own = greyModelFromJoint(start, q_rad, link_inertia_kgm2, 0.0, groups.delay_samples);
  checkStructure(start, groups, own);

  plant::JointParams p = start;
  // Flow gain: the valve coefficient, hence a, is proportional to the rated flow.
  p.valve.rated_flow_m3ps = start.valve.rated_flow_m3ps * v[kFlowGain] / own.value[kFlowGain];

  // Hydraulic stiffness: both dead volumes scaled by one factor s; K_h(s) falls monotonically
  // from the swept volume's alone (s -> 0) towards zero. Bisection on log s.
  const double p_mean = 0.5 * (start.supply_pressure_pa + start.return_pressure_pa);
  const auto stiffness = [&](double s) {
    plant::JointParams t = start;
    t.chambers.dead_volume_a_m3 = s * start.chambers.dead_volume_a_m3;
    t.chambers.dead_volume_b_m3 = s * start.chambers.dead_volume_b_m3;
    return plant::hydraulicStiffness(t, q_rad, p_mean);
  };
  const double target = v[kStiffness];
  constexpr double kMinScale = 1.0e-6, kMaxScale = 1.0e6;
  if (target >= stiffness(kMinScale)) {
    refuse(start, "hydraulic_stiffness_nm_per_rad is " + text(target) + " N m/rad, above the " +
                      text(stiffness(kMinScale)) + " N m/rad the actuator's swept volume alone gives at " +
                      text(q_rad) +
                      " rad: expected the bulk modulus or the actuator to change, which this mapping keeps");
  }
  if (target <= stiffness(kMaxScale)) {
    refuse(start, "hydraulic_stiffness_nm_per_rad is " + text(target) + " N m/rad, below the " +
                      text(stiffness(kMaxScale)) +
                      " N m/rad of dead volumes 1e6 times the plant's: expected a stiffness "
                      "within the dead volumes' reach");
  }
  double lo = std::log(kMinScale), hi = std::log(kMaxScale);
  for (int k = 0; k < 200 && hi - lo > 1e-15; ++k) {
    const double mid = 0.5 * (lo + hi);
    (stiffness(std::exp(mid)) > target ? lo : hi) = mid;
  }
  const double scale = std::exp(0.5 * (lo + hi));
  p.chambers.dead_volume_a_m3 = scale * start.chambers.dead_volume_a_m3;
  p.chambers.dead_volume_b_m3 = scale * start.chambers.dead_volume_b_m3;

  // Leakage: c = C_i / D^2 at q (D from the flow gain's own ratio: a D = k_a K_q).
  const double d = start.valve.amplifier_gain_per_v * plant::noLoadFlowGain(start) / own.value[kFlowGain];
  p.chambers.internal_leakage_m3ps_per_pa = v[kLeakage] * d * d;

  // Inertia: the actuator's share, the link's being the arm model's.
  std::vector<std::string> notes;
  double actuator_inertia = v[kInertia] - link_inertia_kgm2;
  if (actuator_inertia < -kInertiaBelowLinkTolerance * link_inertia_kgm2) {
    refuse(start, "inertia_kgm2 is " + text(v[kInertia]) + " kg m^2, below the link's own " + text(link_inertia_kgm2) +
                      " kg m^2 (arm model at " + text(q_rad) + " rad) by more than " +
                      text(100.0 * kInertiaBelowLinkTolerance) +
                      " %: expected at least the link's inertia, or an arm model with a lighter link");
  }
  if (actuator_inertia < 0.0) {
    notes.push_back("inertia_kgm2 " + text(v[kInertia]) + " kg m^2 is " +
                    text(100.0 * -actuator_inertia / link_inertia_kgm2) + " % below the link's own " +
                    text(link_inertia_kgm2) + " kg m^2 (arm model), which the plant keeps: actuator inertia set to 0");
    actuator_inertia = 0.0;
  }
  p.actuator.inertia_kgm2 = actuator_inertia;

  p.friction.viscous_nms_per_rad = v[kViscous];
  p.friction.coulomb_nm = v[kCoulomb];
  p.friction.static_nm = v[kCoulomb] + v[kStribeck];
  return {p, notes};
}

}  // namespace fullarm::identification
