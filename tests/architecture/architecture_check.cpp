#include "architecture_check.hpp"

#include <algorithm>
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>
#include <stdexcept>

namespace fullarm::architecture {
namespace {

namespace fs = std::filesystem;

std::string readText(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot be read");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> splitCells(const std::string& row) {
  std::vector<std::string> cells;
  std::string cell;
  for (std::size_t i = 1; i < row.size(); ++i) {
    if (row[i] == '|') {
      cells.push_back(cell);
      cell.clear();
    } else {
      cell += row[i];
    }
  }
  return cells;
}

std::set<std::string> moduleNamesIn(const std::string& text) {
  std::set<std::string> names;
  static const std::regex kModule(R"(`([a-z_]+)`)");
  for (std::sregex_iterator it(text.begin(), text.end(), kModule), end; it != end; ++it) names.insert((*it)[1]);
  return names;
}

bool isSource(const fs::path& p) {
  const std::string ext = p.extension().string();
  return ext == ".hpp" || ext == ".cpp" || ext == ".h";
}

// The unit of a file: its stem, so foo.hpp and foo.cpp are one unit.
std::string unitOf(const fs::path& p) {
  return p.stem().string();
}

struct Include {
  std::string target;  // the quoted include path
  int line = 0;
};

std::vector<Include> quotedIncludes(const fs::path& file) {
  std::vector<Include> out;
  std::ifstream in(file);
  std::string line;
  int number = 0;
  static const std::regex kInclude(R"(^\s*#\s*include\s*"([^"]+)\")");
  while (std::getline(in, line)) {
    ++number;
    std::smatch m;
    if (std::regex_search(line, m, kInclude)) out.push_back({m[1], number});
  }
  return out;
}

// Modules reachable from `name` through documented dependencies (itself included).
std::set<std::string> reachable(const std::string& name,
                                const std::map<std::string, const DocumentedModule*>& by_name) {
  std::set<std::string> seen;
  std::vector<std::string> pending{name};
  while (!pending.empty()) {
    const std::string m = pending.back();
    pending.pop_back();
    if (!seen.insert(m).second) continue;
    const auto it = by_name.find(m);
    if (it == by_name.end()) continue;
    for (const std::string& d : it->second->depends_on) pending.push_back(d);
  }
  return seen;
}

}  // namespace

std::vector<DocumentedModule> readModuleTable(const fs::path& architecture_md) {
  std::istringstream in(readText(architecture_md));
  std::string line;
  int floor_col = -1;
  int target_col = -1;
  int deps_col = -1;
  std::vector<DocumentedModule> modules;
  bool header_seen = false;
  while (std::getline(in, line)) {
    if (line.rfind("|", 0) != 0) {
      if (!modules.empty()) break;  // the first table only
      floor_col = target_col = deps_col = -1;
      header_seen = false;
      continue;
    }
    const std::vector<std::string> cells = splitCells(line);
    if (!header_seen) {
      header_seen = true;
      for (std::size_t i = 0; i < cells.size(); ++i) {
        std::string c = cells[i];
        c.erase(std::remove(c.begin(), c.end(), ' '), c.end());
        if (c == "floor") floor_col = static_cast<int>(i);
        if (c == "target") target_col = static_cast<int>(i);
        if (c == "dependson") deps_col = static_cast<int>(i);
      }
      continue;
    }
    if (line.find("---") != std::string::npos) continue;
    if (target_col < 0 || deps_col < 0) continue;  // another kind of table
    if (static_cast<int>(cells.size()) <= std::max({floor_col, target_col, deps_col})) {
      throw std::runtime_error(architecture_md.string() +
                               ": the module table needs the columns module, target, depends on");
    }
    static const std::regex kTarget(R"(`fullarm::([a-z_]+)`|`fullarm` executable)");
    std::smatch m;
    const std::string& target = cells[static_cast<std::size_t>(target_col)];
    if (!std::regex_search(target, m, kTarget)) continue;  // tests/, bench/, config/ rows
    DocumentedModule mod;
    mod.name = m[1].matched ? std::string(m[1]) : std::string("apps");
    mod.floor = static_cast<int>(modules.size());
    if (floor_col >= 0) {
      try {
        mod.floor = std::stoi(cells[static_cast<std::size_t>(floor_col)]);
      } catch (const std::exception&) {
        throw std::runtime_error(architecture_md.string() + ": module " + mod.name +
                                 ": the floor column is not a number");
      }
    }
    std::set<std::string> deps = moduleNamesIn(cells[static_cast<std::size_t>(deps_col)]);
    for (const std::string& d : deps) mod.depends_on.insert(d);
    modules.push_back(std::move(mod));
  }
  if (modules.empty()) throw std::runtime_error(architecture_md.string() + ": no module table found");
  return modules;
}

std::set<std::string> cmakeModuleDeps(const fs::path& cmakelists) {
  const std::string text = readText(cmakelists);
  static const std::regex kModuleCall(R"((fullarm_add_module|add_executable)\s*\()");
  if (!std::regex_search(text, kModuleCall)) {
    throw std::runtime_error(cmakelists.string() + ": defines no fullarm module (fullarm_add_module) or program");
  }
  std::set<std::string> deps;
  static const std::regex kDep(R"(fullarm::([a-z_]+))");
  for (std::sregex_iterator it(text.begin(), text.end(), kDep), end; it != end; ++it) deps.insert((*it)[1]);
  return deps;
}

std::vector<std::string> checkTree(const fs::path& root, const std::vector<DocumentedModule>& modules) {
  std::vector<std::string> problems;
  std::map<std::string, const DocumentedModule*> by_name;
  std::map<std::string, int> floor;
  for (std::size_t i = 0; i < modules.size(); ++i) {
    by_name[modules[i].name] = &modules[i];
    floor[modules[i].name] = modules[i].floor;
  }

  // The documented order: every dependency sits on a lower floor and is itself documented.
  for (const DocumentedModule& m : modules) {
    for (const std::string& d : m.depends_on) {
      if (!floor.contains(d)) {
        problems.push_back("module " + m.name + " depends on " + d + ", which the table does not list");
      } else if (floor[d] >= floor[m.name]) {
        problems.push_back("module " + m.name + " (floor " + std::to_string(m.floor) + ") depends on " + d +
                           " (floor " + std::to_string(floor[d]) + "), which is not on a lower floor");
      }
    }
    if (!fs::is_directory(root / m.name)) problems.push_back("module " + m.name + " is documented but has no folder");
  }

  // The CMake targets against the table, both ways.
  for (const auto& entry : fs::directory_iterator(root)) {
    const fs::path cm = entry.path() / "CMakeLists.txt";
    if (!entry.is_directory() || !fs::exists(cm)) continue;
    const std::string name = entry.path().filename().string();
    if (name == "tests" || name == "bench" || name == "build") continue;
    const std::string text = readText(cm);
    if (text.find("fullarm_add_module(" + name) == std::string::npos && name != "apps") continue;
    if (!by_name.contains(name)) {
      problems.push_back("module " + name + " has a CMake target but is not in the module table");
      continue;
    }
    std::set<std::string> deps = cmakeModuleDeps(cm);
    deps.erase(name);
    const std::set<std::string>& documented = by_name[name]->depends_on;
    for (const std::string& d : deps) {
      if (!documented.contains(d))
        problems.push_back("module " + name + " links fullarm::" + d + " but the table does not list that dependency");
    }
    for (const std::string& d : documented) {
      if (!deps.contains(d))
        problems.push_back("module " + name + " is documented to depend on " + d +
                           " but its CMake target does not link it");
    }
  }

  // Includes: only the module itself and what it may reach; never another module's src/.
  for (const DocumentedModule& m : modules) {
    const fs::path dir = root / m.name;
    if (!fs::is_directory(dir)) continue;
    const std::set<std::string> allowed = reachable(m.name, by_name);
    std::map<std::string, std::set<std::string>> unit_edges;  // unit -> units of this module it includes
    std::map<std::string, std::string> unit_file;
    for (const auto& entry : fs::recursive_directory_iterator(dir)) {
      if (!entry.is_regular_file() || !isSource(entry.path())) continue;
      const fs::path rel = fs::relative(entry.path(), root);
      const std::string unit = unitOf(entry.path());
      unit_edges[unit];
      unit_file[unit] = rel.string();
      for (const Include& inc : quotedIncludes(entry.path())) {
        const std::string where = rel.string() + ":" + std::to_string(inc.line);
        if (inc.target.find("src/") != std::string::npos || inc.target.find("../") != std::string::npos) {
          problems.push_back(where + " includes \"" + inc.target + "\": a module's src/ is private to it");
          continue;
        }
        static const std::regex kFullarm(R"(^fullarm/([a-z_]+)/(.+)$)");
        std::smatch im;
        if (!std::regex_match(inc.target, im, kFullarm)) {
          // A private header of the same folder (src/foo.hpp): part of this module.
          unit_edges[unit].insert(fs::path(inc.target).stem().string());
          continue;
        }
        const std::string other = im[1];
        if (other == m.name) {
          unit_edges[unit].insert(fs::path(std::string(im[2])).stem().string());
        } else if (!allowed.contains(other)) {
          problems.push_back(where + " includes \"" + inc.target + "\": module " + m.name + " may not use module " +
                             other + " (not among its documented dependencies)");
        }
      }
    }
    // Cycles between units (a unit does not count as including itself).
    std::map<std::string, int> state;  // 0 new, 1 on the stack, 2 done
    std::vector<std::string> stack;
    std::function<void(const std::string&)> visit = [&](const std::string& u) {
      state[u] = 1;
      stack.push_back(u);
      for (const std::string& v : unit_edges[u]) {
        if (v == u || !unit_edges.contains(v)) continue;
        if (state[v] == 1) {
          std::string cycle;
          for (auto it = std::find(stack.begin(), stack.end(), v); it != stack.end(); ++it) cycle += *it + " -> ";
          problems.push_back("module " + m.name + " has an include cycle: " + cycle + v);
        } else if (state[v] == 0) {
          visit(v);
        }
      }
      stack.pop_back();
      state[u] = 2;
    };
    for (const auto& [u, edges] : unit_edges) {
      if (state[u] == 0) visit(u);
    }
  }
  return problems;
}

}  // namespace fullarm::architecture
