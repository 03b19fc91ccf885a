#include "equations_check.hpp"

#include <cctype>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <stdexcept>

namespace fullarm::docs {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> splitCells(const std::string& row) {
  std::vector<std::string> cells;
  std::string cell;
  for (std::size_t i = 1; i < row.size(); ++i) {
    if (row[i] == '|' && row[i - 1] != '\\') {
      cells.push_back(cell);
      cell.clear();
    } else {
      cell += row[i];
    }
  }
  return cells;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  const auto e = s.find_last_not_of(" \t");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

std::string unquote(const std::string& s) {
  std::string t = trim(s);
  if (t.size() >= 2 && t.front() == '`' && t.back() == '`') t = t.substr(1, t.size() - 2);
  return t;
}

std::vector<std::string> readLines(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot be read");
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

// The source files once per process: the check looks up many names in the same tree.
const std::map<fs::path, std::vector<std::string>>& sources(const std::vector<fs::path>& dirs) {
  static std::map<std::string, std::map<fs::path, std::vector<std::string>>> cache;
  std::string key;
  for (const fs::path& d : dirs) key += d.string() + "\n";
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  std::map<fs::path, std::vector<std::string>>& files = cache[key];
  for (const fs::path& dir : dirs) {
    if (!fs::is_directory(dir)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(dir)) {
      const std::string ext = entry.path().extension().string();
      if (entry.is_regular_file() && (ext == ".cpp" || ext == ".hpp")) files[entry.path()] = readLines(entry.path());
    }
  }
  return files;
}

bool isCommentLine(const std::string& line) {
  const std::string t = trim(line);
  return t.rfind("//", 0) == 0 || t.rfind("*", 0) == 0 || t.rfind("/*", 0) == 0;
}

}  // namespace

std::vector<EquationEntry> readEquationEntries(const fs::path& equations_md) {
  const std::vector<std::string> lines = readLines(equations_md);
  std::vector<EquationEntry> entries;
  int tag_col = -1;
  int code_col = -1;
  bool in_table = false;
  static const std::regex kFunction(R"(`((?:[A-Z][A-Za-z0-9]*::)?[a-z][A-Za-z0-9]*)`)");
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string& line = lines[i];
    const int number = static_cast<int>(i) + 1;
    if (line.rfind("|", 0) != 0) {
      in_table = false;
      tag_col = code_col = -1;
      continue;
    }
    const std::vector<std::string> cells = splitCells(line);
    if (!in_table) {
      in_table = true;
      for (std::size_t c = 0; c < cells.size(); ++c) {
        const std::string h = trim(cells[c]);
        if (h == "tag") tag_col = static_cast<int>(c);
        if (h == "code") code_col = static_cast<int>(c);
      }
      continue;
    }
    if (tag_col < 0 || code_col < 0 || line.find("---") != std::string::npos) continue;
    if (static_cast<int>(cells.size()) <= std::max(tag_col, code_col)) {
      throw std::runtime_error(equations_md.string() + ":" + std::to_string(number) + ": row has too few cells");
    }
    EquationEntry e;
    e.line = number;
    e.tag = unquote(cells[static_cast<std::size_t>(tag_col)]);
    if (e.tag.empty())
      throw std::runtime_error(equations_md.string() + ":" + std::to_string(number) + ": row has no tag");
    const std::string& code = cells[static_cast<std::size_t>(code_col)];
    for (std::sregex_iterator it(code.begin(), code.end(), kFunction), end; it != end; ++it) {
      const std::string name = (*it)[1];
      const std::string last = name.substr(name.rfind(':') == std::string::npos ? 0 : name.rfind(':') + 1);
      // kName is a constant (an enumerator), not a function.
      if (last.size() > 1 && last[0] == 'k' && std::isupper(static_cast<unsigned char>(last[1])) != 0) continue;
      e.functions.push_back(name);
    }
    if (e.functions.empty()) {
      throw std::runtime_error(equations_md.string() + ":" + std::to_string(number) + ": row " + e.tag +
                               " names no function in its code column");
    }
    entries.push_back(std::move(e));
  }
  return entries;
}

std::vector<FunctionDefinition> findDefinitions(const std::vector<fs::path>& dirs, const std::string& name) {
  std::vector<FunctionDefinition> found;
  // The name, not preceded by an identifier character, '.', or '->' (a call on an object), and
  // followed by a parameter list.
  const std::string escaped = std::regex_replace(name, std::regex(R"(::)"), "::");
  const std::regex head("(^|[^A-Za-z0-9_.>:])" + escaped + R"(\s*\()");
  for (const auto& [file, lines] : sources(dirs)) {
    for (std::size_t i = 0; i < lines.size(); ++i) {
      const std::string& line = lines[i];
      // The plain search first: the regular expression runs only on the few lines that hold
      // the name, not on every line of the tree for every name.
      if (line.find(name) == std::string::npos || isCommentLine(line) || !std::regex_search(line, head)) continue;
      // A definition starts at column 0 (free functions and out-of-class members) or inside a
      // class (inline members); a call is indented inside another body and followed by ';'.
      // Read on to the first ';' or '{' outside parentheses.
      int depth = 0;
      bool body = false;
      std::size_t end_line = i;
      std::size_t end_col = 0;
      bool decided = false;
      const std::size_t start = line.find(name.substr(name.rfind(':') == std::string::npos ? 0 : name.rfind(':') + 1));
      for (std::size_t j = i; j < lines.size() && j < i + 40 && !decided; ++j) {
        const std::string& l = lines[j];
        for (std::size_t c = (j == i ? start : 0); c < l.size(); ++c) {
          const char ch = l[c];
          if (ch == '(') ++depth;
          if (ch == ')') --depth;
          if (depth < 0) {  // the name was an argument of a call
            decided = true;
            break;
          }
          if (depth == 0 && (ch == ';' || ch == '{')) {
            body = ch == '{';
            end_line = j;
            end_col = c;
            decided = true;
            break;
          }
        }
      }
      if (!body) continue;
      // A call inside a condition, a lambda or an initialiser can be followed by a brace too:
      // a definition's name is preceded by its return type only (no parenthesis, assignment,
      // return or stream operator).
      const std::string before = line.substr(0, start);
      if (before.find_first_of("(=") != std::string::npos || before.find("return") != std::string::npos ||
          before.find("<<") != std::string::npos) {
        continue;
      }
      FunctionDefinition def;
      def.file = file;
      def.line = static_cast<int>(i) + 1;
      // Leading comment block.
      std::size_t k = i;
      while (k > 0 && isCommentLine(lines[k - 1])) --k;
      for (std::size_t j = k; j < i; ++j) def.text += lines[j] + "\n";
      // Body, brace-matched from the opening brace.
      int braces = 0;
      for (std::size_t j = end_line; j < lines.size(); ++j) {
        const std::string& l = lines[j];
        bool closed = false;
        for (std::size_t c = (j == end_line ? end_col : 0); c < l.size(); ++c) {
          if (l[c] == '{') ++braces;
          if (l[c] == '}' && --braces == 0) {
            closed = true;
            break;
          }
        }
        def.text += l + "\n";
        if (closed) break;
      }
      for (std::size_t j = i; j < end_line; ++j) def.text += lines[j] + "\n";
      found.push_back(std::move(def));
    }
  }
  return found;
}

std::vector<std::string> checkEquations(const fs::path& equations_md, const std::vector<fs::path>& dirs) {
  std::vector<std::string> problems;
  for (const EquationEntry& e : readEquationEntries(equations_md)) {
    for (const std::string& f : e.functions) {
      const std::vector<FunctionDefinition> defs = findDefinitions(dirs, f);
      const std::string where = equations_md.filename().string() + ":" + std::to_string(e.line) + " " + e.tag;
      if (defs.empty()) {
        problems.push_back(where + ": function " + f + " is not defined in the source tree");
        continue;
      }
      bool tagged = false;
      for (const FunctionDefinition& d : defs) tagged = tagged || d.text.find(e.tag) != std::string::npos;
      if (!tagged) {
        problems.push_back(where + ": " + f + " (" + defs.front().file.filename().string() + ":" +
                           std::to_string(defs.front().line) + ") does not carry the tag '" + e.tag + "'");
      }
    }
  }
  return problems;
}

}  // namespace fullarm::docs
