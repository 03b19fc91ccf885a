#pragma once
/// @file
/// A plant joint whose parameter groups are an identified model's: each group of the reduced
/// model (grey_box.hpp) is carried by one designated plant parameter, the others kept from a
/// starting joint, so that `plant`, `tune`, `validate` and `run` can use the identified joint.
///
/// Each group and the plant parameter that carries it (docs/identification.md has the reasons):
/// - flow gain a = k_a K_q / D: valve.rated_flow_m3ps, scaled (the amplifier gain and stroke also
///   set the laps and rounding in volts, the area the other groups);
/// - hydraulic stiffness K_h = beta (D_a^2/V_a + D_b^2/V_b): both dead volumes, by one factor (the
///   fluid is shared by every joint);
/// - leakage c = C_i / D^2: chambers.internal_leakage_m3ps_per_pa;
/// - inertia J = link + actuator: actuator.inertia_kgm2 (the link's is the arm model's);
/// - viscous b, Coulomb tau_c: friction.viscous_nms_per_rad, friction.coulomb_nm;
/// - Stribeck tau_st: friction.static_nm = tau_c + tau_st.
///
/// Not written: the static load tau_g (the arm model's gravity), the offsets u_0, q_off, tau_off
/// (the valve's null and the sensors' calibration) and the delay (the I/O device's latency).
/// A group cannot say how it splits into its parts: a larger valve, a higher amplifier gain and
/// a smaller actuator give the same flow gain; stiffer oil and smaller chambers the same
/// hydraulic stiffness; a heavier link and a heavier actuator the same inertia.

#include <string>
#include <vector>

#include "fullarm/identification/grey_box.hpp"
#include "fullarm/plant/joint_params.hpp"

namespace fullarm::identification {

/// How far below the link's own inertia (as a fraction of it) an identified inertia may lie and
/// still be carried, with the actuator's inertia set to zero: the link dominates the group, and
/// the fit is expected to find the inertia within 10 % on noisy data.
inline constexpr double kInertiaBelowLinkTolerance = 0.1;

/// A plant joint carrying identified groups, and what it could not carry exactly.
struct IdentifiedPlantJoint {
  plant::JointParams joint;
  /// One sentence per group carried only approximately (an inertia below the link's own within
  /// kInertiaBelowLinkTolerance); empty when every group is exact.
  std::vector<std::string> notes;
};

/// `start` with its rated flow, dead volumes, internal leakage, actuator inertia and friction set
/// so that greyModelFromJoint(result, q_rad, link_inertia_kgm2, ...) gives `groups`' flow gain,
/// hydraulic stiffness, leakage, inertia and friction (the table above); everything else is
/// `start`'s. An inertia below the link's own by at most kInertiaBelowLinkTolerance of it gives
/// a zero actuator inertia and a note.
/// @param q_rad the angle the groups hold at (the experiment's hold angle)
/// @param link_inertia_kgm2 the link's inertia about the joint at q_rad (arm model, locked neighbours)
/// @throws std::invalid_argument naming the group and its value when no plant parameter can carry
///   it: a non-positive or non-finite group, an inertia further below the link's own, a hydraulic
///   stiffness above what the actuator's swept volume alone allows or below that of dead volumes
///   1e6 times the start's, a fixed structure (stall torque, underlap, edge rounding, spool,
///   load-cell filter) more than 0.1 % from `start`'s at q_rad (a model identified on another valve or
///   actuator), or a joint without hydraulics.
[[nodiscard]] IdentifiedPlantJoint plantJointWithGroups(const plant::JointParams& start, const GreyModel& groups,
                                                        double q_rad, double link_inertia_kgm2);

}  // namespace fullarm::identification
