#pragma once
/// @file
/// Classical stability margins of a scalar loop transfer L (negative-feedback convention:
/// the closed loop is 1/(1 + L)), computed from its frequency response on a logarithmic grid
/// with every crossing refined by bisection (offline, not @rt).
///
/// Definitions (Skogestad & Postlethwaite, Multivariable Feedback Control, 2nd ed., sec. 2.4;
/// MATLAB `allmargin` for the delay margin):
///   gain margin GM = 1/|L(j w180)| at each phase crossover w180 (arg L = -180 deg);
///   phase margin PM = 180 deg + arg L(j wc) at each gain crossover wc (|L| = 1);
///   delay margin DM = PM [rad] / wc (smallest over the crossovers with PM > 0);
///   peak sensitivity Ms = max_w |1/(1 + L(j w))|;
///   sector (circle-criterion) margin min_w Re L(j w): Re L > -1 for the saturation sector [0, 1].

#include <complex>
#include <functional>
#include <limits>
#include <vector>

namespace fullarm::design {

/// Frequency response of a scalar loop: L(w) for w in rad/s (s = j w, or z = e^{j w T}).
using LoopResponse = std::function<std::complex<double>(double)>;

/// Where to look: a logarithmic grid on [w_min, w_max], refined at every crossing.
struct MarginOptions {
  double w_min_radps = 1e-3;
  double w_max_radps = 1e3;
  int grid_points = 2000;
  /// Discrete loop of period T: w_max is clipped to the Nyquist frequency pi/T, and a real
  /// negative L(e^{j pi}) counts as a phase crossover there.
  double sample_time_s = 0.0;
};

/// Margins of one loop. Values without a crossover are +infinity (GM, PM, DM) and their
/// frequency NaN.
struct LoopMargins {
  double gain_margin = std::numeric_limits<double>::infinity();  ///< smallest GM > 1 (upward)
  double gain_margin_radps = std::numeric_limits<double>::quiet_NaN();
  /// Largest GM < 1 (a conditionally stable loop goes unstable when its gain drops by this
  /// factor); 0 when there is none.
  double lower_gain_margin = 0.0;
  double lower_gain_margin_radps = std::numeric_limits<double>::quiet_NaN();
  double phase_margin_deg = std::numeric_limits<double>::infinity();  ///< smallest over the crossovers
  double phase_margin_radps = std::numeric_limits<double>::quiet_NaN();
  double delay_margin_s = std::numeric_limits<double>::infinity();
  double delay_margin_radps = std::numeric_limits<double>::quiet_NaN();
  double peak_sensitivity = 0.0;  ///< Ms
  double peak_sensitivity_radps = std::numeric_limits<double>::quiet_NaN();
  double min_real = std::numeric_limits<double>::infinity();  ///< min Re L over the grid
  double min_real_radps = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> phase_crossovers_radps;
  std::vector<double> gain_crossovers_radps;
};

/// Computes the margins of `loop` (see the file comment for the definitions).
/// @throws std::invalid_argument for an empty or inverted frequency range or < 16 grid points.
[[nodiscard]] LoopMargins computeMargins(const LoopResponse& loop, const MarginOptions& options);

}  // namespace fullarm::design
