#include "fullarm/haptics/scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <utility>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/core/yaml_reader.hpp"
#include "fullarm/haptics/geometry.hpp"
#include "fullarm/haptics/mesh_import.hpp"
#include "fullarm/haptics/primitives.hpp"

namespace fullarm::haptics {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr int kSchemaVersion = 1;

// {translation_m: [x, y, z], rpy_deg: [roll, pitch, yaw]} (rpy optional, default zero).
Eigen::Isometry3d readPose(const core::YamlMap& m) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = m.vector3("translation_m", "metres");
  if (m.has("rpy_deg")) {
    const Eigen::Vector3d rpy = m.vector3("rpy_deg", "roll, pitch, yaw in degrees") * kDegToRad;
    X.linear() = arm::rotationFromRpy(rpy.x(), rpy.y(), rpy.z());
  }
  m.finish();
  return X;
}

std::string formatLength(double value_m) {
  std::ostringstream s;
  s << value_m;
  return s.str();
}

// A mesh already imported for another object of the same scene (same file, scale, origin and
// weld tolerance): the scene's objects share one import.
struct CachedMesh {
  std::filesystem::path file;
  double scale = 1.0;
  Eigen::Matrix4d X_OF;
  double weld_tolerance_m = 0.0;
  double max_edge_m = 0.0;
  bool collapse_double_sided = true;
  std::shared_ptr<const TriMesh> mesh;
};

class SceneReader {
 public:
  explicit SceneReader(std::filesystem::path file) : file_(std::move(file)) {}

  Scene read(const core::YamlMap& root) {
    Scene scene;
    scene.source = file_;
    const int version = root.integer("schema_version");
    if (version != kSchemaVersion) {
      root.fail("schema_version", "expected " + std::to_string(kSchemaVersion) + ", got " + std::to_string(version));
    }
    scene.name = root.string("name");
    scene.description = root.optionalString("description").value_or("");
    if (const std::optional<std::string> cache = root.optionalString("hierarchy_cache")) {
      if (cache->empty()) root.fail("hierarchy_cache", "expected a folder (relative to the scene file)");
      const std::filesystem::path base = file_.empty() ? std::filesystem::current_path() : file_.parent_path();
      scene.hierarchy_cache_dir = std::filesystem::absolute((base / *cache).lexically_normal());
    }
    readArm(root.map("arm"), scene);
    const core::YamlList objects = root.list("objects");
    if (objects.size() == 0) root.fail("objects", "expected at least one object");
    scene.objects.reserve(objects.size());
    for (std::size_t i = 0; i < objects.size(); ++i) {
      const core::YamlMap object = objects.map(i);
      scene.objects.push_back(readObject(object));
      if (scene.objectIndex(scene.objects.back().name) != static_cast<int>(scene.objects.size()) - 1) {
        object.fail("name", "duplicate object name '" + scene.objects.back().name + "' (names must be unique)");
      }
    }
    if (const auto targets = root.optionalList("targets")) {
      for (std::size_t i = 0; i < targets->size(); ++i) readTarget(targets->map(i), scene);
    }
    root.finish();
    return scene;
  }

 private:
  void readArm(const core::YamlMap& m, Scene& scene) {
    scene.shoulder_S_m = m.vector3("shoulder_m", "metres, scene frame");
    scene.heading_rad = m.optionalNumber("heading_deg", "degrees").value_or(0.0) * kDegToRad;
    if (const auto postures = m.optionalList("postures")) {
      for (std::size_t i = 0; i < postures->size(); ++i) {
        const core::YamlMap p = postures->map(i);
        ScenePosture posture;
        posture.name = p.string("name");
        (void)p.list("q_rad");  // marks the key read and checks that it is a list
        const YAML::Node values = p.node()["q_rad"];
        if (values.size() == 0) p.fail("q_rad", "expected a list of joint angles [rad], got an empty list");
        posture.q_rad.resize(static_cast<Eigen::Index>(values.size()));
        for (std::size_t k = 0; k < values.size(); ++k) {
          double value = 0.0;
          if (!values[k].IsScalar() || !YAML::convert<double>::decode(values[k], value) || !std::isfinite(value)) {
            p.fail("q_rad", "element " + std::to_string(k) + " is not a finite number (joint angle in rad)");
          }
          posture.q_rad[static_cast<Eigen::Index>(k)] = value;
        }
        p.finish();
        if (scene.posture(posture.name) != nullptr) p.fail("name", "duplicate posture name '" + posture.name + "'");
        scene.postures.push_back(std::move(posture));
      }
    }
    m.finish();
  }

  // {name, object, position_m, approach, push}: checked against the objects already read.
  static void readTarget(const core::YamlMap& m, Scene& scene) {
    SceneTarget target;
    target.name = m.string("name");
    if (scene.target(target.name) != nullptr) m.fail("name", "duplicate target name '" + target.name + "'");
    target.object = m.string("object");
    const int object = scene.objectIndex(target.object);
    if (object < 0) {
      std::string names;
      for (const SceneObject& o : scene.objects) names += (names.empty() ? "" : ", ") + o.name;
      m.fail("object", "no object '" + target.object + "' in the scene (objects: " + names + ")");
    }
    target.position_S_m = m.vector3("position_m", "metres, scene frame");
    const auto unit = [&m](const char* key) {
      const Eigen::Vector3d v = m.vector3(key, "a direction in the scene frame");
      if (!(v.norm() > 1e-9)) m.fail(key, "expected a non-zero direction, got a zero vector");
      return Eigen::Vector3d(v.normalized());
    };
    target.approach_S = unit("approach");
    target.push_S = unit("push");
    m.finish();
    const SceneObject& o = scene.objects[static_cast<std::size_t>(object)];
    const Eigen::Vector3d p_O = o.X_SO.inverse() * target.position_S_m;
    double best_sq = std::numeric_limits<double>::infinity();
    for (int t = 0; t < o.mesh.numTriangles(); ++t) {
      const Eigen::Vector3i& tri = o.mesh.triangle(t);
      best_sq = std::min(best_sq, squaredDistancePointTriangle(p_O, o.mesh.vertex(tri[0]), o.mesh.vertex(tri[1]),
                                                               o.mesh.vertex(tri[2])));
    }
    const double distance = std::sqrt(best_sq);
    if (distance > kTargetMaxObjectDistance_m) {
      std::ostringstream msg;
      msg << "target '" << target.name << "' lies " << distance << " m from the surface of its object '"
          << target.object << "' (at most " << kTargetMaxObjectDistance_m << " m: a grasp is on the object)";
      m.fail("position_m", msg.str());
    }
    scene.targets.push_back(std::move(target));
  }

  SceneObject readObject(const core::YamlMap& m) {
    SceneObject object;
    object.name = m.string("name");
    object.X_SO = readPose(m.map("pose"));
    readShape(m.map("shape"), object);
    m.finish();
    return object;
  }

  void readShape(const core::YamlMap& m, SceneObject& object) {
    const std::string type = m.string("type");
    try {
      if (type == "mesh") {
        readMesh(m, object);
      } else if (type == "box") {
        const Eigen::Vector3d size = m.vector3("size_m", "metres");
        const double max_edge = m.number("max_edge_m", "metres");
        m.finish();
        object.mesh = makeBox(size, max_edge);
        object.shape =
            "box " + formatLength(size.x()) + " x " + formatLength(size.y()) + " x " + formatLength(size.z()) + " m";
      } else if (type == "cylinder") {
        const double radius = m.number("radius_m", "metres");
        const double length = m.number("length_m", "metres");
        const int segments = m.integer("segments");
        const double max_edge = m.number("max_edge_m", "metres");
        m.finish();
        object.mesh = makeCylinder(radius, length, segments, max_edge);
        object.shape = "cylinder r " + formatLength(radius) + " m, length " + formatLength(length) + " m";
      } else if (type == "capsule") {
        const Eigen::Vector3d from = m.vector3("from_m", "metres");
        const Eigen::Vector3d to = m.vector3("to_m", "metres");
        const double radius = m.number("radius_m", "metres");
        const int segments = m.integer("segments");
        const int rings = m.integer("rings");
        m.finish();
        object.mesh = makeCapsule(from, to, radius, segments, rings);
        object.shape = "capsule r " + formatLength(radius) + " m, length " + formatLength((to - from).norm()) + " m";
      } else if (type == "rectangular_frame") {
        const double width = m.number("outer_width_m", "metres");
        const double height = m.number("outer_height_m", "metres");
        const double bar = m.number("bar_width_m", "metres");
        const double depth = m.number("depth_m", "metres");
        const double max_edge = m.number("max_edge_m", "metres");
        m.finish();
        object.mesh = makeRectangularFrame(width, height, bar, depth, max_edge);
        object.shape = "rectangular frame " + formatLength(width) + " x " + formatLength(height) + " m, opening " +
                       formatLength(width - 2 * bar) + " x " + formatLength(height - 2 * bar) + " m";
      } else if (type == "i_beam") {
        const double height = m.number("height_m", "metres");
        const double flange_width = m.number("flange_width_m", "metres");
        const double flange_thickness = m.number("flange_thickness_m", "metres");
        const double web_thickness = m.number("web_thickness_m", "metres");
        const double length = m.number("length_m", "metres");
        const double max_edge = m.number("max_edge_m", "metres");
        m.finish();
        object.mesh = makeIBeam(height, flange_width, flange_thickness, web_thickness, length, max_edge);
        object.shape = "I-beam " + formatLength(height) + " m high, " + formatLength(length) + " m long";
      } else {
        m.fail("type", "expected one of mesh, box, cylinder, capsule, rectangular_frame, i_beam; got '" + type + "'");
      }
    } catch (const MeshError& e) {
      // A primitive builder rejected its parameters, or a mesh file could not be imported.
      m.fail(type == "mesh" ? "file" : "", e.what());
    }
  }

  void readMesh(const core::YamlMap& m, SceneObject& object) {
    const std::filesystem::path relative = m.string("file");
    MeshImportOptions options;
    options.scale = m.optionalNumber("scale", "metres per file unit").value_or(1.0);
    if (!(options.scale > 0.0)) m.fail("scale", "expected a number > 0 (metres per file unit)");
    if (m.has("origin")) options.X_OF = readPose(m.map("origin"));
    options.weld_tolerance_m = m.optionalNumber("weld_tolerance_m", "metres").value_or(kDefaultImportWeldToleranceM);
    if (options.weld_tolerance_m < 0.0) m.fail("weld_tolerance_m", "expected a number >= 0 m");
    options.max_edge_m = m.optionalNumber("max_edge_m", "metres").value_or(0.0);
    if (options.max_edge_m < 0.0) m.fail("max_edge_m", "expected a number > 0 m (or leave it out: no refinement)");
    const std::string collapse = m.optionalString("collapse_double_sided").value_or("true");
    if (collapse != "true" && collapse != "false") {
      m.fail("collapse_double_sided", "expected true or false, got '" + collapse + "'");
    }
    options.collapse_double_sided_solids = collapse == "true";
    m.finish();
    const std::filesystem::path base = file_.empty() ? std::filesystem::current_path() : file_.parent_path();
    const std::filesystem::path path = (base / relative).lexically_normal();
    object.mesh_file = std::filesystem::absolute(path);
    object.shape = "mesh " + relative.filename().string();
    for (const CachedMesh& cached : cache_) {
      if (cached.file == object.mesh_file && cached.scale == options.scale && cached.X_OF == options.X_OF.matrix() &&
          cached.weld_tolerance_m == options.weld_tolerance_m && cached.max_edge_m == options.max_edge_m &&
          cached.collapse_double_sided == options.collapse_double_sided_solids) {
        object.mesh = *cached.mesh;
        return;
      }
    }
    object.mesh = importMesh(object.mesh_file, options);
    cache_.push_back({object.mesh_file, options.scale, options.X_OF.matrix(), options.weld_tolerance_m,
                      options.max_edge_m, options.collapse_double_sided_solids,
                      std::make_shared<const TriMesh>(object.mesh)});
  }

  std::filesystem::path file_;
  std::vector<CachedMesh> cache_;
};

}  // namespace

int Scene::objectIndex(std::string_view object_name) const noexcept {
  for (std::size_t i = 0; i < objects.size(); ++i) {
    if (objects[i].name == object_name) return static_cast<int>(i);
  }
  return -1;
}

const ScenePosture* Scene::posture(std::string_view posture_name) const noexcept {
  for (const ScenePosture& p : postures) {
    if (p.name == posture_name) return &p;
  }
  return nullptr;
}

const SceneTarget* Scene::target(std::string_view target_name) const noexcept {
  for (const SceneTarget& t : targets) {
    if (t.name == target_name) return &t;
  }
  return nullptr;
}

long Scene::numTriangles() const noexcept {
  long n = 0;
  for (const SceneObject& o : objects) n += o.mesh.numTriangles();
  return n;
}

Scene parseScene(std::string_view yaml_text, const std::filesystem::path& file) {
  return SceneReader(file).read(core::YamlMap::parse(yaml_text, file));
}

Scene loadScene(const std::filesystem::path& file) {
  return SceneReader(file).read(core::YamlMap::load(file));
}

Eigen::Isometry3d armBasePose(const Scene& scene, const arm::ArmModel& model) {
  Eigen::Isometry3d X_SW = Eigen::Isometry3d::Identity();
  X_SW.linear() = Eigen::AngleAxisd(scene.heading_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  X_SW.translation() = scene.shoulder_S_m - X_SW.linear() * model.X_WB.translation();
  return X_SW;
}

CollisionWorld makeCollisionWorld(const Scene& scene, const arm::ArmModel& model,
                                  const CollisionWorld::Options& options) {
  CollisionWorld::Options o = options;
  if (o.hierarchy_cache_dir.empty()) o.hierarchy_cache_dir = scene.hierarchy_cache_dir;
  CollisionWorld world(model, o);
  const Eigen::Isometry3d X_WS = armBasePose(scene, model).inverse();
  for (const SceneObject& object : scene.objects) world.addObject(object.name, object.mesh, X_WS * object.X_SO);
  return world;
}

Eigen::VectorXd scenePosture(const Scene& scene, std::string_view name, const arm::ArmModel& model) {
  const ScenePosture* posture = scene.posture(name);
  int index = 0;
  for (; index < static_cast<int>(scene.postures.size()); ++index) {
    if (&scene.postures[static_cast<std::size_t>(index)] == posture) break;
  }
  const std::string key = "arm.postures[" + std::to_string(index) + "].q_rad";
  if (posture == nullptr) {
    std::string names;
    for (const ScenePosture& p : scene.postures) names += (names.empty() ? "" : ", ") + p.name;
    throw core::ConfigError(scene.source, "arm.postures",
                            "no posture named '" + std::string(name) +
                                "' (the scene has: " + (names.empty() ? std::string("none") : names) + ")");
  }
  if (posture->q_rad.size() > model.numJoints()) {
    throw core::ConfigError(scene.source, key,
                            "has " + std::to_string(posture->q_rad.size()) + " values but the arm model '" +
                                model.name + "' has " + std::to_string(model.numJoints()) + " joints");
  }
  Eigen::VectorXd q = model.defaultPosture();
  q.head(posture->q_rad.size()) = posture->q_rad;
  for (Eigen::Index i = 0; i < posture->q_rad.size(); ++i) {
    const arm::JointLimits& lim = model.joints[static_cast<std::size_t>(i)].limits;
    if (q[i] < lim.min_rad || q[i] > lim.max_rad) {
      std::ostringstream msg;
      msg << "element " << i << " (" << model.joints[static_cast<std::size_t>(i)].name << ") = " << q[i]
          << " rad is outside the joint range [" << lim.min_rad << ", " << lim.max_rad << "] rad";
      throw core::ConfigError(scene.source, key, msg.str());
    }
  }
  return q;
}

}  // namespace fullarm::haptics
