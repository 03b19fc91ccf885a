#include "output_files.hpp"

#include <fstream>

namespace fullarm::app {

void writeTextFile(const std::filesystem::path& path, const std::string& text) {
  writeOutput(path, [&] {
    if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
    std::ofstream out(path);
    out << text;
    if (!out) throw std::runtime_error("cannot write " + path.string());
  });
}

void createOutputFolder(const std::filesystem::path& folder) {
  writeOutput(folder, [&] { std::filesystem::create_directories(folder); });
}

}  // namespace fullarm::app
