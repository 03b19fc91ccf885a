#include "fullarm/design/tuner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlopt.hpp>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "fullarm/core/random.hpp"

namespace fullarm::design {

namespace {

constexpr int kVariables = 5;
/// Objective of an infeasible point in the global stage: above every feasible objective.
constexpr double kInfeasiblePenalty = 1e3;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
/// Goal value of a point whose goals cannot be computed (finite, so that COBYLA's linear models
/// stay finite).
constexpr double kUnscorable = 1e6;

using Vector = std::vector<double>;

// Log10 box of the five variables.
void boxOf(const TuningBounds& b, Vector& lo, Vector& hi) {
  const double* pairs[kVariables] = {b.inertia_kgm2, b.damping_nms_per_rad, b.stiffness_nm_per_rad, b.gain_v_s_per_rad,
                                     b.lambda_per_s};
  lo.resize(kVariables);
  hi.resize(kVariables);
  for (int i = 0; i < kVariables; ++i) {
    if (!(pairs[i][0] > 0.0) || !(pairs[i][1] >= pairs[i][0]) || !std::isfinite(pairs[i][1])) {
      throw std::invalid_argument("tuning bounds: expected 0 < low <= high for every variable (low = high fixes it)");
    }
    lo[i] = std::log10(pairs[i][0]);
    hi[i] = std::log10(pairs[i][1]);
  }
}

controllers::JointGains gainsAt(const controllers::JointGains& base, const Vector& x) {
  controllers::JointGains g = base;
  g.impedance.inertia_kgm2 = std::pow(10.0, x[0]);
  g.impedance.damping_nms_per_rad = std::pow(10.0, x[1]);
  g.impedance.stiffness_nm_per_rad = std::pow(10.0, x[2]);
  g.sliding_mode.boundary_layer_radps = g.sliding_mode.valve_bound_v / std::pow(10.0, x[3]);
  g.sliding_mode.lambda_per_s = std::pow(10.0, x[4]);
  return g;
}

Vector pointOf(const controllers::JointGains& g, const Vector& lo, const Vector& hi) {
  Vector x = {std::log10(g.impedance.inertia_kgm2), std::log10(std::max(g.impedance.damping_nms_per_rad, 1e-12)),
              std::log10(g.impedance.stiffness_nm_per_rad),
              std::log10(g.sliding_mode.valve_bound_v / g.sliding_mode.boundary_layer_radps),
              std::log10(g.sliding_mode.lambda_per_s)};
  for (int i = 0; i < kVariables; ++i) x[i] = std::clamp(x[i], lo[i], hi[i]);
  return x;
}

std::string resultName(nlopt::result r) {
  switch (r) {
    case nlopt::SUCCESS:
      return "success";
    case nlopt::STOPVAL_REACHED:
      return "stopval_reached";
    case nlopt::FTOL_REACHED:
      return "ftol_reached";
    case nlopt::XTOL_REACHED:
      return "xtol_reached";
    case nlopt::MAXEVAL_REACHED:
      return "maxeval_reached";
    case nlopt::MAXTIME_REACHED:
      return "maxtime_reached";
    case nlopt::FAILURE:
      return "failure";
    case nlopt::INVALID_ARGS:
      return "invalid_args";
    case nlopt::OUT_OF_MEMORY:
      return "out_of_memory";
    case nlopt::ROUNDOFF_LIMITED:
      return "roundoff_limited";
    case nlopt::FORCED_STOP:
      return "forced_stop";
    default:
      return "unknown";
  }
}

// Worst normalised hard goal and its name.
std::pair<double, const char*> worstHard(const GoalValues& v, const TuningGoals& goals) {
  std::pair<double, const char*> worst{v.peak_sensitivity / goals.max_peak_sensitivity, "peak sensitivity Ms"};
  const auto consider = [&](double value, const char* name) {
    if (value > worst.first) worst = {value, name};
  };
  consider(v.spectral_radius - kMarginalPoleTolerance, "spectral radius");
  consider(-v.min_real_loop, "sector condition Re L > -1");
  if (goals.coupled_hard) {
    consider(std::max(v.coupled_spectral_radius - kMarginalPoleTolerance, v.coupled_detector_score),
             "coupled stability and damping over the validated users");
  }
  if (goals.contact_hard) {
    consider(std::max(v.contact_spectral_radius - kMarginalPoleTolerance, v.contact_detector_score),
             "contact stability and damping over the validated users");
  }
  if (goals.passivity_hard) {
    consider(1.0 - v.min_real_impedance / goals.passivity_tolerance_nms_per_rad, "passivity Re Z >= 0");
  }
  return worst;
}

// The search state shared by the NLopt callbacks of one joint.
struct Search {
  const std::vector<PreparedJoint>* models = nullptr;
  const std::vector<PreparedJoint>* coupled = nullptr;
  std::vector<int> active;  // indices of the free variables (NLopt sees only these)
  Vector fixed;             // full point: values of the fixed variables
  const TuningGoals* goals = nullptr;
  controllers::JointGains base;
  Vector last_x;
  GoalValues last;
  GoalValues nonfinite;
  bool have_last = false;
  // Own tracking of the best points (NLopt's returned point is not trusted).
  Vector best_feasible_x;
  double best_feasible = std::numeric_limits<double>::infinity();
  Vector best_any_x;  // least infeasible (smallest hard) when nothing is feasible
  double best_any_hard = std::numeric_limits<double>::infinity();
  std::vector<double>* history = nullptr;
  std::vector<double>* hard_history = nullptr;
  int evaluations = 0;
  std::string error;
  nlopt::opt* running = nullptr;

  // Full point from NLopt's reduced one.
  Vector full(const double* z) const {
    Vector x = fixed;
    for (std::size_t i = 0; i < active.size(); ++i) x[static_cast<std::size_t>(active[i])] = z[i];
    return x;
  }
  Vector reduced(const Vector& x) const {
    Vector z;
    for (int i : active) z.push_back(x[static_cast<std::size_t>(i)]);
    return z;
  }

  const GoalValues& at(const Vector& x) {
    if (have_last && x == last_x) return last;
    if (!std::all_of(x.begin(), x.end(), [](double e) { return std::isfinite(e); })) {
      // COBYLA can step to a non-finite point after a non-finite goal value: score it as the
      // worst finite value instead of building gains from it.
      nonfinite.hard = kUnscorable;
      nonfinite.soft = kUnscorable;
      return nonfinite;
    }
    last = evaluateGoals(*models, gainsAt(base, x), *goals, *coupled);
    last_x = x;
    have_last = true;
    ++evaluations;
    if (last.feasible() && last.soft < best_feasible) {
      best_feasible = last.soft;
      best_feasible_x = x;
    }
    if (last.hard < best_any_hard) {
      best_any_hard = last.hard;
      best_any_x = x;
    }
    history->push_back(std::isfinite(best_feasible) ? best_feasible : kNan);
    hard_history->push_back(best_any_hard);
    return last;
  }

  // Exceptions must not cross NLopt's C code: keep the message and stop the run.
  template <typename F>
  double guarded(const F& f) {
    try {
      return f();
    } catch (const std::exception& e) {
      error = e.what();
    } catch (...) {
      error = "unknown exception";
    }
    if (running != nullptr) running->force_stop();
    return std::numeric_limits<double>::infinity();
  }
};

double penalisedObjective(unsigned /*n*/, const double* x, double* /*grad*/, void* data) {
  auto* s = static_cast<Search*>(data);
  return s->guarded([&] {
    const GoalValues& v = s->at(s->full(x));
    return v.feasible() ? v.soft : kInfeasiblePenalty + v.hard;
  });
}

double softObjective(unsigned /*n*/, const double* x, double* /*grad*/, void* data) {
  auto* s = static_cast<Search*>(data);
  return s->guarded([&] { return s->at(s->full(x)).soft; });
}

double hardConstraint(unsigned /*n*/, const double* x, double* /*grad*/, void* data) {
  auto* s = static_cast<Search*>(data);
  return s->guarded([&] { return s->at(s->full(x)).hard - 1.0; });
}

std::string runOptimizer(nlopt::opt& opt, Search& search, const Vector& x_full) {
  search.running = &opt;
  double f = 0.0;
  std::string name;
  Vector x = search.reduced(x_full);
  try {
    name = resultName(opt.optimize(x, f));
  } catch (const nlopt::forced_stop&) {
    name = "forced_stop";
  } catch (const nlopt::roundoff_limited&) {
    name = "roundoff_limited";
  } catch (const std::exception& e) {
    name = std::string("failure: ") + e.what();
  }
  search.running = nullptr;
  if (!search.error.empty()) throw std::runtime_error("tuner: goal evaluation failed: " + search.error);
  return name;
}

// Two corners of the box: a stiff, fast plant with a light, soft, undamped user and the longest
// delay, and the reverse.
ModelVariation corner(const UncertaintyRanges& r, bool high) {
  ModelVariation v;
  const auto pick = [high](const UniformRange& u, bool same) { return (high == same) ? u.max : u.min; };
  v.bulk_modulus_scale = pick(r.bulk_modulus_scale, true);
  v.valve_gain_scale = pick(r.valve_gain_scale, true);
  v.friction_scale = pick(r.friction_scale, false);
  v.inertia_scale = pick(r.inertia_scale, false);
  v.user_stiffness_nm_per_rad = pick(r.user_stiffness_nm_per_rad, false);
  v.user_damping_nms_per_rad = pick(r.user_damping_nms_per_rad, false);
  v.delay_samples = high ? r.delay_max_samples : r.delay_min_samples;
  return v;
}

}  // namespace

std::pair<double, std::string> worstHardGoal(const GoalValues& values, const TuningGoals& goals) {
  const auto [value, name] = worstHard(values, goals);
  return {value, std::string(name)};
}

GoalValues evaluateGoals(const std::vector<PreparedJoint>& models, const controllers::JointGains& gains,
                         const TuningGoals& goals, const std::vector<PreparedJoint>& coupled) {
  GoalValues worst;
  worst.min_real_loop = std::numeric_limits<double>::infinity();
  worst.min_real_impedance = std::numeric_limits<double>::infinity();
  for (const PreparedJoint& m : models) {
    const LinearChecks c = analyzePrepared(m, gains, VirtualWall{}, false, false);
    const VirtualWall wall{goals.wall_stiffness_nm_per_rad, goals.wall_damping_nms_per_rad};
    const double rho_wall = closedLoopSpectralRadius(m, gains, wall);
    // Free motion: RMS torque the user needs to move the device along the reference.
    double power = 0.0;
    for (double f : goals.reference_hz) {
      const double w = 2.0 * std::numbers::pi * f;
      const std::complex<double> z = renderedImpedance(m, gains, VirtualWall{}, w);
      const double amplitude = std::abs(z * std::complex<double>(0.0, w)) * goals.reference_amplitude_rad;
      power += 0.5 * amplitude * amplitude;
    }
    // Wall: rendered stiffness Re(Z j w) against the target.
    const double wc = 2.0 * std::numbers::pi * goals.wall_check_hz;
    const std::complex<double> zw = renderedImpedance(m, gains, wall, wc) * std::complex<double>(0.0, wc);
    const double wall_error = std::abs(zw.real() / goals.wall_stiffness_nm_per_rad - 1.0);
    worst.peak_sensitivity = std::max(worst.peak_sensitivity, c.margins.peak_sensitivity);
    // The free-position drift pole is left out as in the coupled goal, but only where nothing
    // restores the position (no user spring): elsewhere a real pole just above 1 is a slow
    // divergence that validate's linear check would call unstable.
    const bool free_position = !m.model.include_user || m.model.load.user_stiffness_nm_per_rad == 0.0;
    const double rho_free = free_position ? spectralRadiusWithoutDrift(c.closed_loop_poles) : c.spectral_radius;
    worst.spectral_radius = std::max({worst.spectral_radius, rho_free, rho_wall});
    // A loop that goes unstable at a lower gain (conditional stability) fails the sector goal.
    worst.min_real_loop = std::min(worst.min_real_loop, c.low_gain_stable || !c.stable ? c.margins.min_real : -1e3);
    worst.min_real_impedance = std::min(worst.min_real_impedance, c.min_real_impedance);
    worst.rms_user_torque_nm = std::max(worst.rms_user_torque_nm, std::sqrt(power));
    worst.wall_error = std::max(worst.wall_error, wall_error);
  }
  if (goals.coupled_hard) {
    // Coupled stability and the detector score (coupled_stability.hpp) over the model set and
    // the coupled grid of the validated users.
    for (const std::vector<PreparedJoint>* set : {&models, &coupled}) {
      const CoupledGoal c = evaluateCoupled(*set, gains, goals.detector);
      worst.coupled_spectral_radius = std::max(worst.coupled_spectral_radius, c.spectral_radius);
      if (c.detector_score >= worst.coupled_detector_score) {
        worst.coupled_detector_score = c.detector_score;
        worst.coupled_mode_hz = c.detector_hz;
        worst.coupled_mode_decay_per_s = c.detector_decay_per_s;
      }
    }
  }
  if (goals.contact_hard) {
    // The same users held against the target wall (Eq. C6): the contact hold's detector.
    const VirtualWall wall{goals.wall_stiffness_nm_per_rad, goals.wall_damping_nms_per_rad};
    for (const std::vector<PreparedJoint>* set : {&models, &coupled}) {
      const CoupledGoal c = evaluateCoupledContact(*set, gains, wall, goals.contact_detector);
      worst.contact_spectral_radius = std::max(worst.contact_spectral_radius, c.spectral_radius);
      if (c.detector_score >= worst.contact_detector_score) {
        worst.contact_detector_score = c.detector_score;
        worst.contact_mode_hz = c.detector_hz;
        worst.contact_mode_decay_per_s = c.detector_decay_per_s;
      }
    }
  }
  worst.hard = worstHard(worst, goals).first;
  worst.soft = std::max(worst.rms_user_torque_nm / goals.target_rms_torque_nm, worst.wall_error / goals.wall_accuracy);
  if (!std::isfinite(worst.hard) || !std::isfinite(worst.soft)) {
    worst.hard = kUnscorable;
    worst.soft = kUnscorable;
  }
  return worst;
}

// T7: systune formulation (reports/equations.md).
TuningResult tuneJoint(const JointPlantModel& nominal, double q_rad, const controllers::JointGains& initial,
                       const LoopSetup& setup, const TuningGoals& goals, const TuningBounds& bounds,
                       const UncertaintyRanges& ranges, const TunerOptions& options) {
  controllers::validateJointGains(initial, setup.control_period_s, {}, initial.name);
  if (options.global_evaluations < 1 || options.local_evaluations < 0 || options.rounds < 1 ||
      options.worst_case_samples < 0 || options.grid_points < 16) {
    throw std::invalid_argument("tuner options: expected evaluations >= 1, rounds >= 1, grid_points >= 16");
  }
  Vector lo;
  Vector hi;
  boxOf(bounds, lo, hi);
  LoopSetup s = setup;
  s.grid_points = options.grid_points;
  TuningResult result;
  result.joint = initial.name;
  result.initial = initial;

  ModelVariation nominal_variation;
  nominal_variation.delay_samples = setup.delay_samples;
  nominal_variation.user_stiffness_nm_per_rad = nominal.load.user_stiffness_nm_per_rad;
  nominal_variation.user_damping_nms_per_rad = nominal.load.user_damping_nms_per_rad;
  result.model_set = {nominal_variation};
  std::vector<PreparedJoint> models = {prepareVariation(nominal, q_rad, s, nominal_variation)};
  // The coupled grid of the validation box around the nominal plant (coupled_stability.hpp).
  if (goals.coupled_hard || goals.contact_hard)
    result.coupled_models = prepareCoupledGrid(nominal, q_rad, s, {nominal_variation}, ranges);
  const std::vector<PreparedJoint>& coupled = result.coupled_models;

  Search search;
  search.goals = &goals;
  search.coupled = &coupled;
  search.fixed = pointOf(initial, lo, hi);
  Vector lo_free;
  Vector hi_free;
  for (int i = 0; i < kVariables; ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (hi[k] > lo[k]) {
      search.active.push_back(i);
      lo_free.push_back(lo[k]);
      hi_free.push_back(hi[k]);
    } else {
      search.fixed[k] = lo[k];
    }
  }
  const auto free_count = static_cast<unsigned>(search.active.size());
  search.base = initial;
  search.history = &result.history;
  search.hard_history = &result.hard_history;
  Vector start = pointOf(initial, lo, hi);
  for (int round = 0; round < options.rounds; ++round) {
    search.models = &models;
    search.have_last = false;
    // Scores from earlier rounds are for a smaller model set: re-score the incumbents.
    search.best_feasible = std::numeric_limits<double>::infinity();
    search.best_any_hard = std::numeric_limits<double>::infinity();
    for (const Vector* incumbent : {&search.best_feasible_x, &search.best_any_x, &start}) {
      if (incumbent->size() == kVariables) (void)search.at(Vector(*incumbent));
    }
    if (free_count == 0) break;  // everything fixed: nothing to search
    // Global stage on the penalised objective (DIRECT-L is deterministic; ISRES uses the
    // thread-local NLopt generator, seeded here).
    nlopt::opt global(options.global == GlobalAlgorithm::kIsres ? nlopt::GN_ISRES : nlopt::GN_ORIG_DIRECT_L,
                      free_count);
    if (options.global == GlobalAlgorithm::kIsres) nlopt::srand(options.seed + static_cast<unsigned long>(round));
    global.set_lower_bounds(lo_free);
    global.set_upper_bounds(hi_free);
    global.set_min_objective(penalisedObjective, &search);
    global.set_maxeval(options.global_evaluations);
    Vector x = start;
    result.nlopt_results.push_back("round " + std::to_string(round) + " global: " + runOptimizer(global, search, x));
    // Local polish: COBYLA on the soft objective with the hard goals as one constraint, from
    // the best feasible point (or the least infeasible one).
    if (options.local_evaluations > 0) {
      nlopt::opt local(nlopt::LN_COBYLA, free_count);
      local.set_lower_bounds(lo_free);
      local.set_upper_bounds(hi_free);
      local.set_min_objective(softObjective, &search);
      local.add_inequality_constraint(hardConstraint, &search, 0.0);
      local.set_maxeval(options.local_evaluations);
      local.set_xtol_rel(1e-4);
      local.set_initial_step(0.1);
      x = search.best_feasible_x.size() == kVariables ? search.best_feasible_x : search.best_any_x;
      result.nlopt_results.push_back("round " + std::to_string(round) + " local: " + runOptimizer(local, search, x));
    }
    start = search.best_feasible_x.size() == kVariables ? search.best_feasible_x : search.best_any_x;
    if (round + 1 == options.rounds) break;
    // Worst case: the model (corners and seeded random samples) on which the incumbent does
    // worst; added to the set if it is worse than the set already is (both without the coupled
    // grid, which is in every evaluation anyway: like is compared with like).
    const controllers::JointGains incumbent = gainsAt(initial, start);
    const double set_hard = evaluateGoals(models, incumbent, goals).hard;
    ModelVariation worst_v;
    double worst_hard = -std::numeric_limits<double>::infinity();
    std::vector<ModelVariation> candidates = {corner(ranges, true), corner(ranges, false)};
    // Seeded draws of the box from the worst-case search's own stream of this joint (uncertainty.hpp):
    // round r draws indices [r N, (r + 1) N), N = worst_case_samples.
    for (int i = 0; i < options.worst_case_samples; ++i) {
      candidates.push_back(drawVariation(ranges, options.seed ^ kWorstCaseSearchSalt, core::nameSlot(initial.name),
                                         round * options.worst_case_samples + i));
    }
    for (const ModelVariation& v : candidates) {
      const std::vector<PreparedJoint> one = {prepareVariation(nominal, q_rad, s, v)};
      const double h = evaluateGoals(one, incumbent, goals).hard;
      if (h > worst_hard) {
        worst_hard = h;
        worst_v = v;
      }
    }
    if (!(worst_hard > set_hard + 1e-6)) break;
    result.model_set.push_back(worst_v);
    models.push_back(prepareVariation(nominal, q_rad, s, worst_v));
  }

  result.evaluations = search.evaluations;
  result.feasible = search.best_feasible_x.size() == kVariables && std::isfinite(search.best_feasible);
  const Vector best = result.feasible ? search.best_feasible_x : search.best_any_x;
  result.tuned = result.feasible ? gainsAt(initial, best) : initial;
  result.initial_goals = evaluateGoals(models, initial, goals, coupled);
  // The goals of the returned gains (the starting gains when nothing was feasible).
  result.tuned_goals = evaluateGoals(models, result.tuned, goals, coupled);
  std::ostringstream v;
  if (result.feasible) {
    v << initial.name << ": every hard goal met on " << models.size() << " model(s); worst soft goal "
      << result.tuned_goals.soft << " (initial gains: " << result.initial_goals.soft
      << (result.initial_goals.feasible() ? ", feasible" : ", infeasible") << ")";
  } else {
    const auto [value, name] = worstHard(evaluateGoals(models, gainsAt(initial, best), goals, coupled), goals);
    v << initial.name << ": infeasible - no gains in the search box meet the hard goals; the least violating point "
      << "still fails the " << name << " goal (normalised " << value << " > 1)";
  }
  result.verdict = v.str();
  return result;
}

}  // namespace fullarm::design
