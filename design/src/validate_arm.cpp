#include "fullarm/design/validate_arm.hpp"

#include <algorithm>
#include <chrono>
#include <iomanip>
#include <sstream>
#include <thread>

namespace fullarm::design {
namespace {

// The model names of `names` (short or model names) in the gains file; every joint when empty.
std::vector<std::string> modelNames(const controllers::GainsConfig& gains, const std::vector<std::string>& names) {
  std::vector<std::string> out;
  if (names.empty()) {
    for (const controllers::JointGains& g : gains.joints) out.push_back(g.name);
    return out;
  }
  for (const std::string& n : names) {
    out.push_back(gains.joints[static_cast<std::size_t>(controllers::findGainsJoint(gains, n))].name);
  }
  return out;
}

}  // namespace

bool ArmValidationResult::pass() const noexcept {
  return !joints.empty() &&
         std::all_of(joints.begin(), joints.end(), [](const JointValidationResult& j) { return j.pass; });
}

std::string describeVariation(const ModelVariation& s) {
  std::ostringstream os;
  os << std::setprecision(3) << "bulk modulus x" << s.bulk_modulus_scale << ", valve gain x" << s.valve_gain_scale
     << ", friction x" << s.friction_scale << ", inertia x" << s.inertia_scale << ", user K "
     << s.user_stiffness_nm_per_rad << " N m/rad, B " << s.user_damping_nms_per_rad << " N m s/rad, delay "
     << s.delay_samples;
  return os.str();
}

ArmValidationResult validateArm(const arm::ArmModel& model, const plant::PlantConfig& plant_config,
                                const controllers::GainsConfig& gains, const ValidationConfig& config,
                                const ArmValidationOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<std::string> joint_names = modelNames(gains, options.joints);
  const std::vector<std::string> claim_joints =
      options.paper_claim ? modelNames(gains, options.paper_claim_joints) : std::vector<std::string>{};
  ArmValidationResult out;
  out.config = config;
  out.gains_source = gains.source;
  out.threads =
      options.threads > 0 ? options.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::vector<JointScenario> nominal;
  for (const std::string& name : joint_names) {
    nominal.push_back(validationScenario(makeJointScenario(model, plant_config, gains, name), config));
  }
  out.joints.resize(nominal.size());
  const std::vector<double> z_width_dampings(std::begin(kValidationZWidthDampings),
                                             std::end(kValidationZWidthDampings));
  // Linear checks and (optionally) the paper-claim measurement, one job per joint.
  core::Progress& progress = core::progressOrQuiet(options.progress);
  progress.begin(options.paper_claim ? "validate: linear checks and paper claim" : "validate: linear checks",
                 nominal.size());
  parallelFor(static_cast<int>(nominal.size()), out.threads, [&](int j) {
    JointValidationResult& o = out.joints[static_cast<std::size_t>(j)];
    o.nominal = nominal[static_cast<std::size_t>(j)];
    o.linear = analyzeScenario(o.nominal, config.linear, config.ranges.delay_max_samples, z_width_dampings);
    if (std::find(claim_joints.begin(), claim_joints.end(), o.nominal.joint_name) != claim_joints.end()) {
      o.claim = measurePaperClaim(o.nominal);
      o.has_claim = true;
    }
    progress.step(o.nominal.joint_name + (o.linear.pass ? ": linear checks pass" : ": linear checks FAIL"));
  });
  progress.end();
  const auto t1 = std::chrono::steady_clock::now();
  const std::vector<JointMonteCarlo> mc = runMonteCarlo(nominal, config, out.threads, options.progress);
  out.monte_carlo_wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  for (std::size_t j = 0; j < nominal.size(); ++j) {
    JointValidationResult& o = out.joints[j];
    o.monte_carlo = mc[j];
    const MonteCarloRun& worst = o.monte_carlo.runs[static_cast<std::size_t>(o.monte_carlo.worst)];
    o.worst_result = simulateJoint(variationScenario(nominal[j], worst.sample), &o.worst_trace);
    o.pass = o.linear.pass && o.monte_carlo.pass();
    std::ostringstream v;
    if (!o.linear.pass) v << "linear: " << o.linear.reason << ". ";
    if (!o.monte_carlo.pass()) {
      v << "Monte-Carlo: " << o.monte_carlo.failures << " of " << o.monte_carlo.runs.size()
        << " runs failed; worst run #" << worst.sample.index << " (" << describeVariation(worst.sample)
        << "): " << worst.result.failure;
    }
    o.verdict = o.pass ? "pass" : v.str();
  }
  out.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace fullarm::design
