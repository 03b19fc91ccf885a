#pragma once
/// @file
/// The DTS reference's identified gravity load and the physically consistent set fitted to it.
///
/// The SL robot package for the DTS master (GitHub wonjsohn/sarcos @979c5fb, restated in
/// docs/dts-reference.md) ships a link parameter set identified on the real arm by SL's xpest
/// (`LinkParameters.cf`, first block; reference section 4.3). It predicts the arm's torques, but
/// no rigid body has its inertias and its mass distribution is not physical (a 1 g upper arm).
/// Gravity depends only on each link's mass and first moment, so its gravity torques are a
/// target a consistent set can be fitted to: fitToReferenceGravity evaluates them over many
/// postures on our arm's kinematics and fits with fitConsistentGravityParameters.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/identification/gravity.hpp"

namespace fullarm::identification {

/// `model` with the reference's masses and centres of mass on R_SFE .. R_WAA (first moments moved
/// from SL's link frames into the modified-DH frames, reference section 2.4) and every other link
/// massless (SL's hand links are all zero). Only its gravity is meaningful (inertias unchanged).
/// @throws std::invalid_argument when `model` lacks one of the seven arm joints (by name)
[[nodiscard]] arm::ArmModel withReferenceGravity(const arm::ArmModel& model);

/// A static posture the reference publishes with its torques (section 4.5, zero velocity and
/// acceleration: the gravity torques of SL's generated inverse dynamics, six decimals).
struct PublishedGravity {
  std::array<double, 7> q_rad;   ///< R_SFE .. R_WAA
  std::array<double, 7> tau_nm;  ///< R_SFE .. R_WAA
};

/// The reference's published static postures (three).
[[nodiscard]] std::vector<PublishedGravity> publishedGravity();

/// Settings of the fit to the reference's torques.
struct ReferenceFitOptions {
  int train_postures = 400;    ///< random postures inside the limits (the seven arm joints)
  int heldout_postures = 200;  ///< other random postures, for the held-out residual
  double inset_rad = 0.02;     ///< postures stay this far inside every limit
  std::uint64_t seed = 1;
  GravityBounds bounds;
};

/// Residuals against the reference's gravity torques, per arm joint (R_SFE .. R_WAA).
struct GravityComparison {
  Eigen::VectorXd train_rms_nm;      ///< RMS over the training postures
  Eigen::VectorXd heldout_rms_nm;    ///< RMS over the held-out postures
  Eigen::VectorXd published_max_nm;  ///< largest |error| at the published postures
  /// Least-squares gain k of the model's torque on the reference's over the held-out postures
  /// (model ~ k reference): 1.3 is 30 % stronger.
  Eigen::VectorXd gain;
};

/// Outcome of the fit.
struct ReferenceGravityFit {
  GravityFit fit;        ///< the consistent fit (nominal: the model given)
  arm::ArmModel fitted;  ///< the nominal with the fitted masses and centres of mass
  GravityComparison fitted_vs_reference;
  GravityComparison nominal_vs_reference;
  std::vector<std::string> joints;  ///< the seven arm joints' names
};

/// Fits a consistent set to the reference's gravity torques on `nominal`'s kinematics (hand
/// joints at the nominal default posture) and compares it and the nominal with the reference.
/// @throws as withReferenceGravity and fitConsistentGravityParameters
[[nodiscard]] ReferenceGravityFit fitToReferenceGravity(const arm::ArmModel& nominal,
                                                        const ReferenceFitOptions& options = {});

}  // namespace fullarm::identification
