#include "fullarm/identification/frf.hpp"

#include <unsupported/Eigen/FFT>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace fullarm::identification {

FrfEstimate estimateFrf(const std::vector<double>& r, const std::vector<double>& u, const std::vector<double>& y,
                        double sample_period_s, const FrfOptions& options) {
  const std::size_t n = options.segment_samples > 0 ? static_cast<std::size_t>(options.segment_samples) : 0;
  if (r.size() != u.size() || r.size() != y.size()) {
    throw std::invalid_argument("FRF: excitation, command and output differ in length (" + std::to_string(r.size()) +
                                ", " + std::to_string(u.size()) + ", " + std::to_string(y.size()) + ")");
  }
  if (n < 8)
    throw std::invalid_argument("FRF: segment of " + std::to_string(options.segment_samples) + " samples, need >= 8");
  if (r.size() < n) {
    throw std::invalid_argument("FRF: record of " + std::to_string(r.size()) +
                                " samples is shorter than one segment (" + std::to_string(n) + ")");
  }
  if (!(options.overlap >= 0.0 && options.overlap < 1.0)) {
    throw std::invalid_argument("FRF: overlap " + std::to_string(options.overlap) + " outside [0, 1)");
  }
  if (!(sample_period_s > 0.0)) throw std::invalid_argument("FRF: sample period must be positive");

  std::vector<double> window(n, 1.0);
  if (options.hann_window) {
    for (std::size_t k = 0; k < n; ++k) {
      window[k] = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(n));
    }
  }
  const std::size_t step =
      std::max<std::size_t>(1, static_cast<std::size_t>(std::floor(static_cast<double>(n) * (1.0 - options.overlap))));
  const std::size_t bins = n / 2;  // k = 1 .. n/2 - 1 kept
  using C = std::complex<double>;
  std::vector<double> s_rr(bins, 0.0), s_uu(bins, 0.0), s_yy(bins, 0.0);
  std::vector<C> s_ry(bins), s_ru(bins), s_uy(bins);
  Eigen::FFT<double> fft;
  std::vector<double> seg(n);
  std::vector<C> fr, fu, fy;
  auto transform = [&](const std::vector<double>& x, std::size_t start, std::vector<C>& out) {
    double mean = 0.0;
    for (std::size_t k = 0; k < n; ++k) mean += x[start + k];
    mean /= static_cast<double>(n);
    for (std::size_t k = 0; k < n; ++k) seg[k] = (x[start + k] - mean) * window[k];
    fft.fwd(out, seg);
  };
  FrfEstimate e;
  // I5: Welch-averaged cross spectra; H1 = S_uy / S_uu, instrument estimate S_ry / S_ru.
  for (std::size_t start = 0; start + n <= r.size(); start += step) {
    transform(r, start, fr);
    transform(u, start, fu);
    transform(y, start, fy);
    for (std::size_t k = 1; k < bins; ++k) {
      s_rr[k] += std::norm(fr[k]);
      s_uu[k] += std::norm(fu[k]);
      s_yy[k] += std::norm(fy[k]);
      s_ry[k] += std::conj(fr[k]) * fy[k];
      s_ru[k] += std::conj(fr[k]) * fu[k];
      s_uy[k] += std::conj(fu[k]) * fy[k];
    }
    ++e.segments;
  }
  const double df = 1.0 / (static_cast<double>(n) * sample_period_s);
  auto coherence = [](C sxy, double sxx, double syy) {
    return sxx > 0.0 && syy > 0.0 ? std::norm(sxy) / (sxx * syy) : 0.0;
  };
  // The Hann window's main lobe spans three bins: bin 1 shares it with DC, which the mean
  // removal has altered, so a windowed estimate starts at bin 2.
  const std::size_t first_bin = options.hann_window ? 2 : 1;
  for (std::size_t k = first_bin; k < bins; ++k) {
    e.frequency_hz.push_back(static_cast<double>(k) * df);
    e.h1.push_back(s_uu[k] > 0.0 ? s_uy[k] / s_uu[k] : C{});
    e.instrument.push_back(std::abs(s_ru[k]) > 0.0 ? s_ry[k] / s_ru[k] : C{});
    e.coherence_uy.push_back(coherence(s_uy[k], s_uu[k], s_yy[k]));
    e.coherence_ry.push_back(coherence(s_ry[k], s_rr[k], s_yy[k]));
    e.coherence_ru.push_back(coherence(s_ru[k], s_rr[k], s_uu[k]));
  }
  return e;
}

double magnitudeDb(std::complex<double> h) noexcept {
  return 20.0 * std::log10(std::abs(h));
}

}  // namespace fullarm::identification
