#include "access_population.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli_values.hpp"
#include "exit_codes.hpp"
#include "fullarm/accessibility/population.hpp"
#include "fullarm/accessibility/population_reach.hpp"
#include "fullarm/accessibility/population_shares.hpp"
#include "fullarm/arm/arm_scaling.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/core/sweep.hpp"
#include "fullarm/haptics/scene.hpp"
#include "fullarm/mpi/mpi_sweep.hpp"
#include "fullarm/reports/report.hpp"
#include "output_files.hpp"

namespace fullarm::app {
namespace {

namespace acc = accessibility;

// The values of one technician in the sweep's rows.
enum Column : std::size_t {
  kFemale = 0,
  kUpperArm = 1,
  kForearm = 2,
  kRadiusScale = 3,
  kStrength = 4,
  kVerdict = 5,  // three: free, contact allowed, hand only (0 reachable, 1 unreachable, 2 unknown)
  kSource = 8,   // three: 0 repaired, 1 fresh
  kPushAnalysed = 11,
  kPushUnbraced = 12,
  kPushBraced = 13,
  kUnbracedOk = 14,
  kBracedOk = 15,
  kColumns = 16,
};

constexpr const char* kSweepName = "technicians";
constexpr const char* kSweepFile = "technicians.sweep";
constexpr const char* kTaskFile = "population.json";
constexpr const char* kTaskFormat = "fullarm access population 1";
constexpr std::array<const char*, acc::kReachModes> kModeKeys = {"free", "contact_allowed", "hand_only"};

double verdictCode(acc::Verdict v) {
  return v == acc::Verdict::kReachable ? 0.0 : v == acc::Verdict::kUnreachable ? 1.0 : 2.0;
}

const char* verdictOfCode(double code) {
  return code == 0.0 ? "reachable" : code == 1.0 ? "unreachable" : "unknown";
}

std::string readText(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw core::ConfigError(file, "", "cannot be read");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The task without the paths of its files (which may differ between the machines of one run).
nlohmann::json withoutPaths(nlohmann::json task) {
  for (const char* key : {"scene_file", "arm_file", "human_file"}) task.erase(key);
  return task;
}

// Everything a technician's outcome depends on, for summary.json and the shards.
struct Setup {
  arm::ArmModel model;
  haptics::Scene scene;
  acc::PopulationTask task;
  acc::PopulationOptions population;
  acc::NominalReach nominal;
  double nominal_upper_arm_m = 0.0;
  double nominal_forearm_m = 0.0;
  nlohmann::json description;
  core::SweepSpec spec;
};

Setup makeSetup(const AccessOptions& o) {
  if (!o.force_n) {
    throw core::ConfigError("", "--force", "a population needs the push the task needs (--force N)");
  }
  Setup s;
  s.population.technicians = *o.population;
  s.population.female_share = o.mix;
  s.population.seed = static_cast<std::uint64_t>(o.seed);
  acc::validatePopulationOptions(s.population);

  const std::filesystem::path arm_file = configPathOr(o.arm_config, arm::defaultArmModelPath);
  const std::filesystem::path human_file = configPathOr(o.human_config, acc::defaultHumanArmPath);
  s.model = arm::loadArmModel(arm_file);
  const arm::ArmSize size = arm::armSizeOf(s.model);
  if (!size.upper_arm_length_m || !size.forearm_length_m) {
    throw core::ConfigError(arm_file, "upper_arm_joint",
                            "a population needs an arm model that names its upper-arm and "
                            "forearm joints");
  }
  s.nominal_upper_arm_m = *size.upper_arm_length_m;
  s.nominal_forearm_m = *size.forearm_length_m;
  s.scene = haptics::loadScene(o.scene);
  s.task.model = &s.model;
  s.task.scene = &s.scene;
  s.task.target = o.target;
  s.task.params = haptics::loadHapticsParams(haptics::defaultHapticsParamsPath());
  s.task.human = acc::loadHumanArm(human_file, s.model);
  s.task.reach = accessReachOptions(o);
  s.task.repair_iterations = static_cast<long>(o.repair_iterations);
  s.task.brace = accessBraceOptions(o);
  s.task.required_force_n = *o.force_n;
  std::cerr << "access: population of " << s.population.technicians << " technicians (share of women " << o.mix
            << ", seed " << o.seed << "); the nominal arm's reach in three modes\n";
  s.nominal = acc::planNominalReach(s.task);

  nlohmann::json& d = s.description;
  d["format"] = kTaskFormat;
  d["scene"] = s.scene.name;
  d["scene_file"] = std::filesystem::absolute(s.scene.source).string();
  d["target"] = s.nominal.target.name;
  d["arm_file"] = std::filesystem::absolute(arm_file).string();
  d["human_file"] = std::filesystem::absolute(human_file).string();
  d["technicians"] = s.population.technicians;
  d["share_of_women"] = o.mix;
  d["seed"] = o.seed;
  d["required_push_n"] = *o.force_n;
  d["planner"] = o.planner;
  d["iterations_budget"] = o.iterations;
  d["repair_iterations"] = o.repair_iterations;
  d["brace_evaluations"] = o.brace_evaluations;
  d["limits"] = {{"clearance_margin_m", o.clearance_m},
                 {"max_link_force_n", o.max_link_force_n},
                 {"max_skin_depth_m", o.max_skin_depth_m}};
  d["nominal_segments_m"] = {{"upper_arm", s.nominal_upper_arm_m}, {"forearm", s.nominal_forearm_m}};
  nlohmann::json nominal;
  for (std::size_t m = 0; m < acc::kReachModes; ++m) {
    nominal[kModeKeys[m]] = acc::verdictName(s.nominal.result(acc::kReachModeOrder[m]).verdict);
  }
  d["nominal_reach"] = nominal;

  s.spec.name = kSweepName;
  s.spec.samples = s.population.technicians;
  s.spec.seed = s.population.seed;
  s.spec.values_per_sample = static_cast<int>(kColumns);
  s.spec.input_hash =
      core::sweepInputHash(withoutPaths(d).dump() + "\n" + readText(s.scene.source) + "\n" + readText(arm_file) + "\n" +
                           readText(human_file) + "\n" + readText(haptics::defaultHapticsParamsPath()));
  return s;
}

core::SweepFunction technicianFunction(const Setup& s) {
  return [&s](std::int64_t sample, core::RandomStream& rng, std::span<double> out) {
    const acc::Technician t =
        acc::drawTechnician(s.population, sample, rng, s.nominal_upper_arm_m, s.nominal_forearm_m);
    const auto seed = static_cast<std::uint32_t>(rng.next() >> 32U);
    const acc::TechnicianOutcome r = acc::evaluateTechnician(s.task, s.nominal, t, seed);
    out[kFemale] = t.female ? 1.0 : 0.0;
    out[kUpperArm] = t.upper_arm_m;
    out[kForearm] = t.forearm_m;
    out[kRadiusScale] = t.link_radius_scale;
    out[kStrength] = t.strength_scale;
    for (std::size_t m = 0; m < acc::kReachModes; ++m) {
      out[kVerdict + m] = verdictCode(r.reach[m].verdict);
      out[kSource + m] = r.reach[m].source == acc::ReachSource::kRepaired ? 0.0 : 1.0;
    }
    out[kPushAnalysed] = r.push_analysed ? 1.0 : 0.0;
    out[kPushUnbraced] = r.push_unbraced_n;
    out[kPushBraced] = r.push_braced_n;
    out[kUnbracedOk] = r.push_unbraced_ok ? 1.0 : 0.0;
    out[kBracedOk] = r.push_braced_ok ? 1.0 : 0.0;
  };
}

std::string percent(double share) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(1) << share * 100.0 << " %";
  return s.str();
}

nlohmann::json criterionJson(const acc::CriterionSummary& c) {
  nlohmann::json j;
  j["successes"] = c.wilson.successes;
  j["trials"] = c.wilson.trials;
  j["share"] = c.wilson.share;
  j["confidence"] = c.wilson.confidence;
  j["wilson"] = {c.wilson.lower, c.wilson.upper};
  j["clopper_pearson"] = {c.clopper_pearson.lower, c.clopper_pearson.upper};
  nlohmann::json odds;
  nlohmann::json failures;
  for (int k = 0; k < acc::kPopulationFactors; ++k) {
    const char* name = acc::factorName(static_cast<acc::PopulationFactor>(k));
    odds[name] = c.log_odds_per_sd[static_cast<std::size_t>(k)];
    failures[name] = c.failures_by_factor[static_cast<std::size_t>(k)];
  }
  j["log_odds_per_sd"] = odds;
  j["intercept"] = c.intercept;
  j["fit_separated"] = c.fit_separated;
  j["failures_by_factor"] = failures;
  j["failures_unexplained"] = c.failures_unexplained;
  return j;
}

std::string csvNumber(double v) {
  if (std::isnan(v)) return "";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  std::ostringstream s;
  s << std::setprecision(10) << v;
  return s.str();
}

// summary.json, technicians.csv and report.html of the whole population.
void writePopulation(const nlohmann::json& task, const core::SweepResults& all, const std::string& out_dir) {
  const std::size_t n = all.sample.size();
  std::vector<acc::Technician> technicians(n);
  std::array<std::vector<bool>, 5> success;
  for (auto& s : success) s.assign(n, false);
  std::array<std::int64_t, acc::kReachModes> repaired{};
  std::int64_t women = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::span<const double> v = all.row(i);
    acc::Technician& t = technicians[i];
    t.index = all.sample[i];
    t.female = v[kFemale] != 0.0;
    t.upper_arm_m = v[kUpperArm];
    t.forearm_m = v[kForearm];
    t.link_radius_scale = v[kRadiusScale];
    t.strength_scale = v[kStrength];
    women += t.female ? 1 : 0;
    for (std::size_t m = 0; m < acc::kReachModes; ++m) {
      success[m][i] = v[kVerdict + m] == 0.0;
      repaired[m] += v[kSource + m] == 0.0 ? 1 : 0;
    }
    success[3][i] = v[kUnbracedOk] != 0.0;
    success[4][i] = v[kBracedOk] != 0.0;
  }
  const double force_n = task.at("required_push_n").get<double>();
  std::ostringstream f;
  f << force_n;
  const std::array<std::string, 5> keys = {"reach_free", "reach_contact_allowed", "reach_hand_only", "push_unbraced",
                                           "push_braced"};
  const std::array<std::string, 5> labels = {"reach, free", "reach, contact allowed", "reach, hand only",
                                             "reach (contact allowed) and push " + f.str() + " N without bracing",
                                             "reach (contact allowed) and push " + f.str() + " N with bracing"};
  std::array<acc::CriterionSummary, 5> criteria;
  // Reach depends on the arm's size only; the push on size and strength.
  for (std::size_t c = 0; c < 5; ++c) {
    criteria[c] = acc::summariseCriterion(technicians, success[c], 0.95,
                                          c < acc::kReachModes ? acc::kSizeFactors : acc::kAllFactors);
  }

  reports::Report report("access", "Accessibility of a population: " + task.at("scene").get<std::string>() +
                                       ", target " + task.at("target").get<std::string>());
  const acc::CriterionSummary& braced = criteria[4];
  report.setVerdict(true, percent(braced.wilson.share) + " of " + std::to_string(n) +
                              " technicians reach the target (" + "contact allowed) and push " + f.str() +
                              " N with bracing (95 % Wilson interval " + percent(braced.wilson.lower) + " to " +
                              percent(braced.wilson.upper) + ")");
  report.addHeadlineNumber("share_push_braced", "Reach and push with bracing", braced.wilson.share * 100.0, "%");
  report.addHeadlineNumber("share_reach_contact", "Reach, contact allowed", criteria[1].wilson.share * 100.0, "%");
  nlohmann::json& r = report.results()["population"];
  r["task"] = task;
  r["technicians"] = static_cast<std::int64_t>(n);
  r["women"] = women;
  for (std::size_t c = 0; c < 5; ++c) r["criteria"][keys[c]] = criterionJson(criteria[c]);
  for (std::size_t m = 0; m < acc::kReachModes; ++m) {
    r["reach_repair"][kModeKeys[m]] = {{"repaired", repaired[m]},
                                       {"fresh", static_cast<std::int64_t>(n) - repaired[m]}};
  }

  reports::Table shares;
  shares.caption =
      "Shares of the population with 95 % intervals, and the failures split by the factor that limits "
      "each (a logistic fit on the standardised log segment lengths for the reach rows, and on those "
      "and log strength for the push rows)";
  shares.columns = {"Criterion",
                    "Successes",
                    "Share",
                    "Wilson low",
                    "Wilson high",
                    "Clopper-Pearson low",
                    "Clopper-Pearson high",
                    "Limited by upper arm",
                    "Limited by forearm",
                    "Limited by strength",
                    "Unexplained"};
  std::cout << "Population of " << n << " technicians (" << women << " women), scene "
            << task.at("scene").get<std::string>() << ", target " << task.at("target").get<std::string>() << "\n";
  for (std::size_t c = 0; c < 5; ++c) {
    const acc::CriterionSummary& s = criteria[c];
    shares.rows.push_back({labels[c], static_cast<double>(s.wilson.successes), s.wilson.share, s.wilson.lower,
                           s.wilson.upper, s.clopper_pearson.lower, s.clopper_pearson.upper,
                           static_cast<double>(s.failures_by_factor[0]), static_cast<double>(s.failures_by_factor[1]),
                           static_cast<double>(s.failures_by_factor[2]), static_cast<double>(s.failures_unexplained)});
    std::cout << "  " << labels[c] << ": " << s.wilson.successes << " of " << n << " = " << percent(s.wilson.share)
              << " (Wilson " << percent(s.wilson.lower) << " to " << percent(s.wilson.upper) << "; failures limited by"
              << " upper arm " << s.failures_by_factor[0] << ", forearm " << s.failures_by_factor[1] << ", strength "
              << s.failures_by_factor[2] << ", unexplained " << s.failures_unexplained << ")\n";
  }
  shares.significant_digits = 4;
  reports::Section& section = report.addSection("Shares");
  section.addTable(std::move(shares));
  reports::Table repair;
  repair.caption = "How each technician's reach was answered: the nominal arm's path repaired, or planned afresh";
  repair.columns = {"Mode", "Nominal arm", "Repaired", "Fresh"};
  for (std::size_t m = 0; m < acc::kReachModes; ++m) {
    repair.rows.push_back(
        {acc::reachModeName(acc::kReachModeOrder[m]), task.at("nominal_reach").at(kModeKeys[m]).get<std::string>(),
         static_cast<double>(repaired[m]), static_cast<double>(n - static_cast<std::size_t>(repaired[m]))});
  }
  section.addTable(std::move(repair));

  // The map: arm length against strength, each technician a point coloured by outcome.
  reports::XyChart map;
  map.title = "Which arm sizes and strengths succeed";
  map.x_axis = {"Upper arm + forearm", "mm", false};
  map.y_axis = {"Strength scale (1: the human arm file's figures)", "", false};
  map.series = {{"reaches and pushes with bracing", {}, {}, reports::SeriesMode::kMarkers, {}},
                {"reaches, too weak with bracing", {}, {}, reports::SeriesMode::kMarkers, {}},
                {"cannot reach (contact allowed)", {}, {}, reports::SeriesMode::kMarkers, {}}};
  for (std::size_t i = 0; i < n; ++i) {
    const acc::Technician& t = technicians[i];
    const std::size_t k = success[4][i] ? 0 : success[1][i] ? 1 : 2;
    map.series[k].x.push_back((t.upper_arm_m + t.forearm_m) * 1e3);
    map.series[k].y.push_back(t.strength_scale);
    map.series[k].point_labels.push_back("technician " + std::to_string(t.index) + (t.female ? " (woman)" : " (man)"));
  }
  std::erase_if(map.series, [](const reports::Series& s) { return s.x.empty(); });
  map.caption = "Each point a technician; the shoulder stands where the scene puts the arm's base.";
  report.addSection("Map").addScatterChart(std::move(map));

  std::ostringstream csv;
  csv << "index,sex,upper_arm_m,forearm_m,link_radius_scale,strength_scale,free,contact_allowed,hand_only,"
         "free_source,contact_allowed_source,hand_only_source,push_unbraced_n,push_braced_n,push_unbraced_ok,"
         "push_braced_ok\n";
  for (std::size_t i = 0; i < n; ++i) {
    const std::span<const double> v = all.row(i);
    csv << all.sample[i] << "," << (v[kFemale] != 0.0 ? "F" : "M") << "," << csvNumber(v[kUpperArm]) << ","
        << csvNumber(v[kForearm]) << "," << csvNumber(v[kRadiusScale]) << "," << csvNumber(v[kStrength]);
    for (std::size_t m = 0; m < acc::kReachModes; ++m) csv << "," << verdictOfCode(v[kVerdict + m]);
    for (std::size_t m = 0; m < acc::kReachModes; ++m) csv << "," << (v[kSource + m] == 0.0 ? "repaired" : "fresh");
    csv << "," << csvNumber(v[kPushUnbraced]) << "," << csvNumber(v[kPushBraced]) << "," << v[kUnbracedOk] << ","
        << v[kBracedOk] << "\n";
  }
  if (!out_dir.empty()) {
    writeReport(report, out_dir);
    writeTextFile(std::filesystem::path(out_dir) / "technicians.csv", csv.str());
    std::cout << "\nReport: " << (std::filesystem::absolute(out_dir) / "report.html").string() << "\n";
  }
}

int threadCount(int requested, bool under_mpi) {
  if (requested > 0) return requested;
  if (under_mpi) return 1;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

}  // namespace

int runAccessPopulation(const AccessOptions& o) {
  if (o.scene.empty()) throw core::ConfigError("", "--scene", "access needs a scene (--scene FILE)");
  if (!o.population) throw core::ConfigError("", "--population", "the number of technicians is missing");
  // OpenMPI's mpirun sets OMPI_COMM_WORLD_SIZE in every process it starts.
  const bool under_mpi = std::getenv("OMPI_COMM_WORLD_SIZE") != nullptr;
  std::optional<core::ShardSpec> shard;
  if (!o.shard.empty()) {
    shard = core::parseShardSpec(o.shard);
    if (o.out_dir.empty()) throw core::ConfigError("", "--shard", "a shard needs --out (the folder its file goes to)");
    if (under_mpi)
      throw core::ConfigError("", "--shard", "--shard and mpirun do not combine: mpirun spreads the shards");
  }
  if (!(o.mix >= 0.0 && o.mix <= 1.0)) throw core::ConfigError("", "--mix", "must lie in [0, 1]");
  const Setup s = makeSetup(o);
  const int threads = threadCount(o.threads, under_mpi);
  core::Progress& progress = core::progressOrQuiet(o.progress);
  const core::SweepFunction evaluate = technicianFunction(s);
  const auto advance = [&progress](std::int64_t) { progress.advance(); };
  core::SweepResults results;
  if (under_mpi) {
    int argc = 0;
    char** argv = nullptr;
    const mpi::Session session(argc, argv);
    std::ostringstream line;
    line << "access: rank " << session.rank() << " of " << session.size() << ", " << threads << " threads\n";
    std::cerr << line.str() << std::flush;
    const core::SampleRange mine = core::shardRange(s.spec.samples, {session.rank() + 1, session.size()});
    progress.begin("access population (rank " + std::to_string(session.rank()) + ")",
                   static_cast<std::size_t>(mine.end - mine.begin));
    results = mpi::runSweepOverRanks(session, s.spec, evaluate, threads, advance);
    progress.end();
    if (session.rank() != 0) return kExitPass;
  } else {
    const core::ShardSpec part = shard.value_or(core::ShardSpec{});
    const core::SampleRange mine = core::shardRange(s.spec.samples, part);
    progress.begin("access population", static_cast<std::size_t>(mine.end - mine.begin));
    results = core::runSweep(s.spec, part, evaluate, threads, advance);
    progress.end();
  }
  if (shard) {
    const std::filesystem::path dir(o.out_dir);
    createOutputFolder(dir);
    core::writeSweepResults(results, dir / kSweepFile);
    writeTextFile(dir / kTaskFile, s.description.dump(2) + "\n");
    std::cout << "Shard " << shard->index << "/" << shard->count << " of " << s.spec.samples
              << " technicians: " << results.sample.size() << " written to " << (dir / kSweepFile).string()
              << "; merge the shards with `fullarm access merge --out DIR SHARD_DIR/technicians.sweep...`\n";
    return kExitPass;
  }
  writePopulation(s.description, results, o.out_dir);
  return kExitPass;
}

int runAccessMerge(const AccessMergeOptions& o) {
  std::vector<core::SweepResults> shards;
  nlohmann::json task;
  for (const std::string& shard_file : o.shards) {
    const std::filesystem::path file(shard_file);
    const std::filesystem::path task_file = file.parent_path() / kTaskFile;
    if (file.filename() != kSweepFile || !std::filesystem::is_regular_file(task_file)) {
      throw core::ConfigError(file, "shards",
                              std::string("is not a shard (a shard is the ") + kSweepFile +
                                  " that `fullarm access --population N --shard i/N --out DIR` "
                                  "writes, with its " +
                                  kTaskFile + " beside it)");
    }
    nlohmann::json t;
    try {
      t = nlohmann::json::parse(readText(task_file));
    } catch (const nlohmann::json::exception& e) {
      throw core::ConfigError(task_file, "", std::string("is not valid JSON: ") + e.what());
    }
    if (!t.is_object() || t.value("format", "") != kTaskFormat) {
      throw core::ConfigError(task_file, "format",
                              std::string("is not a population task (expected format '") + kTaskFormat + "')");
    }
    if (task.is_null()) {
      task = t;
    } else if (withoutPaths(t) != withoutPaths(task)) {
      throw core::ConfigError(task_file, "",
                              "belongs to another population than " + o.shards.front() +
                                  " (scene, target, options or nominal reach differ)");
    }
    shards.push_back(core::readSweepResults(file));
  }
  const core::SweepResults all = core::mergeSweepResults(shards);
  if (all.spec.name != kSweepName || all.spec.values_per_sample != static_cast<int>(kColumns)) {
    throw core::ConfigError(o.shards.front(), "shards", "the shards are not a population's technicians");
  }
  std::cerr << "access merge: " << shards.size() << " shards, " << all.sample.size() << " technicians\n";
  writePopulation(task, all, o.out_dir);
  return kExitPass;
}

}  // namespace fullarm::app
