#include "fullarm/hil/run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/core/data_paths.hpp"
#include "fullarm/hil/fake_daq.hpp"
#include "fullarm/hil/lcm_io.hpp"
#include "fullarm/hil/sim_io.hpp"

namespace fullarm::hil {

const char* clockKindName(ClockKind clock) noexcept {
  return clock == ClockKind::kLockstep ? "lockstep" : "realtime";
}

Percentiles percentiles(std::vector<double> values) {
  Percentiles p;
  if (values.empty()) return p;
  std::sort(values.begin(), values.end());
  const auto at = [&](double q) {
    const std::size_t i = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size()))) - 1;
    return values[std::min(i, values.size() - 1)];
  };
  p.p50_s = at(0.50);
  p.p99_s = at(0.99);
  p.max_s = values.back();
  return p;
}

namespace {

std::filesystem::path orDefault(const std::filesystem::path& given, const std::filesystem::path& fallback) {
  return given.empty() ? fallback : given;
}

}  // namespace

HilSession::HilSession(const RunOptions& options, bool build_device) : options_(options) {
  if (!(options.duration_s > 0.0) || !std::isfinite(options.duration_s)) {
    throw core::ConfigError({}, "--duration", "expected a positive duration in seconds");
  }
  options_.scene = orDefault(options.scene, core::defaultScenePath("valve_wall.yaml"));
  options_.user = orDefault(options.user, defaultScriptedUserPath());
  options_.arm_config = orDefault(options.arm_config, arm::defaultArmModelPath());
  options_.plant_config = orDefault(options.plant_config, plant::defaultPlantConfigPath());
  options_.gains_config = orDefault(options.gains_config, controllers::defaultGainsConfigPath());
  options_.haptics_config = orDefault(options.haptics_config, haptics::defaultHapticsParamsPath());
  options_.hil_config = orDefault(options.hil_config, defaultHilConfigPath());
  options_.daq_config = orDefault(options.daq_config, defaultDaqConfigPath());

  if (build_device && options.io == IoKind::kComedi && options.clock == ClockKind::kLockstep) {
    throw core::ConfigError({}, "--clock",
                            "lockstep runs in simulated time: the real board (--io comedi) needs --clock realtime");
  }
  model_ = std::make_unique<arm::ArmModel>(arm::loadArmModel(options_.arm_config));
  scene_ = std::make_unique<haptics::Scene>(haptics::loadScene(options_.scene));
  world_ = std::make_unique<haptics::CollisionWorld>(haptics::makeCollisionWorld(*scene_, *model_));
  config_ = loadHilConfig(options_.hil_config);
  if (options.delivery_delay_ticks) {
    if (*options.delivery_delay_ticks < 1) throw core::ConfigError({}, "delivery delay", "expected >= 1 tick");
    config_.delivery_delay_ticks = *options.delivery_delay_ticks;
  }
  if (options.global_period_ticks) {
    if (*options.global_period_ticks < 1) throw core::ConfigError({}, "global period", "expected >= 1 tick");
    config_.global_period_ticks = *options.global_period_ticks;
    config_.supervisor.global_period_s = config_.global_period_ticks * config_.control_period_s;
  }
  haptics_ = haptics::loadHapticsParams(options_.haptics_config);
  haptics_.mode = options.mode;
  gains_ = controllers::loadGainsConfig(options_.gains_config, *model_);
  if (std::abs(gains_.control_period_s - config_.control_period_s) > 1e-12) {
    throw core::ConfigError(config_.source, "control_period_s",
                            "is " + std::to_string(config_.control_period_s) + " s but the gains file " +
                                gains_.source.string() + " was designed for " +
                                std::to_string(gains_.control_period_s) + " s");
  }
  plant_ = plant::loadPlantConfig(options_.plant_config, *model_);
  plant_.solver.integrator = config_.sim_integrator;
  plant_.seed = options.seed;
  posture_ = haptics::scenePosture(*scene_, options.start_posture, *model_);

  // The device's joints: the plant's joints for the simulated back-ends, the channel map's for
  // comedi.
  arm::JointSelection joints;
  if (options.io == IoKind::kComedi || options.io == IoKind::kFakeDaq)
    daq_ = loadDaqConfig(options_.daq_config, *model_);
  if (options.io == IoKind::kComedi) {
    std::vector<int> indices;
    for (const DaqJoint& j : daq_.joints) indices.push_back(model_->jointIndex(j.name));
    joints = arm::JointSelection(model_->numJoints(), indices);
  } else {
    std::vector<int> indices;
    for (const plant::JointParams& j : plant_.joints) indices.push_back(model_->jointIndex(j.name));
    joints = arm::JointSelection(model_->numJoints(), indices);
  }
  tick_ = makeTickModel(*model_, *world_, haptics_, gains_, config_.supervisor, joints, posture_);
  if (!build_device) return;

  IoBackendOptions io;
  io.io = options.io;
  io.period_s = config_.control_period_s;
  io.latency_samples = config_.latency_samples;
  io.safety = config_.io_safety;
  io.plant = &plant_;
  io.posture = posture_;
  if (options.io == IoKind::kSim && options.sim_uses_daq_converters) daq_ = loadDaqConfig(options_.daq_config, *model_);
  io.daq = &daq_;
  io.sim_uses_daq_converters = options.sim_uses_daq_converters;
  io.fakedaq_state_file = options.fakedaq_state_file;
  io.lcm_joints = joints;
  io.lcm_url = options.lcm_url;
  // Real time: a reading must come within 0.6 of a period to leave the tick its compute time;
  // lockstep waits long, for determinism.
  if (options.clock == ClockKind::kRealtime) io.lcm_reply_timeout_s = 0.6 * config_.control_period_s;
  backend_ = std::make_unique<IoBackend>(*model_, io);
  device_ = &backend_->device();
  arm_ = backend_->simulatedArm();
  if (arm_ != nullptr && options_.scripted_user) {
    user_ = std::make_unique<ScriptedUser>(loadScriptedUser(options_.user), *model_,
                                           haptics::armBasePose(*scene_, *model_));
    arm_->setUser(user_.get());
  }
  if (device_->joints().modelIndices() != joints.modelIndices()) {
    throw DeviceError("the I/O device's joints differ from the tick's: check the channel map " + daq_.source.string() +
                      " against the plant file " + plant_.source.string());
  }
}

HilSession::~HilSession() = default;

RunResult HilSession::run(const RunHooks& hooks) {
  if (!device_) throw std::logic_error("HilSession: built without a device (replay only)");
  if (ran_) throw std::logic_error("HilSession: a session runs once");
  ran_ = true;
  return options_.clock == ClockKind::kLockstep ? runLockstep(hooks) : runRealtime(hooks);
}

RunResult HilSession::startResult() const {
  RunResult r;
  r.options = options_;
  r.io_name = ioKindName(options_.io);
  for (int k = 0; k < tick_.device_joints.size(); ++k) {
    r.joint_names.push_back(model_->joints[static_cast<std::size_t>(tick_.device_joints.modelIndex(k))].name);
  }
  for (const arm::Joint& j : model_->joints) r.link_names.push_back(j.name);
  return r;
}

void HilSession::finishResult(RunResult& r) const {
  for (const TickTelemetry& t : r.telemetry) {
    for (int e = 0; e < t.num_events; ++e) r.events.push_back(t.events[static_cast<std::size_t>(e)]);
    if (t.sweep_exceeded_mask != 0) ++r.sweep_exceeded_ticks;
  }
  if (!r.telemetry.empty()) {
    r.tripped = r.telemetry.back().supervisor_state == SupervisorState::kTripped;
    r.trip_cause = r.telemetry.back().trip_cause;
  }
  for (const double f : r.user_force_n) r.max_user_force_n = std::max(r.max_user_force_n, f);
  if (user_ && !r.hand_W_m.empty()) r.hand_to_target_m = (r.hand_W_m.back() - user_->pathPoint(1e9)).norm();
}

std::vector<TickTelemetry> HilSession::replay(const RunResult& recorded) const {
  std::vector<TickTelemetry> out;
  out.reserve(recorded.inputs.size());
  TickData data(tick_);
  IoVector valve;
  TickTelemetry telemetry;
  for (const RecordedTick& in : recorded.inputs) {
    MinimaDelivery delivery;
    TickInputs inputs;
    inputs.sample = &in.sample;
    inputs.device_status = in.device_status;
    inputs.requests = in.requests;
    if (in.adopted_set >= 0) {
      const RecordedSet& set = recorded.sets.at(static_cast<std::size_t>(in.adopted_set - 1));
      delivery.set_id = set.id;
      delivery.minima = set.minima;
      delivery.query_q_rad = set.query_q_rad;
      inputs.minima = &delivery;
    }
    stepTick(tick_, data, inputs, valve, telemetry);
    out.push_back(telemetry);
  }
  return out;
}

RunResult runHil(const RunOptions& options, const RunHooks& hooks) {
  HilSession session(options);
  return session.run(hooks);
}

}  // namespace fullarm::hil
