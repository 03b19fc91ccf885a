#include "fullarm/identification/excitation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace fullarm::identification {
namespace {

void requirePositive(double value, const char* what) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw std::invalid_argument(std::string(what) + " must be positive and finite, got " + std::to_string(value));
  }
}

void requireChirpBand(double start_hz, double stop_hz, double duration_s, double sample_period_s) {
  requirePositive(sample_period_s, "sample period [s]");
  requirePositive(duration_s, "duration [s]");
  requirePositive(start_hz, "start frequency [Hz]");
  requirePositive(stop_hz, "stop frequency [Hz]");
  const double nyquist_hz = 0.5 / sample_period_s;
  if (stop_hz > nyquist_hz || start_hz > nyquist_hz) {
    throw std::invalid_argument("chirp band " + std::to_string(start_hz) + ".." + std::to_string(stop_hz) +
                                " Hz reaches above the Nyquist frequency " + std::to_string(nyquist_hz) + " Hz");
  }
}

std::size_t sampleCount(double duration_s, double sample_period_s) {
  return static_cast<std::size_t>(std::llround(duration_s / sample_period_s));
}

SampledSignal emptySignal(std::size_t n, double sample_period_s) {
  SampledSignal s;
  s.sample_period_s = sample_period_s;
  s.time_s.resize(n);
  s.value_v.resize(n);
  for (std::size_t k = 0; k < n; ++k) s.time_s[k] = static_cast<double>(k) * sample_period_s;
  return s;
}

// Feedback taps (1-based register positions) of a maximum-length Fibonacci LFSR per order
// (primitive trinomials and pentanomials; Xilinx XAPP052 table). Unused entries are 0.
constexpr std::array<std::array<int, 4>, 25> kPrbsTaps{{
    {0, 0, 0, 0},   {0, 0, 0, 0},   {2, 1, 0, 0},    {3, 2, 0, 0},     {4, 3, 0, 0},   {5, 3, 0, 0},  {6, 5, 0, 0},
    {7, 6, 0, 0},   {8, 6, 5, 4},   {9, 5, 0, 0},    {10, 7, 0, 0},    {11, 9, 0, 0},  {12, 6, 4, 1}, {13, 4, 3, 1},
    {14, 5, 3, 1},  {15, 14, 0, 0}, {16, 15, 13, 4}, {17, 14, 0, 0},   {18, 11, 0, 0}, {19, 6, 2, 1}, {20, 17, 0, 0},
    {21, 19, 0, 0}, {22, 21, 0, 0}, {23, 18, 0, 0},  {24, 23, 22, 17},
}};

}  // namespace

SampledSignal linearChirp(double amplitude_v, double start_hz, double stop_hz, double duration_s,
                          double sample_period_s) {
  requireChirpBand(start_hz, stop_hz, duration_s, sample_period_s);
  SampledSignal s = emptySignal(sampleCount(duration_s, sample_period_s), sample_period_s);
  const double rate = (stop_hz - start_hz) / duration_s;
  for (std::size_t k = 0; k < s.time_s.size(); ++k) {
    const double t = s.time_s[k];
    s.value_v[k] = amplitude_v * std::sin(2.0 * std::numbers::pi * (start_hz * t + 0.5 * rate * t * t));
  }
  return s;
}

SampledSignal logChirp(double amplitude_v, double start_hz, double stop_hz, double duration_s, double sample_period_s) {
  requireChirpBand(start_hz, stop_hz, duration_s, sample_period_s);
  if (!(stop_hz > start_hz)) {
    throw std::invalid_argument("a logarithmic chirp needs stop frequency > start frequency, got " +
                                std::to_string(start_hz) + " .. " + std::to_string(stop_hz) + " Hz");
  }
  SampledSignal s = emptySignal(sampleCount(duration_s, sample_period_s), sample_period_s);
  const double log_ratio = std::log(stop_hz / start_hz);
  for (std::size_t k = 0; k < s.time_s.size(); ++k) {
    const double t = s.time_s[k];
    const double phase = start_hz * duration_s * std::expm1(log_ratio * t / duration_s) / log_ratio;
    s.value_v[k] = amplitude_v * std::sin(2.0 * std::numbers::pi * phase);
  }
  return s;
}

SampledSignal prbs(double amplitude_v, int order, int clock_samples, int periods, double sample_period_s) {
  requirePositive(sample_period_s, "sample period [s]");
  if (order < 2 || order > 24) {
    throw std::invalid_argument("PRBS order must be 2..24, got " + std::to_string(order));
  }
  if (clock_samples < 1) throw std::invalid_argument("PRBS clock period must be >= 1 sample");
  if (periods < 1) throw std::invalid_argument("PRBS needs at least one period");
  const std::size_t length = (std::size_t{1} << order) - 1;
  const std::size_t n = length * static_cast<std::size_t>(clock_samples) * static_cast<std::size_t>(periods);
  SampledSignal s = emptySignal(n, sample_period_s);
  const auto& taps = kPrbsTaps[static_cast<std::size_t>(order)];
  // I4: Fibonacci LFSR, x_{k+n} = XOR of the tapped bits; period 2^n - 1 for primitive taps.
  std::uint32_t reg = (1u << order) - 1u;  // any non-zero state
  std::size_t k = 0;
  for (std::size_t bit = 0; bit < length * static_cast<std::size_t>(periods); ++bit) {
    const std::uint32_t out = (reg >> (order - 1)) & 1u;
    std::uint32_t feedback = 0;
    for (int tap : taps) {
      if (tap > 0) feedback ^= (reg >> (tap - 1)) & 1u;
    }
    reg = ((reg << 1) | feedback) & ((1u << order) - 1u);
    const double level = out != 0u ? amplitude_v : -amplitude_v;
    for (int c = 0; c < clock_samples; ++c) s.value_v[k++] = level;
  }
  return s;
}

int prbsClockSamplesForBand(double band_hz, double sample_period_s) {
  requirePositive(band_hz, "PRBS band [Hz]");
  requirePositive(sample_period_s, "sample period [s]");
  return std::max(1, static_cast<int>(std::lround(1.0 / (2.0 * band_hz * sample_period_s))));
}

Multisine schroederMultisine(double amplitude_v, double low_hz, double high_hz, double period_s, int periods,
                             double sample_period_s) {
  requirePositive(sample_period_s, "sample period [s]");
  requirePositive(period_s, "multisine period [s]");
  requirePositive(high_hz, "multisine upper frequency [Hz]");
  if (periods < 1) throw std::invalid_argument("a multisine needs at least one period");
  if (high_hz > 0.5 / sample_period_s) {
    throw std::invalid_argument("multisine upper frequency " + std::to_string(high_hz) +
                                " Hz is above the Nyquist frequency " + std::to_string(0.5 / sample_period_s) + " Hz");
  }
  Multisine m;
  m.samples_per_period = static_cast<int>(std::llround(period_s / sample_period_s));
  if (m.samples_per_period < 2) throw std::invalid_argument("multisine period shorter than two samples");
  m.fundamental_hz = 1.0 / (m.samples_per_period * sample_period_s);
  const int k_lo = std::max(1, static_cast<int>(std::ceil(low_hz / m.fundamental_hz - 1e-9)));
  const int k_hi =
      std::min(static_cast<int>(std::floor(high_hz / m.fundamental_hz + 1e-9)), (m.samples_per_period - 1) / 2);
  if (k_hi < k_lo) {
    throw std::invalid_argument("no harmonic of " + std::to_string(m.fundamental_hz) + " Hz lies in " +
                                std::to_string(low_hz) + ".." + std::to_string(high_hz) + " Hz");
  }
  for (int k = k_lo; k <= k_hi; ++k) m.harmonics.push_back(k);
  const double count = static_cast<double>(m.harmonics.size());
  std::vector<double> one(static_cast<std::size_t>(m.samples_per_period), 0.0);
  for (std::size_t i = 0; i < m.harmonics.size(); ++i) {
    const double j = static_cast<double>(i + 1);
    const double phase = -std::numbers::pi * j * (j - 1.0) / count;  // I3: Schroeder 1970
    const double w = 2.0 * std::numbers::pi * m.harmonics[i] / m.samples_per_period;
    for (std::size_t n = 0; n < one.size(); ++n) one[n] += std::cos(w * static_cast<double>(n) + phase);
  }
  double peak = 0.0;
  for (double v : one) peak = std::max(peak, std::abs(v));
  for (double& v : one) v *= amplitude_v / peak;
  m.crest_factor = crestFactor(one);
  m.signal = emptySignal(one.size() * static_cast<std::size_t>(periods), sample_period_s);
  for (std::size_t k = 0; k < m.signal.value_v.size(); ++k) m.signal.value_v[k] = one[k % one.size()];
  return m;
}

SampledSignal stepSequence(const std::vector<double>& levels_v, double hold_s, double sample_period_s) {
  requirePositive(sample_period_s, "sample period [s]");
  requirePositive(hold_s, "step hold [s]");
  if (levels_v.empty()) throw std::invalid_argument("a step sequence needs at least one level");
  const std::size_t per = std::max<std::size_t>(1, sampleCount(hold_s, sample_period_s));
  SampledSignal s = emptySignal(per * levels_v.size(), sample_period_s);
  for (std::size_t k = 0; k < s.value_v.size(); ++k) s.value_v[k] = levels_v[k / per];
  return s;
}

double crestFactor(const std::vector<double>& values) {
  double peak = 0.0;
  double sum_sq = 0.0;
  for (double v : values) {
    peak = std::max(peak, std::abs(v));
    sum_sq += v * v;
  }
  if (values.empty() || sum_sq == 0.0) return 0.0;
  return peak / std::sqrt(sum_sq / static_cast<double>(values.size()));
}

}  // namespace fullarm::identification
