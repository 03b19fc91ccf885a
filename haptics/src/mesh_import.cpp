#include "fullarm/haptics/mesh_import.hpp"

#include "fullarm/haptics/mesh_repair.hpp"
#include "fullarm/haptics/mesh_subdivision.hpp"

#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fcntl.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <limits>
#include <new>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <utility>
#include <vector>

namespace fullarm::haptics {
namespace {

// A defect found while reading; the caller adds the file name (MeshError).
class ImportDefect : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct RawMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> triangles;
};

std::string lowerExtension(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

Eigen::Matrix4d toEigen(const aiMatrix4x4& m) {
  Eigen::Matrix4d e;
  e << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
  return e;
}

void checkOptions(const std::string& source, const MeshImportOptions& options) {
  if (!std::isfinite(options.scale) || options.scale <= 0.0) {
    std::ostringstream msg;
    msg << "import scale must be a finite number > 0 (metres per file unit), got " << options.scale;
    throw MeshError(source, msg.str());
  }
  const Eigen::Matrix3d R = options.X_OF.linear();
  constexpr double kRotationTolerance = 1e-9;
  if (!options.X_OF.matrix().allFinite() || !(R.transpose() * R).isIdentity(kRotationTolerance) ||
      R.determinant() < 0.0) {
    throw MeshError(source, "import pose X_OF must be a finite rigid transform (orthonormal rotation, det +1)");
  }
  if (!std::isfinite(options.weld_tolerance_m) || options.weld_tolerance_m < 0.0) {
    std::ostringstream msg;
    msg << "weld tolerance must be a finite value >= 0 m, got " << options.weld_tolerance_m;
    throw MeshError(source, msg.str());
  }
  if (!std::isfinite(options.max_edge_m) || options.max_edge_m < 0.0) {
    std::ostringstream msg;
    msg << "refinement edge length max_edge_m must be a finite value >= 0 m (0: off), got " << options.max_edge_m;
    throw MeshError(source, msg.str());
  }
  if (!std::isfinite(options.time_limit_s) || options.time_limit_s <= 0.0) {
    std::ostringstream msg;
    msg << "import time limit must be a finite number > 0 s, got " << options.time_limit_s;
    throw MeshError(source, msg.str());
  }
}

// assimp 5.2's PLY reader loops forever or crashes on a truncated header: require the magic
// line and an end_header line within the first 64 KiB before it sees the file.
void checkPlyHeader(const std::filesystem::path& file) {
  constexpr std::size_t kMaxHeaderBytes = 64 * 1024;
  std::ifstream in(file, std::ios::binary);
  std::string head(kMaxHeaderBytes, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  if (head.rfind("ply\n", 0) != 0 && head.rfind("ply\r\n", 0) != 0) {
    throw ImportDefect("not a PLY file: the first line must be 'ply'");
  }
  const std::size_t end = head.find("\nend_header");
  if (end == std::string::npos) {
    throw ImportDefect("PLY header has no 'end_header' line in its first 64 KiB (truncated file?)");
  }
  if (head.find("\nformat ") == std::string::npos || head.find("\nformat ") > end) {
    throw ImportDefect("PLY header has no 'format' line");
  }
}

// Accumulates the triangles of every node (depth first) with the node's transform.
class Flattener {
 public:
  Flattener(const aiScene& scene, const Eigen::Matrix4d& X_OR) : scene_(scene), X_OR_(X_OR) {}

  void visit(const aiNode& node, const Eigen::Matrix4d& X_RP, int depth) {
    // A malformed file could nest nodes arbitrarily deep; recursion depth is bounded.
    constexpr int kMaxDepth = 1000;
    if (depth > kMaxDepth) throw ImportDefect("scene graph nested deeper than 1000 nodes");
    const Eigen::Matrix4d X_RN = X_RP * toEigen(node.mTransformation);
    if (!X_RN.allFinite()) {
      throw ImportDefect("node '" + std::string(node.mName.C_Str()) + "' has a non-finite transform");
    }
    const Eigen::Matrix4d X_ON = X_OR_ * X_RN;
    for (unsigned i = 0; i < node.mNumMeshes; ++i) {
      const unsigned mesh_index = node.mMeshes[i];
      if (mesh_index >= scene_.mNumMeshes || scene_.mMeshes[mesh_index] == nullptr) {
        throw ImportDefect("node '" + std::string(node.mName.C_Str()) + "' refers to a missing mesh");
      }
      addMesh(*scene_.mMeshes[mesh_index], X_ON);
    }
    for (unsigned c = 0; c < node.mNumChildren; ++c) {
      if (node.mChildren[c] != nullptr) visit(*node.mChildren[c], X_RN, depth + 1);
    }
  }

  RawMesh take() { return std::move(mesh_); }

 private:
  void addMesh(const aiMesh& mesh, const Eigen::Matrix4d& X_ON) {
    if ((mesh.mPrimitiveTypes & aiPrimitiveType_TRIANGLE) == 0 || mesh.mVertices == nullptr) return;
    const std::size_t base = mesh_.vertices.size();
    if (base + mesh.mNumVertices > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
      throw ImportDefect("more than 2^31 vertices");
    }
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& p = mesh.mVertices[v];
      const Eigen::Vector4d p_O = X_ON * Eigen::Vector4d(p.x, p.y, p.z, 1.0);
      mesh_.vertices.emplace_back(p_O.head<3>());
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines of a mixed mesh
      Eigen::Vector3i tri;
      for (int k = 0; k < 3; ++k) {
        const unsigned index = face.mIndices[k];
        if (index >= mesh.mNumVertices) {
          throw ImportDefect("mesh '" + std::string(mesh.mName.C_Str()) + "' face " + std::to_string(f) +
                             " refers to vertex " + std::to_string(index) + " of " + std::to_string(mesh.mNumVertices));
        }
        tri[k] = static_cast<int>(base + index);
      }
      mesh_.triangles.push_back(tri);
    }
  }

  const aiScene& scene_;
  Eigen::Matrix4d X_OR_;  // root of the file's scene graph -> mesh frame O, with scale
  RawMesh mesh_;
};

// Reads the file with assimp in this process. @throws ImportDefect
RawMesh readWithAssimp(const std::filesystem::path& file, const Eigen::Matrix4d& X_OR) {
  Assimp::Importer importer;
  // Point and line primitives carry no surface: drop them instead of keeping empty meshes.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const unsigned flags = aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_ValidateDataStructure;
  const aiScene* scene = nullptr;
  try {
    scene = importer.ReadFile(file.string(), flags);
  } catch (const std::bad_alloc&) {
    throw ImportDefect("out of memory while reading the file (corrupt element counts?)");
  } catch (const std::exception& e) {
    throw ImportDefect(std::string("cannot read the mesh: ") + e.what());
  }
  if (scene == nullptr) {
    std::string why = importer.GetErrorString();
    if (why.empty()) why = "unknown error";
    throw ImportDefect("cannot read the mesh (malformed or truncated file?): " + why);
  }
  if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0 || scene->mRootNode == nullptr) {
    throw ImportDefect("the file holds an incomplete scene (no geometry)");
  }
  Flattener flattener(*scene, X_OR);
  flattener.visit(*scene->mRootNode, Eigen::Matrix4d::Identity(), 0);
  return flattener.take();
}

// Pipe message from the reader process: one status byte, then either a length-prefixed
// error text or the vertex and triangle counts and arrays.
constexpr std::uint8_t kStatusOk = 0;
constexpr std::uint8_t kStatusDefect = 1;

bool writeAll(int fd, const void* data, std::size_t size) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

[[noreturn]] void runReaderChild(int fd, const std::filesystem::path& file, const Eigen::Matrix4d& X_OR) {
  std::string message;
  std::uint8_t status = kStatusOk;
  RawMesh mesh;
  try {
    mesh = readWithAssimp(file, X_OR);
  } catch (const std::exception& e) {
    status = kStatusDefect;
    message = e.what();
  }
  bool ok = writeAll(fd, &status, 1);
  if (status == kStatusDefect) {
    const std::uint64_t length = message.size();
    ok = ok && writeAll(fd, &length, sizeof length) && writeAll(fd, message.data(), message.size());
  } else {
    const std::uint64_t counts[2] = {mesh.vertices.size(), mesh.triangles.size()};
    ok = ok && writeAll(fd, counts, sizeof counts);
    for (const Eigen::Vector3d& v : mesh.vertices) ok = ok && writeAll(fd, v.data(), 3 * sizeof(double));
    for (const Eigen::Vector3i& t : mesh.triangles) ok = ok && writeAll(fd, t.data(), 3 * sizeof(int));
  }
  ::close(fd);
  // _exit: no atexit handlers or stdio flushes of the parent's state run in the child.
  ::_exit(ok ? 0 : 3);
}

// Reads everything from `fd` until EOF or the deadline; returns false on timeout.
bool readUntilEof(int fd, std::chrono::steady_clock::time_point deadline, std::string& out) {
  char buffer[65536];
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    pollfd pfd{fd, POLLIN, 0};
    const int ready = ::poll(&pfd, 1, static_cast<int>(std::min<long long>(left.count(), 1000)));
    if (ready < 0 && errno == EINTR) continue;
    if (ready < 0) throw ImportDefect(std::string("poll on the reader pipe failed: ") + std::strerror(errno));
    if (ready == 0) continue;
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw ImportDefect(std::string("read from the reader pipe failed: ") + std::strerror(errno));
    if (n == 0) return true;
    out.append(buffer, static_cast<std::size_t>(n));
  }
}

RawMesh decodeMessage(const std::string& bytes) {
  std::size_t pos = 0;
  auto take = [&](void* dst, std::size_t size) {
    if (bytes.size() - pos < size) throw ImportDefect("the mesh reader process sent an incomplete result");
    std::memcpy(dst, bytes.data() + pos, size);
    pos += size;
  };
  std::uint8_t status = 0;
  take(&status, 1);
  if (status == kStatusDefect) {
    std::uint64_t length = 0;
    take(&length, sizeof length);
    if (length > bytes.size() - pos) throw ImportDefect("the mesh reader process sent an incomplete result");
    throw ImportDefect(bytes.substr(pos, static_cast<std::size_t>(length)));
  }
  std::uint64_t counts[2] = {0, 0};
  take(counts, sizeof counts);
  const std::uint64_t expected = counts[0] * 3 * sizeof(double) + counts[1] * 3 * sizeof(int);
  if (counts[0] > bytes.size() || counts[1] > bytes.size() || expected != bytes.size() - pos) {
    throw ImportDefect("the mesh reader process sent an inconsistent result");
  }
  RawMesh mesh;
  mesh.vertices.resize(static_cast<std::size_t>(counts[0]));
  mesh.triangles.resize(static_cast<std::size_t>(counts[1]));
  for (Eigen::Vector3d& v : mesh.vertices) take(v.data(), 3 * sizeof(double));
  for (Eigen::Vector3i& t : mesh.triangles) take(t.data(), 3 * sizeof(int));
  return mesh;
}

// Runs readWithAssimp in a forked child so that a crash or a hang of the reader on a malformed
// file becomes an ImportDefect here.
RawMesh readIsolated(const std::filesystem::path& file, const Eigen::Matrix4d& X_OR, double time_limit_s) {
  // Pending output of the caller must not be written twice (by the child as well).
  std::fflush(nullptr);
  int fds[2];
  if (::pipe(fds) != 0) throw ImportDefect(std::string("cannot create a pipe: ") + std::strerror(errno));
  const pid_t child = ::fork();
  if (child < 0) {
    const int err = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    throw ImportDefect(std::string("cannot start the mesh reader process: ") + std::strerror(err));
  }
  if (child == 0) {
    ::close(fds[0]);
    // assimp prints its internal assertion failures on stderr; the result goes through the pipe.
    const int null_fd = ::open("/dev/null", O_WRONLY);
    if (null_fd >= 0) ::dup2(null_fd, STDERR_FILENO);
    runReaderChild(fds[1], file, X_OR);
  }
  ::close(fds[1]);
  const auto deadline =
      std::chrono::steady_clock::now() +
      std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(time_limit_s));
  std::string bytes;
  bool finished = false;
  try {
    finished = readUntilEof(fds[0], deadline, bytes);
  } catch (...) {
    ::kill(child, SIGKILL);
    ::waitpid(child, nullptr, 0);
    ::close(fds[0]);
    throw;
  }
  ::close(fds[0]);
  if (!finished) ::kill(child, SIGKILL);
  int status = 0;
  while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  if (!finished) {
    std::ostringstream msg;
    msg << "the mesh reader did not finish within " << time_limit_s << " s (malformed file?)";
    throw ImportDefect(msg.str());
  }
  if (WIFSIGNALED(status)) {
    throw ImportDefect("the mesh reader (assimp) crashed on this file with signal " + std::to_string(WTERMSIG(status)) +
                       " (malformed or truncated file?)");
  }
  if (!bytes.empty() && bytes[0] == static_cast<char>(kStatusDefect)) return decodeMessage(bytes);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    throw ImportDefect("the mesh reader (assimp) failed on this file (exit status " +
                       std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) +
                       "; malformed or truncated file?)");
  }
  return decodeMessage(bytes);
}

}  // namespace

bool isSupportedMeshFile(const std::filesystem::path& file) {
  const std::string ext = lowerExtension(file);
  return ext == ".dae" || ext == ".obj" || ext == ".stl" || ext == ".ply";
}

TriMesh importMesh(const std::filesystem::path& file, const MeshImportOptions& options) {
  const std::string source = file.string();
  checkOptions(source, options);
  const std::string ext = lowerExtension(file);
  if (!isSupportedMeshFile(file)) {
    throw MeshError(source,
                    "unsupported mesh format '" + file.extension().string() + "' (expected .dae, .obj, .stl or .ply)");
  }
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) {
    throw MeshError(source, std::filesystem::exists(file, ec) ? "is not a regular file" : "no such file");
  }

  // assimp's COLLADA reader turns every file to Y up (rotating a Z_UP file by -90 deg about x);
  // fullarm is z up, so rotate back by +90 deg about x: y -> z, z -> -y.
  Eigen::Matrix4d X_OR = Eigen::Matrix4d::Identity();
  if (ext == ".dae") X_OR.block<3, 3>(0, 0) << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  Eigen::Matrix4d scale = Eigen::Matrix4d::Identity();
  scale.block<3, 3>(0, 0) *= options.scale;
  X_OR = options.X_OF.matrix() * scale * X_OR;

  RawMesh raw;
  try {
    if (ext == ".ply") checkPlyHeader(file);
    raw = readIsolated(file, X_OR, options.time_limit_s);
  } catch (const ImportDefect& e) {
    throw MeshError(source, e.what());
  }
  if (raw.triangles.empty()) {
    throw MeshError(source, "the file holds no triangle (only points/lines, or no geometry)");
  }
  TriMesh mesh = TriMesh::build(source, std::move(raw.vertices), std::move(raw.triangles), options.weld_tolerance_m);
  if (options.collapse_double_sided_solids) mesh = collapseDoubleSidedSolids(mesh);
  if (options.max_edge_m > 0.0) mesh = refineLongEdges(mesh, options.max_edge_m);
  return mesh;
}

}  // namespace fullarm::haptics
