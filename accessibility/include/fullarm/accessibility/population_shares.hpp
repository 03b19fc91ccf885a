#pragma once
/// @file
/// Shares of a technician population that meet a criterion (reach in one mode, push at least F
/// with or without bracing), with confidence intervals, and what limits the rest: a logistic fit
/// of success on the technicians' body dimensions and strength, and the split of the failures by
/// the factor that weighs most against each (docs/accessibility.md, "Population").

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "fullarm/accessibility/population.hpp"

namespace fullarm::accessibility {

/// A share with its two-sided confidence interval.
struct ShareInterval {
  std::int64_t successes = 0;
  std::int64_t trials = 0;
  double share = 0.0;  ///< successes / trials
  double lower = 0.0;
  double upper = 1.0;
  double confidence = 0.95;
};

/// The Wilson score interval (Wilson 1927): the shares p with |share - p| <= z sqrt(p (1 - p) / n),
/// z the normal quantile of (1 + confidence) / 2.
/// @throws std::invalid_argument for trials < 1, successes outside [0, trials] or confidence
///         outside (0, 1).
[[nodiscard]] ShareInterval wilsonInterval(std::int64_t successes, std::int64_t trials, double confidence = 0.95);

/// The exact Clopper-Pearson interval (Clopper and Pearson 1934): lower bound p with
/// P(X >= successes | p) = (1 - confidence) / 2, upper with P(X <= successes | p) = the same,
/// X ~ Binomial(trials, p); 0 and 1 at the ends. Solved by bisection on the binomial tails.
/// @throws std::invalid_argument as wilsonInterval.
[[nodiscard]] ShareInterval clopperPearsonInterval(std::int64_t successes, std::int64_t trials,
                                                   double confidence = 0.95);

/// The factors a technician's outcome is explained by.
enum class PopulationFactor { kUpperArm = 0, kForearm = 1, kStrength = 2 };
/// Number of PopulationFactor values.
inline constexpr int kPopulationFactors = 3;
/// "upper arm", "forearm", "strength".
[[nodiscard]] const char* factorName(PopulationFactor factor) noexcept;

/// One criterion over a population.
struct CriterionSummary {
  ShareInterval wilson;           ///< the share with its Wilson interval
  ShareInterval clopper_pearson;  ///< the same share with the exact interval
  /// Logistic fit P(success) = 1 / (1 + exp(-(b0 + sum_k b_k x_k))) with x_k the factor's
  /// standardised log (log length or log strength minus its population mean, over its standard
  /// deviation): b_k, the change in log-odds per standard deviation of factor k. Zero when every
  /// technician succeeds or every one fails.
  std::array<double, kPopulationFactors> log_odds_per_sd{};
  double intercept = 0.0;      ///< b0
  bool fit_separated = false;  ///< the factors separate successes from failures (b stopped by the penalty)
  /// Failures split by their limiting factor: for each failed technician, the factor k with the
  /// most negative b_k x_k (the one that lowers that technician's odds most below a technician
  /// with the population's mean factors).
  std::array<std::int64_t, kPopulationFactors> failures_by_factor{};
  /// Failures where no factor lowers the odds (b_k x_k >= 0 for every k): not explained by the
  /// body dimensions or strength the fit sees.
  std::int64_t failures_unexplained = 0;
};

/// Which factors may explain a criterion: reach depends on the arm's size, never on its strength,
/// so a reach criterion leaves strength out of the fit (its coefficient stays 0 and no failure is
/// put on it, however strength happens to correlate with the failures in a finite sample).
using FactorMask = std::array<bool, kPopulationFactors>;
/// Every factor.
inline constexpr FactorMask kAllFactors{true, true, true};
/// The arm's segment lengths only (the reach criteria).
inline constexpr FactorMask kSizeFactors{true, true, false};

/// Summarises `success` (one flag per technician, same order) over `technicians`, explaining the
/// failures by the factors in `factors` only.
/// The logistic fit is Newton's method on the log-likelihood with a small ridge penalty
/// (1e-3 sum b_k^2, not on b0) so that it ends when the data separate.
/// @throws std::invalid_argument when the sizes differ or there are no technicians.
[[nodiscard]] CriterionSummary summariseCriterion(const std::vector<Technician>& technicians,
                                                  const std::vector<bool>& success, double confidence = 0.95,
                                                  const FactorMask& factors = kAllFactors);

}  // namespace fullarm::accessibility
