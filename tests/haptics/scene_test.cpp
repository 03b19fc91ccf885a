// Scenes: scenes/valve_wall.yaml against the geometry it describes (meshes imported
// independently, the opening checked by point-triangle distances, the shoulder placed where
// the file says), strict YAML errors with key paths, and truncated/mutated scene files that
// must give core::ConfigError, never a crash.
#include "fullarm/haptics/scene.hpp"
#include "fullarm/core/data_paths.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "arm_test_util.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/haptics/geometry.hpp"
#include "fullarm/haptics/mesh_import.hpp"
#include "fullarm/haptics/primitives.hpp"
#include "matrix_compare.hpp"
#include "scratch_dir.hpp"

namespace fullarm::haptics {
namespace {

namespace fs = std::filesystem;
using fullarm::testing::matricesNear;
constexpr double kTight = 1e-12;

fs::path valveWallFile() {
  return arm::test::sourcePath("scenes/valve_wall.yaml");
}

const Scene& valveWall() {
  static const Scene scene = loadScene(valveWallFile());
  return scene;
}

// Smallest distance from p (scene frame) to an object of the scene, over all its triangles.
double distanceToObject(const Scene& scene, int object, const Eigen::Vector3d& p_S) {
  const SceneObject& o = scene.objects[static_cast<std::size_t>(object)];
  const Eigen::Vector3d p_O = o.X_SO.inverse() * p_S;
  double best = 1e300;
  for (int t = 0; t < o.mesh.numTriangles(); ++t) {
    const Eigen::Vector3i& tri = o.mesh.triangle(t);
    best = std::min(
        best,
        closestPointTriangle(p_O, o.mesh.vertex(tri[0]), o.mesh.vertex(tri[1]), o.mesh.vertex(tri[2])).distance_m);
  }
  return best;
}

TEST(SceneTest, ValveWallHasTheObjectsItDescribes) {
  const Scene& scene = valveWall();
  EXPECT_EQ(scene.name, "valve_wall");
  EXPECT_EQ(scene.source, valveWallFile());
  const std::vector<std::string> names = {"access_wall_left",
                                          "access_wall_right",
                                          "access_wall_below_opening",
                                          "access_wall_above_opening",
                                          "opening_frame",
                                          "truss",
                                          "valve_wall",
                                          "wheel_valve"};
  ASSERT_EQ(scene.objects.size(), names.size());
  for (std::size_t i = 0; i < names.size(); ++i) {
    EXPECT_EQ(scene.objects[i].name, names[i]);
    EXPECT_EQ(scene.objectIndex(names[i]), static_cast<int>(i));
  }
  EXPECT_EQ(scene.objectIndex("nothing"), -1);
  EXPECT_TRUE(matricesNear(scene.shoulder_S_m, Eigen::Vector3d(0.283, 0.0, 1.40), kTight));
  ASSERT_NE(scene.posture("reach_valve"), nullptr);
  EXPECT_EQ(scene.posture("reach_valve")->q_rad.size(), 7);

  // Meshes equal an independent import of the same files with the same options.
  MeshImportOptions wall_options;
  wall_options.X_OF = Eigen::Translation3d(-0.004536186, -0.003571748, 0.0);
  const TriMesh wall = importMesh(
      arm::test::sourcePath("scenes/meshes/gazebo-drc/drc_practice_valve_wall/five_dice_wall.dae"), wall_options);
  for (const char* name : {"access_wall_left", "access_wall_right", "valve_wall"}) {
    const TriMesh& m = scene.objects[static_cast<std::size_t>(scene.objectIndex(name))].mesh;
    ASSERT_EQ(m.numTriangles(), wall.numTriangles()) << name;
    for (int v = 0; v < m.numVertices(); ++v) ASSERT_EQ(m.vertex(v), wall.vertex(v)) << name;
  }
  const TriMesh box = makeBox(Eigen::Vector3d(0.30, 0.00952, 1.12), 0.05);
  EXPECT_EQ(scene.objects[2].mesh.numTriangles(), box.numTriangles());
  EXPECT_GT(scene.numTriangles(), 16000);  // 27,027 as written; the walls' inward copies removed

  // Poses as written: translation, and rpy (90 deg roll) of the opening frame.
  EXPECT_TRUE(matricesNear(scene.objects[1].X_SO.translation(), Eigen::Vector3d(0.40, 0.30, 0.0), kTight));
  const Eigen::Matrix3d roll90 = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  EXPECT_TRUE(matricesNear(scene.objects[4].X_SO.linear(), roll90, kTight));
}

TEST(SceneTest, ValveWallOpeningIsOpenAndTheWallIsClosedBesideIt) {
  const Scene& scene = valveWall();
  const int wall_objects[] = {0, 1, 2, 3, 4};  // panels, boxes and the frame of the access wall
  auto clearance = [&](const Eigen::Vector3d& p_S) {
    double d = 1e300;
    for (int o : wall_objects) d = std::min(d, distanceToObject(scene, o, p_S));
    return d;
  };
  // The opening is 0.30 x 0.28 m centred at (0.25, 1.26) in x-z: its centre is 0.14 m from the
  // nearest edge of the 0.30 m wide, 0.28 m high inner rectangle.
  EXPECT_NEAR(clearance({0.25, 0.30476, 1.26}), 0.14, 1e-6);
  // Anywhere else on the wall plane within the sheet there is material (distance ~0).
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(-0.8, 0.30476, 0.3), Eigen::Vector3d(0.8, 0.30476, 1.0),
                                   Eigen::Vector3d(0.25, 0.30476, 0.5), Eigen::Vector3d(0.25, 0.30476, 2.0)}) {
    EXPECT_LT(clearance(p), 0.006) << p.transpose();  // inside a 9.5 mm sheet
  }
}

TEST(SceneTest, ShoulderIsPlacedWhereTheSceneSaysAndGravityStaysDown) {
  const arm::ArmModel& model = arm::test::defaultModel();
  Scene scene = valveWall();
  for (double heading_deg : {0.0, 90.0, -30.0}) {
    scene.heading_rad = heading_deg * M_PI / 180.0;
    const Eigen::Isometry3d X_SW = armBasePose(scene, model);
    EXPECT_TRUE(matricesNear(X_SW * model.X_WB.translation(), scene.shoulder_S_m, kTight));
    EXPECT_TRUE(matricesNear(X_SW.linear() * Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitZ(), kTight));
    // The collision world holds every object at X_WO = X_SW^-1 X_SO.
    const CollisionWorld world = makeCollisionWorld(scene, model);
    ASSERT_EQ(world.numObjects(), static_cast<int>(scene.objects.size()));
    for (int o = 0; o < world.numObjects(); ++o) {
      EXPECT_TRUE(matricesNear((X_SW * world.object(o).X_WO).matrix(),
                               scene.objects[static_cast<std::size_t>(o)].X_SO.matrix(), kTight));
    }
  }
}

TEST(SceneTest, ReachPostureGoesThroughTheOpening) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const Scene& scene = valveWall();
  const Eigen::VectorXd q = scenePosture(scene, "reach_valve", model);
  ASSERT_EQ(q.size(), model.numJoints());
  EXPECT_EQ(q.tail(model.numJoints() - 7), model.defaultPosture().tail(model.numJoints() - 7));
  arm::ArmData data(model);
  arm::computeForwardKinematics(model, data, q);
  const Eigen::Isometry3d X_SW = armBasePose(scene, model);
  // The hand point is behind the access wall (y > 0.31) and in front of the valve wall.
  const Eigen::Vector3d hand_S = X_SW * data.X_WT.translation();
  EXPECT_GT(hand_S.y(), 0.31);
  EXPECT_LT(hand_S.y(), 0.72);
  // Where the forearm axis crosses the wall plane it is inside the opening.
  const int forearm = model.jointIndex("R_WR");
  const arm::LinkGeometry& g = model.joints[static_cast<std::size_t>(forearm)].geometry;
  const Eigen::Vector3d a = X_SW * data.X_WL[static_cast<std::size_t>(forearm)] * g.from_m;
  const Eigen::Vector3d b = X_SW * data.X_WL[static_cast<std::size_t>(forearm)] * g.to_m;
  ASSERT_LT(a.y(), 0.30476);
  ASSERT_GT(b.y(), 0.30476);
  const Eigen::Vector3d crossing = a + (b - a) * (0.30476 - a.y()) / (b.y() - a.y());
  EXPECT_GT(crossing.x(), 0.10 + g.radius_m);
  EXPECT_LT(crossing.x(), 0.40 - g.radius_m);
  EXPECT_GT(crossing.z(), 1.12 + g.radius_m);
  EXPECT_LT(crossing.z(), 1.40 - g.radius_m);
}

TEST(SceneTest, PostureErrorsNameTheScene) {
  const arm::ArmModel& model = arm::test::defaultModel();
  Scene scene = valveWall();
  EXPECT_THROW((void)scenePosture(scene, "fly", model), core::ConfigError);
  scene.postures[0].q_rad = Eigen::VectorXd::Zero(model.numJoints() + 1);
  try {
    (void)scenePosture(scene, "reach_valve", model);
    FAIL();
  } catch (const core::ConfigError& e) {
    EXPECT_EQ(e.keyPath(), "arm.postures[0].q_rad");
    EXPECT_EQ(e.file(), valveWallFile());
  }
  scene.postures[0].q_rad = Eigen::VectorXd::Constant(2, 3.0);  // beyond R_SFE's 1.37 rad
  try {
    (void)scenePosture(scene, "reach_valve", model);
    FAIL();
  } catch (const core::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("R_SFE"), std::string::npos) << e.what();
  }
}

// A small primitive-only scene for the error and fuzz tests (no file I/O unless a mesh is named).
const char* kSmallScene = R"(schema_version: 1
name: small
arm:
  shoulder_m: [0.0, 0.0, 1.4]
  heading_deg: 10.0
  postures:
    - name: up
      q_rad: [1.0, -0.2]
objects:
  - name: block
    pose: {translation_m: [0.0, 0.5, 1.0], rpy_deg: [0.0, 0.0, 45.0]}
    shape: {type: box, size_m: [0.2, 0.1, 0.3], max_edge_m: 0.1}
  - name: post
    pose: {translation_m: [0.3, 0.5, 1.0]}
    shape: {type: cylinder, radius_m: 0.05, length_m: 1.0, segments: 12, max_edge_m: 0.2}
  - name: rail
    pose: {translation_m: [0.0, 0.6, 1.2]}
    shape: {type: capsule, from_m: [-0.3, 0, 0], to_m: [0.3, 0, 0], radius_m: 0.02, segments: 8, rings: 2}
  - name: surround
    pose: {translation_m: [0.0, 0.4, 1.3], rpy_deg: [90, 0, 0]}
    shape: {type: rectangular_frame, outer_width_m: 0.4, outer_height_m: 0.3, bar_width_m: 0.03, depth_m: 0.05, max_edge_m: 0.1}
  - name: beam
    pose: {translation_m: [0.0, 0.7, 1.0]}
    shape: {type: i_beam, height_m: 0.2, flange_width_m: 0.1, flange_thickness_m: 0.01, web_thickness_m: 0.008, length_m: 1.0, max_edge_m: 0.2}
)";

TEST(SceneTest, SmallSceneParsesEveryPrimitive) {
  const Scene scene = parseScene(kSmallScene, "small.yaml");
  ASSERT_EQ(scene.objects.size(), 5u);
  EXPECT_NEAR(scene.heading_rad, 10.0 * M_PI / 180.0, kTight);
  EXPECT_EQ(scene.objects[0].mesh.numTriangles(), makeBox({0.2, 0.1, 0.3}, 0.1).numTriangles());
  EXPECT_EQ(scene.objects[4].mesh.numTriangles(), makeIBeam(0.2, 0.1, 0.01, 0.008, 1.0, 0.2).numTriangles());
  EXPECT_EQ(scene.objects[0].shape, "box 0.2 x 0.1 x 0.3 m");
  EXPECT_TRUE(scene.objects[0].mesh_file.empty());
  const Eigen::Matrix3d yaw45 = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_TRUE(matricesNear(scene.objects[0].X_SO.linear(), yaw45, kTight));
}

// Replaces the first occurrence of `from` in the small scene by `to`.
std::string edited(const std::string& from, const std::string& to) {
  std::string text = kSmallScene;
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

struct BadCase {
  std::string text;
  std::string key_path;  // expected core::ConfigError::keyPath()
  std::string message;   // expected part of the message
};

TEST(SceneTest, StrictYamlErrorsNameTheKeyPath) {
  const std::vector<BadCase> cases = {
      {edited("schema_version: 1", "schema_version: 2"), "schema_version", "expected 1"},
      {edited("schema_version: 1\n", ""), "schema_version", "missing required key"},
      {edited("name: small", "name: small\ncolour: red"), "colour", "unknown key"},
      {edited("heading_deg: 10.0", "heading_deg: east"), "arm.heading_deg", "finite number"},
      {edited("shoulder_m: [0.0, 0.0, 1.4]", "shoulder_m: [0.0, 1.4]"), "arm.shoulder_m", "3 finite numbers"},
      {edited("q_rad: [1.0, -0.2]", "q_rad: [1.0, up]"), "arm.postures[0].q_rad", "element 1"},
      {edited("q_rad: [1.0, -0.2]", "q_rad: 1.0"), "arm.postures[0].q_rad", "expected a list"},
      {edited("q_rad: [1.0, -0.2]", "q_rad: []"), "arm.postures[0].q_rad", "empty list"},
      {edited("    - name: up\n      q_rad: [1.0, -0.2]",
              "    - name: up\n      q_rad: [1.0]\n    - name: up\n      q_rad: [2.0]"),
       "arm.postures[1].name", "duplicate posture"},
      {edited("name: post", "name: block"), "objects[1].name", "duplicate object name 'block'"},
      {edited("type: box", "type: sphere"), "objects[0].shape.type", "expected one of mesh, box"},
      {edited("size_m: [0.2, 0.1, 0.3]", "size_m: [0.2, -0.1, 0.3]"), "objects[0].shape", "makeBox"},
      {edited("segments: 12", "segments: 2"), "objects[1].shape", "segments"},
      {edited("segments: 12", "segments: 12.5"), "objects[1].shape.segments", "integer"},
      {edited("bar_width_m: 0.03", "bar_width_m: 0.3"), "objects[3].shape", ""},
      {edited("    pose: {translation_m: [0.3, 0.5, 1.0]}", "    pose: {rpy_deg: [0, 0, 0]}"),
       "objects[1].pose.translation_m", "missing required key"},
      {edited("rpy_deg: [0.0, 0.0, 45.0]", "rpy_deg: [0.0, 45.0]"), "objects[0].pose.rpy_deg", "3 finite numbers"},
      {edited("max_edge_m: 0.1}\n  - name: post", "max_edge_m: 0.1, colour: red}\n  - name: post"),
       "objects[0].shape.colour", "unknown key"},
      {edited("shape: {type: box, size_m: [0.2, 0.1, 0.3], max_edge_m: 0.1}",
              "shape: {type: mesh, file: no_such_mesh.stl}"),
       "objects[0].shape.file", "no such file"},
      {edited("shape: {type: box, size_m: [0.2, 0.1, 0.3], max_edge_m: 0.1}",
              "shape: {type: mesh, file: a.stl, scale: 0}"),
       "objects[0].shape.scale", "> 0"},
      {"schema_version: 1\nname: x\narm: {shoulder_m: [0, 0, 1]}\nobjects: []\n", "objects", "at least one object"},
      {"schema_version: 1\nname: x\narm: {shoulder_m: [0, 0, 1]}\nobjects: {a: 1}\n", "objects", "expected a list"},
      {"[1, 2, 3]\n", "<document>", "expected a map"},
      {"schema_version: 1\nname: [unclosed\n", "", "YAML syntax error"},
  };
  for (const BadCase& c : cases) {
    SCOPED_TRACE(c.text);
    try {
      (void)parseScene(c.text, "bad_scene.yaml");
      ADD_FAILURE() << "no error; expected " << c.key_path;
    } catch (const core::ConfigError& e) {
      EXPECT_EQ(e.keyPath(), c.key_path) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
      EXPECT_EQ(e.file(), fs::path("bad_scene.yaml"));
    }
  }
}

// Targets name an object of the scene and lie on it: a grasp on the block's top face is read
// (directions normalised), and a target on an unknown object, with a zero direction, a second
// one of the same name or 0.3 m above the block is an error naming its key.
TEST(SceneTest, TargetsAreReadAndCheckedAgainstTheirObject) {
  const std::string target =
      "targets:\n  - name: top\n    object: block\n    position_m: [0.0, 0.5, 1.2]\n"
      "    approach: [0.0, 0.0, -2.0]\n    push: [1.0, 1.0, 0.0]\n";
  const Scene scene = parseScene(std::string(kSmallScene) + target, "small.yaml");
  ASSERT_EQ(scene.targets.size(), 1u);
  ASSERT_NE(scene.target("top"), nullptr);
  EXPECT_EQ(scene.target("top")->object, "block");
  EXPECT_TRUE(matricesNear(scene.target("top")->approach_S, Eigen::Vector3d(0.0, 0.0, -1.0), kTight));
  EXPECT_NEAR(scene.target("top")->push_S.norm(), 1.0, kTight);
  EXPECT_EQ(scene.target("none"), nullptr);
  EXPECT_TRUE(parseScene(kSmallScene, "small.yaml").targets.empty());  // the key is optional

  const auto replaced = [&target](const std::string& from, const std::string& to) {
    std::string text = target;
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
    return std::string(kSmallScene) + text;
  };
  const std::vector<BadCase> cases = {
      {replaced("object: block", "object: wall"), "targets[0].object", "no object 'wall'"},
      {replaced("approach: [0.0, 0.0, -2.0]", "approach: [0.0, 0.0, 0.0]"), "targets[0].approach", "non-zero"},
      {replaced("position_m: [0.0, 0.5, 1.2]", "position_m: [0.0, 0.5, 1.45]"), "targets[0].position_m",
       "from the surface of its object 'block'"},
      {std::string(kSmallScene) + target + target.substr(std::string("targets:\n").size()), "targets[1].name",
       "duplicate target name"},
  };
  for (const BadCase& c : cases) {
    SCOPED_TRACE(c.text);
    try {
      (void)parseScene(c.text, "bad_scene.yaml");
      ADD_FAILURE() << "no error; expected " << c.key_path;
    } catch (const core::ConfigError& e) {
      EXPECT_EQ(e.keyPath(), c.key_path) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
    }
  }
}

TEST(SceneTest, ErrorsCarryTheLineOfTheBadValue) {
  try {
    (void)parseScene(edited("segments: 12", "segments: 12.5"), "bad_scene.yaml");
    FAIL();
  } catch (const core::ConfigError& e) {
    EXPECT_EQ(e.line(), 15);  // the `post` object's shape line
  }
}

TEST(SceneTest, MeshErrorsBecomeConfigErrorsWithTheMeshMessage) {
  const fs::path dir = fullarm::test::scratchDir("fullarm_scene_test_mesh");
  { std::ofstream(dir / "broken.obj") << "v 0 0 0\nv 1 0 0\nf 1 2 7\n"; }
  const std::string text =
      edited("shape: {type: box, size_m: [0.2, 0.1, 0.3], max_edge_m: 0.1}", "shape: {type: mesh, file: broken.obj}");
  try {
    (void)parseScene(text, dir / "scene.yaml");
    FAIL();
  } catch (const core::ConfigError& e) {
    EXPECT_EQ(e.keyPath(), "objects[0].shape.file");
    EXPECT_NE(std::string(e.what()).find((dir / "broken.obj").string()), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

TEST(SceneTest, RelativeMeshPathsResolveAgainstTheSceneFolderAndShareOneImport) {
  const fs::path dir = fullarm::test::scratchDir("fullarm_scene_test_relative");
  fs::create_directories(dir / "meshes");
  {
    std::ofstream(dir / "meshes" / "tri.stl")
        << "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1000 0 0\nvertex 0 1000 0\nendloop\n"
           "endfacet\nendsolid t\n";
  }
  std::string text = edited("shape: {type: box, size_m: [0.2, 0.1, 0.3], max_edge_m: 0.1}",
                            "shape: {type: mesh, file: meshes/tri.stl, scale: 0.001}");
  const std::string cylinder = "shape: {type: cylinder, radius_m: 0.05, length_m: 1.0, segments: 12, max_edge_m: 0.2}";
  text.replace(text.find(cylinder), cylinder.size(),
               "shape: {type: mesh, file: meshes/../meshes/tri.stl, scale: 0.001, max_edge_m: 0.3}");
  const Scene scene = parseScene(text, dir / "scene.yaml");
  EXPECT_EQ(scene.objects[0].mesh_file, fs::absolute(dir / "meshes" / "tri.stl"));
  EXPECT_EQ(scene.objects[0].mesh.numTriangles(), 1);
  EXPECT_NEAR(scene.objects[0].mesh.area(), 0.5, kTight);  // 1000 mm legs at 0.001 m/mm
  // Same file with refinement: a separate import, every edge <= 0.3 m, same area.
  EXPECT_GT(scene.objects[1].mesh.numTriangles(), 1);
  EXPECT_NEAR(scene.objects[1].mesh.area(), 0.5, kTight);
  fs::remove_all(dir);
}

// A tetrahedron written twice, once per winding (the double-sided export): by default the scene
// keeps its outward copy (4 triangles, positive enclosed volume); collapse_double_sided: false
// keeps the file's 8 (a separate import of the same file); any other value is an error.
TEST(SceneTest, DoubleSidedSolidsAreCollapsedUnlessTheSceneSaysOtherwise) {
  const fs::path dir = fullarm::test::scratchDir("fullarm_scene_test_double_sided");
  {
    const Eigen::Vector3d v[4] = {{0, 0, 0}, {100, 0, 0}, {0, 100, 0}, {0, 0, 100}};
    const int outward[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    std::ofstream stl(dir / "tet.stl");
    stl << "solid t\n";
    for (const bool flip : {true, false}) {
      for (const auto& f : outward) {
        stl << "facet normal 0 0 0\nouter loop\n";
        for (int k : {0, flip ? 2 : 1, flip ? 1 : 2}) stl << "vertex " << v[f[k]].transpose() << "\n";
        stl << "endloop\nendfacet\n";
      }
    }
    stl << "endsolid t\n";
  }
  std::string text = edited("shape: {type: box, size_m: [0.2, 0.1, 0.3], max_edge_m: 0.1}",
                            "shape: {type: mesh, file: tet.stl, scale: 0.001}");
  const std::string cylinder = "shape: {type: cylinder, radius_m: 0.05, length_m: 1.0, segments: 12, max_edge_m: 0.2}";
  text.replace(text.find(cylinder), cylinder.size(),
               "shape: {type: mesh, file: tet.stl, scale: 0.001, collapse_double_sided: false}");
  const Scene scene = parseScene(text, dir / "scene.yaml");
  const TriMesh& once = scene.objects[0].mesh;
  ASSERT_EQ(once.numTriangles(), 4);
  double volume = 0.0;
  for (int t = 0; t < 4; ++t) {
    const auto& tri = once.triangle(t);
    volume += once.vertex(tri[0]).dot(once.vertex(tri[1]).cross(once.vertex(tri[2]))) / 6.0;
  }
  EXPECT_NEAR(volume, 0.1 * 0.1 * 0.1 / 6.0, kTight);  // outward: the tetrahedron's volume, positive
  EXPECT_EQ(scene.objects[1].mesh.numTriangles(), 8);
  text.replace(text.find("collapse_double_sided: false"), 28, "collapse_double_sided: maybe");
  try {
    (void)parseScene(text, dir / "scene.yaml");
    ADD_FAILURE() << "no error for collapse_double_sided: maybe";
  } catch (const core::ConfigError& e) {
    EXPECT_EQ(e.keyPath(), "objects[1].shape.collapse_double_sided");
    EXPECT_NE(std::string(e.what()).find("expected true or false"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

// Truncated and byte-mutated scene texts: each must parse or throw core::ConfigError.
TEST(SceneTest, TruncatedAndMutatedScenesGiveConfigErrorNeverACrash) {
  const std::string text = kSmallScene;
  int parsed = 0;
  int rejected = 0;
  auto attempt = [&](const std::string& candidate) {
    try {
      const Scene scene = parseScene(candidate, "fuzz.yaml");
      EXPECT_FALSE(scene.objects.empty());
      ++parsed;
    } catch (const core::ConfigError&) {
      ++rejected;
    }
  };
  for (std::size_t n = 0; n <= text.size(); n += 7) attempt(text.substr(0, n));
  std::mt19937 rng(77);
  const std::string special = " \n:-[]{},.#0123456789\"'";
  std::uniform_int_distribution<std::size_t> pos(0, text.size() - 1);
  std::uniform_int_distribution<int> count(1, 6);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<std::size_t> pick(0, special.size() - 1);
  for (int m = 0; m < 400; ++m) {
    std::string candidate = text;
    const int n = count(rng);
    for (int k = 0; k < n; ++k) {
      candidate[pos(rng)] = byte(rng) % 2 == 0 ? static_cast<char>(byte(rng)) : special[pick(rng)];
    }
    attempt(candidate);
  }
  EXPECT_GT(rejected, 100);
  EXPECT_GT(parsed, 0);  // the full text and harmless mutations (inside numbers) still parse
}

TEST(SceneTest, MissingSceneFileIsAConfigError) {
  EXPECT_THROW((void)loadScene("/nonexistent/scene.yaml"), core::ConfigError);
}

// The shipped-scene lookup used by `fullarm demo`: a test program runs from the build tree, so
// it finds the source tree's scenes/; $FULLARM_SCENE_DIR overrides it.
TEST(SceneTest, DefaultScenePathFindsTheSourceTreeAndHonoursTheEnvironment) {
  ASSERT_EQ(std::getenv("FULLARM_SCENE_DIR"), nullptr);
  const fs::path found = core::defaultScenePath("valve_wall.yaml");
  EXPECT_TRUE(fs::equivalent(found, valveWallFile())) << found;
  EXPECT_EQ(loadScene(found).name, "valve_wall");
  ASSERT_EQ(setenv("FULLARM_SCENE_DIR", "/elsewhere/scenes", 1), 0);
  EXPECT_EQ(core::defaultScenePath("valve_wall.yaml"), fs::path("/elsewhere/scenes/valve_wall.yaml"));
  ASSERT_EQ(unsetenv("FULLARM_SCENE_DIR"), 0);
  EXPECT_TRUE(fs::equivalent(core::defaultScenePath("valve_wall.yaml"), valveWallFile()));
}

}  // namespace
}  // namespace fullarm::haptics
