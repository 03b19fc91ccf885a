// Every option of the `fullarm` program, from its own table of declared options (cli.hpp),
// fed the values that must be refused: NaN, infinities and values just outside the declared
// range for numbers; empty and repeated entries for lists; and so on per kind. Each case runs the
// program in-process and expects exit code 2 with a message naming the option. An option added
// later is covered by being declared; one added without the declarer fails
// EveryParsedOptionIsDeclared.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "cli.hpp"
#include "exit_codes.hpp"

namespace fullarm::app {
namespace {

struct BadValue {
  std::string value;
  std::string why;
};

std::string shortest(double value) {
  std::ostringstream out;
  out.precision(17);
  out << value;
  return out.str();
}

// Values the option's declaration refuses.
std::vector<BadValue> badValues(const OptionSpec& spec) {
  switch (spec.kind) {
    case OptionKind::kNumber: {
      // Just outside the range: one part in a thousand of the range's width (or of the bound).
      const double margin = std::max({(spec.max - spec.min) * 1e-3, std::abs(spec.min) * 1e-3, 1e-12});
      return {{"nan", "NaN"},
              {"inf", "infinity"},
              {"-inf", "minus infinity"},
              {"NaN", "NaN spelt otherwise"},
              {shortest(spec.min - margin), "below the range"},
              {shortest(spec.max + std::max((spec.max - spec.min) * 1e-3, std::abs(spec.max) * 1e-3)),
               "above the range"},
              {"", "empty"},
              {"1x", "not a number"}};
    }
    case OptionKind::kInteger:
      return {{"nan", "NaN"},
              {"inf", "infinity"},
              {std::to_string(static_cast<long long>(spec.min) - 1), "below the range"},
              {std::to_string(static_cast<long long>(spec.max) + 1), "above the range"},
              {"1.5", "not an integer"},
              {"", "empty"}};
    case OptionKind::kList:
      return {{"", "empty"}, {",", "two empty entries"}, {"EB,,WR", "an empty entry"}, {"EB,EB", "a repeated entry"},
              {"EB, EB", "a repeated entry with a space"}};
    case OptionKind::kNumberList:
      return {{"", "empty"}, {"nan", "NaN"}, {"0.1,inf", "infinity"}, {"0.1,,0.2", "an empty element"},
              {",", "no number"}, {"0.1,x", "not a number"}};
    case OptionKind::kChoice:
      return {{"", "empty"}, {"no-such-choice", "not a choice"}};
    case OptionKind::kName:
      return {{"", "empty"}, {" ", "blank"}};
    case OptionKind::kFile:
      return {{"", "empty"}, {"/nonexistent/fullarm/option_table_test.yaml", "missing file"}};
    case OptionKind::kFolder:
      return {{"", "empty"}};
    case OptionKind::kFlag:
      return {};
  }
  return {};
}

std::vector<std::string> words(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string word; in >> word;) out.push_back(word);
  return out;
}

TEST(OptionTableTest, EveryParsedOptionIsDeclared) {
  const OptionTable table = declaredOptions();
  const std::vector<ParsedOption> parsed = parsedOptions();
  ASSERT_FALSE(parsed.empty());
  for (const ParsedOption& option : parsed) {
    const bool declared = std::any_of(table.specs().begin(), table.specs().end(), [&](const OptionSpec& spec) {
      return spec.command == option.command &&
             std::find(option.names.begin(), option.names.end(), spec.name) != option.names.end();
    });
    EXPECT_TRUE(declared) << "'" << option.command << " " << option.names.front()
                          << "' is parsed but not declared with OptionDeclarer (apps/cli_options.hpp): declare it "
                             "with its kind and range";
  }
}

TEST(OptionTableTest, TheTableHoldsTheProgramsOptions) {
  // Spot checks that the table is the program's: a numeric option of each long command.
  const OptionTable table = declaredOptions();
  const auto has = [&](const std::string& command, const std::string& name, OptionKind kind) {
    return std::any_of(table.specs().begin(), table.specs().end(), [&](const OptionSpec& s) {
      return s.command == command && s.name == name && s.kind == kind;
    });
  };
  EXPECT_TRUE(has("plant simulate", "--duration", OptionKind::kNumber));
  EXPECT_TRUE(has("plant simulate", "--amplitude", OptionKind::kNumber));
  EXPECT_TRUE(has("arm show", "--q", OptionKind::kNumberList));
  EXPECT_TRUE(has("tune", "--joints", OptionKind::kList));
  EXPECT_TRUE(has("validate", "--joints", OptionKind::kList));
  EXPECT_TRUE(has("validate", "--samples", OptionKind::kInteger));
  EXPECT_TRUE(has("", "--quiet", OptionKind::kFlag));
  for (const OptionSpec& spec : table.specs()) {
    if (spec.kind == OptionKind::kNumber || spec.kind == OptionKind::kInteger) {
      EXPECT_TRUE(std::isfinite(spec.min) && std::isfinite(spec.max) && spec.min < spec.max)
          << spec.command << " " << spec.name << ": a declared range needs finite bounds";
    }
  }
}

TEST(OptionTableTest, EveryOptionRefusesItsBadValues) {
  const OptionTable table = declaredOptions();
  int cases = 0;
  for (const OptionSpec& spec : table.specs()) {
    for (const BadValue& bad : badValues(spec)) {
      // "--name value" as a shell passes it; "--name=-inf" for a value that starts with a dash.
      std::vector<std::string> args = words(spec.command);
      if (!bad.value.empty() && bad.value.front() == '-') {
        args.push_back(spec.name + "=" + bad.value);
      } else {
        args.push_back(spec.name);
        args.push_back(bad.value);
      }
      std::ostringstream out;
      std::ostringstream err;
      const int code = runFullarm(args, out, err);
      const std::string shown = "fullarm " + spec.command + " " + spec.name + "='" + bad.value + "' (" + bad.why + ")";
      EXPECT_EQ(code, kExitBadInput) << shown << "\nstdout: " << out.str() << "\nstderr: " << err.str();
      EXPECT_NE(err.str().find(spec.name), std::string::npos)
          << shown << ": the message must name the option\nstderr: " << err.str();
      EXPECT_NE(err.str().find("expected"), std::string::npos)
          << shown << ": the message must say what was expected\nstderr: " << err.str();
      EXPECT_TRUE(out.str().empty()) << shown << ": nothing may run\nstdout: " << out.str();
      ++cases;
    }
  }
  EXPECT_GT(cases, 200);
}

TEST(OptionTableTest, ValuesAtTheBoundsAreAccepted) {
  // The range is inclusive: `--help` after a value at either bound shows help and exits 0, so
  // the value passed its check (and nothing runs).
  const OptionTable table = declaredOptions();
  for (const OptionSpec& spec : table.specs()) {
    if (spec.kind != OptionKind::kNumber && spec.kind != OptionKind::kInteger) continue;
    for (const double bound : {spec.min, spec.max}) {
      std::vector<std::string> args = words(spec.command);
      args.push_back(spec.name + "=" + (spec.kind == OptionKind::kInteger
                                            ? std::to_string(static_cast<long long>(bound))
                                            : shortest(bound)));
      args.push_back("--help");
      std::ostringstream out;
      std::ostringstream err;
      EXPECT_EQ(runFullarm(args, out, err), kExitPass) << spec.command << " " << spec.name << "=" << bound << "\n"
                                                       << err.str();
    }
  }
}

std::vector<OptionSpec> optionsOf(const OptionTable& table, const std::string& command) {
  std::vector<OptionSpec> out;
  for (const OptionSpec& spec : table.specs()) {
    if (spec.command == command) out.push_back(spec);
  }
  return out;
}

bool sameDeclaration(const OptionSpec& a, const OptionSpec& b) {
  return a.name == b.name && a.kind == b.kind && a.min == b.min && a.max == b.max && a.unit == b.unit;
}

// `fullarm local` is `fullarm run` with the global node's search: the run's options, declared by
// the same code, less --search; its modes are the run's less `both`.
TEST(OptionTableTest, TheLocalNodeHasTheRunsOptionsButTheSearch) {
  const OptionTable table = declaredOptions();
  const std::vector<OptionSpec> run = optionsOf(table, "run");
  const std::vector<OptionSpec> local = optionsOf(table, "local");
  ASSERT_FALSE(run.empty());
  std::size_t i = 0;
  for (const OptionSpec& spec : run) {
    if (spec.name == "--search") continue;
    ASSERT_LT(i, local.size()) << spec.name << " missing from local";
    EXPECT_TRUE(sameDeclaration(spec, local[i])) << spec.name << " vs " << local[i].name;
    if (spec.name == "--mode") {
      EXPECT_EQ(local[i].choices, (std::vector<std::string>{"full-arm", "hand-only"}));
    } else {
      EXPECT_EQ(spec.choices, local[i].choices) << spec.name;
    }
    ++i;
  }
  EXPECT_EQ(i, local.size()) << "local declares an option run does not";
}

// The loop's commands read the same input files through the same options.
TEST(OptionTableTest, TheLoopCommandsDeclareTheSameFileOptions) {
  const OptionTable table = declaredOptions();
  const std::vector<std::string> files = {"--scene", "--config",         "--plant-config",
                                          "--gains", "--haptics-config", "--hil-config"};
  for (const char* command : {"run", "local", "global", "plant serve"}) {
    const std::vector<OptionSpec> options = optionsOf(table, command);
    for (const std::string& name : files) {
      const auto it = std::find_if(options.begin(), options.end(), [&](const OptionSpec& s) { return s.name == name; });
      ASSERT_NE(it, options.end()) << command << " lacks " << name;
      EXPECT_EQ(it->kind, OptionKind::kFile) << command << " " << name;
    }
  }
}

}  // namespace
}  // namespace fullarm::app
