#include "fullarm/accessibility/reach.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <ompl/base/PlannerData.h>
#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/ProjectionEvaluator.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/goals/GoalStates.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/datastructures/NearestNeighborsLinear.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/geometric/planners/sbl/SBL.h>
#include <ompl/util/Console.h>

#include "fullarm/arm/kinematics.hpp"

namespace fullarm::accessibility {
namespace {

namespace ob = ompl::base;
namespace og = ompl::geometric;

constexpr int kArm = 7;
constexpr int kWristLink = 5;
constexpr double kProjectionCell_m = 0.05;
constexpr double kCheckTick_s = 1e-3;  // one haptic tick: the springs of a posture at rest

// Sampler and planners seeded per query: OMPL's global seed works only before the first RNG
// exists and is shared by the whole process, so each RNG here gets its own seed.
class SeededSampler : public ob::RealVectorStateSampler {
 public:
  SeededSampler(const ob::StateSpace* space, std::uint32_t seed) : ob::RealVectorStateSampler(space) {
    rng_.setLocalSeed(seed);
  }
};

class SeededRrtConnect : public og::RRTConnect {
 public:
  SeededRrtConnect(const ob::SpaceInformationPtr& si, std::uint32_t seed) : og::RRTConnect(si) {
    rng_.setLocalSeed(seed);
    setNearestNeighbors<ompl::NearestNeighborsLinear>();  // exact, no random pivots
  }
};

class SeededSbl : public og::SBL {
 public:
  SeededSbl(const ob::SpaceInformationPtr& si, std::uint32_t seed) : og::SBL(si) { rng_.setLocalSeed(seed); }
};

Eigen::VectorXd fullConfiguration(const Eigen::VectorXd& base, const ob::State* s) {
  Eigen::VectorXd q = base;
  const double* v = s->as<ob::RealVectorStateSpace::StateType>()->values;
  for (int j = 0; j < kArm; ++j) q[j] = v[j];
  return q;
}

void setState(ob::State* s, const Eigen::VectorXd& q) {
  double* v = s->as<ob::RealVectorStateSpace::StateType>()->values;
  for (int j = 0; j < kArm; ++j) v[j] = q[j];
}

// The wrist point in the world: a 3D projection in which SBL's grid cells mean the same at the
// shoulder and at the hand.
class WristProjection : public ob::ProjectionEvaluator {
 public:
  WristProjection(const ob::StateSpacePtr& space, const arm::ArmModel& model, Eigen::VectorXd q_base)
      : ob::ProjectionEvaluator(space), model_(model), q_base_(std::move(q_base)), fk_(model) {}
  unsigned int getDimension() const override { return 3; }
  void defaultCellSizes() override { cellSizes_.assign(3, kProjectionCell_m); }
  void project(const ob::State* state, Eigen::Ref<Eigen::VectorXd> projection) const override {
    arm::computeForwardKinematics(model_, fk_, fullConfiguration(q_base_, state));
    projection = fk_.o_W[kWristLink];
  }

 private:
  const arm::ArmModel& model_;
  Eigen::VectorXd q_base_;
  mutable arm::ArmData fk_;
};

bool validIn(const PostureCheck& c, ReachMode mode) {
  return c.valid(mode);
}

std::string formatM(double v) {
  std::ostringstream s;
  s.precision(3);
  s << v * 1e3 << " mm";
  return s.str();
}

struct Goals {
  std::vector<IkSolution> solutions;
  std::vector<PostureCheck> checks;
};

Goals sweepGoals(const ReachProblem& p, ReachChecker& checker, const ReachOptions& options) {
  Goals g;
  g.solutions = sweepGoalConfigurations(*p.model, p.target, p.q_start, options.ik);
  g.checks.reserve(g.solutions.size());
  for (const IkSolution& s : g.solutions) g.checks.push_back(checker.check(s.q_rad));
  return g;
}

// How far a check is from valid in `mode` (0: valid), used to pick the goal that came closest:
// metres short of the distance limit, plus 1 mm per newton above the force limit.
double violation(const PostureCheck& c, const std::vector<int>& links, const arm::ArmModel& model,
                 const ReachLimits& lim, double d_f, ReachMode mode, int& worst_link) {
  double worst = 0.0;
  worst_link = -1;
  for (int l : links) {
    const auto i = static_cast<std::size_t>(l);
    double v = 0.0;
    if (mode == ReachMode::kContactAllowed) {
      v = std::max(d_f - lim.max_skin_depth_m - c.link_distance_m[i], 0.0) +
          std::max(c.link_force_n[i] - lim.max_link_force_n, 0.0) * 1e-3;
    } else if (mode == ReachMode::kFree || haptics::isHandLink(model, l)) {
      v = std::max(lim.clearance_margin_m - c.link_distance_m[i], 0.0);
    }
    if (v > worst) {
      worst = v;
      worst_link = l;
    }
  }
  return worst;
}

// The space of the seven arm joints in their limits, the seeded sampler and `checker`'s
// validity in `mode` (the other joints at `q_base`'s values).
ob::SpaceInformationPtr makeSpaceInformation(ReachChecker& checker, ReachMode mode, const Eigen::VectorXd& q_base,
                                             const ReachOptions& options) {
  const arm::ArmModel& model = checker.model();
  auto space = std::make_shared<ob::RealVectorStateSpace>(kArm);
  ob::RealVectorBounds bounds(kArm);
  const Eigen::VectorXd lo = model.lowerLimits();
  const Eigen::VectorXd hi = model.upperLimits();
  for (int j = 0; j < kArm; ++j) {
    bounds.setLow(static_cast<unsigned>(j), lo[j]);
    bounds.setHigh(static_cast<unsigned>(j), hi[j]);
  }
  space->setBounds(bounds);
  const std::uint32_t seed = options.seed;
  space->setStateSamplerAllocator([seed](const ob::StateSpace* s) { return std::make_shared<SeededSampler>(s, seed); });
  auto si = std::make_shared<ob::SpaceInformation>(space);
  si->setStateValidityChecker(
      [&checker, q_base, mode](const ob::State* s) { return checker.check(fullConfiguration(q_base, s)).valid(mode); });
  si->setStateValidityCheckingResolution(options.motion_resolution);
  si->setup();
  return si;
}

// The planner of `options`, seeded with its seed.
ob::PlannerPtr makePlanner(const ob::SpaceInformationPtr& si, const arm::ArmModel& model, const Eigen::VectorXd& q_base,
                           const ReachOptions& options) {
  if (options.planner == ReachPlanner::kSbl) {
    auto sbl = std::make_shared<SeededSbl>(si, options.seed);
    sbl->setProjectionEvaluator(std::make_shared<WristProjection>(si->getStateSpace(), model, q_base));
    return sbl;
  }
  return std::make_shared<SeededRrtConnect>(si, options.seed);
}

ReachResult planWithGoals(const ReachProblem& p, ReachMode mode, const ReachOptions& options, const Goals& goals,
                          ReachChecker& checker) {
  const arm::ArmModel& model = *p.model;
  ReachResult r;
  r.mode = mode;
  r.links = checker.geometryLinks();
  const long checks_before = checker.checks();
  GoalCertificate& cert = r.goals;
  cert.swivel_samples = options.ik.swivel_samples;
  cert.roll_samples = options.ik.roll_samples;
  cert.swivel_step_deg = 360.0 / options.ik.swivel_samples;
  cert.roll_step_deg = 360.0 / options.ik.roll_samples;
  cert.solved = static_cast<int>(goals.solutions.size());
  std::vector<std::size_t> valid_goals;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < goals.checks.size(); ++i) {
    if (validIn(goals.checks[i], mode)) {
      valid_goals.push_back(i);
      continue;
    }
    int link = -1;
    const double v = violation(goals.checks[i], r.links, model, options.limits, p.params.force_threshold_m, mode, link);
    if (v < best && link >= 0) {
      best = v;
      cert.closest_link = model.joints[static_cast<std::size_t>(link)].name;
      cert.closest_distance_m = goals.checks[i].link_distance_m[static_cast<std::size_t>(link)];
      cert.closest_force_n = goals.checks[i].link_force_n[static_cast<std::size_t>(link)];
    }
  }
  cert.valid = static_cast<int>(valid_goals.size());
  if (!valid_goals.empty()) cert.closest_link.clear();

  std::ostringstream why;
  if (valid_goals.empty()) {
    r.verdict = Verdict::kUnreachable;
    why << "no valid goal configuration: " << cert.solved << " solved over " << cert.swivel_samples << " swivel x "
        << cert.roll_samples << " roll samples (" << cert.swivel_step_deg << " x " << cert.roll_step_deg
        << " degree steps)";
    if (!cert.closest_link.empty()) {
      why << "; closest: link " << cert.closest_link << " at " << formatM(cert.closest_distance_m) << ", "
          << cert.closest_force_n << " N";
    }
    r.reason = why.str();
    r.checks = checker.checks() - checks_before;
    return r;
  }
  const PostureCheck start_check = checker.check(p.q_start);
  if (!validIn(start_check, mode)) {
    r.verdict = Verdict::kUnknown;
    r.reason = "the start posture is not valid in this mode";
    r.checks = checker.checks() - checks_before;
    return r;
  }

  // The planner over the seven arm joints.
  const Eigen::VectorXd q_base = p.q_start;
  const std::uint32_t seed = options.seed;
  const ob::SpaceInformationPtr si = makeSpaceInformation(checker, mode, q_base, options);
  const ob::StateSpacePtr space = si->getStateSpace();

  auto pdef = std::make_shared<ob::ProblemDefinition>(si);
  ob::ScopedState<> start(space);
  setState(start.get(), p.q_start);
  pdef->addStartState(start);
  auto goal = std::make_shared<ob::GoalStates>(si);
  for (std::size_t i : valid_goals) {
    ob::ScopedState<> g(space);
    setState(g.get(), goals.solutions[i].q_rad);
    goal->addState(g);
  }
  pdef->setGoal(goal);

  const ob::PlannerPtr planner = makePlanner(si, model, q_base, options);
  r.planner = reachPlannerName(options.planner);
  planner->setProblemDefinition(pdef);
  planner->setup();
  long evaluations = 0;
  const long budget = options.max_iterations;
  const ob::PlannerTerminationCondition ptc([&evaluations, budget] { return ++evaluations > budget; });
  const ob::PlannerStatus status = planner->solve(ptc);
  r.iterations = std::min(evaluations, budget);

  if (status == ob::PlannerStatus::EXACT_SOLUTION) {
    r.verdict = Verdict::kReachable;
    const auto path = pdef->getSolutionPath()->as<og::PathGeometric>();
    for (std::size_t i = 0; i < path->getStateCount(); ++i) {
      r.path.push_back(fullConfiguration(q_base, path->getState(static_cast<unsigned>(i))));
    }
    // Profile along the path at the motion resolution.
    r.path_min_distance_m.assign(r.links.size(), std::numeric_limits<double>::infinity());
    r.path_max_force_n.assign(r.links.size(), 0.0);
    const double step = options.motion_resolution * space->getMaximumExtent();
    for (std::size_t i = 0; i < r.path.size(); ++i) {
      const int n = i + 1 < r.path.size()
                        ? std::max(1, static_cast<int>(std::ceil((r.path[i + 1] - r.path[i]).norm() / step)))
                        : 1;
      for (int k = 0; k < n; ++k) {
        const Eigen::VectorXd q = i + 1 < r.path.size()
                                      ? Eigen::VectorXd(r.path[i] + (r.path[i + 1] - r.path[i]) * (double(k) / n))
                                      : r.path[i];
        const PostureCheck c = checker.check(q);
        for (std::size_t l = 0; l < r.links.size(); ++l) {
          const auto li = static_cast<std::size_t>(r.links[l]);
          r.path_min_distance_m[l] = std::min(r.path_min_distance_m[l], c.link_distance_m[li]);
          r.path_max_force_n[l] = std::max(r.path_max_force_n[l], c.link_force_n[li]);
        }
      }
    }
    why << "path of " << r.path.size() << " states to one of " << cert.valid << " valid goal configurations, found by "
        << r.planner << " in " << r.iterations << " of " << budget << " iterations";
  } else {
    r.verdict = Verdict::kUnknown;
    ob::PlannerData data(si);
    planner->getPlannerData(data);
    double closest = std::numeric_limits<double>::infinity();
    for (unsigned i = 0; i < data.numVertices(); ++i) {
      const ob::PlannerDataVertex& v = data.getVertex(i);
      if (v.getTag() == 2) continue;  // RRT-Connect's goal tree
      closest = std::min(closest,
                         (checker.handPoint(fullConfiguration(q_base, v.getState())) - p.target.position_W_m).norm());
    }
    r.closest_approach_m = closest;
    why << "iteration budget of " << budget << " ran out (" << r.planner << ", seed " << seed << ") with " << cert.valid
        << " valid goal configurations; closest approach of the hand to the target " << formatM(closest);
  }
  r.reason = why.str();
  r.checks = checker.checks() - checks_before;
  return r;
}

void validateOptions(const ReachOptions& options, const haptics::HapticsParams& params) {
  validateReachLimits(options.limits, params.force_threshold_m);
  if (options.max_iterations < 1) throw ReachInputError("reach: max_iterations must be at least 1");
  if (!(options.motion_resolution > 0.0 && options.motion_resolution < 0.1)) {
    throw ReachInputError("reach: motion_resolution must lie in (0, 0.1)");
  }
  if (options.ik.swivel_samples < 1 || options.ik.roll_samples < 1) {
    throw ReachInputError("reach: the goal sweep needs at least one swivel and one roll sample");
  }
}

}  // namespace

const char* reachModeName(ReachMode mode) noexcept {
  switch (mode) {
    case ReachMode::kFree:
      return "free";
    case ReachMode::kContactAllowed:
      return "contact-allowed";
    case ReachMode::kHandOnly:
      return "hand-only";
  }
  return "?";
}

const char* reachPlannerName(ReachPlanner planner) noexcept {
  return planner == ReachPlanner::kSbl ? "sbl" : "rrt-connect";
}

const char* verdictName(Verdict verdict) noexcept {
  switch (verdict) {
    case Verdict::kReachable:
      return "reachable";
    case Verdict::kUnreachable:
      return "unreachable";
    case Verdict::kUnknown:
      return "unknown";
  }
  return "?";
}

void validateReachLimits(const ReachLimits& limits, double force_threshold_m) {
  const auto check = [](double v, const char* name) {
    if (!std::isfinite(v) || v < 0.0) {
      std::ostringstream s;
      s << "reach limits: " << name << " must be a finite value >= 0, got " << v;
      throw ReachInputError(s.str());
    }
  };
  check(limits.clearance_margin_m, "clearance_margin_m");
  check(limits.max_link_force_n, "max_link_force_n");
  check(limits.max_skin_depth_m, "max_skin_depth_m");
  if (limits.max_skin_depth_m >= force_threshold_m) {
    std::ostringstream s;
    s << "reach limits: max_skin_depth_m " << limits.max_skin_depth_m << " m must lie below the force threshold d_f "
      << force_threshold_m << " m (deeper, the link would touch the surface)";
    throw ReachInputError(s.str());
  }
}

bool PostureCheck::valid(ReachMode mode) const noexcept {
  switch (mode) {
    case ReachMode::kFree:
      return valid_free;
    case ReachMode::kContactAllowed:
      return valid_contact;
    case ReachMode::kHandOnly:
      return valid_hand_only;
  }
  return false;
}

ReachChecker::ReachChecker(const arm::ArmModel& model, const haptics::CollisionWorld& world,
                           const haptics::HapticsParams& params, const ReachLimits& limits, int grasp_object)
    : model_(model),
      world_(world),
      params_(params),
      limits_(limits),
      fk_(model),
      contact_(model, 512),
      grasp_object_(grasp_object) {
  params_.mode = haptics::RenderMode::kFullArm;
  for (int l = 0; l < model.numJoints(); ++l) {
    if (world.linkShape(l) != haptics::LinkShape::kNone) links_.push_back(l);
  }
  cutoff_m_ = std::max(limits.clearance_margin_m, params.force_threshold_m) + 0.005;
}

Eigen::Vector3d ReachChecker::handPoint(const Eigen::VectorXd& q) {
  arm::computeForwardKinematics(model_, fk_, q);
  return fk_.X_WT.translation();
}

PostureCheck ReachChecker::check(const Eigen::VectorXd& q) {
  ++checks_;
  arm::computeForwardKinematics(model_, fk_, q);
  world_.globalSearch(fk_, cutoff_m_, params_.prune_radius_m, minima_);
  if (grasp_object_ >= 0) {
    std::erase_if(minima_, [this](const haptics::LocalMinimum& m) {
      return m.object == grasp_object_ && haptics::isHandLink(model_, m.link);
    });
  }
  const auto n = static_cast<std::size_t>(model_.numJoints());
  PostureCheck c;
  c.link_distance_m.assign(n, std::numeric_limits<double>::infinity());
  c.link_force_n.assign(n, 0.0);
  for (const haptics::LocalMinimum& m : minima_) {
    auto& d = c.link_distance_m[static_cast<std::size_t>(m.link)];
    d = std::min(d, m.distance_m);
  }
  if (minima_.size() > contact_.f_W.size()) contact_ = haptics::ContactData(model_, static_cast<int>(minima_.size()));
  haptics::resetContactRecords(contact_);
  haptics::computeContactForces(params_, model_, fk_, minima_, kCheckTick_s, contact_);
  for (std::size_t i = 0; i < minima_.size(); ++i) {
    if (contact_.rendered[i] != 0) c.link_force_n[static_cast<std::size_t>(minima_[i].link)] += contact_.f_W[i].norm();
  }
  c.valid_free = true;
  c.valid_contact = true;
  c.valid_hand_only = true;
  const double d_min_contact = params_.force_threshold_m - limits_.max_skin_depth_m;
  for (int l : links_) {
    const auto i = static_cast<std::size_t>(l);
    const bool clear = c.link_distance_m[i] >= limits_.clearance_margin_m;
    if (!clear) c.valid_free = false;
    if (!clear && haptics::isHandLink(model_, l)) c.valid_hand_only = false;
    if (c.link_distance_m[i] < d_min_contact || c.link_force_n[i] > limits_.max_link_force_n) c.valid_contact = false;
  }
  return c;
}

ReachResult planReach(const ReachProblem& problem, ReachMode mode, const ReachOptions& options) {
  if (problem.model == nullptr || problem.world == nullptr) throw std::invalid_argument("planReach: no model or world");
  if (problem.q_start.size() != problem.model->numJoints()) {
    throw std::invalid_argument("planReach: start posture of the wrong size");
  }
  validateOptions(options, problem.params);
  ompl::msg::noOutputHandler();
  ReachChecker checker(*problem.model, *problem.world, problem.params, options.limits, problem.target.object_index);
  const Goals goals = sweepGoals(problem, checker, options);
  return planWithGoals(problem, mode, options, goals, checker);
}

bool ReachStudy::handOnlyFalsePositive() const noexcept {
  return hand_only.verdict == Verdict::kReachable && contact.verdict == Verdict::kUnreachable;
}

ReachStudy studyReach(const ReachProblem& problem, const ReachOptions& options) {
  if (problem.model == nullptr || problem.world == nullptr)
    throw std::invalid_argument("studyReach: no model or world");
  if (problem.q_start.size() != problem.model->numJoints()) {
    throw std::invalid_argument("studyReach: start posture of the wrong size");
  }
  validateOptions(options, problem.params);
  ompl::msg::noOutputHandler();
  ReachChecker checker(*problem.model, *problem.world, problem.params, options.limits, problem.target.object_index);
  const Goals goals = sweepGoals(problem, checker, options);
  ReachStudy s;
  s.free = planWithGoals(problem, ReachMode::kFree, options, goals, checker);
  s.contact = planWithGoals(problem, ReachMode::kContactAllowed, options, goals, checker);
  s.hand_only = planWithGoals(problem, ReachMode::kHandOnly, options, goals, checker);
  return s;
}

double motionStep(const arm::ArmModel& model, double motion_resolution) {
  const Eigen::VectorXd span = (model.upperLimits() - model.lowerLimits()).head(kArm);
  return motion_resolution * span.norm();
}

bool motionValid(ReachChecker& checker, ReachMode mode, const Eigen::VectorXd& a, const Eigen::VectorXd& b,
                 double step_rad) {
  const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step_rad)));
  for (int k = 0; k <= n; ++k) {
    const Eigen::VectorXd q = a + (b - a) * (static_cast<double>(k) / n);
    if (!checker.check(q).valid(mode)) return false;
  }
  return true;
}

std::vector<Eigen::VectorXd> planBetween(ReachChecker& checker, ReachMode mode, const Eigen::VectorXd& from,
                                         const Eigen::VectorXd& to, const ReachOptions& options) {
  const arm::ArmModel& model = checker.model();
  if (from.size() != model.numJoints() || to.size() != model.numJoints()) {
    throw std::invalid_argument("planBetween: configurations of the wrong size");
  }
  if (options.max_iterations < 1) throw ReachInputError("reach: max_iterations must be at least 1");
  if (!(options.motion_resolution > 0.0 && options.motion_resolution < 0.1)) {
    throw ReachInputError("reach: motion_resolution must lie in (0, 0.1)");
  }
  ompl::msg::noOutputHandler();
  const ob::SpaceInformationPtr si = makeSpaceInformation(checker, mode, from, options);
  auto pdef = std::make_shared<ob::ProblemDefinition>(si);
  ob::ScopedState<> start(si->getStateSpace());
  setState(start.get(), from);
  pdef->addStartState(start);
  auto goal = std::make_shared<ob::GoalStates>(si);
  ob::ScopedState<> g(si->getStateSpace());
  setState(g.get(), to);
  goal->addState(g);
  pdef->setGoal(goal);
  const ob::PlannerPtr planner = makePlanner(si, model, from, options);
  planner->setProblemDefinition(pdef);
  planner->setup();
  long evaluations = 0;
  const long budget = options.max_iterations;
  const ob::PlannerTerminationCondition ptc([&evaluations, budget] { return ++evaluations > budget; });
  std::vector<Eigen::VectorXd> path;
  if (planner->solve(ptc) != ob::PlannerStatus::EXACT_SOLUTION) return path;
  const auto solution = pdef->getSolutionPath()->as<og::PathGeometric>();
  for (std::size_t i = 0; i < solution->getStateCount(); ++i) {
    path.push_back(fullConfiguration(from, solution->getState(static_cast<unsigned>(i))));
  }
  path.back() = to;  // the goal state exactly, hand joints included
  return path;
}

}  // namespace fullarm::accessibility
