// The repository's own text speaks of the product and refers only to what the repository holds:
// every file of the source tree (code, comments, docs, configuration, scripts, CI) is scanned
// for references to files outside the repository and for words that tell how the product was
// made rather than what it does (history lives in git log). A hit names the file, the line and
// the rule. The README's hand build is checked against the quick start's install script.

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

const fs::path kRoot = FULLARM_SOURCE_DIR;

struct Rule {
  const char* name;
  std::regex pattern;
};

std::regex icase(const char* pattern) {
  return std::regex(pattern, std::regex::ECMAScript | std::regex::icase);
}

// References to files that are not in the repository.
const std::vector<Rule>& referenceRules() {
  static const std::vector<Rule> rules = {
      {"a folder beside the repository", std::regex(R"((\.\./|/work/)shared\b)")},
      {"the shared reference folders", std::regex(R"(\bshared/(paper|research|reference|meshes|tools)\b)")},
      {"a design file outside the repository (docs/architecture.md)",
       std::regex(R"(\bDESIGN\.md\b)")},
      {"research notes outside the repository (docs/sources.md)", std::regex(R"(\bresearch/[A-Za-z_]+\.md\b)")},
      {"the DTS reference outside the repository (docs/dts-reference.md)", std::regex(R"(sarcos-master-arm\.md)")},
  };
  return rules;
}

// Words that tell how the product was made.
const std::vector<Rule>& historyRules() {
  static const std::vector<Rule> rules = {
      {"an issue (say what the code does and why)", icase(R"(\bissues?\b|\bkIssue)")},
      {"a brief", icase(R"(\bbriefs?\b)")},
      {"a reviewer", icase(R"(\breviewer)")},
      {"a work session", icase(R"(\bthis session\b|\bsession's\b)")},
      {"a numbered pass of work", icase(R"(\b(first|second|third|fourth|fifth|sixth|seventh|eighth) pass\b)")},
      {"a branch", icase(R"(\bbranch `[a-z0-9-]+`|\bunmerged\b|\bmerged main\b)")},
      {"a branch name",
       std::regex(R"(\b(ctrl-jk|ctrl-ms|ctrl-sfe|ctrl-pass\d|snch-b|snch-c|snch-1ms|snch-trav|hapt-fast|hapt-tick|)"
                  R"(tick-edge|plant-w2?|plant-tol|plant-arm|plant-pi)\b)")},
      {"a figure tied to a day's machine (name the processor and core count)",
       icase(R"(machine at hand|\btoday\b|\bthat day\b|development machine|shared( 2-core)? machine|)"
             R"(the earlier,? (\S+ )?slower|what else was running|other helpers)")},
  };
  return rules;
}

bool skipped(const std::string& path) {
  static const std::array<const char*, 8> suffixes = {".dae", ".png", ".jpg", ".sdf", ".config",
                                                      "package-lock.json", "LICENSE", ".ico"};
  for (const char* suffix : suffixes) {
    if (path.ends_with(suffix)) return true;
  }
  // This file states the rules.
  return path == "tests/repository/product_text_test.cpp";
}

// The repository's files, relative to its root: `git ls-files` where the tree is a git checkout,
// else every file below the root except build and package folders.
std::vector<std::string> repositoryFiles() {
  std::vector<std::string> files;
  const std::string command = "git -C '" + kRoot.string() + "' ls-files 2>/dev/null";
  if (FILE* pipe = popen(command.c_str(), "r")) {
    std::array<char, 4096> line{};
    while (fgets(line.data(), static_cast<int>(line.size()), pipe) != nullptr) {
      std::string name(line.data());
      while (!name.empty() && (name.back() == '\n' || name.back() == '\r')) name.pop_back();
      if (!name.empty()) files.push_back(name);
    }
    pclose(pipe);
  }
  if (!files.empty()) return files;
  for (auto it = fs::recursive_directory_iterator(kRoot); it != fs::recursive_directory_iterator(); ++it) {
    const std::string name = fs::relative(it->path(), kRoot).generic_string();
    if (it->is_directory() && (name.starts_with("build") || name == "node_modules" || name == ".git" ||
                               name == "out")) {
      it.disable_recursion_pending();
      continue;
    }
    if (it->is_regular_file()) files.push_back(name);
  }
  return files;
}

std::vector<std::string> hits(const std::vector<Rule>& rules, bool check_doc_links) {
  std::vector<std::string> found;
  const std::regex doc_link(R"(\bdocs/([A-Za-z0-9_-]+)\.md\b)");
  for (const std::string& file : repositoryFiles()) {
    if (skipped(file) || !fs::is_regular_file(kRoot / file)) continue;
    std::ifstream in(kRoot / file);
    std::string line;
    for (int number = 1; std::getline(in, line); ++number) {
      for (const Rule& rule : rules) {
        if (std::regex_search(line, rule.pattern)) {
          found.push_back(file + ":" + std::to_string(number) + ": " + rule.name + ": " + line.substr(0, 160));
        }
      }
      if (!check_doc_links) continue;
      for (auto it = std::sregex_iterator(line.begin(), line.end(), doc_link); it != std::sregex_iterator(); ++it) {
        const fs::path target = kRoot / "docs" / ((*it)[1].str() + ".md");
        if (!fs::is_regular_file(target)) {
          found.push_back(file + ":" + std::to_string(number) + ": a document the repository lacks: " +
                          it->str());
        }
      }
    }
  }
  return found;
}

std::string listed(const std::vector<std::string>& lines) {
  std::ostringstream out;
  for (const std::string& line : lines) out << "  " << line << "\n";
  return out.str();
}

TEST(ProductText, TheRepositoryHoldsEveryFileItRefersTo) {
  ASSERT_TRUE(fs::is_regular_file(kRoot / "README.md")) << kRoot;
  const std::vector<std::string> found = hits(referenceRules(), true);
  EXPECT_TRUE(found.empty()) << found.size() << " reference(s) outside the repository:\n" << listed(found);
}

TEST(ProductText, NoWordTellsHowTheProductWasMade) {
  const std::vector<std::string> found = hits(historyRules(), false);
  EXPECT_TRUE(found.empty()) << found.size() << " line(s) of history in the product's text:\n" << listed(found);
}

std::string fileText(const fs::path& file) {
  std::ifstream in(file);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::set<std::string> words(const std::string& text) {
  std::set<std::string> out;
  std::istringstream in(text);
  for (std::string word; in >> word;) out.insert(word);
  return out;
}

// The hand build of the README installs what scripts/setup-deps installs (the Debian packages of
// its list, Node.js and npm), then the npm packages, before it configures.
TEST(ProductText, TheReadmeHandBuildInstallsWhatSetupDepsInstalls) {
  const std::string setup = fileText(kRoot / "scripts/setup-deps");
  const std::size_t list_start = setup.find("packages=(");
  const std::size_t list_end = setup.find("\n)", list_start);
  ASSERT_NE(list_start, std::string::npos);
  ASSERT_NE(list_end, std::string::npos);
  std::set<std::string> needed = {"nodejs", "npm"};
  std::istringstream list(setup.substr(list_start + 10, list_end - list_start - 10));
  for (std::string line; std::getline(list, line);) {
    line = line.substr(0, line.find('#'));
    for (const std::string& word : words(line)) needed.insert(word);
  }
  ASSERT_GT(needed.size(), 10U);

  const std::string readme = fileText(kRoot / "README.md");
  const std::size_t section = readme.find("## Building by hand");
  ASSERT_NE(section, std::string::npos);
  const std::size_t install = readme.find("apt-get install", section);
  const std::size_t npm = readme.find("npm ci", section);
  const std::size_t configure = readme.find("cmake --preset release", section);
  ASSERT_NE(install, std::string::npos) << "the hand build installs no Debian package";
  ASSERT_NE(npm, std::string::npos) << "the hand build lacks npm ci, which configure needs";
  ASSERT_NE(configure, std::string::npos);
  EXPECT_LT(install, npm);
  EXPECT_LT(npm, configure) << "npm ci must come before configure";
  // The install command: its continuation lines up to the first line not ending in a backslash.
  std::string command;
  std::istringstream lines(readme.substr(install + 15));
  for (std::string line; std::getline(lines, line);) {
    const bool continued = !line.empty() && line.back() == '\\';
    // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on `" " + std::string` at -O3.
    command += ' ';
    command += continued ? line.substr(0, line.size() - 1) : line;
    if (!continued) break;
  }
  const std::set<std::string> listed = words(command);
  for (const std::string& package : needed) {
    EXPECT_TRUE(listed.count(package) == 1) << "README's hand build does not install " << package;
  }
  for (const std::string& package : listed) {
    EXPECT_TRUE(needed.count(package) == 1) << "README's hand build installs " << package
                                            << ", which scripts/setup-deps does not";
  }
}

// The rules must be able to fail: each catches the kind of line it exists for, and passes a
// line that only looks alike.
TEST(ProductText, TheRulesCatchWhatTheyAreFor) {
  const auto caught = [](const std::vector<Rule>& rules, const std::string& line) {
    for (const Rule& rule : rules) {
      if (std::regex_search(line, rule.pattern)) return true;
    }
    return false;
  };
  for (const char* line : {"see `../shared/DESIGN.md`", "`shared/reference/x.md`", "research/plant.md 1.2",
                           "restated in sarcos-master-arm.md"}) {
    EXPECT_TRUE(caught(referenceRules(), line)) << line;
  }
  for (const char* line : {"(issue 5)", "The issue's linear hard goals", "issue 4's brief", "a reviewer's note",
                           "branch `snch-b`", "ctrl-jk", "on this session's idle machine", "Issue 3, fifth pass",
                           "the machine at hand", "kIssueFrequency", "merged main"}) {
    EXPECT_TRUE(caught(historyRules(), line)) << line;
  }
  for (const char* line : {"shared_ptr<const TriMesh>", "the shared job pool", "a 2-core AMD EPYC",
                           "tissue stiffness", "snch-based search", "passes the check"}) {
    EXPECT_FALSE(caught(historyRules(), line) || caught(referenceRules(), line)) << line;
  }
}

}  // namespace
