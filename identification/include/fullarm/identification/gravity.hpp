#pragma once
/// @file
/// The arm's gravity load from static holds. Gravity torque is linear in each link's mass and
/// first moments, g(q) = Y(q) pi with pi = [m, m c_x, m c_y, m c_z] per link (centre of mass c
/// in the link frame) (I8). Only the combinations in the row space of the stacked regressor are
/// determined by holds (the base parameters); the fit takes the least-squares solution closest
/// to the nominal model, so the directions the holds cannot see keep their nominal values.

#include <Eigen/Core>
#include <vector>

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::identification {

/// Y(q) (joints x 4 links): column 4 i + 0 is link i's mass, 4 i + 1..3 its first moments.
[[nodiscard]] Eigen::MatrixXd gravityRegressor(const arm::ArmModel& model, const Eigen::VectorXd& q);

/// pi of `model` (4 per link).
[[nodiscard]] Eigen::VectorXd gravityParameters(const arm::ArmModel& model);

/// `model` with the masses and centres of mass of `pi` (c = first moment / mass); inertias
/// about the centre of mass unchanged.
/// @throws std::invalid_argument when a link's mass is not positive (not physically consistent)
[[nodiscard]] arm::ArmModel withGravityParameters(const arm::ArmModel& model, const Eigen::VectorXd& pi);

/// Result of a gravity fit.
struct GravityFit {
  Eigen::VectorXd parameters;       ///< pi, closest to the nominal among the least-squares solutions
  int rank = 0;                     ///< number of base parameters the holds determine
  Eigen::MatrixXd base_directions;  ///< rank x 4 links: rows span what the holds determine
  Eigen::VectorXd base_values;      ///< base_directions * parameters
  Eigen::VectorXd residual_rms_nm;  ///< per joint, over the holds
  bool positive_masses = false;     ///< every link's fitted mass > 0
};

/// Fits pi to measured holding torques: `torques_nm[k]` holds the arm still at `postures[k]`
/// (both configuration vectors). pi = pi_nom + Y^+ (tau - Y pi_nom) over the links that have
/// mass in `nominal` (massless links stay massless).
/// @throws std::invalid_argument for no holds or vectors of the wrong size
[[nodiscard]] GravityFit fitGravityParameters(const arm::ArmModel& nominal,
                                              const std::vector<Eigen::VectorXd>& postures,
                                              const std::vector<Eigen::VectorXd>& torques_nm);

}  // namespace fullarm::identification
