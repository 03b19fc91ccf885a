#include "fullarm/identification/reference_gravity.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/core/random.hpp"

namespace fullarm::identification {
namespace {

constexpr std::array<const char*, 7> kArmJoints{"R_SFE", "R_SAA", "R_HR", "R_EB", "R_WR", "R_WFE", "R_WAA"};

/// docs/dts-reference.md 4.3 (LinkParameters.cf, first block): mass [kg] and first moment m c
/// [kg m] in SL's link frame, R_SFE .. R_WAA.
struct SlGravity {
  double m;
  double mcx, mcy, mcz;
};
constexpr std::array<SlGravity, 7> kSlGravity{{
    {0.0, 0.0, 0.0, 0.0},
    {0.0, 0.0, 0.0, 0.0},
    {0.001015, -0.000006, -0.000020, 0.000001},
    {0.184753, 0.004733, -0.028430, 0.031864},
    {3.357057, 0.139895, 0.111372, 0.192788},
    {1.339042, 0.068897, -0.033112, 0.036859},
    {0.895628, -0.046017, 0.070786, 0.026518},
}};

/// docs/dts-reference.md 2.4: SL link frame i -> modified-DH link frame i,
/// p_DH = Rz(phi) p_SL + delta e_z.
constexpr std::array<double, 7> kPhiDeg{0.0, 90.0, 180.0, 90.0, 0.0, 90.0, -90.0};
constexpr std::array<double, 7> kDeltaM{0.0, 0.0, -0.287, 0.0025, -0.2781, -0.0081, 0.0};

std::vector<int> armJointIndices(const arm::ArmModel& model) {
  std::vector<int> out;
  for (const char* name : kArmJoints) {
    int found = -1;
    for (std::size_t i = 0; i < model.joints.size(); ++i) {
      if (model.joints[i].name == name) found = static_cast<int>(i);
    }
    if (found < 0) throw std::invalid_argument(std::string("reference gravity: the arm model has no joint ") + name);
    out.push_back(found);
  }
  return out;
}

Eigen::VectorXd gravityAt(const arm::ArmModel& model, arm::ArmData& data, const Eigen::VectorXd& q) {
  arm::computeGravityTorques(model, data, q);
  return data.tau_gravity;
}

/// Random postures: the seven arm joints uniform inside their limits less `inset`, the others at
/// the default posture.
std::vector<Eigen::VectorXd> randomPostures(const arm::ArmModel& model, const std::vector<int>& arm, int count,
                                            double inset, std::uint64_t seed, std::uint64_t stream) {
  std::vector<Eigen::VectorXd> out;
  for (int p = 0; p < count; ++p) {
    core::RandomStream rng(seed, stream, static_cast<std::uint64_t>(p));
    Eigen::VectorXd q = model.defaultPosture();
    for (int i : arm) {
      const auto& limits = model.joints[static_cast<std::size_t>(i)].limits;
      q[i] = rng.uniform(limits.min_rad + inset, limits.max_rad - inset);
    }
    out.push_back(q);
  }
  return out;
}

GravityComparison compare(const arm::ArmModel& model, const arm::ArmModel& reference, const std::vector<int>& arm,
                          const std::vector<Eigen::VectorXd>& train, const std::vector<Eigen::VectorXd>& heldout) {
  arm::ArmData data_m(model);
  arm::ArmData data_r(reference);
  const auto n = static_cast<Eigen::Index>(arm.size());
  GravityComparison c;
  auto rms = [&](const std::vector<Eigen::VectorXd>& qs) {
    Eigen::VectorXd sum = Eigen::VectorXd::Zero(n);
    for (const auto& q : qs) {
      const Eigen::VectorXd e = gravityAt(model, data_m, q) - gravityAt(reference, data_r, q);
      for (Eigen::Index k = 0; k < n; ++k)
        sum[k] += e[arm[static_cast<std::size_t>(k)]] * e[arm[static_cast<std::size_t>(k)]];
    }
    return Eigen::VectorXd((sum / static_cast<double>(qs.size())).cwiseSqrt());
  };
  c.train_rms_nm = rms(train);
  c.heldout_rms_nm = rms(heldout);
  Eigen::VectorXd cross = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd ref2 = Eigen::VectorXd::Zero(n);
  for (const auto& q : heldout) {
    const Eigen::VectorXd gm = gravityAt(model, data_m, q);
    const Eigen::VectorXd gr = gravityAt(reference, data_r, q);
    for (Eigen::Index k = 0; k < n; ++k) {
      const int i = arm[static_cast<std::size_t>(k)];
      cross[k] += gm[i] * gr[i];
      ref2[k] += gr[i] * gr[i];
    }
  }
  c.gain = cross.cwiseQuotient(ref2);
  c.published_max_nm = Eigen::VectorXd::Zero(n);
  for (const auto& hold : publishedGravity()) {
    Eigen::VectorXd q = model.defaultPosture();
    for (Eigen::Index k = 0; k < n; ++k) q[arm[static_cast<std::size_t>(k)]] = hold.q_rad[static_cast<std::size_t>(k)];
    const Eigen::VectorXd g = gravityAt(model, data_m, q);
    for (Eigen::Index k = 0; k < n; ++k) {
      c.published_max_nm[k] = std::max(c.published_max_nm[k], std::abs(g[arm[static_cast<std::size_t>(k)]] -
                                                                       hold.tau_nm[static_cast<std::size_t>(k)]));
    }
  }
  return c;
}

}  // namespace

arm::ArmModel withReferenceGravity(const arm::ArmModel& model) {
  const std::vector<int> arm = armJointIndices(model);
  arm::ArmModel out = model;
  for (auto& j : out.joints) {
    j.inertial.mass_kg = 0.0;
    j.inertial.com_m.setZero();
  }
  for (std::size_t k = 0; k < arm.size(); ++k) {
    const SlGravity& sl = kSlGravity[k];
    if (sl.m <= 0.0) continue;
    const Eigen::Matrix3d r =
        Eigen::AngleAxisd(kPhiDeg[k] * std::numbers::pi / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    auto& link = out.joints[static_cast<std::size_t>(arm[k])].inertial;
    link.mass_kg = sl.m;
    link.com_m = r * (Eigen::Vector3d(sl.mcx, sl.mcy, sl.mcz) / sl.m) + Eigen::Vector3d(0.0, 0.0, kDeltaM[k]);
  }
  return out;
}

std::vector<PublishedGravity> publishedGravity() {
  // docs/dts-reference.md 4.5, the rows with zero velocity and acceleration.
  return {
      {{0, 0, 0, 0, 0, 0, 0}, {-0.562100, -4.643438, 0, -0.794989, 0, 0.936021, 0.451427}},
      {{0, -0.3, 0, 1.57, 0, 0, 0}, {6.335692, -9.479287, 2.647867, 8.559779, -2.522645, 0.301918, 0.663739}},
      {{0.3, -0.5, 0.4, 1.2, -0.6, 0.3, -0.2},
       {8.665802, -16.088640, 1.940005, 8.050332, -2.456954, 0.576961, 0.340992}},
  };
}

ReferenceGravityFit fitToReferenceGravity(const arm::ArmModel& nominal, const ReferenceFitOptions& options) {
  const std::vector<int> arm = armJointIndices(nominal);
  const arm::ArmModel reference = withReferenceGravity(nominal);
  const auto train = randomPostures(nominal, arm, options.train_postures, options.inset_rad, options.seed, 1);
  const auto heldout = randomPostures(nominal, arm, options.heldout_postures, options.inset_rad, options.seed, 2);
  arm::ArmData data(reference);
  std::vector<Eigen::VectorXd> torques;
  for (const auto& q : train) {
    torques.push_back(gravityAt(reference, data, q));
  }
  ReferenceGravityFit out;
  // Only the arm joints' torques are the reference's: SL leaves the hand links out of its
  // estimation and forces their torques to zero, which says nothing about our hand links' load.
  out.fit = fitConsistentGravityParameters(nominal, train, torques, options.bounds, arm);
  out.fitted = withGravityParameters(nominal, out.fit.parameters);
  out.fitted_vs_reference = compare(out.fitted, reference, arm, train, heldout);
  out.nominal_vs_reference = compare(nominal, reference, arm, train, heldout);
  for (const char* name : kArmJoints) out.joints.emplace_back(name);
  return out;
}

}  // namespace fullarm::identification
