#include "fullarm/core/yaml_reader.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include "fullarm/core/config_error.hpp"

namespace fullarm::core {
namespace {

int lineOf(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.line >= 0 ? mark.line + 1 : 0;
}

std::string describe(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Null:
      return "nothing (null)";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a map";
    case YAML::NodeType::Scalar:
      return "'" + node.Scalar() + "'";
    default:
      return "an undefined value";
  }
}

std::string expected(std::string_view what, std::string_view unit_hint) {
  std::string text(what);
  if (!unit_hint.empty()) {
    text += " (";
    text += unit_hint;
    text += ")";
  }
  return text;
}

}  // namespace

YamlMap::YamlMap(const YAML::Node& node, std::string path, std::filesystem::path file)
    : node_(node),
      path_(std::move(path)),
      file_(std::move(file)),
      used_(std::make_shared<std::set<std::string, std::less<>>>()) {
  if (!node_.IsMap()) {
    throw ConfigError(file_, path_.empty() ? "<document>" : path_, "expected a map of keys, got " + describe(node_),
                      lineOf(node_));
  }
  // yaml-cpp keeps the first of two equal keys and drops the second without a word: a user who
  // appends an override would silently get the old value.
  std::set<std::string, std::less<>> seen;
  for (const auto& entry : node_) {
    if (!seen.insert(entry.first.Scalar()).second) {
      throw ConfigError(file_, keyPath(entry.first.Scalar()), "duplicate key (each key may appear once)",
                        lineOf(entry.first));
    }
  }
}

YamlMap YamlMap::parse(std::string_view text, const std::filesystem::path& file) {
  YAML::Node root;
  try {
    root = YAML::Load(std::string(text));
  } catch (const YAML::Exception& e) {
    throw ConfigError(file, "", "YAML syntax error: " + e.msg, e.mark.line >= 0 ? e.mark.line + 1 : 0);
  }
  return YamlMap(root, "", file);
}

YamlMap YamlMap::load(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ConfigError(file, "", "cannot open the file for reading");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw ConfigError(file, "", "error while reading the file");
  return parse(text.str(), file);
}

std::string YamlMap::keyPath(std::string_view key) const {
  if (path_.empty()) return std::string(key);
  if (key.empty()) return path_;
  return path_ + "." + std::string(key);
}

void YamlMap::fail(std::string_view key, const std::string& message) const {
  int line = lineOf(node_);
  if (!key.empty()) {
    const YAML::Node child = node_[std::string(key)];
    if (child.IsDefined()) line = lineOf(child);
  }
  throw ConfigError(file_, keyPath(key), message, line);
}

bool YamlMap::has(std::string_view key) const {
  return node_[std::string(key)].IsDefined();
}

YAML::Node YamlMap::get(std::string_view key) const {
  const YAML::Node child = node_[std::string(key)];
  if (!child.IsDefined()) {
    throw ConfigError(file_, keyPath(key), "missing required key '" + std::string(key) + "'", lineOf(node_));
  }
  used_->emplace(key);
  return child;
}

double YamlMap::number(std::string_view key, std::string_view unit_hint) const {
  const YAML::Node child = get(key);
  const std::string want = expected("a finite number", unit_hint);
  if (!child.IsScalar()) fail(key, "expected " + want + ", got " + describe(child));
  double value = 0.0;
  if (!YAML::convert<double>::decode(child, value) || !std::isfinite(value)) {
    fail(key, "expected " + want + ", got " + describe(child));
  }
  return value;
}

std::optional<double> YamlMap::optionalNumber(std::string_view key, std::string_view unit_hint) const {
  if (!has(key)) return std::nullopt;
  return number(key, unit_hint);
}

int YamlMap::integer(std::string_view key) const {
  const YAML::Node child = get(key);
  int value = 0;
  if (!child.IsScalar() || !YAML::convert<int>::decode(child, value)) {
    fail(key, "expected an integer, got " + describe(child));
  }
  return value;
}

std::string YamlMap::string(std::string_view key) const {
  const YAML::Node child = get(key);
  if (!child.IsScalar() || child.Scalar().empty()) {
    fail(key, "expected a non-empty string, got " + describe(child));
  }
  return child.Scalar();
}

std::optional<std::string> YamlMap::optionalString(std::string_view key) const {
  if (!has(key)) return std::nullopt;
  return string(key);
}

Eigen::Vector3d YamlMap::vector3(std::string_view key, std::string_view unit_hint) const {
  const YAML::Node child = get(key);
  const std::string want = expected("a list of 3 finite numbers", unit_hint);
  if (!child.IsSequence() || child.size() != 3) fail(key, "expected " + want + ", got " + describe(child));
  Eigen::Vector3d v;
  for (std::size_t i = 0; i < 3; ++i) {
    double value = 0.0;
    if (!child[i].IsScalar() || !YAML::convert<double>::decode(child[i], value) || !std::isfinite(value)) {
      fail(key, "expected " + want + ", element " + std::to_string(i) + " is " + describe(child[i]));
    }
    v[static_cast<Eigen::Index>(i)] = value;
  }
  return v;
}

YamlMap YamlMap::map(std::string_view key) const {
  return YamlMap(get(key), keyPath(key), file_);
}

YamlList YamlMap::list(std::string_view key) const {
  const YAML::Node child = get(key);
  if (!child.IsSequence()) fail(key, "expected a list, got " + describe(child));
  return YamlList(child, keyPath(key), file_);
}

std::optional<YamlList> YamlMap::optionalList(std::string_view key) const {
  if (!has(key)) return std::nullopt;
  return list(key);
}

void YamlMap::finish() const {
  for (const auto& entry : node_) {
    const std::string key = entry.first.Scalar();
    if (used_->find(key) == used_->end()) {
      throw ConfigError(file_, keyPath(key), "unknown key (check its spelling and the schema in docs/)",
                        lineOf(entry.first));
    }
  }
}

YamlList::YamlList(const YAML::Node& node, std::string path, std::filesystem::path file)
    : node_(node), path_(std::move(path)), file_(std::move(file)) {}

YamlMap YamlList::map(std::size_t i) const {
  return YamlMap(node_[i], path_ + "[" + std::to_string(i) + "]", file_);
}

int lineOfKeyPath(const YAML::Node& root, std::string_view key_path) {
  YAML::Node node;
  node.reset(root);
  std::size_t pos = 0;
  while (pos < key_path.size()) {
    std::size_t end = key_path.find('.', pos);
    if (end == std::string_view::npos) end = key_path.size();
    std::string_view part = key_path.substr(pos, end - pos);
    std::optional<std::size_t> index;
    if (const std::size_t bracket = part.find('['); bracket != std::string_view::npos) {
      index = static_cast<std::size_t>(std::stoul(std::string(part.substr(bracket + 1))));
      part = part.substr(0, bracket);
    }
    if (!node.IsMap()) return 0;
    // Node::operator= would assign through the reference; reset() rebinds it.
    const YAML::Node& current = node;
    YAML::Node child = current[std::string(part)];
    if (!child.IsDefined()) return 0;
    if (index) {
      if (!child.IsSequence() || *index >= child.size()) return 0;
      const YAML::Node& list = child;
      YAML::Node element = list[*index];
      child.reset(element);
    }
    node.reset(child);
    pos = end + 1;
  }
  return lineOf(node);
}

}  // namespace fullarm::core
