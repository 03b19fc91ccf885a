// One joint identified from two 20 s closed-loop experiments at 1 kHz (a PRBS and a Schroeder
// multisine on the reduced joint model with known parameters and the plant's valve structure), from a corner of a x3 box on 2 threads: the
// wall time of the global stage and of the Levenberg-Marquardt polish side by side, the
// simulations each ran, and the recovered parameters against the truth (BENCHMARKS.md).
//
//   identification_fit_bench [global_samples]

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fullarm/identification/excitation.hpp"
#include "fullarm/identification/grey_box.hpp"

namespace id = fullarm::identification;

namespace {

id::ExperimentData experiment(const id::GreyModel& truth, const std::vector<double>& r, double hold_gain) {
  id::ExperimentData d;
  d.excitation_v = r;
  d.hold_gain_v_per_rad = hold_gain;
  d.hold_rad = 0.0;
  d.q_rad.assign(r.size(), 0.0);
  d.tau_nm.assign(r.size(), 0.0);
  const id::Simulation s = id::simulateClosedLoop(truth, d);
  d.q_rad = s.q_rad;
  d.tau_nm = s.tau_nm;
  d.command_v = s.command_v;
  return d;
}

}  // namespace

int main(int argc, char** argv) {
  constexpr double kT = 1.0e-3;
  id::GreyModel truth;
  truth.value = {0.4, 8.0e3, 5.0e-4, 0.06, 0.8, 0.6, 0.4, 4.0, 0.0, 0.0, 0.0};
  truth.delay_samples = 2;
  // The valve's and the load's known structure, as greyModelFromJoint gives it for a plant joint.
  truth.stall_torque_nm = 250.0;
  truth.underlap_v = 0.04;
  truth.edge_rounding_v = 0.02;
  truth.load_gradient_nm_per_rad = 5.0;
  const id::SampledSignal prbs = id::prbs(1.5, 12, 5, 1, kT);                    // 20.5 s
  const id::Multisine ms = id::schroederMultisine(2.0, 0.5, 120.0, 4.0, 5, kT);  // 20 s
  const std::vector<id::ExperimentData> data{experiment(truth, prbs.value_v, 10.0),
                                             experiment(truth, ms.signal.value_v, 15.0)};
  id::FitOptions options = id::defaultFitOptions(truth, 3.0);
  options.global_samples = argc > 1 ? std::atoi(argv[1]) : 100;
  options.polished_candidates = 2;
  options.threads = 2;
  options.params[id::kStribeck].free = false;  // held at its value, as config/identification.yaml does
  id::GreyModel start = truth;
  for (int i : {id::kFlowGain, id::kStiffness, id::kLeakage, id::kInertia, id::kViscous, id::kCoulomb}) {
    start.value[static_cast<std::size_t>(i)] *= (i % 2 == 0) ? 2.9 : 1.0 / 2.9;
  }
  start.delay_samples = 0;
  const auto t0 = std::chrono::steady_clock::now();
  const id::FitResult fit = id::fitGreyModel(data, start, options);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("samples %zu + %zu, global stage %d points x %d delays\n", data[0].q_rad.size(), data[1].q_rad.size(),
              options.global_samples, options.max_delay_samples + 1);
  std::printf("global stage  %8.2f s\npolish        %8.2f s\ntotal wall    %8.2f s, %d simulations\n",
              fit.global_seconds, fit.polish_seconds, wall, fit.evaluations);
  std::printf("delay %d samples (truth %d)\n", fit.model.delay_samples, truth.delay_samples);
  for (int i = 0; i < id::kGreyParams; ++i) {
    const double w = truth.value[static_cast<std::size_t>(i)];
    const double v = fit.model.value[static_cast<std::size_t>(i)];
    std::printf("%-32s %12.6g  truth %12.6g  error %+.3f %%\n", id::greyParamName(i), v, w,
                w != 0.0 ? 100.0 * (v - w) / w : 0.0);
  }
  return 0;
}
