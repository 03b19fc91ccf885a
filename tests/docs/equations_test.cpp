// reports/equations.md and the code agree both ways: every function a row names exists and
// carries the row's tag. The checker itself is tested on a small tree.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "equations_check.hpp"
#include "scratch_dir.hpp"

namespace fullarm::docs {
namespace {

namespace fs = std::filesystem;

fs::path sourceDir() {
  const char* root = std::getenv("FULLARM_SOURCE_DIR");
  return root != nullptr ? fs::path(root) : fs::current_path();
}

std::vector<fs::path> codeDirs(const fs::path& root) {
  std::vector<fs::path> dirs;
  for (const char* d : {"core", "arm", "plant", "haptics", "controllers", "design", "identification", "hil",
                        "accessibility", "mpi", "reports", "apps", "bench", "tests"}) {
    dirs.push_back(root / d);
  }
  return dirs;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string s;
  for (const std::string& l : lines) s += "  " + l + "\n";
  return s;
}

TEST(Equations, EveryRowNamesFunctionsThatCarryItsTag) {
  const fs::path root = sourceDir();
  const std::vector<EquationEntry> entries = readEquationEntries(root / "reports" / "equations.md");
  ASSERT_GE(entries.size(), 60u);
  // The paper's equations are all there.
  for (const char* tag : {"Eq. (1)", "Eq. (2)", "Eq. (3)", "Eq. (4)", "Eq. (5)", "Eq. (6)", "Eq. (7)", "Eq. (8)"}) {
    EXPECT_TRUE(std::any_of(entries.begin(), entries.end(), [&](const EquationEntry& e) { return e.tag == tag; }))
        << tag;
  }
  const std::vector<std::string> problems = checkEquations(root / "reports" / "equations.md", codeDirs(root));
  EXPECT_TRUE(problems.empty()) << "reports/equations.md and the code disagree:\n" << joined(problems);
}

class EquationsTree : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = test::scratchDir("equations") / ::testing::UnitTest::GetInstance()->current_test_info()->name();
    fs::remove_all(root_);
    write("eq.md",
          "# Equations\n\n| tag | equation | code | source |\n|---|---|---|---|\n"
          "| `X1` | a = b | `alpha` (`m/src/a.cpp`), `Widget::beta` | here |\n"
          "| `X2` | c = d \\| e | `gamma`, `ControllerKind::kThing` | here |\n");
    write("m/src/a.cpp",
          "// X1: a = b\n"
          "double alpha(double b) {\n  return b;\n}\n\n"
          "double Widget::beta(double x) const {\n  // X1 for the member too\n  return alpha(x);\n}\n\n"
          "int gamma(int d) {\n  const int e = alpha(d);  // X2 here\n  return e;\n}\n");
  }
  void write(const std::string& rel, const std::string& text) {
    fs::create_directories((root_ / rel).parent_path());
    std::ofstream(root_ / rel) << text;
  }
  std::vector<std::string> check() { return checkEquations(root_ / "eq.md", {root_ / "m"}); }
  fs::path root_;
};

TEST_F(EquationsTree, AConsistentTreePasses) {
  const std::vector<EquationEntry> entries = readEquationEntries(root_ / "eq.md");
  ASSERT_EQ(entries.size(), 2u);
  EXPECT_EQ(entries[0].tag, "X1");
  EXPECT_EQ(entries[0].functions, (std::vector<std::string>{"alpha", "Widget::beta"}));
  EXPECT_EQ(entries[1].functions, (std::vector<std::string>{"gamma"}));  // kThing is a constant
  const std::vector<std::string> problems = check();
  EXPECT_TRUE(problems.empty()) << joined(problems);
}

TEST_F(EquationsTree, AMissingFunctionIsReported) {
  write("eq.md", "| tag | equation | code | source |\n|---|---|---|---|\n| `X1` | a = b | `delta` | here |\n");
  const std::vector<std::string> problems = check();
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("function delta is not defined"), std::string::npos) << problems[0];
}

TEST_F(EquationsTree, AFunctionWithoutItsTagIsReported) {
  write("m/src/a.cpp", "double alpha(double b) {\n  return b;  // X2\n}\n");
  write("eq.md", "| tag | equation | code | source |\n|---|---|---|---|\n| `X1` | a = b | `alpha` | here |\n");
  const std::vector<std::string> problems = check();
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("does not carry the tag 'X1'"), std::string::npos) << problems[0];
}

TEST_F(EquationsTree, ACallIsNotADefinition) {
  // gamma calls alpha inside its body; only the real definition of alpha counts.
  const std::vector<FunctionDefinition> defs = findDefinitions({root_ / "m"}, "alpha");
  ASSERT_EQ(defs.size(), 1u);
  EXPECT_EQ(defs[0].line, 2);
  EXPECT_NE(defs[0].text.find("X1: a = b"), std::string::npos);
}

TEST_F(EquationsTree, ARowWithoutAFunctionIsAnError) {
  write("eq.md", "| tag | equation | code | source |\n|---|---|---|---|\n| `X1` | a = b | only prose | here |\n");
  EXPECT_THROW((void)readEquationEntries(root_ / "eq.md"), std::runtime_error);
}

}  // namespace
}  // namespace fullarm::docs
