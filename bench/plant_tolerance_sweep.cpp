// Accuracy budget of the plant's solver tolerances: for the shipped tolerances and for scaled
// or re-balanced ones, the relative RMS error of every joint's angle and load pressure against
// a tight CVODES reference (rtol 1e-8, absolute tolerances 1000x tighter) on four full-scale
// 0.5-80 Hz chirps (the EB joint and the 7-joint arm, each from the default posture and from
// 0.1 rad inside the upper limits), the rtol-halving difference on the EB chirp (the plant tests' 0.5 % criterion), and
// the CPU-time real-time factor of 5 s of EB and arm chirp. Prints a Markdown table.
//
//   build/release/bench/plant_tolerance_sweep [--integrator rodas3|rodas4|ros34pw2|cvodes] [--variant NAME]...
//
// --variant (repeatable) runs only the named rows of the table (default: all); --scales
// R,S,SR,P,A,V (repeatable) adds and runs a row with the shipped rtol, atol_spool,
// atol_spool_rate_per_s, atol_pressure_pa, atol_angle_rad and atol_velocity_radps multiplied by
// those factors; --per-joint adds a table of every arm joint's errors for each row.
//
// The error metric is the one of tests/plant/chirp_test.cpp: sqrt(sum (a - b)^2 / sum (a - mean a)^2).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/plant/arm_plant.hpp"
#include "fullarm/plant/plant_config.hpp"
#include "fullarm/plant/signals.hpp"

namespace {

using namespace fullarm;
using namespace fullarm::plant;

const arm::ArmModel& model() {
  static const arm::ArmModel m = arm::loadArmModel(arm::defaultArmModelPath());
  return m;
}
const PlantConfig& config() {
  static const PlantConfig c = loadPlantConfig(defaultPlantConfigPath(), model());
  return c;
}

struct Trace {
  std::vector<std::vector<double>> q, p_load;  // [joint][period]
  SolverStats stats;
  double cpu_s = 0.0;
};

double cpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// Full-scale 0.5-80 Hz chirp on every active joint; `from_limit_rad` > 0 starts every active
// joint that far inside its upper limit.
Trace runChirp(const std::vector<JointParams>& joints, const SolverOptions& options, double duration_s,
               double from_limit_rad, bool record = true) {
  Eigen::VectorXd posture = model().defaultPosture();
  if (from_limit_rad > 0.0) {
    for (const JointParams& j : joints) posture[model().jointIndex(j.name)] = j.max_rad - from_limit_rad;
  }
  ArmPlant plant;
  plant.configure(model(), joints, posture, UserArmParams{}, options, config().seed);
  const int n = plant.numJoints();
  SignalParams s;
  s.kind = SignalKind::kChirp;
  s.amplitude = 1.0 / joints[0].valve.amplifier_gain_per_v;
  s.start_hz = 0.5;
  s.stop_hz = 80.0;
  s.duration_s = duration_s;
  PlantCommand cmd = PlantCommand::zero(n);
  Trace t;
  t.q.resize(static_cast<std::size_t>(n));
  t.p_load.resize(static_cast<std::size_t>(n));
  const int periods = static_cast<int>(std::lround(duration_s * 1000.0));
  const double t0 = cpuSeconds();
  for (int k = 0; k < periods; ++k) {
    for (int j = 0; j < n; ++j) cmd.command[j] = signalValue(s, k * 1e-3);
    if (!plant.step(1e-3, cmd).ok()) {
      std::fprintf(stderr, "solver failure: %s\n", plant.lastError());
      std::exit(1);
    }
    if (!record) continue;
    for (int j = 0; j < n; ++j) {
      const JointState st = plant.state(j);
      t.q[static_cast<std::size_t>(j)].push_back(st.q_rad);
      t.p_load[static_cast<std::size_t>(j)].push_back(st.p_a_pa - st.p_b_pa);
    }
  }
  t.cpu_s = cpuSeconds() - t0;
  t.stats = plant.stats();
  return t;
}

struct Worst {
  double q = 0.0, p = 0.0;
};
// The plant tests' criterion is 0.5 % RMS between rtol and rtol / 2; a default tolerance must keep
// every joint within a quarter of it against the tight reference (docs/plant.md).
constexpr double kBudget = 0.25 * 0.005;
Worst worstError(const Trace& ref, const Trace& t) {
  Worst w;
  for (std::size_t j = 0; j < ref.q.size(); ++j) {
    w.q = std::max(w.q, normalisedRmsDifference(ref.q[j], t.q[j]));
    w.p = std::max(w.p, normalisedRmsDifference(ref.p_load[j], t.p_load[j]));
  }
  return w;
}

struct Variant {
  std::string name;
  double rtol = 1.0, spool = 1.0, spool_rate = 1.0, pressure = 1.0, angle = 1.0, velocity = 1.0;
};

SolverOptions apply(const Variant& v, IntegratorKind integrator) {
  SolverOptions o = config().solver;
  o.integrator = integrator;
  o.rtol *= v.rtol;
  o.atol_spool *= v.spool;
  o.atol_spool_rate_per_s *= v.spool_rate;
  o.atol_pressure_pa *= v.pressure;
  o.atol_angle_rad *= v.angle;
  o.atol_velocity_radps *= v.velocity;
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  IntegratorKind integrator = IntegratorKind::kRodas3;
  std::vector<std::string> only;
  bool per_joint = false;
  std::vector<Variant> custom;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--integrator") == 0 && i + 1 < argc) {
      const std::string v = argv[++i];
      if (v == "rodas3") {
        integrator = IntegratorKind::kRodas3;
      } else if (v == "rodas4") {
        integrator = IntegratorKind::kRodas4;
      } else if (v == "ros34pw2") {
        integrator = IntegratorKind::kRos34pw2;
      } else if (v == "cvodes") {
        integrator = IntegratorKind::kCvodes;
      } else {
        std::fprintf(stderr, "--integrator: expected rodas3, rodas4, ros34pw2 or cvodes, got '%s'\n", v.c_str());
        return 2;
      }
    } else if (std::strcmp(argv[i], "--per-joint") == 0) {
      per_joint = true;
    } else if (std::strcmp(argv[i], "--scales") == 0 && i + 1 < argc) {
      Variant v;
      v.name = argv[++i];
      int consumed = 0;
      const bool parsed = std::sscanf(argv[i], "%lf,%lf,%lf,%lf,%lf,%lf%n", &v.rtol, &v.spool, &v.spool_rate,
                                      &v.pressure, &v.angle, &v.velocity, &consumed) == 6 &&
                          argv[i][consumed] == '\0';
      const bool positive = parsed && v.rtol > 0.0 && v.spool > 0.0 && v.spool_rate > 0.0 && v.pressure > 0.0 &&
                            v.angle > 0.0 && v.velocity > 0.0 &&
                            std::isfinite(v.rtol * v.spool * v.spool_rate * v.pressure * v.angle * v.velocity);
      if (!positive) {
        std::fprintf(
            stderr,
            "--scales: expected six finite positive factors rtol,spool,spool_rate,pressure,angle,velocity, got "
            "'%s'\n",
            argv[i]);
        return 2;
      }
      custom.push_back(v);
      only.push_back(v.name);
    } else if (std::strcmp(argv[i], "--variant") == 0 && i + 1 < argc) {
      only.emplace_back(argv[++i]);
    } else {
      std::fprintf(
          stderr,
          "usage: %s [--integrator rodas3|rodas4|ros34pw2|cvodes] [--variant NAME]... [--scales R,S,SR,P,A,V]... "
          "[--per-joint]\n",
          argv[0]);
      return 2;
    }
  }
  std::vector<Variant> variants = {
      {"shipped", 1, 1, 1, 1, 1, 1},
      {"all x0.125", 0.125, 0.125, 0.125, 0.125, 0.125, 0.125},
      {"all x0.25", 0.25, 0.25, 0.25, 0.25, 0.25, 0.25},
      {"all x0.5", 0.5, 0.5, 0.5, 0.5, 0.5, 0.5},
      {"all x2", 2, 2, 2, 2, 2, 2},
      {"all x4", 4, 4, 4, 4, 4, 4},
      {"all x8", 8, 8, 8, 8, 8, 8},
      {"rtol x4", 4, 1, 1, 1, 1, 1},
      {"atols x4", 1, 4, 4, 4, 4, 4},
      {"angle x10 (1/4 count)", 1, 1, 1, 1, 10, 1},
      {"velocity x10", 1, 1, 1, 1, 1, 10},
      {"velocity x0.1", 1, 1, 1, 1, 1, 0.1},
      {"pressure x4 (0.2 % supply)", 1, 1, 1, 4, 1, 1},
      {"spool x10", 1, 10, 10, 1, 1, 1},
      {"pressure x0.25", 1, 1, 1, 0.25, 1, 1},
      {"rtol x0.5", 0.5, 1, 1, 1, 1, 1},
  };
  variants.insert(variants.end(), custom.begin(), custom.end());
  for (const std::string& name : only) {
    if (std::none_of(variants.begin(), variants.end(), [&](const Variant& v) { return v.name == name; })) {
      std::fprintf(stderr, "--variant: no row named '%s'; the rows are:", name.c_str());
      for (const Variant& v : variants) std::fprintf(stderr, " '%s'", v.name.c_str());
      std::fprintf(stderr, "\n");
      return 2;
    }
  }

  const std::vector<JointParams> arm_joints = config().joints;
  const std::vector<JointParams> eb = {config().joints[static_cast<std::size_t>(findPlantJoint(config(), "EB"))]};

  struct Scenario {
    const char* name;
    const std::vector<JointParams>* joints;
    double duration_s, from_limit_rad;
    Trace ref;
  };
  std::vector<Scenario> scenarios = {{"EB mid", &eb, 4.0, 0.0, {}},
                                     {"EB limit", &eb, 4.0, 0.1, {}},
                                     {"arm mid", &arm_joints, 1.0, 0.0, {}},
                                     {"arm limit", &arm_joints, 1.0, 0.1, {}}};
  for (Scenario& s : scenarios) {
    s.ref = runChirp(*s.joints, tightReferenceOptions(config().solver), s.duration_s, s.from_limit_rad);
    std::fprintf(stderr, "reference %s: %.1f s CPU\n", s.name, s.ref.cpu_s);
  }

  std::printf(
      "| tolerances | EB mid q / p_L | EB limit q / p_L | arm mid q / p_L (worst joint) | arm limit q / p_L "
      "(worst joint) | within 1/4 of 0.5 %% | EB rtol/2 q / p_L | EB chirp RTF (steps, rej /s) | arm chirp RTF (steps, "
      "rej /s) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  std::string joint_table;
  for (const Variant& v : variants) {
    if (!only.empty() && std::find(only.begin(), only.end(), v.name) == only.end()) continue;
    const SolverOptions o = apply(v, integrator);
    std::printf("| %s |", v.name.c_str());
    bool within = true;
    for (Scenario& s : scenarios) {
      const Trace t = runChirp(*s.joints, o, s.duration_s, s.from_limit_rad);
      const Worst w = worstError(s.ref, t);
      within = within && w.q <= kBudget && w.p <= kBudget;
      std::printf(" %.1e / %.1e |", w.q, w.p);
      if (per_joint && s.joints == &arm_joints) {
        char line[128];
        std::snprintf(line, sizeof line, "| %s | %s |", v.name.c_str(), s.name);
        joint_table += line;
        for (std::size_t j = 0; j < t.q.size(); ++j) {
          std::snprintf(line, sizeof line, " %.1e / %.1e |", normalisedRmsDifference(s.ref.q[j], t.q[j]),
                        normalisedRmsDifference(s.ref.p_load[j], t.p_load[j]));
          joint_table += line;
        }
        joint_table += "\n";
      }
    }
    std::printf(" %s |", within ? "yes" : "no");
    SolverOptions half = o;
    half.rtol *= 0.5;
    const Worst h = worstError(runChirp(eb, o, 4.0, 0.0), runChirp(eb, half, 4.0, 0.0));
    std::printf(" %.1e / %.1e |", h.q, h.p);
    for (const std::vector<JointParams>* joints : {&eb, &arm_joints}) {
      double best = 1e300;
      Trace t;
      for (int r = 0; r < 3; ++r) {
        t = runChirp(*joints, o, 5.0, 0.0, false);
        best = std::min(best, t.cpu_s);
      }
      std::printf(" %.1fx (%ld, %ld) |", 5.0 / best, t.stats.steps / 5, t.stats.err_test_fails / 5);
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  if (per_joint) {
    std::printf("\n| tolerances | arm chirp |");
    for (const JointParams& j : arm_joints) std::printf(" %s q / p_L |", j.name.c_str());
    std::printf("\n|---|---|");
    for (std::size_t j = 0; j < arm_joints.size(); ++j) std::printf("---|");
    std::printf("\n%s", joint_table.c_str());
  }
  return 0;
}
