// `fullarm access --population` end to end on a small population: the same summary on 1 and 2
// threads, from two shards merged and under `mpirun -np 2`; the per-technician CSV; bad
// population options and bad merges refused with exit code 2 and a message naming the option.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "cli_runner.hpp"

namespace {

using fullarm::test::runFullarm;

const std::string kScene = std::string(FULLARM_TEST_SOURCE_DIR) + "/scenes/accessibility/env5.yaml";
// Environment 5 splits a small population between reaching and not; few brace postures keep it quick.
const std::string kPopulation =
    "access --scene " + kScene + " --population 5 --mix 0.5 --seed 3 --force 60 --brace-evaluations 10";

nlohmann::json results(const std::filesystem::path& dir) {
  std::ifstream in(dir / "summary.json");
  return nlohmann::json::parse(in)["results"]["population"];
}

std::string text(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::filesystem::path dir(const std::string& name) {
  return fullarm::test::cliTempDir("fullarm_access_population_cli_test", name);
}

// One process for all the comparisons: every run is a population of its own, so the reference
// is computed once.
TEST(AccessPopulationCliTest, OneOrTwoThreadsTwoShardsAndMpirunGiveTheSameAnswer) {
  const std::filesystem::path one = dir("one");
  const auto reference = runFullarm(kPopulation + " --threads 1 --out " + one.string());
  ASSERT_EQ(reference.exit_code, 0) << reference.output;
  {  // the outputs
    const nlohmann::json r = results(one);
    ASSERT_TRUE(r.contains("criteria")) << r.dump();
    EXPECT_EQ(r["technicians"], 5);
    for (const char* key : {"reach_free", "reach_contact_allowed", "reach_hand_only", "push_unbraced", "push_braced"}) {
      const nlohmann::json& c = r["criteria"][key];
      EXPECT_EQ(c["trials"], 5) << key;
      const double share = c["share"].get<double>();
      EXPECT_LE(c["wilson"][0].get<double>(), share) << key;
      EXPECT_GE(c["wilson"][1].get<double>(), share) << key;
      EXPECT_LE(c["clopper_pearson"][0].get<double>(), share) << key;
      EXPECT_GE(c["clopper_pearson"][1].get<double>(), share) << key;
    }
    // Bracing never lowers the push, and pushing needs reaching first.
    EXPECT_LE(r["criteria"]["push_unbraced"]["successes"].get<int>(),
              r["criteria"]["push_braced"]["successes"].get<int>());
    EXPECT_LE(r["criteria"]["push_braced"]["successes"].get<int>(),
              r["criteria"]["reach_contact_allowed"]["successes"].get<int>());
    for (const char* mode : {"free", "contact_allowed", "hand_only"}) {
      EXPECT_EQ(r["reach_repair"][mode]["repaired"].get<int>() + r["reach_repair"][mode]["fresh"].get<int>(), 5)
          << mode;
    }
    const std::string csv = text(one / "technicians.csv");
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 6) << csv;  // header and five technicians
    EXPECT_NE(reference.output.find("access population [0/5]"), std::string::npos) << reference.output;  // progress
    EXPECT_NE(reference.output.find("access population: done"), std::string::npos) << reference.output;
    EXPECT_TRUE(std::filesystem::exists(one / "report.html"));
  }
  {  // two threads
    const std::filesystem::path two = dir("two");
    const auto r = runFullarm(kPopulation + " --threads 2 --out " + two.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(results(two), results(one));
    EXPECT_EQ(text(two / "technicians.csv"), text(one / "technicians.csv"));
  }
  {  // two shards merged; bad merges refused
    const std::filesystem::path s1 = dir("shard1");
    const std::filesystem::path s2 = dir("shard2");
    for (const auto& [shard, folder] : {std::pair{"1/2", s1}, std::pair{"2/2", s2}}) {
      const auto r = runFullarm(kPopulation + " --threads 1 --shard " + shard + " --out " + folder.string());
      ASSERT_EQ(r.exit_code, 0) << r.output;
    }
    const std::filesystem::path merged = dir("merged");
    const std::string f1 = (s1 / "technicians.sweep").string();
    const std::string f2 = (s2 / "technicians.sweep").string();
    const auto m = runFullarm("access merge --out " + merged.string() + " " + f2 + " " + f1);
    ASSERT_EQ(m.exit_code, 0) << m.output;
    EXPECT_EQ(results(merged), results(one));
    EXPECT_EQ(text(merged / "technicians.csv"), text(one / "technicians.csv"));

    // A shard missing, given twice, or of another population.
    const auto missing = runFullarm("access merge --out " + dir("bad1").string() + " " + f1);
    EXPECT_EQ(missing.exit_code, 2) << missing.output;
    EXPECT_NE(missing.output.find("missing"), std::string::npos) << missing.output;
    const auto twice = runFullarm("access merge --out " + dir("bad2").string() + " " + f1 + " " + f1);
    EXPECT_EQ(twice.exit_code, 2) << twice.output;
    const std::filesystem::path other = dir("other");
    ASSERT_EQ(runFullarm("access --scene " + kScene +
                         " --population 5 --mix 0.5 --seed 4 --force 60 --brace-evaluations 10 --threads 1 --shard 2/2"
                         " --out " +
                         other.string())
                  .exit_code,
              0);
    const auto mismatched = runFullarm("access merge --out " + dir("bad3").string() + " " + f1 + " " +
                                       (other / "technicians.sweep").string());
    EXPECT_EQ(mismatched.exit_code, 2) << mismatched.output;
    EXPECT_NE(mismatched.output.find("another population"), std::string::npos) << mismatched.output;
    const auto not_a_shard =
        runFullarm("access merge --out " + dir("bad4").string() + " " + (one / "technicians.csv").string());
    EXPECT_EQ(not_a_shard.exit_code, 2) << not_a_shard.output;
    EXPECT_NE(not_a_shard.output.find("not a shard"), std::string::npos) << not_a_shard.output;
  }
  {  // mpirun on two ranks
    // As root (CI containers) OpenMPI refuses to start without both variables.
    setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
    setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
    const std::filesystem::path spread = dir("mpi");
    const std::string command = std::string(FULLARM_MPIEXEC) + " -np 2 --oversubscribe " + FULLARM_EXE + " " +
                                kPopulation + " --out " + spread.string() + " 2>&1";
    FILE* pipe = popen(command.c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    std::string output;
    char buffer[4096];
    std::size_t n = 0;
    while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) output.append(buffer, n);
    const int status = pclose(pipe);
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << output;
    EXPECT_NE(output.find("(rank 1)"), std::string::npos) << output;  // the second rank's progress
    EXPECT_EQ(results(spread), results(one));
  }
}

TEST(AccessPopulationOptionsTest, BadOptionsExitTwoNamingTheOption) {
  const std::string base = "access --scene " + kScene + " --force 60 ";
  const std::string x = dir("bad_options").string();
  struct Case {
    std::string args;
    std::string names;
  };
  for (const Case& c :
       {Case{"--population 0", "--population"}, Case{"--population -3", "--population"},
        Case{"--population 5 --mix nan", "--mix"}, Case{"--population 5 --mix 1.5", "--mix"},
        Case{"--population 5 --mix -0.1", "--mix"}, Case{"--population 5 --shard 0/2 --out " + x, "--shard"},
        Case{"--population 5 --shard 3/2 --out " + x, "--shard"},
        Case{"--population 5 --shard a/b --out " + x, "--shard"}, Case{"--population 5 --shard 1/2", "--shard"},
        Case{"--shard 1/2 --out " + x, "--shard"}, Case{"--mix 0.3", "--mix"}, Case{"--threads 2", "--threads"},
        Case{"--repair-iterations 50", "--repair-iterations"}}) {
    const auto r = runFullarm(base + c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find(c.names), std::string::npos) << c.args << "\n" << r.output;
  }
  const auto no_force = runFullarm("access --scene " + kScene + " --population 5");
  EXPECT_EQ(no_force.exit_code, 2) << no_force.output;
  EXPECT_NE(no_force.output.find("--force"), std::string::npos) << no_force.output;
}

}  // namespace
