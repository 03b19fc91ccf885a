#include "fullarm/accessibility/population_reach.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <stdexcept>

#include "fullarm/accessibility/ik.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/haptics/query.hpp"

namespace fullarm::accessibility {
namespace {

std::size_t modeSlot(ReachMode mode) {
  switch (mode) {
    case ReachMode::kFree:
      return 0;
    case ReachMode::kContactAllowed:
      return 1;
    case ReachMode::kHandOnly:
      return 2;
  }
  return 0;
}

// A program's push as a number: the optimum, +infinity when no torque limit bounds it, NaN when
// there is none (the arm cannot hold the posture).
double pushValue(const ForceLpResult& r) {
  if (r.status == ForceStatus::kOptimal) return r.push_n;
  if (r.status == ForceStatus::kUnbounded) return std::numeric_limits<double>::infinity();
  return std::numeric_limits<double>::quiet_NaN();
}

// The larger of two pushes, NaN only when both are.
double betterPush(double a, double b) {
  if (std::isnan(a)) return b;
  if (std::isnan(b)) return a;
  return std::max(a, b);
}

// The goal candidates of a repair, nearest first: the nominal swivel and roll, then swivels
// 5, 10 and 20 degrees to either side, each with the hand rolled 0, +-30 and +-60 degrees about its
// pointing axis.
struct RepairGoalOffset {
  double swivel_rad = 0.0;
  double roll_rad = 0.0;
};

const std::vector<RepairGoalOffset>& repairGoalOffsets() {
  static const std::vector<RepairGoalOffset> offsets = [] {
    constexpr double kDeg = std::numbers::pi / 180.0;
    std::vector<RepairGoalOffset> out;
    for (const double roll : {0.0, 30.0, -30.0, 60.0, -60.0}) {
      for (const double swivel : {0.0, 5.0, -5.0, 10.0, -10.0, 20.0, -20.0}) {
        out.push_back({swivel * kDeg, roll * kDeg});
      }
    }
    std::stable_sort(out.begin(), out.end(), [](const RepairGoalOffset& a, const RepairGoalOffset& b) {
      return std::abs(a.swivel_rad) + std::abs(a.roll_rad) < std::abs(b.swivel_rad) + std::abs(b.roll_rad);
    });
    return out;
  }();
  return offsets;
}

}  // namespace

const ReachResult& NominalReach::result(ReachMode mode) const noexcept {
  switch (mode) {
    case ReachMode::kFree:
      return study.free;
    case ReachMode::kContactAllowed:
      return study.contact;
    case ReachMode::kHandOnly:
      return study.hand_only;
  }
  return study.free;
}

const TechnicianReach& TechnicianOutcome::reachIn(ReachMode mode) const noexcept {
  return reach[modeSlot(mode)];
}

const char* reachSourceName(ReachSource source) noexcept {
  return source == ReachSource::kRepaired ? "repaired" : "fresh";
}

NominalReach planNominalReach(const PopulationTask& task) {
  if (task.model == nullptr || task.scene == nullptr)
    throw std::invalid_argument("planNominalReach: no model or scene");
  const haptics::Scene& scene = *task.scene;
  if (scene.posture("rest") == nullptr) {
    throw core::ConfigError(scene.source, "arm.postures", "the scene has no posture 'rest' (the start of the reach)");
  }
  const haptics::CollisionWorld world = haptics::makeCollisionWorld(scene, *task.model);
  NominalReach n;
  n.target = resolveTarget(scene, *task.model, task.target);
  n.q_start = haptics::scenePosture(scene, "rest", *task.model);
  ReachProblem p;
  p.model = task.model;
  p.world = &world;
  p.params = task.params;
  p.q_start = n.q_start;
  p.target = n.target;
  n.study = studyReach(p, task.reach);
  return n;
}

std::vector<Eigen::VectorXd> repairPath(ReachChecker& checker, ReachMode mode, const GraspTarget& target,
                                        const arm::ArmModel& nominal_model,
                                        const std::vector<Eigen::VectorXd>& nominal_path, const ReachOptions& options,
                                        long repair_iterations) {
  const arm::ArmModel& model = checker.model();
  if (nominal_path.size() < 2) return {};
  // The goal: the nominal goal's hand orientation and swivel angle on the technician's arm,
  // else the nearest of the neighbouring swivels and rolls that gives a valid goal.
  arm::ArmData fk_nominal(nominal_model);
  arm::computeForwardKinematics(nominal_model, fk_nominal, nominal_path.back());
  const Eigen::Matrix3d R_W = fk_nominal.X_WL[static_cast<std::size_t>(nominal_model.tool_link)].linear();
  const Eigen::Vector3d pointing_W = R_W.col(0);
  const double swivel = swivelAngle(fk_nominal);
  arm::ArmData fk(model);
  IkSolution goal;
  for (const RepairGoalOffset& offset : repairGoalOffsets()) {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(offset.roll_rad, pointing_W).toRotationMatrix() * R_W;
    IkSolution candidate =
        solveIk(model, fk, target.position_W_m, R, swivel + offset.swivel_rad, nominal_path.back(), options.ik);
    if (candidate.converged && checker.check(candidate.q_rad).valid(mode)) {
      goal = std::move(candidate);
      break;
    }
  }
  if (!goal.converged) return {};

  std::vector<Eigen::VectorXd> waypoints = nominal_path;
  waypoints.back() = goal.q_rad;
  std::vector<bool> valid(waypoints.size());
  for (std::size_t i = 0; i < waypoints.size(); ++i) valid[i] = checker.check(waypoints[i]).valid(mode);
  if (!valid.front() || !valid.back()) return {};

  const double step = motionStep(model, options.motion_resolution);
  ReachOptions local = options;
  local.max_iterations = repair_iterations;
  std::vector<Eigen::VectorXd> path{waypoints.front()};
  std::size_t a = 0;
  while (a + 1 < waypoints.size()) {
    std::size_t b = a + 1;
    while (!valid[b]) ++b;  // the last waypoint is valid
    if (b == a + 1 && motionValid(checker, mode, waypoints[a], waypoints[b], step)) {
      path.push_back(waypoints[b]);
    } else {
      const std::vector<Eigen::VectorXd> stretch = planBetween(checker, mode, waypoints[a], waypoints[b], local);
      if (stretch.empty()) return {};
      path.insert(path.end(), stretch.begin() + 1, stretch.end());
    }
    a = b;
  }
  return path;
}

TechnicianOutcome evaluateTechnician(const PopulationTask& task, const NominalReach& nominal,
                                     const Technician& technician, std::uint32_t seed, ReachStrategy strategy) {
  if (task.model == nullptr || task.scene == nullptr) {
    throw std::invalid_argument("evaluateTechnician: no model or scene");
  }
  TechnicianOutcome out;
  out.technician = technician;
  const arm::ArmModel model = technicianArm(*task.model, technician);
  const HumanArm human = technicianStrength(task.human, technician);
  const haptics::CollisionWorld world = haptics::makeCollisionWorld(*task.scene, model);
  ReachProblem problem;
  problem.model = &model;
  problem.world = &world;
  problem.params = task.params;
  problem.q_start = nominal.q_start;
  problem.target = resolveTarget(*task.scene, model, task.target);
  ReachOptions options = task.reach;
  options.seed = seed;

  // Repair where the nominal arm reached.
  std::array<bool, kReachModes> answered{};
  if (strategy == ReachStrategy::kRepair) {
    ReachChecker checker(model, world, task.params, options.limits, problem.target.object_index);
    for (std::size_t m = 0; m < kReachModes; ++m) {
      const ReachMode mode = kReachModeOrder[m];
      TechnicianReach& r = out.reach[m];
      r.mode = mode;
      const ReachResult& nominal_result = nominal.result(mode);
      if (nominal_result.verdict != Verdict::kReachable) continue;
      r.path =
          repairPath(checker, mode, problem.target, *task.model, nominal_result.path, options, task.repair_iterations);
      if (r.path.empty()) continue;
      r.verdict = Verdict::kReachable;
      r.source = ReachSource::kRepaired;
      answered[m] = true;
    }
  }
  // Afresh elsewhere: one mode alone, several sharing the goal sweep.
  const auto missing = static_cast<int>(std::count(answered.begin(), answered.end(), false));
  if (missing > 0) {
    ReachStudy fresh;
    if (missing == 1) {
      const auto m = static_cast<std::size_t>(std::find(answered.begin(), answered.end(), false) - answered.begin());
      const ReachResult r = planReach(problem, kReachModeOrder[m], options);
      (m == 0 ? fresh.free : m == 1 ? fresh.contact : fresh.hand_only) = r;
    } else {
      fresh = studyReach(problem, options);
    }
    for (std::size_t m = 0; m < kReachModes; ++m) {
      if (answered[m]) continue;
      const ReachResult& r = m == 0 ? fresh.free : m == 1 ? fresh.contact : fresh.hand_only;
      out.reach[m] = TechnicianReach{kReachModeOrder[m], r.verdict, ReachSource::kFresh, r.path};
    }
  }

  // The push at the reached grasp (contact allowed) and at the brace posture.
  const TechnicianReach& contact = out.reachIn(ReachMode::kContactAllowed);
  if (contact.verdict == Verdict::kReachable) {
    const std::unique_ptr<haptics::GlobalSearch> search = haptics::makeGlobalSearch(haptics::SearchKind::kSnch, world);
    BraceSearchOptions bo = task.brace;
    bo.seed = seed;
    const BraceSearchResult brace =
        searchBracePosture(model, human, world, *search, task.params, contact.path.back(), problem.target.push_W, bo);
    out.push_analysed = true;
    out.push_braced_n = pushValue(brace.best.braced);
    out.push_unbraced_n = betterPush(pushValue(brace.start.unbraced), pushValue(brace.best.unbraced));
    out.push_braced_ok = out.push_braced_n >= task.required_force_n;
    out.push_unbraced_ok = out.push_unbraced_n >= task.required_force_n;
  }
  return out;
}

}  // namespace fullarm::accessibility
