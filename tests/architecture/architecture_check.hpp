#pragma once
// The layering rules of docs/architecture.md, checked on a source tree: the documented module
// table against the CMake targets, includes against the documented dependencies, no include of
// another module's src/, and no include cycle between the units (a header and its source file)
// of one module.

#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace fullarm::architecture {

/// One row of the module table.
struct DocumentedModule {
  std::string name;                  ///< folder and target suffix: `arm` for fullarm::arm
  int floor = 0;                     ///< the floor column (the row number when there is none)
  std::set<std::string> depends_on;  ///< fullarm modules it may use directly
};

/// Reads the module table of `architecture_md`: the rows whose target column names
/// `fullarm::<name>` (or the `fullarm` executable for `apps`), in order, with their floor and
/// their "depends on" column's module names (in backquotes). Throws std::runtime_error naming the file when there is no
/// table or a row is malformed.
[[nodiscard]] std::vector<DocumentedModule> readModuleTable(const std::filesystem::path& architecture_md);

/// The fullarm modules a module's CMakeLists.txt links (the `fullarm::<x>` names of its
/// fullarm_add_module call, or of target_link_libraries for apps). Throws std::runtime_error
/// when the file has no module definition.
[[nodiscard]] std::set<std::string> cmakeModuleDeps(const std::filesystem::path& cmakelists);

/// Every problem found in the tree at `root` against `modules`, one sentence each (empty when
/// the tree follows the rules).
[[nodiscard]] std::vector<std::string> checkTree(const std::filesystem::path& root,
                                                 const std::vector<DocumentedModule>& modules);

}  // namespace fullarm::architecture
