// Kinematics and gravity of the 7-DOF DTS arm: fullarm's allocation-free functions side by side
// with orocos-kdl's recursive solvers on the same model and configurations.

#include <benchmark/benchmark.h>

#include <kdl/chaindynparam.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <random>
#include <vector>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/arm/kdl_conversion.hpp"
#include "fullarm/arm/kinematics.hpp"

namespace {

using namespace fullarm::arm;

constexpr int kConfigurations = 256;

const ArmModel& armModel() {
  static const ArmModel model = [] {
    ArmModel m = loadArmModel(defaultArmModelPath());
    m.joints.resize(static_cast<std::size_t>(m.numArmJoints()));  // the 7-DOF arm
    return m;
  }();
  return model;
}

const std::vector<Eigen::VectorXd>& configurations() {
  static const std::vector<Eigen::VectorXd> qs = [] {
    std::mt19937 rng(5);
    std::vector<Eigen::VectorXd> v;
    const ArmModel& m = armModel();
    for (int k = 0; k < kConfigurations; ++k) {
      Eigen::VectorXd q(m.numJoints());
      for (int i = 0; i < m.numJoints(); ++i) {
        const JointLimits& lim = m.joints[static_cast<std::size_t>(i)].limits;
        q[i] = std::uniform_real_distribution<double>(lim.min_rad, lim.max_rad)(rng);
      }
      v.push_back(q);
    }
    return v;
  }();
  return qs;
}

void BM_Fullarm_ForwardKinematics(benchmark::State& state) {
  const ArmModel& model = armModel();
  ArmData data(model);
  std::size_t k = 0;
  for (auto _ : state) {
    computeForwardKinematics(model, data, configurations()[k++ % kConfigurations]);
    benchmark::DoNotOptimize(data.X_WT);
  }
}
BENCHMARK(BM_Fullarm_ForwardKinematics);

void BM_Kdl_ForwardKinematics(benchmark::State& state) {
  const KDL::Chain chain = toKdlChain(armModel(), armModel().numJoints() - 1);
  KDL::ChainFkSolverPos_recursive fk(chain);
  KDL::JntArray q(chain.getNrOfJoints());
  KDL::Frame f;
  std::size_t k = 0;
  for (auto _ : state) {
    q.data = configurations()[k++ % kConfigurations];
    fk.JntToCart(q, f);  // tip frame only; fullarm's FK computes every link frame
    benchmark::DoNotOptimize(f);
  }
}
BENCHMARK(BM_Kdl_ForwardKinematics);

void BM_Fullarm_KinematicsAndGravity(benchmark::State& state) {
  const ArmModel& model = armModel();
  ArmData data(model);
  std::size_t k = 0;
  for (auto _ : state) {
    computeGravityTorques(model, data, configurations()[k++ % kConfigurations]);  // includes FK
    benchmark::DoNotOptimize(data.tau_gravity.data());
  }
}
BENCHMARK(BM_Fullarm_KinematicsAndGravity);

void BM_Kdl_KinematicsAndGravity(benchmark::State& state) {
  const ArmModel& model = armModel();
  const KDL::Chain chain = toKdlChain(model, model.numJoints() - 1);
  KDL::ChainFkSolverPos_recursive fk(chain);
  KDL::ChainDynParam dyn(chain, KDL::Vector(0, 0, -9.81));
  KDL::JntArray q(chain.getNrOfJoints());
  KDL::JntArray g(chain.getNrOfJoints());
  KDL::Frame f;
  std::size_t k = 0;
  for (auto _ : state) {
    q.data = configurations()[k++ % kConfigurations];
    fk.JntToCart(q, f);
    dyn.JntToGravity(q, g);
    benchmark::DoNotOptimize(g.data.data());
  }
}
BENCHMARK(BM_Kdl_KinematicsAndGravity);

void BM_Fullarm_PointJacobian(benchmark::State& state) {
  const ArmModel& model = armModel();
  ArmData data(model);
  PointJacobian J;
  std::size_t k = 0;
  const int link = model.numJoints() - 1;
  for (auto _ : state) {
    computeForwardKinematics(model, data, configurations()[k++ % kConfigurations]);
    computePointJacobian(model, data, link, data.X_WT.translation(), J);
    benchmark::DoNotOptimize(J.data());
  }
}
BENCHMARK(BM_Fullarm_PointJacobian);

void BM_Kdl_Jacobian(benchmark::State& state) {
  const KDL::Chain chain = toKdlChain(armModel(), armModel().numJoints() - 1);
  KDL::ChainJntToJacSolver solver(chain);
  KDL::JntArray q(chain.getNrOfJoints());
  KDL::Jacobian J(chain.getNrOfJoints());
  std::size_t k = 0;
  for (auto _ : state) {
    q.data = configurations()[k++ % kConfigurations];
    solver.JntToJac(q, J);
    benchmark::DoNotOptimize(J.data.data());
  }
}
BENCHMARK(BM_Kdl_Jacobian);

void BM_Fullarm_MassMatrix(benchmark::State& state) {
  const ArmModel& model = armModel();
  ArmData data(model);
  std::size_t k = 0;
  for (auto _ : state) {
    computeMassMatrix(model, data, configurations()[k++ % kConfigurations]);
    benchmark::DoNotOptimize(data.mass_matrix.data());
  }
}
BENCHMARK(BM_Fullarm_MassMatrix);

void BM_Kdl_MassMatrix(benchmark::State& state) {
  const KDL::Chain chain = toKdlChain(armModel(), armModel().numJoints() - 1);
  KDL::ChainDynParam dyn(chain, KDL::Vector(0, 0, -9.81));
  KDL::JntArray q(chain.getNrOfJoints());
  KDL::JntSpaceInertiaMatrix M(chain.getNrOfJoints());
  std::size_t k = 0;
  for (auto _ : state) {
    q.data = configurations()[k++ % kConfigurations];
    dyn.JntToMass(q, M);
    benchmark::DoNotOptimize(M.data.data());
  }
}
BENCHMARK(BM_Kdl_MassMatrix);

}  // namespace

BENCHMARK_MAIN();
