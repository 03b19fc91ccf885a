#include "fullarm/design/nonlinear_stage.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "fullarm/core/random.hpp"

namespace fullarm::design {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Point {
  double log_damping = 0.0;    // log10 B_m
  double log_gain = 0.0;       // log10 B_o/eps
  double log_lambda = 0.0;     // log10 lambda
  double log_inertia = 0.0;    // log10 J_m
  double log_stiffness = 0.0;  // log10 K_m
  bool operator==(const Point&) const = default;
};

Point pointOf(const controllers::JointGains& g) {
  return {std::log10(std::max(g.impedance.damping_nms_per_rad, 1e-12)),
          std::log10(g.sliding_mode.valve_bound_v / g.sliding_mode.boundary_layer_radps),
          std::log10(std::max(g.sliding_mode.lambda_per_s, 1e-12)),
          std::log10(std::max(g.impedance.inertia_kgm2, 1e-12)),
          std::log10(std::max(g.impedance.stiffness_nm_per_rad, 1e-12))};
}

// The gains of `base` at point `p`; J_m and K_m are moved only when they were (a stage that does
// not search them writes base's values bit for bit).
controllers::JointGains gainsAt(const controllers::JointGains& base, const Point& p) {
  controllers::JointGains g = base;
  const Point b = pointOf(base);
  g.impedance.damping_nms_per_rad = std::pow(10.0, p.log_damping);
  g.sliding_mode.boundary_layer_radps = g.sliding_mode.valve_bound_v / std::pow(10.0, p.log_gain);
  g.sliding_mode.lambda_per_s = std::pow(10.0, p.log_lambda);
  if (p.log_inertia != b.log_inertia) g.impedance.inertia_kgm2 = std::pow(10.0, p.log_inertia);
  if (p.log_stiffness != b.log_stiffness) g.impedance.stiffness_nm_per_rad = std::pow(10.0, p.log_stiffness);
  return g;
}

// Poll directions of the compass search, in this order: (d log B_m, d log B_o/eps, d log lambda,
// d log J_m, d log K_m). The two after the axes move B_m and lambda together: the damping of the
// user-device mode of a stiff, undamped user grows with B_m only as far as the sliding-mode loop
// (lambda) renders it (docs/analysis.md, "HR's run 264"), a diagonal valley the axis directions
// cannot enter. The last four (J_m, K_m) are polled only with
// NonlinearStageOptions::search_inertia_stiffness.
constexpr std::size_t kBasePollDirections = 8;
constexpr std::array<std::array<double, 5>, 12> kPollDirections = {{{1.0, 0.0, 0.0, 0.0, 0.0},
                                                                    {-1.0, 0.0, 0.0, 0.0, 0.0},
                                                                    {0.0, 1.0, 0.0, 0.0, 0.0},
                                                                    {0.0, -1.0, 0.0, 0.0, 0.0},
                                                                    {0.0, 0.0, 1.0, 0.0, 0.0},
                                                                    {0.0, 0.0, -1.0, 0.0, 0.0},
                                                                    {1.0, 0.0, 1.0, 0.0, 0.0},
                                                                    {-1.0, 0.0, -1.0, 0.0, 0.0},
                                                                    {0.0, 0.0, 0.0, 1.0, 0.0},
                                                                    {0.0, 0.0, 0.0, -1.0, 0.0},
                                                                    {0.0, 0.0, 0.0, 0.0, 1.0},
                                                                    {0.0, 0.0, 0.0, 0.0, -1.0}}};

bool sameGains(const controllers::JointGains& a, const controllers::JointGains& b) {
  return a.impedance.inertia_kgm2 == b.impedance.inertia_kgm2 &&
         a.impedance.damping_nms_per_rad == b.impedance.damping_nms_per_rad &&
         a.impedance.stiffness_nm_per_rad == b.impedance.stiffness_nm_per_rad &&
         a.sliding_mode.lambda_per_s == b.sliding_mode.lambda_per_s &&
         a.sliding_mode.valve_bound_v == b.sliding_mode.valve_bound_v &&
         a.sliding_mode.boundary_layer_radps == b.sliding_mode.boundary_layer_radps &&
         a.torque_filter_hz == b.torque_filter_hz && a.error_rate_filter_hz == b.error_rate_filter_hz &&
         a.valve_limit_v == b.valve_limit_v && a.passivity.enabled == b.passivity.enabled &&
         a.passivity.max_damping_nms_per_rad == b.passivity.max_damping_nms_per_rad &&
         a.passivity.velocity_threshold_radps == b.passivity.velocity_threshold_radps;
}

bool better(const NonlinearScore& a, const NonlinearScore& b) {
  return a.cost < b.cost;
}

// Cost weights: one failure outweighs the other terms together (0.5 + 0.25 * 1 + 0.25 * (< 1)).
constexpr double kHardGoalWeight = 0.5;
constexpr double kMarginWeight = 0.25;
constexpr double kTransparencyWeight = 0.25;
constexpr int kCornerIndex = 1000000;

// Where a block of runs is simulated: on `threads` threads of its own, or on the calling thread
// and the pool's idle workers (a block as large as the threads available now, so no thread
// simulates runs past a failure cap that a sequential evaluation would not reach, unless it
// would otherwise idle).
struct RunSpread {
  int threads = 1;
  core::JobPool* pool = nullptr;
  [[nodiscard]] std::size_t blockSize() const {
    return static_cast<std::size_t>(pool != nullptr ? pool->available() : std::max(threads, 1));
  }
  void run(int n, const std::function<void(int)>& task) const {
    if (pool != nullptr) {
      pool->fanOut(n, task);
    } else {
      parallelFor(n, threads, task);
    }
  }
};

}  // namespace

// T8: nonlinear stage score over the stress corners and the sample set (reports/equations.md).
std::vector<ModelVariation> stressCorners(const UncertaintyRanges& r, double user_fraction) {
  const auto weak = [user_fraction](const UniformRange& u) { return u.min + user_fraction * (u.max - u.min); };
  ModelVariation fast;
  fast.index = kCornerIndex;
  fast.bulk_modulus_scale = r.bulk_modulus_scale.min;
  fast.valve_gain_scale = r.valve_gain_scale.max;
  fast.friction_scale = r.friction_scale.min;
  fast.inertia_scale = r.inertia_scale.min;
  fast.delay_samples = r.delay_max_samples;
  fast.user_stiffness_nm_per_rad = weak(r.user_stiffness_nm_per_rad);
  fast.user_damping_nms_per_rad = weak(r.user_damping_nms_per_rad);
  ModelVariation slow = fast;
  slow.index = kCornerIndex + 1;
  slow.bulk_modulus_scale = r.bulk_modulus_scale.max;
  slow.valve_gain_scale = r.valve_gain_scale.min;
  slow.friction_scale = r.friction_scale.max;
  slow.inertia_scale = r.inertia_scale.max;
  slow.delay_samples = r.delay_min_samples;
  ModelVariation stiff = fast;
  stiff.index = kCornerIndex + 2;
  stiff.user_stiffness_nm_per_rad = r.user_stiffness_nm_per_rad.max;
  return {fast, slow, stiff};
}

// C4: margin of a passed nonlinear run (reports/equations.md).
double detectorMargin(const ClosedLoopResult& run, double threshold_radps) noexcept {
  const auto hold = [threshold_radps](double late, double early) {
    if (!(late > 0.0)) return 0.0;
    const double sustained = early > 0.0 ? late / (kOscillationSustainRatio * early) : 1.0;
    return std::min(late / threshold_radps, sustained);
  };
  return std::max(hold(run.free_hold_speed_rms_radps, run.free_hold_early_speed_rms_radps),
                  hold(run.contact_hold_speed_rms_radps, run.contact_hold_early_speed_rms_radps));
}

// C4: margin of a passed nonlinear run (reports/equations.md).
double passedRunMargin(const ClosedLoopResult& run, double threshold_radps) noexcept {
  double m = detectorMargin(run, threshold_radps);
  if (!run.wall_reached && run.sluggish_push_limit_nm > 0.0) {
    m = std::max(m, run.contact_user_torque_nm / run.sluggish_push_limit_nm);
  }
  return m;
}

std::vector<ModelVariation> ringCorners(const UncertaintyRanges& r) {
  const ModelVariation slow = stressCorners(r, 0.0)[1];
  std::vector<ModelVariation> out;
  int index = kCornerIndex + 3;
  for (const double f : kRingStiffnessFractions) {
    ModelVariation c = slow;
    c.index = index++;
    c.user_damping_nms_per_rad = r.user_damping_nms_per_rad.min;
    c.user_stiffness_nm_per_rad =
        r.user_stiffness_nm_per_rad.min + f * (r.user_stiffness_nm_per_rad.max - r.user_stiffness_nm_per_rad.min);
    out.push_back(c);
  }
  return out;
}

std::vector<ModelVariation> stageSamples(const UncertaintyRanges& ranges, std::uint64_t seed,
                                         const std::string& joint_name, int first, int count) {
  std::vector<ModelVariation> out;
  out.reserve(static_cast<std::size_t>(std::max(count, 0)));
  for (int i = 0; i < count; ++i)
    out.push_back(drawVariation(ranges, seed ^ kNonlinearStageSalt, core::nameSlot(joint_name), first + i));
  return out;
}

// T8: nonlinear stage score over the stress corners and the sample set (reports/equations.md).
NonlinearScore scoreNonlinear(const JointScenario& scenario, const controllers::JointGains& gains,
                              const std::vector<ModelVariation>& set, const LinearRequirements& req, int max_delay,
                              int failure_cap, const LinearHardGoals* hard_goals, int threads, core::JobPool* pool,
                              bool reject_hard_violation) {
  NonlinearScore s;
  JointScenario sc = scenario;
  sc.gains = gains;
  if (hard_goals != nullptr) {
    const auto [value, name] = worstHardGoal(
        evaluateGoals(hard_goals->models, gains, hard_goals->goals, hard_goals->coupled_models), hard_goals->goals);
    s.linear_hard = value;
    s.linear_hard_goal = name;
    s.linear_hard_met = value <= 1.0;
    if (reject_hard_violation && !s.linear_hard_met) {
      s.hard_rejected = true;
      s.cost = kInf;
      s.worst_failure = "violates the linear hard goal " + name;
      return s;
    }
  }
  s.linear_ok = analyzeScenario(sc, req, max_delay, {}).pass;
  if (!s.linear_ok) {
    s.cost = kInf;
    s.worst_failure = "linear check fails (closed loop unstable at some delay)";
    return s;
  }
  double worst_severity = -1.0;
  double rms_sum = 0.0;
  // Runs are simulated in blocks (of `threads`, or of the pool's available threads) and taken in
  // set order, so the score (including where the failure cap stops it) is the sequential one for
  // any thread count and any scheduling.
  const RunSpread spread{threads, pool};
  std::vector<ClosedLoopResult> results;
  for (std::size_t first = 0; first < set.size() && s.failures <= failure_cap;) {
    const std::size_t n = std::min(spread.blockSize(), set.size() - first);
    results.resize(std::max(results.size(), n));
    spread.run(static_cast<int>(n), [&](int j) {
      results[static_cast<std::size_t>(j)] = simulateJoint(variationScenario(sc, set[first + j]));
    });
    for (std::size_t j = 0; j < n; ++j) {
      const ClosedLoopResult& r = results[j];
      rms_sum += r.free_rms_user_torque_nm;
      if (!r.acceptable()) {
        ++s.failures;
        s.failed_runs.push_back({static_cast<int>(first + j), set[first + j], r.failure});
      } else {
        s.worst_passed_severity = std::max(s.worst_passed_severity, runSeverity(r, sc.oscillation_speed_radps));
        s.worst_passed_detector_margin =
            std::max(s.worst_passed_detector_margin, std::min(passedRunMargin(r, sc.oscillation_speed_radps), 1.0));
      }
      const double severity = runSeverity(r, sc.oscillation_speed_radps);
      if (severity > worst_severity) {
        worst_severity = severity;
        s.worst = static_cast<int>(first + j);
        s.worst_failure = r.acceptable() ? std::string() : r.failure;
      }
      ++s.runs;
      if (s.failures > failure_cap) break;  // cannot beat the incumbent any more
    }
    first += n;
  }
  s.mean_rms_user_torque_nm = s.runs > 0 ? rms_sum / static_cast<double>(s.runs) : 0.0;
  s.cost = static_cast<double>(s.failures) + (s.linear_hard_met ? 0.0 : kHardGoalWeight) +
           kMarginWeight * s.worst_passed_detector_margin +
           kTransparencyWeight * (1.0 - 1.0 / (1.0 + s.mean_rms_user_torque_nm));
  return s;
}

namespace {

// Throws std::invalid_argument naming the first option that is out of range, its value and the rule.
void validateStageOptions(const NonlinearStageOptions& o) {
  const auto require = [](bool ok, const char* name, double value, const char* rule) {
    if (ok) return;
    std::ostringstream msg;
    msg << "nonlinear stage options: " << name << " = " << value << ", expected " << rule;
    throw std::invalid_argument(msg.str());
  };
  require(o.samples >= 1, "samples", o.samples, ">= 1");
  require(o.check_samples >= 0, "check_samples", o.check_samples, ">= 0");
  require(o.rounds >= 1, "rounds", o.rounds, ">= 1");
  require(o.max_evaluations >= 0, "max_evaluations", o.max_evaluations, ">= 0");
  require(o.step_decades > 0.0, "step_decades", o.step_decades, "> 0");
  require(o.min_step_decades > 0.0, "min_step_decades", o.min_step_decades, "> 0");
  require(o.max_added_per_round >= 1, "max_added_per_round", o.max_added_per_round, ">= 1");
  require(o.threads >= 1, "threads", o.threads, ">= 1");
  require(o.corner_user_fraction >= 0.0 && o.corner_user_fraction <= 1.0, "corner_user_fraction",
          o.corner_user_fraction, "in [0, 1]");
  require(o.target_margin >= 0.0 && o.target_margin <= 1.0, "target_margin", o.target_margin, "in [0, 1]");
  const auto box = [&](double lo, double hi, const char* lo_name, const char* hi_name) {
    require(lo > 0.0 && std::isfinite(lo), lo_name, lo, "finite and > 0");
    require(hi >= lo && std::isfinite(hi), hi_name, hi, "finite and >= its minimum");
  };
  box(o.min_damping_nms_per_rad, o.max_damping_nms_per_rad, "min_damping_nms_per_rad", "max_damping_nms_per_rad");
  box(o.min_gain_v_s_per_rad, o.max_gain_v_s_per_rad, "min_gain_v_s_per_rad", "max_gain_v_s_per_rad");
  box(o.min_lambda_per_s, o.max_lambda_per_s, "min_lambda_per_s", "max_lambda_per_s");
  box(o.min_inertia_kgm2, o.max_inertia_kgm2, "min_inertia_kgm2", "max_inertia_kgm2");
  box(o.min_stiffness_nm_per_rad, o.max_stiffness_nm_per_rad, "min_stiffness_nm_per_rad", "max_stiffness_nm_per_rad");
}

}  // namespace

NonlinearStageResult refineNonlinear(const JointScenario& scenario, const controllers::JointGains& linear_optimum,
                                     const controllers::JointGains& start, const UncertaintyRanges& ranges,
                                     const LinearRequirements& req, const NonlinearStageOptions& o,
                                     const LinearHardGoals* hard_goals) {
  validateStageOptions(o);
  const int max_delay = ranges.delay_max_samples;
  const std::array<double, 5> lo = {std::log10(o.min_damping_nms_per_rad), std::log10(o.min_gain_v_s_per_rad),
                                    std::log10(o.min_lambda_per_s), std::log10(o.min_inertia_kgm2),
                                    std::log10(o.min_stiffness_nm_per_rad)};
  const std::array<double, 5> hi = {std::log10(o.max_damping_nms_per_rad), std::log10(o.max_gain_v_s_per_rad),
                                    std::log10(o.max_lambda_per_s), std::log10(o.max_inertia_kgm2),
                                    std::log10(o.max_stiffness_nm_per_rad)};

  NonlinearStageResult res;
  // The ring corners first: they are the runs a candidate fails first (measured on SFE and HR), so
  // an evaluation capped at the incumbent's failures stops after the fewest simulations.
  if (o.ring_corners) res.set = ringCorners(ranges);
  if (o.stress_corners) {
    for (const ModelVariation& c : stressCorners(ranges, o.corner_user_fraction)) res.set.push_back(c);
  }
  for (const ModelVariation& sample : stageSamples(ranges, o.seed, scenario.joint_name, 0, o.samples)) {
    res.set.push_back(sample);
  }
  int next_index = o.samples;
  const std::size_t initial_size = res.set.size();

  // Candidates that violate a hard goal are rejected unsimulated once the search is hard-feasible.
  bool reject_hard = false;
  const auto score = [&](const controllers::JointGains& g, int cap = std::numeric_limits<int>::max()) {
    const NonlinearScore s =
        scoreNonlinear(scenario, g, res.set, req, max_delay, cap, hard_goals, o.threads, o.pool, reject_hard);
    ++res.evaluations;
    res.simulations += s.linear_ok ? s.runs : 0;
    return s;
  };
  res.linear_optimum = score(linear_optimum);
  // The linear stage returns its starting gains when no point meets its hard goals: score once.
  res.start = sameGains(start, linear_optimum) ? res.linear_optimum : score(start);
  // The better of the two by cost; its J_m, K_m (and filters, B_o) are kept.
  bool from_start = better(res.start, res.linear_optimum);
  // Hard-feasible search, when that choice would be the starting gains violating a hard goal
  // while the linear optimum meets every one (and validate's linear check): from the linear
  // optimum, whatever its failures, moving only to hard-feasible candidates, J_m and K_m searched
  // too. Joints whose choice meets the hard goals keep the ranking search unchanged.
  reject_hard = o.hard_feasible && hard_goals != nullptr && from_start && !res.start.linear_hard_met &&
                res.linear_optimum.linear_ok && res.linear_optimum.linear_hard_met;
  if (reject_hard) from_start = false;
  const std::size_t poll_directions =
      reject_hard && o.search_inertia_stiffness ? kPollDirections.size() : kBasePollDirections;
  const controllers::JointGains base = from_start ? start : linear_optimum;
  Point best_p = pointOf(base);
  controllers::JointGains best_gains = base;  // the incumbent (base itself until the search moves)
  NonlinearScore best = from_start ? res.start : res.linear_optimum;
  // `best` holds the incumbent's score on the whole current set (no early stop) while this is true.
  bool best_is_final = true;
  res.history.push_back(best.cost);

  for (int round = 0; round < o.rounds; ++round) {
    // Compass search (deterministic poll order: kPollDirections).
    double step = o.step_decades;
    int evaluations = 0;
    // Points scored in this round (the set is fixed within it): none of them beats the incumbent,
    // so a poll that lands on one again (a clamped direction) is skipped without an evaluation.
    std::vector<Point> visited = {best_p};
    while (evaluations < o.max_evaluations && step >= o.min_step_decades &&
           (best.failures > 0 || !best.linear_ok || best.worst_passed_severity >= 1.0 ||
            best.worst_passed_detector_margin > o.target_margin)) {
      bool improved = false;
      for (std::size_t dir = 0; dir < poll_directions && evaluations < o.max_evaluations; ++dir) {
        const std::array<double, 5>& d = kPollDirections[dir];
        Point p = best_p;
        p.log_damping = std::clamp(p.log_damping + d[0] * step, lo[0], hi[0]);
        p.log_gain = std::clamp(p.log_gain + d[1] * step, lo[1], hi[1]);
        p.log_lambda = std::clamp(p.log_lambda + d[2] * step, lo[2], hi[2]);
        // J_m and K_m keep their value bit for bit unless polled (a base outside their box is not
        // pulled onto its edge by the other directions).
        if (d[3] != 0.0) p.log_inertia = std::clamp(p.log_inertia + d[3] * step, lo[3], hi[3]);
        if (d[4] != 0.0) p.log_stiffness = std::clamp(p.log_stiffness + d[4] * step, lo[4], hi[4]);
        if (std::find(visited.begin(), visited.end(), p) != visited.end()) continue;
        visited.push_back(p);
        const NonlinearScore s = score(gainsAt(base, p), best.failures);
        // A candidate rejected by the hard goals cost no simulation: it does not use the budget.
        if (!s.hard_rejected) ++evaluations;
        if (better(s, best)) {
          best = s;
          best_p = p;
          best_gains = gainsAt(base, p);
          improved = true;
          res.history.push_back(best.cost);
          break;  // poll again around the new incumbent
        }
        res.history.push_back(best.cost);
      }
      if (!improved) step *= 0.5;
    }
    // Worst-case addition: a fresh check batch on the incumbent; its failures join the set.
    const std::vector<ModelVariation> check =
        stageSamples(ranges, o.seed, scenario.joint_name, next_index, o.check_samples);
    next_index += o.check_samples;
    JointScenario sc = scenario;
    sc.gains = best_gains;
    std::vector<std::pair<double, ModelVariation>> failed;
    // Blocks of runs taken in batch order: the same failures for any thread count and scheduling.
    const RunSpread spread{o.threads, o.pool};
    std::vector<ClosedLoopResult> results;
    for (std::size_t first = 0, n = 0; first < check.size() && static_cast<int>(failed.size()) < o.max_added_per_round;
         first += n) {
      n = std::min(spread.blockSize(), check.size() - first);
      results.resize(std::max(results.size(), n));
      spread.run(static_cast<int>(n), [&](int j) {
        results[static_cast<std::size_t>(j)] = simulateJoint(variationScenario(sc, check[first + j]));
      });
      for (std::size_t j = 0; j < n; ++j) {
        ++res.simulations;
        if (!results[j].acceptable()) {
          failed.emplace_back(runSeverity(results[j], sc.oscillation_speed_radps), check[first + j]);
        }
        // Enough worst cases for this round: the rest of the batch would not join the set.
        if (static_cast<int>(failed.size()) >= o.max_added_per_round) break;
      }
    }
    res.check_failures.push_back(static_cast<int>(failed.size()));
    if (failed.empty() && best.failures == 0 && best.linear_ok) {
      res.verified = true;
      break;
    }
    std::stable_sort(failed.begin(), failed.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    for (std::size_t i = 0; i < failed.size() && static_cast<int>(i) < o.max_added_per_round; ++i) {
      res.set.push_back(failed[i].second);
    }
    best_is_final = false;
    if (round + 1 < o.rounds) {
      best = score(sc.gains);  // re-score the incumbent on the grown set
      best_is_final = true;
      res.history.push_back(best.cost);
    }
  }
  res.gains = best_gains;
  // The incumbent's score on the final set is already known when the set did not grow after it
  // was scored in full (a capped score stops only past the incumbent's failures, so a
  // zero-failure incumbent's score ran every run); otherwise score it.
  if (best_is_final && best.linear_ok && best.runs == static_cast<int>(res.set.size())) {
    res.final_score = best;
  } else {
    res.final_score = scoreNonlinear(scenario, res.gains, res.set, req, max_delay, std::numeric_limits<int>::max(),
                                     hard_goals, o.threads, o.pool, false);
    res.simulations += res.final_score.runs;
  }
  res.linear_hard_goals_met = res.final_score.linear_hard_met;
  res.verified = res.verified && res.final_score.failures == 0;
  std::ostringstream v;
  v << scenario.joint_name << ": nonlinear stage " << (res.verified ? "verified" : "NOT verified") << " - "
    << res.final_score.failures << " of " << res.final_score.runs << " runs of its sample set fail";
  if (!res.check_failures.empty()) {
    v << ", last check batch "
      << (res.check_failures.back() == 0 ? "0 of " + std::to_string(o.check_samples)
                                         : std::to_string(res.check_failures.back()) + " failed (batch stopped early)");
  }
  v << "; started from the " << (from_start ? "starting" : "linearly tuned") << " gains"
    << (reject_hard ? " and searched only gains that meet the linear hard goals" : "") << " (failures: linear optimum "
    << res.linear_optimum.failures << ", start " << res.start.failures << " of " << initial_size << ")";
  if (!res.verified && !res.final_score.worst_failure.empty()) v << "; worst: " << res.final_score.worst_failure;
  if (hard_goals != nullptr) {
    if (res.linear_hard_goals_met) {
      v << "; the written gains meet the linear hard goals (worst " << res.final_score.linear_hard_goal << " "
        << res.final_score.linear_hard << " <= 1)";
    } else {
      v << "; WARNING: the written gains VIOLATE the linear hard goal " << res.final_score.linear_hard_goal
        << " (normalised " << res.final_score.linear_hard << " > 1): no candidate of the search met the hard goals "
        << "with as few nonlinear failures";
    }
  }
  res.verdict = v.str();
  res.hard_feasible_search = reject_hard;
  if (reject_hard && !res.verified) {
    // The restricted search did not verify: the ranking search (hard goals cost 0.5, from the
    // better start by cost) is written instead, as without the restricted search, whether or not
    // it verifies (measured on SFE: the hard-feasible gains fail stiff users in contact or weak
    // users as too sluggish). Its result carries the attempt and both searches' counts.
    NonlinearStageOptions ranking = o;
    ranking.hard_feasible = false;
    NonlinearStageResult fallback = refineNonlinear(scenario, linear_optimum, start, ranges, req, ranking, hard_goals);
    std::ostringstream f;
    f << fallback.verdict << " (a search restricted to gains that meet the linear hard goals, from the linear "
      << "optimum, ended NOT verified: " << res.final_score.failures << " of " << res.final_score.runs
      << " runs of its sample set fail)";
    fallback.verdict = f.str();
    fallback.hard_feasible_attempt = res.final_score;
    fallback.hard_feasible_attempt_gains = res.gains;
    fallback.evaluations += res.evaluations;
    fallback.simulations += res.simulations;
    return fallback;
  }
  return res;
}

}  // namespace fullarm::design
