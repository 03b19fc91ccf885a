#pragma once
/// @file
/// Coupled stability of the device with the users `fullarm validate` draws, and the damping of
/// the coupled user-device mode that validate's oscillation detector demands (docs/analysis.md,
/// "Coupled stability instead of unconditional passivity"). This is the tuner's hard goal in
/// place of unconditional passivity (Re Z >= 0 of the bare device: Colgate & Hogan 1988), which
/// guarantees stability with *any* passive user, B_h = 0 included, and on the DTS joints admits
/// only gains a user cannot move. Here the user is the validated one: the closed loop of device
/// + user (J_h, K_h, B_h in joint space) is checked on a grid of the validation box (user
/// stiffness, damping, inertia scale, and every computation delay 1-3 samples), in the spirit of
/// Adams & Hannaford (1999): stability of the coupled system for the operator impedances that
/// occur, not for every passive one.
///
/// Damping requirement (Eq. C2-C3 of reports/equations.md): the detector (closed_loop.hpp) judges
/// a hold oscillating when the speed deviation (std about the window mean) of its last window W
/// exceeds the threshold v_th and is at least r = kOscillationSustainRatio of the window before.
/// A mode with many periods per window, e^{-sigma t} sin(w t), gives a window ratio e^{-sigma W}:
/// judged decaying whatever its amplitude iff sigma > sigma_min = ln(1/r) / W (1.386 /s). A mode
/// slower than the window (HR's run 33: 0.32 Hz, sigma 1.49 /s) is not self-similar from window to
/// window (its late window can deviate more than the early one), so the detector passes it only
/// when its late-window deviation is below v_th. detectorModeScore() applies the detector itself
/// to a mode v(t) = V0 e^{-sigma t} cos(w t + phi) over the free hold, worst phase, with V0 the
/// peak speed of the scenario's free-move reference (15/8 A / T of the minimum-jerk move: the
/// speed the mode can carry into the hold); score <= 1 means the detector judges it decaying.
/// Offline (allocates), not @rt.

#include <Eigen/Core>
#include <complex>
#include <limits>
#include <vector>

#include "fullarm/design/closed_loop.hpp"
#include "fullarm/design/linear_analysis.hpp"
#include "fullarm/design/uncertainty.hpp"

namespace fullarm::design {

/// A pole counts as oscillatory when |arg z| exceeds this [rad] (at 1 kHz: 0.16 mHz); a real
/// pole, and a numerically split real pair, does not.
inline constexpr double kOscillatoryArgTolerance = 1e-6;

/// A real pole within this of z = 1 is the free position's drift (K_h = 0: nothing restores the
/// position; the residual of the linearised gravity compensation moves the pole to about
/// 1 + 1e-7): it is left out of the coupled spectral radius and judged by the detector score like
/// any real mode (at |z| = 1 + 1e-4 and 1 kHz the e-folding time is 10 s, longer than a run).
inline constexpr double kDriftPoleTolerance = 1e-4;

/// The slowest oscillatory mode of a discrete closed loop.
struct ModeDecay {
  /// sigma = -ln|z| / T of the slowest oscillatory pole [1/s]; +inf when no pole oscillates.
  double decay_rate_per_s = std::numeric_limits<double>::infinity();
  double frequency_hz = 0.0;     ///< its frequency |arg z| / (2 pi T)
  double damping_ratio = 1.0;    ///< sigma / |s| of s = ln(z) / T
  double spectral_radius = 0.0;  ///< largest |z| of all poles (oscillatory or not)
};

/// The slowest oscillatory mode of the poles `poles_z` of a loop sampled at `period_s`.
/// @throws std::invalid_argument for period_s <= 0.
[[nodiscard]] ModeDecay slowestOscillatoryMode(const Eigen::VectorXcd& poles_z, double period_s);

/// Largest |z| of `poles_z` without the free-position drift: real poles within
/// kDriftPoleTolerance of z = 1 are left out (0 when nothing is left). Both the coupled goal and
/// the tuner's plain spectral-radius goal use it, so one tolerance decides what is drift.
[[nodiscard]] double spectralRadiusWithoutDrift(const Eigen::VectorXcd& poles_z);

/// The decay rate sigma_min = ln(1/ratio) / window [1/s] a mode needs to be judged decaying by a
/// detector that compares consecutive windows of length `window_s` (Eq. C2).
/// @throws std::invalid_argument unless window_s > 0 and 0 < ratio < 1.
[[nodiscard]] double detectorDecayRate(double window_s, double sustain_ratio = kOscillationSustainRatio);

/// Fractions of the validated K_h range (from its low end) on the coupled grid: zero, the weak
/// users that ring slowly (run 33: K_h 4.1 of 75) and the stiffest.
inline constexpr double kCoupledStiffnessFractions[] = {0.0, 1.0 / 64.0, 1.0 / 16.0, 0.25, 1.0};
/// Fractions of the validated B_h range: the undamped user, a lightly damped one, the most damped.
inline constexpr double kCoupledDampingFractions[] = {0.0, 1.0 / 16.0, 1.0};

/// The user/delay grid of the validation box around one plant variation: every combination of
/// the K_h and B_h fractions above, the inertia scale at both ends of its range, and every
/// delay in [delay_min_samples, delay_max_samples]; bulk modulus, valve gain and friction are
/// `plant`'s. Order: delay, inertia, damping, stiffness (stiffness fastest).
[[nodiscard]] std::vector<ModelVariation> coupledVariations(const ModelVariation& plant,
                                                            const UncertaintyRanges& ranges);

/// prepareVariation() of every coupledVariations() of every plant variation in `plants`.
[[nodiscard]] std::vector<PreparedJoint> prepareCoupledGrid(const JointPlantModel& nominal, double q_rad,
                                                            const LoopSetup& setup,
                                                            const std::vector<ModelVariation>& plants,
                                                            const UncertaintyRanges& ranges);

/// What the detector sees of a closed-loop mode over the free hold (closed_loop.hpp).
struct DetectorModel {
  double hold_s = 1.1;            ///< hold length (ScenarioTiming::free_hold_s; contact_hold_s for Eq. C6)
  double window_s = 0.5;          ///< detector window (ScenarioTiming::detect_window_s)
  double threshold_radps = 0.05;  ///< speed-deviation threshold
  double sustain_ratio = kOscillationSustainRatio;
  double initial_speed_radps = 1.125;  ///< V0: the free move's peak reference speed, 15/8 A / T
  double period_s = 1e-3;              ///< sampling of the windows (the control period)
  /// The scenario's free move (minimum jerk from rest, amplitude and duration), used when
  /// `modal_amplitude` is set.
  double move_amplitude_rad = 0.3;
  double move_duration_s = 0.5;
  /// V0 of each mode: false, initial_speed_radps for every mode (the bound of Eq. C3); true, the
  /// mode's own speed amplitude at the start of the hold from the discrete closed loop driven by
  /// the move (modalHoldSpeeds(), Eq. C5).
  bool modal_amplitude = false;
};
/// The detector model of a scenario's free hold (its timing, threshold and free move).
[[nodiscard]] DetectorModel detectorModelOf(const JointScenario& scenario) noexcept;

/// The detector model of a scenario's contact hold (Eq. C6): the contact hold's length, the same
/// window, ratio and threshold, and V0 the peak speed of the contact move's reference,
/// 15/8 (wall gap + push) / T_contact (0.94 rad/s by default): a bound on the speed the arrival at
/// the wall can leave in a contact mode. modal_amplitude is false (the arrival is an impact, not
/// the smooth drive of Eq. C5).
[[nodiscard]] DetectorModel contactDetectorModelOf(const JointScenario& scenario) noexcept;

/// The detector applied to the mode V0 e^{-sigma t} cos(w t + phi) over the hold, worst phase:
/// max over phi of min(late / v_th, late / (r early)), late and early the speed deviations of the
/// last two windows. <= 1: judged decaying for every phase; > 1: judged oscillating for some.
/// @throws std::invalid_argument unless hold_s >= 2 window_s > 0 and the other fields are > 0.
[[nodiscard]] double detectorModeScore(double decay_rate_per_s, double w_radps, const DetectorModel& detector);

/// One closed-loop mode's share of the free hold's speed: q'[N + n] - q'_ss = sum_i coefficient_i
/// pole_i^n over all poles (conjugate pairs carry conjugate coefficients), n counted from the start
/// of the hold.
struct ModalSpeed {
  std::complex<double> pole;         ///< z
  std::complex<double> coefficient;  ///< [rad/s]
};

/// The free hold's speed in the modes of the coupled closed loop (free motion, the model's user and
/// delay) after the scenario's free move (Eq. C5): the user's torque K_h r + B_h r' (r the
/// minimum-jerk reference from rest, sampled and held as validate's harness applies it) drives
/// the closed loop from rest for round(move_duration_s / T) periods; the modal coordinates at the
/// end of the move, less those of the steady state under the final torque, give the coefficients,
/// in one pass over the move's samples per mode (no simulation). The eigenvectors come from the
/// closed loop after a power-of-two diagonal balancing (its states mix pascals and radians).
/// A non-finite closed loop, or one whose balanced eigen-decomposition fails, gives the poles of
/// closedLoopPoles() (which throws std::runtime_error when they do not converge) with NaN
/// coefficients; evaluateCoupled then scores those poles with Eq. C3's bound.
[[nodiscard]] std::vector<ModalSpeed> modalHoldSpeeds(const PreparedJoint& model, const controllers::JointGains& gains,
                                                      const DetectorModel& detector);

/// The coupled goal of one gain set over a set of coupled models (free motion, each model's own
/// user and delay).
struct CoupledGoal {
  double spectral_radius = 0.0;       ///< worst closed-loop spectral radius (drift excluded by evaluateCoupled only)
  ModeDecay slowest;                  ///< the slowest oscillatory mode over the set
  int worst_model = -1;               ///< index of the model with the slowest oscillatory mode
  double detector_score = 0.0;        ///< worst detectorModeScore() of any pole of any model
  double detector_hz = 0.0;           ///< frequency of that pole
  double detector_decay_per_s = 0.0;  ///< and its decay rate
  int detector_model = -1;            ///< index of its model
};
/// Poles, slowest mode and detector score of every model (free motion, each model's own user
/// and delay). Poles decaying faster than ln(1e3 V0 / v_th) / (hold - W) are skipped by the score
/// (their late window is below a thousandth of the threshold).
[[nodiscard]] CoupledGoal evaluateCoupled(const std::vector<PreparedJoint>& models,
                                          const controllers::JointGains& gains, const DetectorModel& detector);

/// The contact goal of one gain set (Eq. C6): the closed loop of every model (its own user and
/// delay) held against `wall`, each mode scored by `contact_detector` (contactDetectorModelOf())
/// with its V0 bound. Nothing is left out as drift (the wall restores the position): the
/// spectral radius is the plain one. Measured on SFE (docs/analysis.md, "Contact damping"): the
/// stiff users' contact oscillations of the nonlinear runs are the contact modes of
/// this loop (1.9-2.4 Hz) whose decay rate is below the detector's ln 2 / W, or that grow.
[[nodiscard]] CoupledGoal evaluateCoupledContact(const std::vector<PreparedJoint>& models,
                                                 const controllers::JointGains& gains, const VirtualWall& wall,
                                                 const DetectorModel& contact_detector);

/// Normalised coupled hard goal (<= 1: met): max(spectral radius, detector score), the
/// free-position pole at z = 1 tolerated as in LinearChecks::stable.
[[nodiscard]] double coupledGoalValue(const CoupledGoal& goal) noexcept;

}  // namespace fullarm::design
