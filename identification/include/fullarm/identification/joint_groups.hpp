#pragma once
/// @file
/// The reduced model's parameter groups (grey_box.hpp) computed from a hydraulic joint of the
/// plant at an operating angle: the nominal start of a fit and the figures an identified model
/// is compared with.

#include <vector>

#include "fullarm/identification/grey_box.hpp"
#include "fullarm/identification/signal_csv.hpp"
#include "fullarm/plant/joint_params.hpp"

namespace fullarm::identification {

/// Groups of `joint` at `q_rad`: a = amplifier gain x no-load flow gain / D(q) (H10), K_h =
/// hydraulic stiffness at mean supply-return pressure (H9), c = internal leakage / D(q)^2, J =
/// `link_inertia_kgm2` + the actuator's inertia, b and tau_c the joint's viscous and Coulomb
/// friction, tau_st = static minus Coulomb friction, tau_g = `load_torque_nm`; offsets zero,
/// delay `delay_samples`. The known structure comes with them: the friction's smoothing and
/// Stribeck velocities, the stall torque D(q) (p_s - p_r), the mean underlap and the edge rounding
/// of the valve's metering edges in volts of command (stroke x amplifier gain per volt), the
/// spool's natural frequency and damping and the load cell's filter. D(q) is the vane's
/// displacement or the cylinder's area times its moment arm.
[[nodiscard]] GreyModel greyModelFromJoint(const plant::JointParams& joint, double q_rad, double link_inertia_kgm2,
                                           double load_torque_nm, int delay_samples);

/// The hydraulic torque the chamber pressures give at each logged angle: tau_h = p_a dV_a/dq +
/// p_b dV_b/dq, the torque the fluid applies to the joint (the plant's H5 chamber geometry of
/// `joint`: a vane's displacement, or a cylinder's piston areas times its moment arm at q, so
/// unequal areas are counted).
/// @throws std::invalid_argument for vectors of unequal length or a joint without hydraulics
[[nodiscard]] std::vector<double> hydraulicTorque(const plant::JointParams& joint, const std::vector<double>& q_rad,
                                                  const std::vector<double>& p_a_pa, const std::vector<double>& p_b_pa);

/// Fills `data.tau_hydraulic_nm` from `log`'s chamber pressures (kPressureColumns) through
/// `joint`'s geometry (hydraulicTorque); no effect for a log without them.
/// @throws std::invalid_argument naming the missing column for a log with only one of the two,
///   or for a log whose rows differ from `data`'s
void addHydraulicTorque(ExperimentData& data, const SignalTable& log, const plant::JointParams& joint);

}  // namespace fullarm::identification
