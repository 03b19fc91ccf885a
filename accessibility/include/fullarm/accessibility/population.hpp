#pragma once
/// @file
/// A population of technicians for the accessibility sweep: each technician's sex, upper-arm and
/// forearm lengths (drawn jointly), link radii and strength, drawn from the sample's own random
/// stream, and the arm model and strength built from them (docs/accessibility.md, "Population").
///
/// Sizes: ANSUR II (US Army 2012, public data) acromion-radiale and radiale-stylion lengths per
/// sex, each a log-normal through its 50th percentile with the spread of its 5th-95th range,
/// upper arm and forearm jointly normal in log space with the per-sex correlation. The landmark
/// lengths are taken as the model's joint-centre distances (no offset). Strength: one log-normal
/// factor on every torque limit of the human arm file, its median the sex's ratio to that file's
/// men's figures, its coefficient of variation 0.25 (Benfica et al. 2018: 0.2-0.3), correlated
/// only weakly with arm size (Harbo et al. 2012). The shoulder stands where the scene puts the
/// arm's base for every technician (a fixed standing distance to the opening).

#include <cstdint>

#include "fullarm/accessibility/human_strength.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/core/random.hpp"

namespace fullarm::accessibility {

/// 5th, 50th and 95th percentiles of one measure [m].
struct Percentiles {
  double p5_m = 0.0;
  double p50_m = 0.0;
  double p95_m = 0.0;
};

/// The figures of one sex.
struct SexFigures {
  Percentiles upper_arm;  ///< acromion-radiale length
  Percentiles forearm;    ///< radiale-stylion length
  double upper_arm_forearm_correlation = 0.0;
  double strength_median = 1.0;  ///< median strength_scale (1: the human arm file's men's figures)
};

/// What the population is drawn from.
struct PopulationFigures {
  SexFigures men;
  SexFigures women;
  double strength_cv = 0.25;               ///< coefficient of variation of strength within a sex
  double strength_size_correlation = 0.3;  ///< of log strength with the arm-size score
};

/// The ANSUR II figures (men n = 4,082, women n = 1,986), the women's strength ratio 0.45 (the
/// mean of the women:men ratios of shoulder flexion, abduction, adduction and elbow flexion and
/// extension in docs/sources.md) and the strength spread above.
[[nodiscard]] PopulationFigures ansur2Figures();

/// Population options.
struct PopulationOptions {
  std::int64_t technicians = 1000;  ///< how many (>= 1)
  double female_share = 0.5;        ///< the mix: share of women in [0, 1]
  std::uint64_t seed = 1;           ///< the sweep's seed
  PopulationFigures figures = ansur2Figures();
};

/// Checks the options.
/// @throws core::ConfigError with key `--population` (technicians < 1), `--mix` (outside [0, 1] or
///         not finite) or `population.figures.<field>` (a percentile not increasing and positive, a
///         correlation outside (-1, 1), a strength figure not positive or not finite).
void validatePopulationOptions(const PopulationOptions& options);

/// One technician.
struct Technician {
  std::int64_t index = 0;  ///< sample number
  bool female = false;
  double upper_arm_m = 0.0;        ///< shoulder to elbow joint centre
  double forearm_m = 0.0;          ///< elbow to wrist joint centre
  double link_radius_scale = 1.0;  ///< on every capsule radius of the arm model
  double strength_scale = 1.0;     ///< on every torque limit of the human arm
};

/// Draws technician `index` from `rng` (the sample's own stream: core::RandomStream(seed,
/// core::nameSlot("technicians"), index) in a population sweep). Five uniforms: one for the sex,
/// two (Box-Muller) for the two length scores, two (Box-Muller, one normal used) for strength. The link radii scale
/// with the geometric mean of the two length ratios to `nominal_upper_arm_m` and `nominal_forearm_m` (the arm model's
/// own segments, whose capsules are taken as the girth of a person of that size).
/// Options are not validated here (validatePopulationOptions). @rt
[[nodiscard]] Technician drawTechnician(const PopulationOptions& options, std::int64_t index, core::RandomStream& rng,
                                        double nominal_upper_arm_m, double nominal_forearm_m) noexcept;

/// Draws technician `index` of the population on `nominal`'s segment lengths, from its own stream.
/// @throws core::ConfigError when the model lacks an upper-arm or forearm joint.
[[nodiscard]] Technician drawTechnician(const PopulationOptions& options, std::int64_t index,
                                        const arm::ArmModel& nominal);

/// The technician's arm model: `nominal` scaled by arm::scaleArm to the technician's segment
/// lengths and link radii (the hand keeps the model's length).
[[nodiscard]] arm::ArmModel technicianArm(const arm::ArmModel& nominal, const Technician& technician);

/// The technician's strength and weight: `nominal` with strength_scale set to the technician's.
[[nodiscard]] HumanArm technicianStrength(const HumanArm& nominal, const Technician& technician);

}  // namespace fullarm::accessibility
