#pragma once
/// @file
/// Excitation signals for identification experiments, sampled at a fixed period: linear and
/// logarithmic chirps, maximum-length PRBS, Schroeder-phase multisines (with their crest
/// factor) and step sequences. Each is added to a joint's valve command during a closed-loop
/// experiment, in volts.

#include <cstdint>
#include <string>
#include <vector>

namespace fullarm::identification {

/// A sampled signal: value[k] holds over [time_s[k], time_s[k] + sample_period_s).
struct SampledSignal {
  double sample_period_s = 1.0e-3;
  std::vector<double> time_s;
  std::vector<double> value_v;
};

/// Linear chirp A sin(2 pi (f0 t + (f1 - f0) t^2 / (2 T))) over [0, T): the instantaneous
/// frequency rises linearly from f0 to f1.
/// @throws std::invalid_argument for a non-positive period, duration or frequency, or f1 above Nyquist
[[nodiscard]] SampledSignal linearChirp(double amplitude_v, double start_hz, double stop_hz, double duration_s,
                                        double sample_period_s);

/// Logarithmic (exponential) chirp A sin(2 pi f0 T (r^(t/T) - 1) / ln r), r = f1 / f0: the
/// instantaneous frequency f0 r^(t/T) rises geometrically, the same time per decade.
/// @throws std::invalid_argument as linearChirp, and for f1 <= f0
[[nodiscard]] SampledSignal logChirp(double amplitude_v, double start_hz, double stop_hz, double duration_s,
                                     double sample_period_s);

/// Maximum-length pseudo-random binary sequence: a Fibonacci linear feedback shift register of
/// `order` bits (2..24, primitive feedback taps) gives a period of 2^order - 1 clock periods of
/// +-A, each clock period `clock_samples` samples long; `periods` whole periods are generated.
/// Its power spectrum is flat to within 3 dB up to about 0.44 / (clock_samples T).
/// @throws std::invalid_argument for an order outside 2..24, clock_samples < 1 or periods < 1
[[nodiscard]] SampledSignal prbs(double amplitude_v, int order, int clock_samples, int periods, double sample_period_s);

/// Clock period (in samples) of a PRBS whose flat band reaches `band_hz`: round(1 / (2 B T)), at
/// least 1 (the first spectral null then sits at about 2 B).
/// @throws std::invalid_argument for a non-positive band or period
[[nodiscard]] int prbsClockSamplesForBand(double band_hz, double sample_period_s);

/// A Schroeder-phase multisine and its figures.
struct Multisine {
  SampledSignal signal;
  double fundamental_hz = 0.0;  ///< 1 / period
  std::vector<int> harmonics;   ///< excited harmonic numbers k (frequency k f0)
  double crest_factor = 0.0;    ///< peak |u| / RMS(u) over one period
  int samples_per_period = 0;
};

/// Schroeder multisine sum_k cos(2 pi k f0 t + phi_k), phi_k = -pi k (k - 1) / N over the N
/// consecutive harmonics k = ceil(f_lo / f0) .. floor(f_hi / f0) (counted from 1 in the phase
/// formula), equal amplitudes, scaled so its peak over a period is `amplitude_v`;
/// `periods` whole periods of length `period_s` (rounded to whole samples).
/// @throws std::invalid_argument when no harmonic lies in the band, f_hi is above Nyquist, or
///   periods < 1
[[nodiscard]] Multisine schroederMultisine(double amplitude_v, double low_hz, double high_hz, double period_s,
                                           int periods, double sample_period_s);

/// Steps: each level held for `hold_s` in turn (levels in volts).
/// @throws std::invalid_argument for no levels or a non-positive hold or period
[[nodiscard]] SampledSignal stepSequence(const std::vector<double>& levels_v, double hold_s, double sample_period_s);

/// Crest factor peak |u| / RMS(u) of a signal (0 for an all-zero signal).
[[nodiscard]] double crestFactor(const std::vector<double>& values);

}  // namespace fullarm::identification
