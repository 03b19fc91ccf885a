#pragma once
// reports/equations.md read as data: every row's tag and the functions it names, and where in
// the source tree each function is defined with the text of its body and leading comment.

#include <filesystem>
#include <string>
#include <vector>

namespace fullarm::docs {

/// One row of an equations table: its tag (`Eq. (1)`, `H12`, `§3.2.2`, ...) and the functions
/// its code column names (`computeContactTorques`, `ArmPlant::evaluateRhs`).
struct EquationEntry {
  std::string tag;
  std::vector<std::string> functions;
  int line = 0;  ///< line of the row in the file
};

/// Reads every table of `equations_md` whose header has the columns `tag` and `code`. A row
/// without a tag or without a function is an error (std::runtime_error naming the file and line).
[[nodiscard]] std::vector<EquationEntry> readEquationEntries(const std::filesystem::path& equations_md);

/// A definition of a function in a source file: where, and the text that carries its tags (the
/// comment lines right above the definition and the body).
struct FunctionDefinition {
  std::filesystem::path file;
  int line = 0;
  std::string text;
};

/// Every definition of `name` (`f` or `Class::f`) in the .cpp/.hpp files below `dirs`: a line
/// that names it followed by a parameter list and a body (declarations ending in `;` and calls
/// inside other bodies do not count).
[[nodiscard]] std::vector<FunctionDefinition> findDefinitions(const std::vector<std::filesystem::path>& dirs,
                                                              const std::string& name);

/// Every problem of `equations_md` against the tree: a named function with no definition, or
/// whose definitions do not carry the row's tag. One sentence each; empty when consistent.
[[nodiscard]] std::vector<std::string> checkEquations(const std::filesystem::path& equations_md,
                                                      const std::vector<std::filesystem::path>& dirs);

}  // namespace fullarm::docs
