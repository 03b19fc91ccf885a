// Writes the recorded approach motion of the valve scene, scenes/valve_wall_approach.csv: 10 s of
// joint angles at 100 Hz (the global search's rate) of the DTS arm reaching from its rest posture
// through the wall opening of scenes/valve_wall.yaml to the wheel valve and back, and prints what
// the motion does (per-link clearance and contacts, closer than d_f = 10 mm, along the way).
//
// The motion is scripted, not captured from a user: from a raised posture (hand beside the
// shoulder, clear of the wall) a minimum-jerk joint-space blend to a posture 0.30 m back along the
// forearm axis of the scene's `reach_valve` posture (0-1.5 s); the insertion, the wrist and elbow
// moving along that axis (lifted by up to 25 mm midway so the forearm clears the truss's ribs)
// until `reach_valve` (1.5-4.5 s), solved by damped least squares on the elbow and wrist
// positions at every sample; two taps of the hand on the wheel rim (4.5-5.5 s); the retraction
// along the same line (5.5-8.5 s) and the blend back (8.5-10 s). The forearm passes through the
// opening (frame, truss), the hand comes within 4 mm of the wheel, no link touches anything. The
// file is what the motion benchmark (bench/haptics_motion_bench.cpp) and the coherence tests
// replay.
//
// build/release/bench/valve_approach_motion scenes/valve_wall_approach.csv
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <vector>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/scene.hpp"

namespace {

using namespace fullarm;
using Eigen::Vector3d;
using Eigen::VectorXd;

constexpr int kJoints = 7;  // the arm joints; the finger joints keep their default
constexpr double kRate_hz = 100.0;
constexpr double kDuration_s = 10.0;
constexpr int kForearm = 4;  // link frame at the wrist; the forearm capsule runs back to the elbow

// Minimum-jerk blend s(t) in [0, 1] for t in [0, 1].
double minimumJerk(double t) {
  return t * t * t * (10.0 - 15.0 * t + 6.0 * t * t);
}

struct Ik {
  const arm::ArmModel& model;
  arm::ArmData fk{model};
  Vector3d elbowL() const { return model.joints[kForearm].geometry.from_m; }

  // The wrist (forearm frame origin) and elbow (forearm capsule's far end) at q.
  Eigen::Matrix<double, 6, 1> points(const VectorXd& q) {
    arm::computeForwardKinematics(model, fk, q);
    Eigen::Matrix<double, 6, 1> x;
    x.head<3>() = fk.X_WL[kForearm].translation();
    x.tail<3>() = fk.X_WL[kForearm] * elbowL();
    return x;
  }

  // Damped least squares from q toward wrist and elbow targets (finite-difference Jacobian).
  VectorXd solve(VectorXd q, const Vector3d& wrist, const Vector3d& elbow) {
    Eigen::Matrix<double, 6, 1> target;
    target << wrist, elbow;
    for (int it = 0; it < 60; ++it) {
      const Eigen::Matrix<double, 6, 1> r = target - points(q);
      if (r.norm() < 1e-7) break;
      Eigen::Matrix<double, 6, kJoints> J;
      for (int j = 0; j < kJoints; ++j) {
        VectorXd dq = q;
        dq[j] += 1e-6;
        J.col(j) = (points(dq) - points(q)) / 1e-6;
      }
      const Eigen::Matrix<double, 6, 6> A = J * J.transpose() + 1e-6 * Eigen::Matrix<double, 6, 6>::Identity();
      const Eigen::Matrix<double, kJoints, 1> step = J.transpose() * A.ldlt().solve(r);
      q.head(kJoints) += step;
      q = q.cwiseMax(model.lowerLimits()).cwiseMin(model.upperLimits());
    }
    return q;
  }
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: valve_approach_motion OUT.csv\n";
    return 2;
  }
  const std::filesystem::path source(FULLARM_SOURCE_DIR);
  const arm::ArmModel model = arm::loadArmModel(source / "config/dts_master.yaml");
  const haptics::Scene scene = haptics::loadScene(source / "scenes/valve_wall.yaml");
  const haptics::CollisionWorld world = haptics::makeCollisionWorld(scene, model);
  const VectorXd rest = haptics::scenePosture(scene, "rest", model);
  const VectorXd reach = haptics::scenePosture(scene, "reach_valve", model);
  Ik ik{model};
  const Eigen::Matrix<double, 6, 1> at_reach = ik.points(reach);
  const Vector3d wrist_reach = at_reach.head<3>();
  const Vector3d elbow_reach = at_reach.tail<3>();
  const Vector3d axis = (wrist_reach - elbow_reach).normalized();
  // Insertion depth: the wrist starts this far back along the forearm axis (hand in front of
  // the wall), and the tap pulls the hand back and pushes it on by `tap_m`.
  constexpr double kInsertion_m = 0.30;
  constexpr double kTap_m = 0.012;
  constexpr double kLift_m = 0.025;
  const VectorXd pre = ik.solve(reach, wrist_reach - kInsertion_m * axis, elbow_reach - kInsertion_m * axis);
  // The start and end: the hand raised beside the shoulder, clear of the wall.
  VectorXd raised = rest;
  raised.head(4) << 0.0, -0.6, -0.4, 2.1;
  // Segments: (end time, kind). Joint-space blends from rest to `pre` and back; along the axis in between.
  std::vector<VectorXd> samples;
  const int n = static_cast<int>(std::lround(kDuration_s * kRate_hz));
  VectorXd q_line = pre;  // warm start of the line IK
  for (int k = 0; k <= n; ++k) {
    const double t = k / kRate_hz;
    VectorXd q;
    // The line, lifted by up to kLift_m between its ends so the forearm clears the truss's ribs.
    auto line = [&](double depth_m) {
      const Vector3d lift_W =
          kLift_m * std::sin(M_PI * std::clamp(depth_m / kInsertion_m, 0.0, 1.0)) * Vector3d::UnitZ();
      q_line = ik.solve(q_line, wrist_reach - depth_m * axis + lift_W, elbow_reach - depth_m * axis + lift_W);
      return q_line;
    };
    if (t < 1.5) {
      q = raised + minimumJerk(t / 1.5) * (pre - raised);
    } else if (t < 4.5) {
      q = line(kInsertion_m * (1.0 - minimumJerk((t - 1.5) / 3.0)));
    } else if (t < 5.5) {
      // Two taps at the wheel: the hand backs off by kTap_m and comes on 4 mm past the reach.
      const double u = 2.0 * (t - 4.5) - std::floor(2.0 * (t - 4.5));
      q = line((kTap_m + 0.004) * std::sin(M_PI * u) - 0.004 * std::sin(M_PI * u) * std::sin(M_PI * u));
    } else if (t < 8.5) {
      q = line(kInsertion_m * minimumJerk((t - 5.5) / 3.0));
    } else {
      q = pre + minimumJerk(std::min(1.0, (t - 8.5) / 1.5)) * (raised - pre);
    }
    samples.push_back(q);
  }
  // What the motion does: per 0.25 s, the clearance of each link and the contacts (d < d_f).
  arm::ArmData fk(model);
  haptics::SnchGlobalSearch search;
  std::vector<haptics::LocalMinimum> minima;
  double max_joint_speed = 0.0;
  double clearance = 0.03;
  int with_contact = 0;
  for (int k = 0; k <= n; ++k) {
    const auto ks = static_cast<std::size_t>(k);
    if (k > 0)
      max_joint_speed = std::max(max_joint_speed, (samples[ks] - samples[ks - 1]).cwiseAbs().maxCoeff() * kRate_hz);
    arm::computeForwardKinematics(model, fk, samples[ks]);
    search.search(world, fk, 0.03, 0.02, minima);
    bool contact = false;
    for (const auto& m : minima) {
      clearance = std::min(clearance, m.distance_m);
      contact = contact || m.distance_m < 0.01;
    }
    with_contact += contact ? 1 : 0;
    if (k % 25 != 0) continue;
    int contacts = 0;
    std::printf("t = %5.2f s:", k / kRate_hz);
    for (int l = 0; l < world.numLinks(); ++l) {
      if (!world.hasLinkGeometry(l)) continue;
      double best = 0.03;
      int object = -1;
      for (const auto& m : minima) {
        if (m.link == l && m.distance_m < best) {
          best = m.distance_m;
          object = m.object;
        }
      }
      std::printf(" %6.1f%-6.6s", 1e3 * best, object >= 0 ? world.object(object).name.c_str() : "");
    }
    for (const auto& m : minima) contacts += m.distance_m < 0.01 ? 1 : 0;
    std::printf("  mm; %zu minima, %d closer than 10 mm\n", minima.size(), contacts);
  }
  std::printf("largest joint speed %.2f rad/s; smallest clearance %.2f mm; %d of %d samples with a contact\n",
              max_joint_speed, 1e3 * clearance, with_contact, n + 1);
  std::ofstream out(argv[1]);
  out << "# DTS arm approach through the wall opening of scenes/valve_wall.yaml to the wheel valve and back\n"
         "# (bench/valve_approach_motion.cpp): 10 s at 100 Hz, joint angles of the arm's seven joints [rad]\n";
  out << "t_s";
  for (int j = 0; j < kJoints; ++j) out << ",q" << j << "_rad";
  out << "\n";
  out.precision(9);
  for (int k = 0; k <= n; ++k) {
    out << k / kRate_hz;
    for (int j = 0; j < kJoints; ++j) out << "," << samples[static_cast<std::size_t>(k)][j];
    out << "\n";
  }
  return 0;
}
