// The repository follows docs/architecture.md: the module table matches the CMake targets, no
// module includes another module's src/ or a module it may not use, and no module has an
// include cycle between its units. The checker itself is tested on small trees that break each
// rule.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "architecture_check.hpp"
#include "scratch_dir.hpp"

namespace fullarm::architecture {
namespace {

namespace fs = std::filesystem;

fs::path sourceDir() {
  const char* root = std::getenv("FULLARM_SOURCE_DIR");
  return root != nullptr ? fs::path(root) : fs::current_path();
}

std::string joined(const std::vector<std::string>& lines) {
  std::string s;
  for (const std::string& l : lines) s += "  " + l + "\n";
  return s;
}

bool mentions(const std::vector<std::string>& problems, const std::string& text) {
  return std::any_of(problems.begin(), problems.end(),
                     [&](const std::string& p) { return p.find(text) != std::string::npos; });
}

TEST(Architecture, TheRepositoryFollowsItsDocumentedLayering) {
  const fs::path root = sourceDir();
  const std::vector<DocumentedModule> modules = readModuleTable(root / "docs" / "architecture.md");
  ASSERT_GE(modules.size(), 8u);
  EXPECT_EQ(modules.front().name, "core");
  EXPECT_EQ(modules.back().name, "apps");
  const std::vector<std::string> problems = checkTree(root, modules);
  EXPECT_TRUE(problems.empty()) << "docs/architecture.md and the tree disagree:\n" << joined(problems);
}

TEST(Architecture, TheControllersModuleDependsOnArmAndCoreOnly) {
  const fs::path root = sourceDir();
  for (const DocumentedModule& m : readModuleTable(root / "docs" / "architecture.md")) {
    if (m.name == "controllers") {
      EXPECT_EQ(m.depends_on, (std::set<std::string>{"arm", "core"}));
      EXPECT_EQ(cmakeModuleDeps(root / "controllers" / "CMakeLists.txt"), (std::set<std::string>{"arm", "core"}));
      return;
    }
  }
  FAIL() << "controllers is not in the module table";
}

// A small tree: core <- lower <- upper, written per test and then broken in one way.
class SyntheticTree : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = test::scratchDir("architecture") / ::testing::UnitTest::GetInstance()->current_test_info()->name();
    fs::remove_all(root_);
    write("docs/architecture.md",
          "# Architecture\n\n| floor | module | target | job | depends on |\n|---|---|---|---|---|\n"
          "| 0 | `core` | `fullarm::core` | floor | — |\n"
          "| 1 | `lower` | `fullarm::lower` | lower | `core` |\n"
          "| 2 | `upper` | `fullarm::upper` | upper | `lower` |\n"
          "| 3 | `apps` | the `fullarm` executable | program | `upper` |\n");
    write("core/CMakeLists.txt", "fullarm_add_module(core SOURCES src/a.cpp)\n");
    write("core/include/fullarm/core/a.hpp", "#pragma once\n");
    write("core/src/a.cpp", "#include \"fullarm/core/a.hpp\"\n");
    write("lower/CMakeLists.txt", "fullarm_add_module(lower SOURCES src/b.cpp PUBLIC_DEPS fullarm::core)\n");
    write("lower/include/fullarm/lower/b.hpp", "#pragma once\n#include \"fullarm/core/a.hpp\"\n");
    write("lower/src/b.cpp", "#include \"fullarm/lower/b.hpp\"\n#include \"helper.hpp\"\n");
    write("lower/src/helper.hpp", "#pragma once\n");
    write("upper/CMakeLists.txt", "fullarm_add_module(upper SOURCES src/c.cpp PUBLIC_DEPS fullarm::lower)\n");
    write("upper/include/fullarm/upper/c.hpp", "#pragma once\n#include \"fullarm/lower/b.hpp\"\n");
    write("upper/include/fullarm/upper/d.hpp", "#pragma once\n#include \"fullarm/upper/c.hpp\"\n");
    write("upper/src/c.cpp", "#include \"fullarm/upper/c.hpp\"\n#include \"fullarm/core/a.hpp\"\n");
    write("apps/CMakeLists.txt",
          "add_executable(fullarm main.cpp)\ntarget_link_libraries(fullarm PRIVATE fullarm::upper)\n");
    write("apps/main.cpp", "#include \"fullarm/upper/d.hpp\"\n");
  }
  void write(const std::string& rel, const std::string& text) {
    fs::create_directories((root_ / rel).parent_path());
    std::ofstream(root_ / rel) << text;
  }
  std::vector<std::string> check() { return checkTree(root_, readModuleTable(root_ / "docs" / "architecture.md")); }
  fs::path root_;
};

TEST_F(SyntheticTree, AConformingTreePasses) {
  const std::vector<std::string> problems = check();
  EXPECT_TRUE(problems.empty()) << joined(problems);
}

TEST_F(SyntheticTree, IncludingAnotherModulesSrcIsReported) {
  write("upper/src/c.cpp", "#include \"fullarm/upper/c.hpp\"\n#include \"../../lower/src/helper.hpp\"\n");
  EXPECT_TRUE(mentions(check(), "upper/src/c.cpp:2 includes \"../../lower/src/helper.hpp\""));
}

TEST_F(SyntheticTree, IncludingAModuleAboveIsReported) {
  write("lower/src/b.cpp", "#include \"fullarm/lower/b.hpp\"\n#include \"fullarm/upper/c.hpp\"\n");
  EXPECT_TRUE(mentions(check(), "module lower may not use module upper"));
}

TEST_F(SyntheticTree, ADocumentedDependencyOnAHigherFloorIsReported) {
  write("docs/architecture.md",
        "| floor | module | target | job | depends on |\n|---|---|---|---|---|\n"
        "| 0 | `core` | `fullarm::core` | floor | — |\n"
        "| 1 | `lower` | `fullarm::lower` | lower | `core`, `upper` |\n"
        "| 2 | `upper` | `fullarm::upper` | upper | `lower` |\n"
        "| 3 | `apps` | the `fullarm` executable | program | `upper` |\n");
  EXPECT_TRUE(mentions(check(), "module lower (floor 1) depends on upper (floor 2), which is not on a lower floor"));
}

TEST_F(SyntheticTree, ACMakeLinkTheTableDoesNotListIsReported) {
  write("lower/CMakeLists.txt",
        "fullarm_add_module(lower SOURCES src/b.cpp PUBLIC_DEPS fullarm::core fullarm::upper)\n");
  EXPECT_TRUE(mentions(check(), "module lower links fullarm::upper but the table does not list that dependency"));
}

TEST_F(SyntheticTree, ADocumentedDependencyTheTargetDoesNotLinkIsReported) {
  write("upper/CMakeLists.txt", "fullarm_add_module(upper SOURCES src/c.cpp)\n");
  EXPECT_TRUE(mentions(check(), "module upper is documented to depend on lower but its CMake target does not link it"));
}

TEST_F(SyntheticTree, AnUndocumentedModuleIsReported) {
  write("extra/CMakeLists.txt", "fullarm_add_module(extra SOURCES src/e.cpp)\n");
  EXPECT_TRUE(mentions(check(), "module extra has a CMake target but is not in the module table"));
}

TEST_F(SyntheticTree, AnIncludeCycleBetweenUnitsIsReported) {
  // c.hpp -> d.hpp through c.cpp, and d.hpp -> c.hpp: units c and d include each other.
  write("upper/src/c.cpp", "#include \"fullarm/upper/c.hpp\"\n#include \"fullarm/upper/d.hpp\"\n");
  const std::vector<std::string> problems = check();
  EXPECT_TRUE(mentions(problems, "module upper has an include cycle")) << joined(problems);
}

TEST_F(SyntheticTree, AMissingTableIsAClearError) {
  write("docs/architecture.md", "# Architecture\n\nno table here\n");
  try {
    (void)readModuleTable(root_ / "docs" / "architecture.md");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("architecture.md: no module table found"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace fullarm::architecture
