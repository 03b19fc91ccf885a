#include "fullarm/accessibility/population_shares.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>

namespace fullarm::accessibility {
namespace {

void checkCounts(std::int64_t successes, std::int64_t trials, double confidence) {
  if (trials < 1) throw std::invalid_argument("share interval: " + std::to_string(trials) + " trials, expected >= 1");
  if (successes < 0 || successes > trials) {
    throw std::invalid_argument("share interval: " + std::to_string(successes) + " successes of " +
                                std::to_string(trials) + " trials");
  }
  if (!(confidence > 0.0 && confidence < 1.0)) {
    throw std::invalid_argument("share interval: confidence " + std::to_string(confidence) + ", expected in (0, 1)");
  }
}

// Standard normal quantile of p in (0.5, 1), by bisection on erfc (exact to double precision).
double normalQuantile(double p) {
  double lo = 0.0;
  double hi = 40.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (1.0 - 0.5 * std::erfc(mid / std::sqrt(2.0)) < p) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

// P(X >= k), X ~ Binomial(n, p), summed in log space from the smaller tail.
double upperTail(std::int64_t k, std::int64_t n, double p) {
  if (k <= 0) return 1.0;
  if (k > n) return 0.0;
  if (p <= 0.0) return 0.0;
  if (p >= 1.0) return 1.0;
  const double lp = std::log(p);
  const double lq = std::log1p(-p);
  const double lgn = std::lgamma(static_cast<double>(n) + 1.0);
  const auto term = [&](std::int64_t i) {
    const auto di = static_cast<double>(i);
    return std::exp(lgn - std::lgamma(di + 1.0) - std::lgamma(static_cast<double>(n - i) + 1.0) + di * lp +
                    static_cast<double>(n - i) * lq);
  };
  double sum = 0.0;
  for (std::int64_t i = k; i <= n; ++i) sum += term(i);
  return std::min(1.0, sum);
}

}  // namespace

ShareInterval wilsonInterval(std::int64_t successes, std::int64_t trials, double confidence) {
  checkCounts(successes, trials, confidence);
  const double z = normalQuantile(0.5 + 0.5 * confidence);
  const auto n = static_cast<double>(trials);
  const double p = static_cast<double>(successes) / n;
  // P2: the Wilson score interval.
  const double z2n = z * z / n;
  const double centre = (p + 0.5 * z2n) / (1.0 + z2n);
  const double half = z / (1.0 + z2n) * std::sqrt(p * (1.0 - p) / n + 0.25 * z2n / n);
  ShareInterval s{successes, trials, p, std::max(0.0, centre - half), std::min(1.0, centre + half), confidence};
  if (successes == 0) s.lower = 0.0;
  if (successes == trials) s.upper = 1.0;
  return s;
}

ShareInterval clopperPearsonInterval(std::int64_t successes, std::int64_t trials, double confidence) {
  checkCounts(successes, trials, confidence);
  const double alpha2 = 0.5 * (1.0 - confidence);
  ShareInterval s{successes, trials, static_cast<double>(successes) / static_cast<double>(trials),
                  0.0,       1.0,    confidence};
  // P3: the Clopper-Pearson bounds from the binomial tails.
  // P(X >= x | p) increases with p: the lower bound is where it reaches alpha/2.
  if (successes > 0) {
    double lo = 0.0;
    double hi = 1.0;
    for (int i = 0; i < 100; ++i) {
      const double mid = 0.5 * (lo + hi);
      (upperTail(successes, trials, mid) < alpha2 ? lo : hi) = mid;
    }
    s.lower = 0.5 * (lo + hi);
  }
  // P(X <= x | p) = 1 - P(X >= x + 1 | p) decreases with p: the upper bound is where it falls to alpha/2.
  if (successes < trials) {
    double lo = 0.0;
    double hi = 1.0;
    for (int i = 0; i < 100; ++i) {
      const double mid = 0.5 * (lo + hi);
      (1.0 - upperTail(successes + 1, trials, mid) > alpha2 ? lo : hi) = mid;
    }
    s.upper = 0.5 * (lo + hi);
  }
  return s;
}

const char* factorName(PopulationFactor factor) noexcept {
  switch (factor) {
    case PopulationFactor::kUpperArm:
      return "upper arm";
    case PopulationFactor::kForearm:
      return "forearm";
    case PopulationFactor::kStrength:
      return "strength";
  }
  return "?";
}

CriterionSummary summariseCriterion(const std::vector<Technician>& technicians, const std::vector<bool>& success,
                                    double confidence, const FactorMask& factors) {
  if (technicians.empty()) throw std::invalid_argument("summariseCriterion: no technicians");
  if (technicians.size() != success.size()) {
    throw std::invalid_argument("summariseCriterion: " + std::to_string(technicians.size()) + " technicians but " +
                                std::to_string(success.size()) + " outcomes");
  }
  const auto n = static_cast<Eigen::Index>(technicians.size());
  std::int64_t wins = 0;
  for (const bool s : success) wins += s ? 1 : 0;
  CriterionSummary out;
  out.wilson = wilsonInterval(wins, n, confidence);
  out.clopper_pearson = clopperPearsonInterval(wins, n, confidence);
  if (wins == 0 || wins == n) {
    out.failures_unexplained = n - wins;
    return out;
  }

  // Standardised log factors.
  Eigen::MatrixXd x(n, kPopulationFactors);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Technician& t = technicians[static_cast<std::size_t>(i)];
    x(i, 0) = std::log(t.upper_arm_m);
    x(i, 1) = std::log(t.forearm_m);
    x(i, 2) = std::log(t.strength_scale);
  }
  for (int k = 0; k < kPopulationFactors; ++k) {
    const double mean = x.col(k).mean();
    x.col(k).array() -= mean;
    const double sd = std::sqrt(x.col(k).squaredNorm() / static_cast<double>(std::max<Eigen::Index>(n - 1, 1)));
    if (sd > 0.0) x.col(k) /= sd;
    // A factor left out is a zero column: its coefficient has only the penalty's pull and stays 0.
    if (!factors[static_cast<std::size_t>(k)]) x.col(k).setZero();
  }
  Eigen::MatrixXd a(n, kPopulationFactors + 1);
  a.col(0).setOnes();
  a.rightCols(kPopulationFactors) = x;
  Eigen::VectorXd y(n);
  for (Eigen::Index i = 0; i < n; ++i) y[i] = success[static_cast<std::size_t>(i)] ? 1.0 : 0.0;

  // P4: Newton on the penalised log-likelihood l(b) - lambda sum_{k>0} b_k^2.
  constexpr double kLambda = 1e-3;
  Eigen::VectorXd b = Eigen::VectorXd::Zero(kPopulationFactors + 1);
  const double p0 = static_cast<double>(wins) / static_cast<double>(n);
  b[0] = std::log(p0 / (1.0 - p0));
  Eigen::VectorXd penalty = Eigen::VectorXd::Constant(kPopulationFactors + 1, 2.0 * kLambda);
  penalty[0] = 0.0;
  for (int iter = 0; iter < 100; ++iter) {
    const Eigen::VectorXd eta = a * b;
    const Eigen::ArrayXd p = 1.0 / (1.0 + (-eta.array()).exp());
    const Eigen::VectorXd grad = a.transpose() * (y.array() - p).matrix() - penalty.cwiseProduct(b);
    const Eigen::ArrayXd w = (p * (1.0 - p)).max(1e-12);
    Eigen::MatrixXd h = a.transpose() * (a.array().colwise() * w).matrix();
    h.diagonal() += penalty;
    const Eigen::VectorXd step = h.ldlt().solve(grad);
    b += step;
    if (step.lpNorm<Eigen::Infinity>() < 1e-10) break;
  }
  out.intercept = b[0];
  for (int k = 0; k < kPopulationFactors; ++k) out.log_odds_per_sd[static_cast<std::size_t>(k)] = b[k + 1];
  // Separation: the fitted probabilities classify every technician correctly.
  const Eigen::VectorXd eta = a * b;
  bool separated = true;
  for (Eigen::Index i = 0; i < n && separated; ++i) separated = (eta[i] > 0.0) == (y[i] > 0.5);
  out.fit_separated = separated;

  for (Eigen::Index i = 0; i < n; ++i) {
    if (y[i] > 0.5) continue;
    int worst = -1;
    double worst_contribution = 0.0;
    for (int k = 0; k < kPopulationFactors; ++k) {
      const double c = b[k + 1] * x(i, k);
      if (c < worst_contribution) {
        worst = k;
        worst_contribution = c;
      }
    }
    if (worst < 0) {
      ++out.failures_unexplained;
    } else {
      ++out.failures_by_factor[static_cast<std::size_t>(worst)];
    }
  }
  return out;
}

}  // namespace fullarm::accessibility
