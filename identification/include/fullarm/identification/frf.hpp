#pragma once
/// @file
/// Non-parametric frequency response from a closed-loop experiment (Welch averaging of
/// windowed, mean-removed segments).
///
/// In closed loop the command u carries the sensor noise fed back through the controller, so
/// the plain H1 estimate S_uy / S_uu is biased (towards minus the inverse of the controller where
/// the noise dominates). The excitation r added to the command is independent of that noise: the
/// estimate S_ry / S_ru (r as the instrument) is consistent. Cross spectra are S_xy = E[conj(X) Y].

#include <complex>
#include <vector>

namespace fullarm::identification {

/// Welch options.
struct FrfOptions {
  int segment_samples = 2048;  ///< segment length (sets the resolution 1 / (segment T))
  double overlap = 0.5;        ///< fraction of a segment shared with the next, in [0, 1)
  bool hann_window = true;     ///< Hann window; false: rectangular (whole periods of a periodic excitation)
};

/// Estimates at the positive frequencies k / (segment T), k = 1 .. segment / 2 - 1 (from k = 2
/// with the Hann window, whose main lobe puts bin 1 next to the removed mean).
struct FrfEstimate {
  std::vector<double> frequency_hz;
  std::vector<std::complex<double>> h1;          ///< S_uy / S_uu (biased under feedback)
  std::vector<std::complex<double>> instrument;  ///< S_ry / S_ru
  std::vector<double> coherence_uy;              ///< |S_uy|^2 / (S_uu S_yy)
  std::vector<double> coherence_ry;              ///< |S_ry|^2 / (S_rr S_yy)
  std::vector<double> coherence_ru;              ///< |S_ru|^2 / (S_rr S_uu)
  int segments = 0;                              ///< segments averaged
};

/// FRF from command u to output y with the excitation r as instrument.
/// @param r excitation, @param u command, @param y output: equal lengths, at least one segment
/// @throws std::invalid_argument for unequal lengths, too short a record, a segment below 8
///   samples, an overlap outside [0, 1) or a non-positive period
[[nodiscard]] FrfEstimate estimateFrf(const std::vector<double>& r, const std::vector<double>& u,
                                      const std::vector<double>& y, double sample_period_s,
                                      const FrfOptions& options = {});

/// 20 log10 |h| [dB].
[[nodiscard]] double magnitudeDb(std::complex<double> h) noexcept;

}  // namespace fullarm::identification
