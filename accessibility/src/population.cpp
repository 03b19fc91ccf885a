#include "fullarm/accessibility/population.hpp"

#include <cmath>
#include <numbers>
#include <string>

#include "fullarm/arm/arm_scaling.hpp"
#include "fullarm/core/config_error.hpp"

namespace fullarm::accessibility {
namespace {

constexpr double kZ95 = 1.6448536269514722;  // standard normal 95th percentile

// Log-normal through p50 with the log spread of the 5th-95th range.
double logSigma(const Percentiles& p) {
  return std::log(p.p95_m / p.p5_m) / (2.0 * kZ95);
}

// P1: a standard normal pair from two uniforms (Box and Muller 1958).
void boxMuller(core::RandomStream& rng, double& z0, double& z1) noexcept {
  const double u1 = 1.0 - rng.uniform01();  // (0, 1]
  const double u2 = rng.uniform01();
  const double r = std::sqrt(-2.0 * std::log(u1));
  z0 = r * std::cos(2.0 * std::numbers::pi * u2);
  z1 = r * std::sin(2.0 * std::numbers::pi * u2);
}

void requireFinite(double v, const std::string& key, bool positive) {
  if (!std::isfinite(v) || (positive && v <= 0.0)) {
    throw core::ConfigError(
        {}, key, std::to_string(v) + (positive ? ": expected a positive finite number" : ": expected a finite number"));
  }
}

void validateSex(const SexFigures& s, const std::string& key) {
  for (const auto& [p, name] : {std::pair{&s.upper_arm, "upper_arm"}, std::pair{&s.forearm, "forearm"}}) {
    const std::string k = key + "." + name;
    requireFinite(p->p5_m, k + ".p5_m", true);
    requireFinite(p->p50_m, k + ".p50_m", true);
    requireFinite(p->p95_m, k + ".p95_m", true);
    if (!(p->p5_m < p->p50_m && p->p50_m < p->p95_m)) {
      throw core::ConfigError({}, k,
                              std::to_string(p->p5_m) + " / " + std::to_string(p->p50_m) + " / " +
                                  std::to_string(p->p95_m) + ": expected p5 < p50 < p95");
    }
  }
  const double r = s.upper_arm_forearm_correlation;
  if (!std::isfinite(r) || r <= -1.0 || r >= 1.0) {
    throw core::ConfigError({}, key + ".upper_arm_forearm_correlation", std::to_string(r) + ": expected -1 < r < 1");
  }
  requireFinite(s.strength_median, key + ".strength_median", true);
}

}  // namespace

PopulationFigures ansur2Figures() {
  PopulationFigures f;
  f.men.upper_arm = {0.307, 0.335, 0.365};
  f.men.forearm = {0.244, 0.267, 0.295};
  f.men.upper_arm_forearm_correlation = 0.72;
  f.men.strength_median = 1.0;
  f.women.upper_arm = {0.283, 0.311, 0.340};
  f.women.forearm = {0.218, 0.241, 0.268};
  f.women.upper_arm_forearm_correlation = 0.69;
  // Women's to men's maximal torques: shoulder flexion about 0.5, abduction 35/74.4, adduction
  // 42/93.7, elbow flexion 31.9/79.5, elbow extension 25/60.5 (docs/sources.md): mean 0.45.
  f.women.strength_median = 0.45;
  f.strength_cv = 0.25;
  f.strength_size_correlation = 0.3;
  return f;
}

void validatePopulationOptions(const PopulationOptions& options) {
  if (options.technicians < 1) {
    throw core::ConfigError({}, "--population",
                            std::to_string(options.technicians) + ": expected at least 1 technician");
  }
  if (!std::isfinite(options.female_share) || options.female_share < 0.0 || options.female_share > 1.0) {
    throw core::ConfigError({}, "--mix",
                            std::to_string(options.female_share) + ": expected the share of women, a number in [0, 1]");
  }
  validateSex(options.figures.men, "population.figures.men");
  validateSex(options.figures.women, "population.figures.women");
  const double cv = options.figures.strength_cv;
  if (!std::isfinite(cv) || cv <= 0.0 || cv > 2.0) {
    throw core::ConfigError({}, "population.figures.strength_cv", std::to_string(cv) + ": expected 0 < cv <= 2");
  }
  const double rs = options.figures.strength_size_correlation;
  if (!std::isfinite(rs) || rs <= -1.0 || rs >= 1.0) {
    throw core::ConfigError({}, "population.figures.strength_size_correlation",
                            std::to_string(rs) + ": expected -1 < r < 1");
  }
}

Technician drawTechnician(const PopulationOptions& options, std::int64_t index, core::RandomStream& rng,
                          double nominal_upper_arm_m, double nominal_forearm_m) noexcept {
  Technician t;
  t.index = index;
  t.female = rng.uniform01() < options.female_share;
  const SexFigures& s = t.female ? options.figures.women : options.figures.men;
  double z_upper = 0.0;
  double z_free = 0.0;
  boxMuller(rng, z_upper, z_free);
  const double r = s.upper_arm_forearm_correlation;
  // P1: the forearm score correlated with the upper arm's; log-normal lengths.
  const double z_fore = r * z_upper + std::sqrt(1.0 - r * r) * z_free;
  t.upper_arm_m = s.upper_arm.p50_m * std::exp(logSigma(s.upper_arm) * z_upper);
  t.forearm_m = s.forearm.p50_m * std::exp(logSigma(s.forearm) * z_fore);
  t.link_radius_scale = std::sqrt(t.upper_arm_m / nominal_upper_arm_m * t.forearm_m / nominal_forearm_m);

  // Strength: log-normal with the sex's median and the CV, its log correlated with the arm-size
  // score (the standardised sum of the two length scores) by strength_size_correlation.
  double z_strength = 0.0;
  double z_unused = 0.0;
  boxMuller(rng, z_strength, z_unused);
  const double size_score = (z_upper + z_fore) / std::sqrt(2.0 + 2.0 * r);
  const double rs = options.figures.strength_size_correlation;
  const double z = rs * size_score + std::sqrt(1.0 - rs * rs) * z_strength;
  const double cv = options.figures.strength_cv;
  const double sigma = std::sqrt(std::log1p(cv * cv));
  t.strength_scale = s.strength_median * std::exp(sigma * z);
  return t;
}

Technician drawTechnician(const PopulationOptions& options, std::int64_t index, const arm::ArmModel& nominal) {
  const arm::ArmSize size = arm::armSizeOf(nominal);
  if (!size.upper_arm_length_m || !size.forearm_length_m || *size.upper_arm_length_m <= 0.0 ||
      *size.forearm_length_m <= 0.0) {
    throw core::ConfigError(nominal.source, "upper_arm_joint",
                            "the population needs an arm model that names its upper-arm and forearm joints");
  }
  core::RandomStream rng(options.seed, static_cast<std::uint64_t>(core::nameSlot("technicians")),
                         static_cast<std::uint64_t>(index));
  return drawTechnician(options, index, rng, *size.upper_arm_length_m, *size.forearm_length_m);
}

arm::ArmModel technicianArm(const arm::ArmModel& nominal, const Technician& technician) {
  arm::ArmSize size;
  size.upper_arm_length_m = technician.upper_arm_m;
  size.forearm_length_m = technician.forearm_m;
  size.link_radius_scale = technician.link_radius_scale;
  return arm::scaleArm(nominal, size);
}

HumanArm technicianStrength(const HumanArm& nominal, const Technician& technician) {
  HumanArm human = nominal;
  human.strength_scale = technician.strength_scale;
  return human;
}

}  // namespace fullarm::accessibility
