// Diagnostic (docs/analysis.md "Known limits"): where does the tuner's worst-case peak
// sensitivity Ms of the shipped gains come from, and is it real?
//
//   ms_worst_case [--peak-speed-amplitude] [JOINT...]        (default: SFE SAA WFE)
//
// As `fullarm tune`, the coupled goal uses the modal amplitude (Eq. C5) unless
// --peak-speed-amplitude asks for Eq. C3's bound (the rule of the figures in docs/analysis.md,
// measured before the modal amplitude became tune's default).
//
// For each joint: rebuilds the linear stage's hard-goal model set exactly as `fullarm tune` does
// (start gains config/dts_tune_start.yaml, tune's default budget and seed), evaluates the shipped
// gains (config/dts_gains.yaml) with evaluateGoals, and prints for every model of the set its Ms,
// the frequency of the peak and the closed-loop poles nearest to it (|z|, f, zeta).

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/controllers/joint_controller.hpp"
#include "fullarm/design/coupled_stability.hpp"
#include "fullarm/design/linear_analysis.hpp"
#include "fullarm/design/scenario_analysis.hpp"
#include "fullarm/design/tuner.hpp"
#include "fullarm/design/validation.hpp"
#include "fullarm/plant/arm_plant.hpp"
#include "fullarm/plant/plant_config.hpp"
#include "ring_experiment.hpp"

namespace fc = fullarm::controllers;
namespace fd = fullarm::design;
namespace ft = fullarm::design::test;

namespace {

struct Context {
  fullarm::arm::ArmModel model;
  fullarm::plant::PlantConfig plant;
  fc::GainsConfig shipped;
  fc::GainsConfig start;
  fd::ValidationConfig validation;
  bool modal_amplitude = true;  // the coupled goal's V0 as `fullarm tune` (Eq. C5) unless --peak-speed-amplitude
};

void printPoles(const Eigen::VectorXcd& z, double T, double near_hz) {
  // Oscillatory poles (upper half plane) sorted by distance in frequency from near_hz; real poles
  // with |z| > 0.99.
  struct P {
    double r, f, zeta, sigma;
  };
  std::vector<P> poles;
  for (Eigen::Index i = 0; i < z.size(); ++i) {
    if (z[i].imag() < -1e-12) continue;
    const double r = std::abs(z[i]);
    if (r == 0.0) continue;
    const std::complex<double> s = std::log(z[i]) / T;
    poles.push_back({r, std::abs(s.imag()) / (2.0 * std::numbers::pi), -s.real() / std::abs(s), -s.real()});
  }
  std::sort(poles.begin(), poles.end(), [&](const P& a, const P& b) {
    return std::abs(std::log((a.f + 1e-3) / (near_hz + 1e-3))) < std::abs(std::log((b.f + 1e-3) / (near_hz + 1e-3)));
  });
  for (std::size_t i = 0; i < std::min<std::size_t>(poles.size(), 4); ++i) {
    std::printf("      pole |z| %.6f  f %8.3f Hz  zeta %+.4f  sigma %+.3f /s\n", poles[i].r, poles[i].f, poles[i].zeta,
                poles[i].sigma);
  }
}

void compareRing(const fd::JointScenario& nominal, const fd::JointPlantModel& jm, const fd::PreparedJoint& p,
                 const fd::ModelVariation& v, const fc::JointGains& gains, double q0, std::complex<double> z_pred) {
  const double T = p.setup.control_period_s;
  const std::complex<double> s_pred = std::log(z_pred) / T;
  const double f = std::abs(s_pred.imag()) / (2.0 * std::numbers::pi);
  const double sigma = -s_pred.real();
  // Fit window: after the burst and 20 ms, long enough for 10 periods and a change of e^{+-3}.
  const double start_s = 3.0 / f + 0.02;
  const double len_s = std::clamp(3.0 / std::max(std::abs(sigma), 1e-3), 10.0 / f, 1.5);
  const auto b = static_cast<std::size_t>(std::lround(start_s / T));
  const auto e = static_cast<std::size_t>(std::lround((start_s + len_s) / T));
  const int dec = std::max(1, static_cast<int>(std::lround(1.0 / (20.0 * f * T))));
  // Burst amplitude: the linear ring's spool excursion stays at 5e-4 (an eighth of the underlap).
  const ft::Ring unit = ft::linearRing(p, gains, f, 1.0, start_s + len_s);
  double unit_spool = 0.0;
  for (double x : unit.spool) unit_spool = std::max(unit_spool, std::abs(x));
  const double a_v = 5e-4 / unit_spool;
  Eigen::VectorXcd poles;
  const ft::Ring lin = ft::linearRing(p, gains, f, a_v, start_s + len_s, &poles);
  const ft::Ring nl = ft::nonlinearRing(nominal, fd::applyVariation(jm, v), v, gains, q0, f, a_v, start_s + len_s);
  double dmin = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < poles.size(); ++i) dmin = std::min(dmin, std::abs(poles[i] - z_pred));
  std::printf(
      "    ring test: predicted f %.3f Hz, sigma %+.3f /s (own closed-loop assembly: nearest pole %.1e away); "
      "burst %.2e V, window %.3f-%.3f s, decimation %d; trim command %.2e V%s\n",
      f, sigma, dmin, a_v, start_s, start_s + len_s, dec, nl.trim_command_v, nl.solver_ok ? "" : " SOLVER FAILED");
  double spool_max = 0.0;
  for (std::size_t k = 0; k < std::min(e, nl.spool.size()); ++k) {
    spool_max = std::max(spool_max, std::abs(nl.spool[k] - nl.spool[0]));
  }
  for (int order : {4, 6, 8}) {
    const std::complex<double> sl = ft::pronyPole(lin.qd, b, e, dec, order, T, s_pred);
    const std::complex<double> sn = ft::pronyPole(nl.qd, b, e, dec, order, T, s_pred);
    std::printf("      Prony order %d: linear sim f %.3f Hz sigma %+.3f /s | nonlinear f %.3f Hz sigma %+.3f /s\n",
                order, std::abs(sl.imag()) / (2.0 * std::numbers::pi), -sl.real(),
                std::abs(sn.imag()) / (2.0 * std::numbers::pi), -sn.real());
  }
  double sig_l = 0.0, f_l = 0.0, sig_n = 0.0, f_n = 0.0;
  ft::envelope(lin.qd, b, e, T, f, &sig_l, &f_l);
  ft::envelope(nl.qd, b, std::min(e, nl.qd.size()), T, f, &sig_n, &f_n);
  double peak_l = 0.0, peak_n = 0.0;
  for (std::size_t k = b; k < e; ++k) {
    peak_l = std::max(peak_l, std::abs(lin.qd[k]));
    if (k < nl.qd.size()) peak_n = std::max(peak_n, std::abs(nl.qd[k]));
  }
  std::printf(
      "      envelope: linear sim f %.3f Hz sigma %+.3f /s | nonlinear f %.3f Hz sigma %+.3f /s; "
      "peak speed in window %.2e / %.2e rad/s; peak spool excursion %.2e (underlap 4e-3)\n",
      f_l, sig_l, f_n, sig_n, peak_l, peak_n, spool_max);
  // The same model linearised at validate's free-hold and wall operating points.
  {
    const fd::JointPlantModel jm_v = fd::applyVariation(jm, v);
    const double q_free = nominal.start_rad + nominal.direction * nominal.timing.free_move_rad;
    const fd::PreparedJoint pf = fd::prepareJoint(jm_v, fd::solveOperatingPoint(jm_v, q_free), p.setup);
    const fd::PreparedJoint pw =
        fd::prepareJoint(jm_v, fd::solveOperatingPoint(jm_v, fd::wallPosition(nominal)), p.setup);
    const fd::ModeDecay mf = fd::slowestOscillatoryMode(fd::closedLoopPoles(pf, gains, fd::VirtualWall{}), T);
    const fd::VirtualWall wall{nominal.wall.stiffness_nm_per_rad, nominal.wall.damping_nms_per_rad};
    const fd::ModeDecay mw = fd::slowestOscillatoryMode(fd::closedLoopPoles(pw, gains, wall), T);
    const fd::LinearChecks lf = fd::analyzePrepared(pf, gains, fd::VirtualWall{}, false, false);
    std::printf(
        "      at validate's operating points: free hold (q %.3f) Ms %.3f at %.3f Hz, spectral radius %.6f, "
        "slowest oscillatory %.3f Hz sigma %+.3f; against the wall spectral radius %.6f, slowest %.3f Hz sigma "
        "%+.3f\n",
        q_free, lf.margins.peak_sensitivity, lf.margins.peak_sensitivity_radps / (2.0 * std::numbers::pi),
        fd::closedLoopSpectralRadius(pf, gains, fd::VirtualWall{}), mf.frequency_hz, mf.decay_rate_per_s,
        fd::closedLoopSpectralRadius(pw, gains, wall), mw.frequency_hz, mw.decay_rate_per_s);
  }
  // Where the ring ends: the nonlinear ring (ideal sensors, no Coulomb) run for 4 s.
  {
    const ft::Ring longer = ft::nonlinearRing(nominal, fd::applyVariation(jm, v), v, gains, q0, f, a_v, 4.0);
    const std::size_t n = longer.qd.size();
    double sp = 0.0;
    for (std::size_t k = n - 500; k < n; ++k) sp = std::max(sp, std::abs(longer.spool[k] - longer.spool[0]));
    std::printf("      after 4 s: speed deviation over the last 0.5 s %.2e rad/s, spool excursion %.2e\n",
                ft::windowStd(longer.qd, n - 500, n), sp);
  }
  // validate's own run of this model (free move, free hold, wall), as drawn and idealised.
  fd::ModelVariation sample = v;
  sample.index = 0;
  for (int mode = 0; mode < 4; ++mode) {
    fd::JointScenario sc = fd::variationScenario(nominal, sample);
    ft::idealize(sc, (mode & 1) != 0, (mode & 2) != 0);
    const fd::ClosedLoopResult r = fd::simulateJoint(sc);
    std::printf(
        "      validate run (%s sensors, %s): %s; hold speed deviation free %.4f (early %.4f), contact %.4f "
        "(early %.4f) rad/s, %.1f Hz%s%s\n",
        (mode & 1) ? "ideal" : "12-bit", (mode & 2) ? "no Coulomb" : "Coulomb", r.acceptable() ? "PASS" : "FAIL",
        r.free_hold_speed_rms_radps, r.free_hold_early_speed_rms_radps, r.contact_hold_speed_rms_radps,
        r.contact_hold_early_speed_rms_radps, r.oscillation_frequency_hz, r.failure.empty() ? "" : ": ",
        r.failure.c_str());
  }
}

void analyseJoint(const Context& c, const std::string& short_name) {
  const int slot = fc::findGainsJoint(c.start, short_name);
  const fc::JointGains& initial = c.start.joints[static_cast<std::size_t>(slot)];
  const fc::JointGains& gains = c.shipped.joints[static_cast<std::size_t>(fc::findGainsJoint(c.shipped, short_name))];
  const fd::JointPlantModel jm = fd::tunerJointModel(c.model, c.plant, c.validation, initial.name);
  const double q = c.model.defaultPosture()[c.model.jointIndex(initial.name)];
  fd::LoopSetup setup;
  setup.control_period_s = c.shipped.control_period_s;
  setup.delay_samples = c.validation.ranges.delay_min_samples;
  fd::TuningGoals goals;
  if (c.validation.wall.enabled) {
    goals.wall_stiffness_nm_per_rad = c.validation.wall.stiffness_nm_per_rad;
    goals.wall_damping_nms_per_rad = c.validation.wall.damping_nms_per_rad;
  }
  const fd::JointScenario sc =
      fd::validationScenario(fd::makeJointScenario(c.model, c.plant, c.shipped, initial.name), c.validation);
  goals.detector = fd::detectorModelOf(sc);
  goals.detector.modal_amplitude = c.modal_amplitude;
  fd::TunerOptions options;  // tune's defaults: 300 + 150 evaluations, 3 rounds
  const fd::TuningResult tr =
      fd::tuneJoint(jm, q, initial, setup, goals, fd::TuningBounds{}, c.validation.ranges, options);
  fd::LoopSetup goal_setup = setup;
  goal_setup.grid_points = options.grid_points;
  std::vector<fd::PreparedJoint> models;
  for (const fd::ModelVariation& v : tr.model_set) models.push_back(fd::prepareVariation(jm, q, goal_setup, v));
  const fd::GoalValues gv = fd::evaluateGoals(models, gains, goals, tr.coupled_models);
  const auto [hard, name] = fd::worstHardGoal(gv, goals);
  std::printf(
      "%s (q %.4f rad): stage hard goals on the shipped gains: Ms %.3f, min Re L %.3f, coupled score %.3f "
      "(%.3f Hz, sigma %.3f /s); worst '%s' %.3f\n",
      initial.name.c_str(), q, gv.peak_sensitivity, gv.min_real_loop, gv.coupled_detector_score, gv.coupled_mode_hz,
      gv.coupled_mode_decay_per_s, name.c_str(), hard);
  // The coupled goal with each mode's own amplitude after the free move (Eq. C5) instead of V0.
  {
    fd::TuningGoals modal = goals;
    modal.detector.modal_amplitude = true;
    const fd::GoalValues gm = fd::evaluateGoals(models, gains, modal, tr.coupled_models);
    const auto [hm, nm] = fd::worstHardGoal(gm, modal);
    std::printf("  with modal V0 (Eq. C5): coupled score %.3f (%.3f Hz, sigma %.3f /s); worst '%s' %.3f\n",
                gm.coupled_detector_score, gm.coupled_mode_hz, gm.coupled_mode_decay_per_s, nm.c_str(), hm);
  }
  // validate's own linear check of the nominal scenario (operating points: end of the free move, wall).
  const fd::ScenarioLinearResult vr = fd::analyzeScenario(sc, c.validation.linear, 1, {});
  std::printf("  validate's nominal: Ms free %.3f at %.3f Hz (q %.4f), contact %.3f at %.3f Hz\n",
              vr.free.margins.peak_sensitivity, vr.free.margins.peak_sensitivity_radps / (2.0 * std::numbers::pi),
              sc.start_rad + sc.direction * sc.timing.free_move_rad, vr.contact.margins.peak_sensitivity,
              vr.contact.margins.peak_sensitivity_radps / (2.0 * std::numbers::pi));
  // The tuner's nominal model at other operating points along the scenario's motion.
  for (double dq : {0.0, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.3}) {
    const double qq = sc.start_rad + sc.direction * dq;
    const fd::PreparedJoint pj = fd::prepareJoint(jm, fd::solveOperatingPoint(jm, qq), goal_setup);
    const fd::LinearChecks l = fd::analyzePrepared(pj, gains, fd::VirtualWall{}, false, false);
    const fd::OperatingPoint& o = pj.coupled.linear.op;
    std::printf(
        "  tuner's nominal at q %.4f: Ms %.3f at %.3f Hz (trim spool %.2e, p_a %.3e, p_b %.3e Pa, command %.2e V)\n",
        qq, l.margins.peak_sensitivity, l.margins.peak_sensitivity_radps / (2.0 * std::numbers::pi),
        o.state[fd::kSpool], o.state[fd::kPressureA], o.state[fd::kPressureB], o.command);
  }
  // How often validate's box holds such a model: seeded draws (not validate's stream), each
  // linearised at the tuner's operating point and at validate's free-hold point, closed loop with
  // the shipped gains.
  const double q_hold = sc.start_rad + sc.direction * sc.timing.free_move_rad;
  for (const double q_lin : {q, q_hold}) {
    constexpr int kDraws = 1000;
    int unstable = 0, ms_over = 0;
    for (int i = 0; i < kDraws; ++i) {
      const fd::ModelVariation d = fd::drawVariation(c.validation.ranges, 20261123, slot, i);
      const fd::PreparedJoint pd = fd::prepareVariation(jm, q_lin, goal_setup, d);
      const fd::LinearChecks l = fd::analyzePrepared(pd, gains, fd::VirtualWall{}, false, false);
      const fd::CoupledGoal cg = fd::evaluateCoupled({pd}, gains, goals.detector);
      if (fd::coupledGoalValue(cg) >= 10.0) {
        if (++unstable <= 3) {
          std::printf(
              "    growing: bulk x%.3f valve x%.3f friction x%.3f inertia x%.3f K_h %.2f B_h %.2f delay %d: "
              "%.3f Hz sigma %+.3f /s\n",
              d.bulk_modulus_scale, d.valve_gain_scale, d.friction_scale, d.inertia_scale, d.user_stiffness_nm_per_rad,
              d.user_damping_nms_per_rad, d.delay_samples, cg.detector_hz, cg.detector_decay_per_s);
        }
      }
      if (l.margins.peak_sensitivity > goals.max_peak_sensitivity) ++ms_over;
    }
    std::printf("  %d seeded draws of validate's box at q %.3f: %d with a growing coupled mode, %d with Ms > %.1f\n",
                kDraws, q_lin, unstable, ms_over, goals.max_peak_sensitivity);
  }
  for (std::size_t i = 0; i < models.size(); ++i) {
    const fd::ModelVariation& v = tr.model_set[i];
    const fd::LinearChecks lc = fd::analyzePrepared(models[i], gains, fd::VirtualWall{}, false, false);
    // The same loop on the fine default grid (600 points), as validate computes it.
    fd::PreparedJoint fine = models[i];
    fine.setup.grid_points = 600;
    const fd::LinearChecks lf = fd::analyzePrepared(fine, gains, fd::VirtualWall{}, false, false);
    const double f_ms = lc.margins.peak_sensitivity_radps / (2.0 * std::numbers::pi);
    std::printf("  model %zu: bulk x%.3f valve x%.3f friction x%.3f inertia x%.3f K_h %.2f B_h %.2f delay %d\n", i,
                v.bulk_modulus_scale, v.valve_gain_scale, v.friction_scale, v.inertia_scale,
                v.user_stiffness_nm_per_rad, v.user_damping_nms_per_rad, v.delay_samples);
    std::printf(
        "    Ms %.3f at %.3f Hz (600-point grid: %.3f at %.3f Hz); GM %.3f (lower %.3f) PM %.1f deg; "
        "min Re L %.3f; spectral radius %.7f (open loop %.7f)\n",
        lc.margins.peak_sensitivity, f_ms, lf.margins.peak_sensitivity,
        lf.margins.peak_sensitivity_radps / (2.0 * std::numbers::pi), lc.margins.gain_margin,
        lc.margins.lower_gain_margin, lc.margins.phase_margin_deg, lc.margins.min_real, lc.spectral_radius,
        lc.open_loop_spectral_radius);
    printPoles(lc.closed_loop_poles, setup.control_period_s, f_ms);
    if (lc.margins.peak_sensitivity >= gv.peak_sensitivity - 1e-9 || lc.spectral_radius > 1.0) {
      // The pole nearest the Ms peak.
      std::complex<double> z_pred(0.0, 0.0);
      double best = std::numeric_limits<double>::infinity();
      for (Eigen::Index k = 0; k < lc.closed_loop_poles.size(); ++k) {
        const std::complex<double> z = lc.closed_loop_poles[k];
        if (z.imag() <= 0.0) continue;
        const double fz = std::arg(z) / (2.0 * std::numbers::pi * setup.control_period_s);
        const double dist = std::abs(std::log(fz / f_ms)) + (1.0 - std::abs(z));
        if (dist < best) {
          best = dist;
          z_pred = z;
        }
      }
      compareRing(sc, jm, models[i], v, gains, q, z_pred);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  Context c{fullarm::arm::loadArmModel(fullarm::arm::defaultArmModelPath()), {}, {}, {}, {}};
  c.plant = fullarm::plant::loadPlantConfig(fullarm::plant::defaultPlantConfigPath(), c.model);
  c.shipped = fc::loadGainsConfig(fc::defaultGainsConfigPath(), c.model);
  c.start = fc::loadGainsConfig(fc::defaultTuneStartGainsPath(), c.model);
  c.validation = fd::loadValidationConfig(fd::defaultValidationConfigPath());
  std::vector<std::string> joints;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--peak-speed-amplitude") {
      c.modal_amplitude = false;
    } else if (!arg.empty() && arg[0] == '-') {
      std::fprintf(stderr, "ms_worst_case: unknown option %s (expected --peak-speed-amplitude or joint names)\n",
                   arg.c_str());
      return 2;
    } else {
      joints.push_back(arg);
    }
  }
  if (joints.empty()) joints = {"SFE", "SAA", "WFE"};
  for (const std::string& j : joints) analyseJoint(c, j);
  return 0;
}
