#include "arm_summary.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numbers>

#include "fullarm/arm/arm_scaling.hpp"
#include "fullarm/arm/dynamics.hpp"

namespace fullarm::app {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr std::uint64_t kReachSeed = 1;
// Half-thickness of the slab through the shoulder shown as the reach cross-section.
constexpr double kSlabHalfThickness_m = 0.02;

const char* actuatorName(const arm::ActuatorGeometry& act) {
  return act.type == arm::ActuatorGeometry::Type::kLinear ? "cylinder on lever" : "rotary";
}

std::vector<double> toVector(const Eigen::VectorXd& v) {
  return {v.data(), v.data() + v.size()};
}

}  // namespace

ArmSummary summarizeArm(const arm::ArmModel& model, const Eigen::VectorXd& q, int samples) {
  ArmSummary s;
  s.q = q;
  arm::ArmData data(model);
  arm::computeGravityTorques(model, data, q);
  s.X_WT = data.X_WT;
  s.tau_gravity = data.tau_gravity;
  for (int i = 0; i < model.numJoints(); ++i) {
    if (std::abs(s.tau_gravity[i]) > model.joints[static_cast<std::size_t>(i)].limits.torque_nm) s.holds_itself = false;
  }
  const arm::ArmSize size = arm::armSizeOf(model);
  s.upper_arm_m = size.upper_arm_length_m.value_or(0.0);
  s.forearm_m = size.forearm_length_m.value_or(0.0);
  s.hand_m = size.hand_length_m.value_or(0.0);
  s.total_mass_kg = model.totalMass();

  s.reach = arm::sampleReach(model, samples, kReachSeed);
  return s;
}

void printArmSummary(const arm::ArmModel& model, const ArmSummary& s, std::ostream& out) {
  const auto flags = out.flags();
  out << "Arm model: " << model.name << "  (" << (model.source.empty() ? "built in code" : model.source.string())
      << ")\n";
  out << "Convention: modified DH (Craig), T = Rx(alpha) Tx(a) Rz(theta) Tz(d), theta = q + offset\n\n";
  out << std::left << std::setw(7) << "joint" << std::setw(8) << "parent" << std::right << std::setw(9) << "alpha"
      << std::setw(9) << "a [m]" << std::setw(9) << "d [m]" << std::setw(9) << "offset" << std::setw(10) << "min"
      << std::setw(9) << "max" << std::setw(9) << "q" << std::setw(11) << "tau_max" << std::setw(11) << "tau_grav"
      << "  actuator\n";
  out << std::setw(7 + 8 + 9) << "[deg]" << std::setw(27) << "[deg]" << std::setw(10) << "[deg]" << std::setw(9)
      << "[deg]" << std::setw(9) << "[deg]" << std::setw(11) << "[N m]" << std::setw(11) << "[N m]"
      << "\n";
  out << std::fixed;
  for (int i = 0; i < model.numJoints(); ++i) {
    const arm::Joint& j = model.joints[static_cast<std::size_t>(i)];
    out << std::left << std::setw(7) << j.name << std::setw(8)
        << (j.parent < 0 ? "base" : model.joints[static_cast<std::size_t>(j.parent)].name) << std::right;
    if (j.dh) {
      out << std::setprecision(1) << std::setw(9) << j.dh->alpha_rad * kRadToDeg << std::setprecision(4) << std::setw(9)
          << j.dh->a_m << std::setw(9) << j.dh->d_m << std::setprecision(1) << std::setw(9)
          << j.dh->theta_offset_rad * kRadToDeg;
    } else {
      out << std::setw(36) << "(hand origin)";
    }
    out << std::setprecision(1) << std::setw(10) << j.limits.min_rad * kRadToDeg << std::setw(9)
        << j.limits.max_rad * kRadToDeg << std::setw(9) << s.q[i] * kRadToDeg << std::setw(11) << j.limits.torque_nm
        << std::setprecision(2) << std::setw(11) << s.tau_gravity[i] << "  " << actuatorName(j.actuator) << "\n";
  }
  out << std::setprecision(4) << "\nLink lengths: upper arm " << s.upper_arm_m << " m, forearm " << s.forearm_m
      << " m, hand " << s.hand_m << " m\n";
  out << std::setprecision(2) << "Total mass: " << s.total_mass_kg << " kg\n";
  out << std::setprecision(3) << "Reach (shoulder centre to hand point, largest of " << s.reach.numPostures()
      << " sampled postures): " << s.reach.reach_m << " m\n";
  const Eigen::Vector3d p = s.X_WT.translation();
  out << std::setprecision(4) << "Hand point at q: p_W = (" << p.x() << ", " << p.y() << ", " << p.z()
      << ") m, rotation rows:\n";
  for (int r = 0; r < 3; ++r) {
    out << "    [" << std::setw(8) << s.X_WT.linear()(r, 0) << " " << std::setw(8) << s.X_WT.linear()(r, 1) << " "
        << std::setw(8) << s.X_WT.linear()(r, 2) << "]\n";
  }
  out << "Gravity torques at q are " << (s.holds_itself ? "within" : "BEYOND") << " the joint torque limits.\n";
  out.flags(flags);
}

void addArmToReport(const arm::ArmModel& model, const ArmSummary& s, reports::Report& report) {
  report.addHeadlineNumber("reach_m", "Reach (sampled)", s.reach.reach_m, "m");
  report.addHeadlineNumber("total_mass_kg", "Total link mass", s.total_mass_kg, "kg");
  report.addHeadlineNumber("upper_arm_m", "Upper arm", s.upper_arm_m, "m");
  report.addHeadlineNumber("forearm_m", "Forearm", s.forearm_m, "m");

  nlohmann::json& arm = report.results()["arm"];
  arm["name"] = model.name;
  arm["source"] = model.source.string();
  arm["dh_convention"] = "modified";
  arm["num_joints"] = model.numJoints();
  arm["num_arm_joints"] = model.numArmJoints();
  arm["total_mass_kg"] = s.total_mass_kg;
  arm["upper_arm_length_m"] = s.upper_arm_m;
  arm["forearm_length_m"] = s.forearm_m;
  arm["hand_length_m"] = s.hand_m;
  arm["reach_m"] = s.reach.reach_m;
  arm["reach_samples"] = s.reach.numPostures();
  arm["q_rad"] = toVector(s.q);
  arm["hand_position_m"] = {s.X_WT.translation().x(), s.X_WT.translation().y(), s.X_WT.translation().z()};
  arm["gravity_torque_nm"] = toVector(s.tau_gravity);
  arm["holds_itself"] = s.holds_itself;
  nlohmann::json joints = nlohmann::json::array();
  for (const arm::Joint& j : model.joints) {
    joints.push_back({{"name", j.name},
                      {"min_rad", j.limits.min_rad},
                      {"max_rad", j.limits.max_rad},
                      {"default_rad", j.default_rad},
                      {"torque_limit_nm", j.limits.torque_nm},
                      {"velocity_limit_radps", j.limits.velocity_radps},
                      {"mass_kg", j.inertial.mass_kg},
                      {"actuator", actuatorName(j.actuator)}});
  }
  arm["joints"] = joints;

  reports::Section& chain = report.addSection("Kinematic chain and joint ranges");
  chain.addParagraph(
      "Modified Denavit-Hartenberg convention (Craig): T = Rx(alpha) Tx(a) Rz(theta) Tz(d), with "
      "theta = q + offset. Ranges, default posture, torque limits and sensor calibration come from "
      "the SL robot package for the DTS master arm (see config/dts_master.yaml for each source).");
  reports::Table table;
  table.caption = "Joints";
  table.columns = {"Joint",
                   "Parent",
                   "alpha [deg]",
                   "a [m]",
                   "d [m]",
                   "offset [deg]",
                   "min [deg]",
                   "max [deg]",
                   "posture [deg]",
                   "torque limit [N·m]",
                   "gravity torque [N·m]",
                   "mass [kg]",
                   "actuator"};
  table.significant_digits = 4;
  for (int i = 0; i < model.numJoints(); ++i) {
    const arm::Joint& j = model.joints[static_cast<std::size_t>(i)];
    const std::string parent = j.parent < 0 ? "base" : model.joints[static_cast<std::size_t>(j.parent)].name;
    std::vector<reports::Cell> row = {j.name, parent};
    if (j.dh) {
      row.insert(row.end(), {j.dh->alpha_rad * kRadToDeg, j.dh->a_m, j.dh->d_m, j.dh->theta_offset_rad * kRadToDeg});
    } else {
      row.insert(row.end(), {"hand", "", "", ""});
    }
    row.insert(row.end(), {j.limits.min_rad * kRadToDeg, j.limits.max_rad * kRadToDeg, s.q[i] * kRadToDeg,
                           j.limits.torque_nm, s.tau_gravity[i], j.inertial.mass_kg, actuatorName(j.actuator)});
    table.rows.push_back(std::move(row));
  }
  chain.addTable(std::move(table));

  reports::Table lengths;
  lengths.caption = "Link lengths";
  lengths.columns = {"Segment", "Length [m]", "Carried by"};
  lengths.rows = {
      {"upper arm", s.upper_arm_m,
       model.upper_arm_joint >= 0 ? "DH d of " + model.joints[static_cast<std::size_t>(model.upper_arm_joint)].name
                                  : "-"},
      {"forearm", s.forearm_m,
       model.forearm_joint >= 0 ? "DH d of " + model.joints[static_cast<std::size_t>(model.forearm_joint)].name : "-"},
      {"hand (wrist to hand point)", s.hand_m,
       "tool translation on " + model.joints[static_cast<std::size_t>(model.tool_link)].name},
  };
  chain.addTable(std::move(lengths));

  reports::Section& reach = report.addSection("Reach");
  reach.addParagraph("Hand points of " + std::to_string(s.reach.numPostures()) +
                     " postures drawn uniformly within the joint ranges (seeded). The cross-section keeps the points "
                     "within ±2 cm of the horizontal plane through the shoulder centre.");
  reports::XyChart cross;
  cross.title = "Reach cross-section (horizontal plane through the shoulder)";
  cross.x_axis = {"x", "m", false};
  cross.y_axis = {"y", "m", false};
  reports::Series slab;
  slab.name = "hand points";
  for (const Eigen::Vector3d& p : s.reach.hand_W) {
    if (std::abs(p.z() - s.reach.shoulder_W.z()) <= kSlabHalfThickness_m) {
      slab.x.push_back(p.x());
      slab.y.push_back(p.y());
    }
  }
  reports::Series shoulder;
  shoulder.name = "shoulder centre";
  shoulder.x = {s.reach.shoulder_W.x()};
  shoulder.y = {s.reach.shoulder_W.y()};
  cross.series = {slab, shoulder};
  reach.addScatterChart(std::move(cross));

  // Density of hand points seen from the side (x-z), as a 2-D histogram.
  constexpr int kBins = 40;
  double x_lo = 1e9, x_hi = -1e9, z_lo = 1e9, z_hi = -1e9;
  for (const Eigen::Vector3d& p : s.reach.hand_W) {
    x_lo = std::min(x_lo, p.x());
    x_hi = std::max(x_hi, p.x());
    z_lo = std::min(z_lo, p.z());
    z_hi = std::max(z_hi, p.z());
  }
  reports::HeatMap density;
  density.title = "Hand-point density, side view (x-z)";
  density.x_axis = {"x", "m", false};
  density.y_axis = {"z", "m", false};
  density.z_axis = {"postures per cell", "", false};
  const double dx = (x_hi - x_lo) / kBins;
  const double dz = (z_hi - z_lo) / kBins;
  for (int b = 0; b < kBins; ++b) {
    density.x.push_back(x_lo + (b + 0.5) * dx);
    density.y.push_back(z_lo + (b + 0.5) * dz);
  }
  density.z.assign(kBins, std::vector<double>(kBins, 0.0));
  for (const Eigen::Vector3d& p : s.reach.hand_W) {
    const int bx = std::clamp(static_cast<int>((p.x() - x_lo) / dx), 0, kBins - 1);
    const int bz = std::clamp(static_cast<int>((p.z() - z_lo) / dz), 0, kBins - 1);
    density.z[static_cast<std::size_t>(bz)][static_cast<std::size_t>(bx)] += 1.0;
  }
  reach.addHeatMap(std::move(density));

  reports::Section& gravity = report.addSection("Gravity load at the posture");
  reports::XyChart load;
  load.title = "Gravity torque as a fraction of the torque limit";
  load.x_axis = {"joint index", "", false};
  load.y_axis = {"|gravity torque| / torque limit", "", false};
  reports::Series frac;
  frac.name = "fraction of limit";
  frac.mode = reports::SeriesMode::kLinesMarkers;
  std::vector<std::string> labels;
  for (int i = 0; i < model.numJoints(); ++i) {
    frac.x.push_back(i + 1);
    frac.y.push_back(std::abs(s.tau_gravity[i]) / model.joints[static_cast<std::size_t>(i)].limits.torque_nm);
    labels.push_back(model.joints[static_cast<std::size_t>(i)].name);
  }
  frac.point_labels = labels;
  load.series = {frac};
  gravity.addLineChart(std::move(load));
}

}  // namespace fullarm::app
