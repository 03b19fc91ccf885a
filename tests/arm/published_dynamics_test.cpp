// Inverse dynamics against the published SL figures of the DTS master (reference
// docs/dts-reference.md §4.5): SL's generated Newton-Euler code evaluated with the
// identified parameter set of section 4.3. That set is not physically consistent (section 4.4),
// so it is built here in code, without validation, only to drive an independent oracle; it
// exercises the off-diagonal inertia convention, which the default model's diagonal inertias
// cannot.

#include <gtest/gtest.h>

#include <array>
#include <numbers>

#include "arm_test_util.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "matrix_compare.hpp"

namespace fullarm::arm {
namespace {

// SL row (reference 4.3): m, first moment m*c, inertia about the SL joint origin (matrix entries).
struct SlLink {
  double m;
  Eigen::Vector3d mc;
  double i11, i12, i13, i22, i23, i33;
};

// Reference 4.3, R_SFE .. R_WAA.
const SlLink kSlLinks[7] = {
    {0.0, {0, 0, 0}, 0, 0, 0, 0, 0, 0.000118},
    {0.0, {0, 0, 0}, 0.002120, -0.001411, 0.000405, 0.001061, -0.000297, 0.000096},
    {0.001015, {-0.000006, -0.000020, 0.000001}, 0.000167, -0.000061, -0.001712, 0.000263, 0.001618, 0.031939},
    {0.184753, {0.004733, -0.028430, 0.031864}, 0.009976, 0.000323, -0.000886, 0.007213, 0.005136, 0.004646},
    {3.357057, {0.139895, 0.111372, 0.192788}, 0.038183, -0.004881, 0.000878, 0.016913, -0.006484, 0.012918},
    {1.339042, {0.068897, -0.033112, 0.036859}, 0.001855, 0.001716, -0.001769, 0.004567, 0.001081, 0.014714},
    {0.895628, {-0.046017, 0.070786, 0.026518}, 0.007859, 0.003288, -0.001617, 0.003268, -0.001317, 0.014124},
};

// Reference 2.4: SL link frame i -> modified-DH link frame i, p_DH = Rz(phi) p_SL + delta e_z.
constexpr double kPhiDeg[7] = {0, 90, 180, 90, 0, 90, -90};
constexpr double kDelta_m[7] = {0, 0, -0.287, 0.0025, -0.2781, -0.0081, 0};

ArmModel slIdentifiedModel() {
  ArmModel model = test::armOnlyModel();
  for (std::size_t i = 0; i < 7; ++i) {
    const SlLink& sl = kSlLinks[i];
    Eigen::Matrix3d I_o;
    I_o << sl.i11, sl.i12, sl.i13, sl.i12, sl.i22, sl.i23, sl.i13, sl.i23, sl.i33;
    const Eigen::Vector3d c_sl = sl.m > 0.0 ? Eigen::Vector3d(sl.mc / sl.m) : Eigen::Vector3d::Zero();
    // Parallel-axis theorem from the SL origin to the centre of mass, in the SL frame.
    const Eigen::Matrix3d I_c =
        I_o - sl.m * (c_sl.squaredNorm() * Eigen::Matrix3d::Identity() - c_sl * c_sl.transpose());
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(kPhiDeg[i] * std::numbers::pi / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    LinkInertial& in = model.joints[i].inertial;
    in.mass_kg = sl.m;
    in.com_m = R * c_sl + Eigen::Vector3d(0, 0, kDelta_m[i]);
    in.inertia_com_kgm2 = R * I_c * R.transpose();
  }
  return model;
}

struct PublishedState {
  std::array<double, 7> q, qd, qdd, tau;
};

TEST(PublishedDynamics, InverseDynamicsMatchesSlGeneratedCode) {
  const ArmModel model = slIdentifiedModel();
  ArmData data(model);
  const PublishedState states[] = {
      {{0, 0, 0, 0, 0, 0, 0}, {}, {}, {-0.562100, -4.643438, 0, -0.794989, 0, 0.936021, 0.451427}},
      {{0, -0.3, 0, 1.57, 0, 0, 0}, {}, {}, {6.335692, -9.479287, 2.647867, 8.559779, -2.522645, 0.301918, 0.663739}},
      {{0.3, -0.5, 0.4, 1.2, -0.6, 0.3, -0.2},
       {},
       {},
       {8.665802, -16.088640, 1.940005, 8.050332, -2.456954, 0.576961, 0.340992}},
      {{0.3, -0.5, 0.4, 1.2, -0.6, 0.3, -0.2},
       {0.5, -0.4, 0.3, 0.8, -0.6, 0.2, 0.1},
       {1, -1, 0.5, 2, -0.5, 1.5, -2},
       {9.532593, -17.222272, 2.100246, 9.125276, -2.667767, 0.773659, 0.410378}},
  };
  // Printed to six decimals; inputs also six decimals.
  constexpr double kTol_nm = 2e-6;
  for (const PublishedState& s : states) {
    const Eigen::Map<const Eigen::VectorXd> q(s.q.data(), 7), qd(s.qd.data(), 7), qdd(s.qdd.data(), 7);
    computeInverseDynamics(model, data, q, qd, qdd);
    EXPECT_MATRIX_NEAR(data.tau, Eigen::Map<const Eigen::VectorXd>(s.tau.data(), 7), kTol_nm);
  }
}

}  // namespace
}  // namespace fullarm::arm
