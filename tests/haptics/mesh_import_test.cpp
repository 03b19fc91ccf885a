// Mesh import through assimp: small files written by the test (OBJ, ASCII and binary STL,
// ASCII and binary PLY, COLLADA with units and up axes) against the coordinates the test wrote;
// the DRC meshes against the box sizes of their Gazebo model.sdf files; and malformed,
// truncated and mutated files, which must give MeshError naming the file, never a crash.
#include "fullarm/haptics/mesh_import.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "scratch_dir.hpp"

namespace fullarm::haptics {
namespace {

namespace fs = std::filesystem;

// Coordinates written by the tests are small binary fractions, exact in float and double, so
// imported vertices must match them exactly up to the transforms applied in double.
constexpr double kExactTolerance = 1e-12;
// The COLLADA unit factor passes through assimp's single-precision node transform.
constexpr double kFloatTolerance = 1e-6;

class MeshImportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fullarm::test::scratchDir(std::string("fullarm_mesh_import_") +
                                     ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& name, const std::string& bytes) const {
    const fs::path path = dir_ / name;
    std::ofstream out(path, std::ios::binary);
    out << bytes;
    return path;
  }

  fs::path dir_;
};

// A unit cube [0,1]^3 as six quads with per-face vertex copies (24 vertices), as exporters
// write it when they store per-face normals.
std::string cubeObj() {
  std::ostringstream s;
  s << "# cube\n";
  const int faces[6][4][3] = {
      {{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}}, {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}},
      {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}}, {{0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0}},
      {{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0}}, {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}}};
  for (const auto& f : faces) {
    for (const auto& v : f) s << "v " << v[0] << " " << v[1] << " " << v[2] << "\n";
  }
  for (int f = 0; f < 6; ++f)
    s << "f " << 4 * f + 1 << " " << 4 * f + 2 << " " << 4 * f + 3 << " " << 4 * f + 4 << "\n";
  return s.str();
}

// Tetrahedron (0,0,0), (2,0,0), (0,2,0), (0,0,2) in file units, outward winding.
const double kTetraVertices[4][3] = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0, 0, 2}};
const int kTetraFaces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

std::string tetraStlAscii() {
  std::ostringstream s;
  s << "solid tetra\n";
  for (const auto& f : kTetraFaces) {
    s << " facet normal 0 0 0\n  outer loop\n";
    for (int k = 0; k < 3; ++k) {
      const double* v = kTetraVertices[f[k]];
      s << "   vertex " << v[0] << " " << v[1] << " " << v[2] << "\n";
    }
    s << "  endloop\n endfacet\n";
  }
  s << "endsolid tetra\n";
  return s.str();
}

std::string tetraStlBinary() {
  std::string s(80, ' ');
  const std::uint32_t count = 4;
  s.append(reinterpret_cast<const char*>(&count), 4);
  for (const auto& f : kTetraFaces) {
    const float normal[3] = {0, 0, 0};
    s.append(reinterpret_cast<const char*>(normal), 12);
    for (int k = 0; k < 3; ++k) {
      const float v[3] = {static_cast<float>(kTetraVertices[f[k]][0]), static_cast<float>(kTetraVertices[f[k]][1]),
                          static_cast<float>(kTetraVertices[f[k]][2])};
      s.append(reinterpret_cast<const char*>(v), 12);
    }
    s.append(2, '\0');
  }
  return s;
}

std::string tetraPlyAscii() {
  std::ostringstream s;
  s << "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 4\nproperty list uchar int vertex_indices\nend_header\n";
  for (const auto& v : kTetraVertices) s << v[0] << " " << v[1] << " " << v[2] << "\n";
  for (const auto& f : kTetraFaces) s << "3 " << f[0] << " " << f[1] << " " << f[2] << "\n";
  return s.str();
}

std::string tetraPlyBinary() {
  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n";
  for (const auto& v : kTetraVertices) {
    const float f[3] = {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
    s.append(reinterpret_cast<const char*>(f), 12);
  }
  for (const auto& f : kTetraFaces) {
    s.push_back('\3');
    s.append(reinterpret_cast<const char*>(f), 12);
  }
  return s;
}

// A COLLADA file with one triangle (0,0,0) (1,0,0) (0,2,0) in a node translated by (0,0,4),
// in unit `meter` metres per file unit and with up axis `up`.
std::string triangleDae(const std::string& up, double meter) {
  return R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="u" meter=")" +
         std::to_string(meter) + R"("/><up_axis>)" + up + R"(</up_axis></asset>
  <library_geometries>
    <geometry id="tri" name="tri"><mesh>
      <source id="tri-pos"><float_array id="tri-pos-array" count="9">0 0 0 1 0 0 0 2 0</float_array>
        <technique_common><accessor source="#tri-pos-array" count="3" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common></source>
      <vertices id="tri-vtx"><input semantic="POSITION" source="#tri-pos"/></vertices>
      <triangles count="1"><input semantic="VERTEX" source="#tri-vtx" offset="0"/><p>0 1 2</p></triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene" name="scene">
      <node id="n" name="n"><translate>0 0 4</translate><instance_geometry url="#tri"/></node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
)";
}

// Sorted vertex list of a mesh, for order-independent comparison.
std::vector<Eigen::Vector3d> sortedVertices(const TriMesh& mesh) {
  std::vector<Eigen::Vector3d> v;
  for (int i = 0; i < mesh.numVertices(); ++i) v.push_back(mesh.vertex(i));
  std::sort(v.begin(), v.end(), [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  });
  return v;
}

void expectSameVertexSet(const TriMesh& mesh, std::vector<Eigen::Vector3d> expected, double tol) {
  std::sort(expected.begin(), expected.end(), [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  });
  const std::vector<Eigen::Vector3d> got = sortedVertices(mesh);
  ASSERT_EQ(got.size(), expected.size()) << mesh.source();
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_LE((got[i] - expected[i]).norm(), tol)
        << "vertex " << i << ": " << got[i].transpose() << " vs " << expected[i].transpose();
  }
}

// Enclosed volume (divergence theorem), about the vertex mean to avoid cancellation.
double signedVolume(const TriMesh& mesh) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int v = 0; v < mesh.numVertices(); ++v) c += mesh.vertex(v) / mesh.numVertices();
  double volume = 0.0;
  for (int t = 0; t < mesh.numTriangles(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangle(t);
    volume += (mesh.vertex(tri[0]) - c).dot((mesh.vertex(tri[1]) - c).cross(mesh.vertex(tri[2]) - c)) / 6.0;
  }
  return volume;
}

TEST_F(MeshImportTest, ObjCubeIsWeldedIntoAClosedMesh) {
  const TriMesh mesh = importMesh(write("cube.obj", cubeObj()));
  EXPECT_EQ(mesh.numVertices(), 8);  // 24 per-face copies welded
  EXPECT_EQ(mesh.numTriangles(), 12);
  EXPECT_EQ(mesh.numEdges(), 18);  // Euler: V - E + F = 2
  EXPECT_EQ(mesh.boundaryEdgeCount(), 0);
  EXPECT_EQ(mesh.nonManifoldEdgeCount(), 0);
  EXPECT_EQ(mesh.weldedVertexCount(), 16);
  EXPECT_NEAR(mesh.area(), 6.0, kExactTolerance);
  EXPECT_NEAR(signedVolume(mesh), 1.0, kExactTolerance);  // outward winding kept
}

TEST_F(MeshImportTest, WeldingCanBeDisabled) {
  MeshImportOptions options;
  options.weld_tolerance_m = 0.0;
  const TriMesh mesh = importMesh(write("cube.obj", cubeObj()), options);
  EXPECT_EQ(mesh.numVertices(), 24);
  EXPECT_EQ(mesh.boundaryEdgeCount(), 24);  // every face is its own patch
}

TEST_F(MeshImportTest, EveryFormatAppliesScaleThenPose) {
  MeshImportOptions options;
  options.scale = 0.001;  // millimetres
  options.X_OF = Eigen::Translation3d(0.5, -0.25, 1.0) * Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized());
  std::vector<Eigen::Vector3d> expected;
  for (const auto& v : kTetraVertices) expected.push_back(options.X_OF * (0.001 * Eigen::Vector3d(v[0], v[1], v[2])));
  const std::pair<std::string, std::string> files[] = {{"tetra_ascii.stl", tetraStlAscii()},
                                                       {"tetra_binary.stl", tetraStlBinary()},
                                                       {"tetra_ascii.ply", tetraPlyAscii()},
                                                       {"tetra_binary.ply", tetraPlyBinary()}};
  for (const auto& [name, bytes] : files) {
    SCOPED_TRACE(name);
    const TriMesh mesh = importMesh(write(name, bytes), options);
    EXPECT_EQ(mesh.numTriangles(), 4);
    EXPECT_EQ(mesh.boundaryEdgeCount(), 0);
    expectSameVertexSet(mesh, expected, kExactTolerance);
    // A rigid pose keeps the volume; the winding stays outward.
    EXPECT_NEAR(signedVolume(mesh), 8.0 / 6.0 * 1e-9, 1e-12 * 1e-9);
  }
}

TEST_F(MeshImportTest, ColladaUnitAndUpAxisGiveZUpMetres) {
  // Z_UP in inches: axes unchanged, coordinates times 0.0254, node translation included.
  const TriMesh z_up = importMesh(write("z_up.dae", triangleDae("Z_UP", 0.0254)));
  expectSameVertexSet(z_up, {{0, 0, 4 * 0.0254}, {0.0254, 0, 4 * 0.0254}, {0, 2 * 0.0254, 4 * 0.0254}},
                      kFloatTolerance * 0.0254);
  // Y_UP in metres: the file's +y becomes +z and its +z becomes -y (right-handed).
  const TriMesh y_up = importMesh(write("y_up.dae", triangleDae("Y_UP", 1.0)));
  expectSameVertexSet(y_up, {{0, -4, 0}, {1, -4, 0}, {0, -4, 2}}, kFloatTolerance);
  EXPECT_NEAR(y_up.faceNormal(0).y(), -1.0, kExactTolerance);  // file normal +z -> -y
}

TEST_F(MeshImportTest, ExtensionIsCaseInsensitive) {
  EXPECT_TRUE(isSupportedMeshFile("a/B.DAE"));
  EXPECT_TRUE(isSupportedMeshFile("x.Stl"));
  EXPECT_FALSE(isSupportedMeshFile("x.gltf"));
  EXPECT_FALSE(isSupportedMeshFile("x"));
  EXPECT_EQ(importMesh(write("CUBE.OBJ", cubeObj())).numTriangles(), 12);
}

// Expects importMesh to throw MeshError whose message names the file and contains `needle`.
void expectMeshError(const fs::path& file, const std::string& needle, const MeshImportOptions& options = {}) {
  try {
    (void)importMesh(file, options);
    ADD_FAILURE() << "no error for " << file;
  } catch (const MeshError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.source(), file.string());
    EXPECT_NE(what.find(file.string()), std::string::npos) << what;
    EXPECT_NE(what.find(needle), std::string::npos) << what;
  }
}

TEST_F(MeshImportTest, BadFilesAndOptionsGiveClearErrors) {
  expectMeshError(dir_ / "missing.obj", "no such file");
  expectMeshError(write("model.gltf", "{}"), "unsupported mesh format '.gltf'");
  expectMeshError(dir_, "unsupported mesh format");
  fs::create_directories(dir_ / "folder.stl");
  expectMeshError(dir_ / "folder.stl", "not a regular file");
  expectMeshError(write("empty.stl", ""), "cannot read the mesh");
  expectMeshError(write("garbage.ply", "this is not a ply file\n"), "not a PLY file");
  expectMeshError(write("header.ply", "ply\nformat ascii 1.0\nelement vertex 3\n"), "no 'end_header'");
  expectMeshError(write("garbage.dae", "<COLLADA><library_geometries>"), "cannot read the mesh");
  expectMeshError(write("lines.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\n"), "cannot read the mesh");
  expectMeshError(write("bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"), "cannot read the mesh");
  expectMeshError(write("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"), "no valid triangle");
  const fs::path cube = write("cube.obj", cubeObj());
  MeshImportOptions options;
  options.scale = 0.0;
  expectMeshError(cube, "scale must be a finite number > 0", options);
  options.scale = std::numeric_limits<double>::quiet_NaN();
  expectMeshError(cube, "scale must be a finite number > 0", options);
  options = {};
  options.X_OF.linear() *= 2.0;
  expectMeshError(cube, "rigid transform", options);
  options = {};
  options.weld_tolerance_m = -1.0;
  expectMeshError(cube, "weld tolerance", options);
}

// Feeds truncated and byte-mutated copies of `bytes` to the importer: each must either load
// into a mesh with finite vertices or throw MeshError; any other exception or a crash fails.
void fuzzFile(const fs::path& dir, const std::string& name, const std::string& bytes, std::mt19937& rng,
              int mutations) {
  int loaded = 0;
  int rejected = 0;
  int reader_hung = 0;
  int reader_crashed = 0;
  auto attempt = [&](const std::string& content, const std::string& what) {
    const fs::path path = dir / name;
    {
      std::ofstream out(path, std::ios::binary | std::ios::trunc);
      out << content;
    }
    // The files are tiny: a reader still busy after half a second is hung (assimp's PLY reader
    // loops forever on some mutated headers).
    MeshImportOptions options;
    options.time_limit_s = 0.5;
    try {
      const TriMesh mesh = importMesh(path, options);
      for (int v = 0; v < mesh.numVertices(); ++v) ASSERT_TRUE(mesh.vertex(v).allFinite()) << what;
      ++loaded;
    } catch (const MeshError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(path.string()), std::string::npos) << what << ": " << message;
      reader_hung += message.find("did not finish") != std::string::npos ? 1 : 0;
      reader_crashed += message.find("crashed") != std::string::npos ? 1 : 0;
      ++rejected;
    }
  };
  // Truncations at 30 evenly spread lengths, including 0 and a few bytes.
  for (int i = 0; i < 30; ++i) {
    const std::size_t length = bytes.size() * static_cast<std::size_t>(i) / 30;
    attempt(bytes.substr(0, length), name + " truncated to " + std::to_string(length) + " bytes");
  }
  // Mutations: 1-8 random bytes replaced by random values or by characters a parser cares about.
  const std::string special = " \n-.0123456789eE+/<>\"{}#";
  std::uniform_int_distribution<std::size_t> position(0, bytes.size() - 1);
  std::uniform_int_distribution<int> count(1, 8);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<std::size_t> pick(0, special.size() - 1);
  for (int m = 0; m < mutations; ++m) {
    std::string mutated = bytes;
    const int n = count(rng);
    for (int k = 0; k < n; ++k) {
      const std::size_t p = position(rng);
      mutated[p] = (byte(rng) % 2 == 0) ? static_cast<char>(byte(rng)) : special[pick(rng)];
    }
    attempt(mutated, name + " mutation " + std::to_string(m));
  }
  std::cout << name << ": " << loaded << " loaded, " << rejected << " rejected (reader hung " << reader_hung
            << ", crashed " << reader_crashed << ")\n";
  EXPECT_GT(rejected, 0) << name;  // truncation to 0 bytes at least
  EXPECT_GT(loaded + rejected, 0);
}

TEST_F(MeshImportTest, TruncatedAndMutatedFilesGiveMeshErrorNeverACrash) {
  std::mt19937 rng(20261121);
  fuzzFile(dir_, "cube.obj", cubeObj(), rng, 100);
  fuzzFile(dir_, "tetra_ascii.stl", tetraStlAscii(), rng, 100);
  fuzzFile(dir_, "tetra_binary.stl", tetraStlBinary(), rng, 100);
  fuzzFile(dir_, "tetra_ascii.ply", tetraPlyAscii(), rng, 100);
  fuzzFile(dir_, "tetra_binary.ply", tetraPlyBinary(), rng, 100);
  fuzzFile(dir_, "triangle.dae", triangleDae("Z_UP", 0.0254), rng, 100);
}

// Plain corruptions on which assimp 5.2 itself crashes (segmentation fault, failed assertion)
// when called in-process: importMesh must turn them into MeshError and keep running.
TEST_F(MeshImportTest, FilesThatCrashAssimpGiveMeshError) {
  std::string no_count = triangleDae("Z_UP", 1.0);
  const std::string count_attribute = " count=\"9\"";
  no_count.erase(no_count.find(count_attribute), count_attribute.size());
  expectMeshError(write("no_count.dae", no_count), "");
  std::string short_body = tetraPlyAscii();
  short_body.resize(short_body.find("end_header\n") + std::string("end_header\n0 0 0\n").size());
  expectMeshError(write("short_body.ply", short_body), "");
  // The importer still works afterwards.
  EXPECT_EQ(importMesh(write("cube.obj", cubeObj())).numTriangles(), 12);
}

// The repository's copies of the DRC meshes (scenes/meshes/gazebo-drc).
fs::path repoMesh(const std::string& relative) {
  return fs::path(FULLARM_SOURCE_DIR) / "scenes" / "meshes" / "gazebo-drc" / relative;
}

struct BoundingBox {
  Eigen::Vector3d min = Eigen::Vector3d::Constant(1e300);
  Eigen::Vector3d max = Eigen::Vector3d::Constant(-1e300);
  Eigen::Vector3d size() const { return max - min; }
};

BoundingBox boundingBox(const TriMesh& mesh) {
  BoundingBox box;
  for (int v = 0; v < mesh.numVertices(); ++v) {
    box.min = box.min.cwiseMin(mesh.vertex(v));
    box.max = box.max.cwiseMax(mesh.vertex(v));
  }
  return box;
}

TEST(MeshImportDrcTest, ValveWallMatchesItsSdfCollisionBox) {
  // model.sdf: collision box 1.2192 x 0.00952 x 2.4384 m at (0.6096, 0.00476, 1.2192); the
  // visual mesh sits at (-0.004536186, -0.003571748, 0). Unit (inch) and Z_UP must both be right
  // for the mesh to land on the box.
  MeshImportOptions options;
  options.X_OF = Eigen::Translation3d(-0.004536186, -0.003571748, 0.0);
  const TriMesh wall = importMesh(repoMesh("drc_practice_valve_wall/five_dice_wall.dae"), options);
  const BoundingBox box = boundingBox(wall);
  constexpr double kMeshVsSdfTolerance = 0.5e-3;  // the SDF box is the mesh's rounded extent
  EXPECT_NEAR(box.min.x(), 0.0, kMeshVsSdfTolerance);
  EXPECT_NEAR(box.max.x(), 1.2192, kMeshVsSdfTolerance);
  EXPECT_NEAR(box.min.y(), 0.0, kMeshVsSdfTolerance);
  EXPECT_NEAR(box.max.y(), 0.00952, kMeshVsSdfTolerance);
  EXPECT_NEAR(box.min.z(), 0.0, kMeshVsSdfTolerance);
  EXPECT_NEAR(box.max.z(), 2.4384, kMeshVsSdfTolerance);
  EXPECT_GT(wall.numTriangles(), 1500);  // 3,280 in the file, both windings; the outward 1,640 kept
}

TEST(MeshImportDrcTest, WheelAndTrussHaveTheirModelSizes) {
  // Wheel valve: the hand wheel's rim radius is 0.124968 m (model.sdf attachment pose z,
  // 4.92 in); its axis is x in the mesh file.
  const TriMesh wheel = importMesh(repoMesh("drc_practice_wheel_valve/valve_wheel.dae"));
  const BoundingBox w = boundingBox(wheel);
  EXPECT_NEAR(w.size().y(), 2 * 0.124968, 1e-3);
  EXPECT_NEAR(w.size().z(), 2 * 0.124968, 1e-3);
  EXPECT_LT(w.size().x(), 0.06);
  // Truss: the size box in its model.sdf is 0.25 x 1.5 x 0.25 m, long axis y.
  const TriMesh truss = importMesh(repoMesh("drc_practice_truss/truss.dae"));
  const BoundingBox t = boundingBox(truss);
  EXPECT_NEAR(t.size().y(), 1.5, 0.03);
  EXPECT_NEAR(t.size().x(), 0.25, 0.05);
  EXPECT_NEAR(t.size().z(), 0.25, 0.05);
}

// Every .dae under `dir` loads, keeps at least the outward half of its triangles and has the size
// of a DRC model; returns how many were checked.
int checkDrcFolder(const fs::path& dir) {
  int files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (entry.path().extension() != ".dae") continue;
    SCOPED_TRACE(entry.path().string());
    ++files;
    const TriMesh mesh = importMesh(entry.path());
    // Some files are double-sided solids: the default import keeps their outward half.
    MeshImportOptions as_is;
    as_is.collapse_double_sided_solids = false;
    const int file_triangles = importMesh(entry.path(), as_is).numTriangles();
    EXPECT_GT(file_triangles, 100);
    EXPECT_GE(2 * mesh.numTriangles(), file_triangles);
    EXPECT_LE(mesh.numTriangles(), file_triangles);
    const BoundingBox box = boundingBox(mesh);
    // Every DRC model is between 1 cm and 3 m across: a unit error (inch vs metre) would miss.
    EXPECT_GT(box.size().maxCoeff(), 0.01);
    EXPECT_LT(box.size().maxCoeff(), 3.0);
  }
  return files;
}

// The repository's copies (scenes/meshes/gazebo-drc), on every machine.
TEST(MeshImportDrcTest, EveryDaeOfTheRepositoryDrcFolderLoads) {
  EXPECT_EQ(checkDrcFolder(repoMesh("")), 3);
}

// The whole DRC folder (nine models) when FULLARM_DRC_MESH_DIR names it; the three the project
// uses are checked above everywhere.
TEST(MeshImportDrcTest, EveryDaeOfTheFullDrcFolderLoads) {
  const fs::path dir = FULLARM_DRC_MESH_DIR;
  if (!fs::is_directory(dir)) GTEST_SKIP() << "DRC mesh folder not found: " << dir;
  EXPECT_EQ(checkDrcFolder(dir), 9);
}

TEST(MeshImportDrcTest, TruncatedDrcWallGivesMeshError) {
  std::ifstream in(repoMesh("drc_practice_valve_wall/five_dice_wall.dae"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 100000u);
  const fs::path dir = fullarm::test::scratchDir("fullarm_truncated_wall");
  const fs::path path = dir / "five_dice_wall.dae";
  for (int i = 1; i < 8; ++i) {
    {
      std::ofstream out(path, std::ios::binary | std::ios::trunc);
      out << bytes.substr(0, bytes.size() * static_cast<std::size_t>(i) / 8);
    }
    EXPECT_THROW((void)importMesh(path), MeshError) << "truncated at " << i << "/8";
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fullarm::haptics
