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

/// What makes a link's gravity parameters physically consistent.
struct GravityBounds {
  double min_mass_kg = 0.01;  ///< every link that has mass in the nominal model keeps at least this
  /// A link without capsule geometry: its centre of mass stays within this of the nominal one.
  double free_radius_m = 0.05;
  /// Weight of the pull towards the nominal, ||pi - pi_nom||^2, against the mean squared torque
  /// residual, times the largest diagonal entry of Y^T Y / rows (so it is scale-free): small, so
  /// it only breaks ties (directions the holds do not see keep their nominal values).
  double tie_weight = 1e-10;
};

/// True when link `i`'s centre of mass `com_m` (link frame) lies inside the link's bounding
/// geometry: its capsule, or (no geometry, a mesh) within `bounds.free_radius_m` of the nominal
/// centre of mass in `nominal`. `slack_m` widens the bound (a solver's tolerance).
[[nodiscard]] bool centreOfMassInside(const arm::ArmModel& nominal, int i, const Eigen::Vector3d& com_m,
                                      const GravityBounds& bounds, double slack_m = 0.0);

/// Result of a gravity fit.
struct GravityFit {
  Eigen::VectorXd parameters;       ///< pi, closest to the nominal among the least-squares solutions
  int rank = 0;                     ///< number of base parameters the holds determine
  Eigen::MatrixXd base_directions;  ///< rank x 4 links: rows span what the holds determine
  Eigen::VectorXd base_values;      ///< base_directions * parameters
  Eigen::VectorXd residual_rms_nm;  ///< per joint, over the holds
  bool positive_masses = false;     ///< every link's fitted mass > 0
  /// every massive link's centre of mass inside its bounding geometry (centreOfMassInside with
  /// the fit's bounds, the default GravityBounds for fitGravityParameters; 1e-6 m of slack)
  bool centres_inside = false;
};

/// Fits pi to measured holding torques: `torques_nm[k]` holds the arm still at `postures[k]`
/// (both configuration vectors). pi = pi_nom + Y^+ (tau - Y pi_nom) over the links that have
/// mass in `nominal` (massless links stay massless). `measured_joints` (model indices; empty: all)
/// are the joints whose torques were measured: the others' rows are left out of the fit (a hand
/// joint a log does not carry is not a measured 0 N m), and their residual is 0.
/// @throws std::invalid_argument for no holds, vectors of the wrong size or a joint index out of range
[[nodiscard]] GravityFit fitGravityParameters(const arm::ArmModel& nominal,
                                              const std::vector<Eigen::VectorXd>& postures,
                                              const std::vector<Eigen::VectorXd>& torques_nm,
                                              const std::vector<int>& measured_joints = {});

/// The physically consistent fit: minimises the mean squared torque residual plus
/// `bounds.tie_weight` times the pull towards the nominal, subject to every massive link's mass
/// >= `bounds.min_mass_kg` and its centre of mass inside its bounding geometry (centreOfMassInside).
/// The constraint set is convex ({(m, m c): c in a convex body} is a cone), so the optimum is
/// unique. When the unconstrained least-squares fit (fitGravityParameters) is consistent it is
/// returned as is; otherwise a log-barrier method with Newton steps solves the constrained
/// problem (from a strictly consistent point near the nominal, which itself may lie on or outside
/// the bounds). `rank` and `base_directions` are those of fitGravityParameters, and so is
/// `measured_joints`.
/// @throws std::invalid_argument as fitGravityParameters, or for a bound of radius 0;
///   std::runtime_error when the result is not consistent within 1e-6 m
[[nodiscard]] GravityFit fitConsistentGravityParameters(const arm::ArmModel& nominal,
                                                        const std::vector<Eigen::VectorXd>& postures,
                                                        const std::vector<Eigen::VectorXd>& torques_nm,
                                                        const GravityBounds& bounds = {},
                                                        const std::vector<int>& measured_joints = {});

}  // namespace fullarm::identification
