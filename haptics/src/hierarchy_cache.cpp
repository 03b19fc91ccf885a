#include "fullarm/haptics/hierarchy_cache.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <type_traits>
#include <vector>

namespace fullarm::haptics {

namespace {

constexpr char kMagic[8] = {'F', 'A', 'S', 'N', 'C', 'H', '\r', '\n'};
// Layout of the file itself (what follows the magic); raised when the layout changes.
constexpr std::uint32_t kFileFormat = 1;

// Word-wise 64-bit hash (multiply, rotate, xor; the finaliser of MurmurHash3): fast on the
// tens of megabytes of a million-triangle mesh, and enough for a cache key.
class Hasher {
 public:
  void add(const void* data, std::size_t bytes) noexcept {
    const auto* p = static_cast<const unsigned char*>(data);
    for (; bytes >= 8; bytes -= 8, p += 8) {
      std::uint64_t w = 0;
      std::memcpy(&w, p, 8);
      mix(w);
    }
    std::uint64_t tail = 0;
    std::memcpy(&tail, p, bytes);
    mix(tail ^ (static_cast<std::uint64_t>(bytes) << 56));
  }
  [[nodiscard]] std::uint64_t value() const noexcept {
    std::uint64_t h = h_;
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdULL;
    h ^= h >> 33;
    h *= 0xc4ceb9fe1a85ec53ULL;
    h ^= h >> 33;
    return h;
  }

 private:
  void mix(std::uint64_t w) noexcept {
    w *= 0x87c37b91114253d5ULL;
    w = (w << 31) | (w >> 33);
    w *= 0x4cf5ad432745937fULL;
    h_ ^= w;
    h_ = ((h_ << 27) | (h_ >> 37)) * 5 + 0x52dce729;
  }
  std::uint64_t h_ = 0x9e3779b97f4a7c15ULL;
};

// Appends trivially copyable values to a byte buffer.
class Writer {
 public:
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const std::size_t n = bytes_.size();
    bytes_.resize(n + sizeof(T));
    std::memcpy(bytes_.data() + n, &v, sizeof(T));
  }
  void putVector3(const Eigen::Vector3d& v) {
    for (int k = 0; k < 3; ++k) put(v[k]);
  }
  template <class T>
  void putArray(const std::vector<T>& v) {
    put(static_cast<std::uint64_t>(v.size()));
    for (const T& x : v) put(x);
  }
  void putArray(const std::vector<Eigen::Vector4f>& v) {
    put(static_cast<std::uint64_t>(v.size()));
    for (const Eigen::Vector4f& x : v) {
      for (int k = 0; k < 4; ++k) put(x[k]);
    }
  }
  [[nodiscard]] std::vector<char>& bytes() noexcept { return bytes_; }

 private:
  std::vector<char> bytes_;
};

// Reads them back with bounds checks (a short file fails, it is never read past its end).
class Reader {
 public:
  Reader(const char* data, std::size_t size) : p_(data), end_(data + size) {}
  template <class T>
  bool get(T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (static_cast<std::size_t>(end_ - p_) < sizeof(T)) return false;
    std::memcpy(&v, p_, sizeof(T));
    p_ += sizeof(T);
    return true;
  }
  bool getVector3(Eigen::Vector3d& v) {
    for (int k = 0; k < 3; ++k) {
      if (!get(v[k])) return false;
    }
    return true;
  }
  template <class T>
  bool getArray(std::vector<T>& v, std::uint64_t max_size) {
    std::uint64_t n = 0;
    if (!get(n) || n > max_size || n > static_cast<std::uint64_t>(end_ - p_) / sizeof(T)) return false;
    v.resize(static_cast<std::size_t>(n));
    for (T& x : v) {
      if (!get(x)) return false;
    }
    return true;
  }
  bool getArray(std::vector<Eigen::Vector4f>& v, std::uint64_t max_size) {
    std::uint64_t n = 0;
    if (!get(n) || n > max_size || n > static_cast<std::uint64_t>(end_ - p_) / (4 * sizeof(float))) return false;
    v.resize(static_cast<std::size_t>(n));
    for (Eigen::Vector4f& x : v) {
      for (int k = 0; k < 4; ++k) {
        if (!get(x[k])) return false;
      }
    }
    return true;
  }
  [[nodiscard]] bool atEnd() const noexcept { return p_ == end_; }

 private:
  const char* p_;
  const char* end_;
};

void putNode(Writer& w, const SnchNode& n) {
  w.putVector3(n.centre_m);
  w.put(n.radius_m);
  w.putVector3(n.box_half_m);
  w.put(n.left);
  w.put(n.right);
  w.putVector3(n.cone_axis);
  w.put(n.cone_half_angle_rad);
  w.put(n.cone_cos);
  w.put(n.cone_sin);
  w.put(n.triangle);
  w.put(static_cast<std::uint8_t>(n.cone_two_sided ? 1 : 0));
}

bool getNode(Reader& r, SnchNode& n) {
  std::uint8_t two_sided = 0;
  const bool ok = r.getVector3(n.centre_m) && r.get(n.radius_m) && r.getVector3(n.box_half_m) && r.get(n.left) &&
                  r.get(n.right) && r.getVector3(n.cone_axis) && r.get(n.cone_half_angle_rad) && r.get(n.cone_cos) &&
                  r.get(n.cone_sin) && r.get(n.triangle) && r.get(two_sided);
  n.cone_two_sided = two_sided != 0;
  return ok && two_sided <= 1;
}

// The payload: everything but the magic, the header and the checksum.
std::vector<char> payload(const MeshHierarchy& h) {
  Writer w;
  const SnchTree& t = h.tree;
  w.put(static_cast<std::uint64_t>(t.nodes.size()));
  for (const SnchNode& n : t.nodes) putNode(w, n);
  w.put(static_cast<std::uint8_t>(t.convex ? 1 : 0));
  w.putArray(t.vertex_graph.offset);
  w.putArray(t.vertex_graph.neighbours);
  w.put(t.support_start_vertex);
  w.putVector3(t.bracket.a_m);
  w.putVector3(t.bracket.b_m);
  w.put(t.bracket.outer_radius_m);
  w.put(t.bracket.inner_radius_m);
  w.put(t.support_table.cells_per_edge);
  w.putArray(t.support_table.start_vertex);
  w.putArray(h.cones.vertex);
  w.putArray(h.cones.edge);
  return std::move(w.bytes());
}

struct Header {
  std::uint32_t file_format = kFileFormat;
  std::uint32_t snch_version = kSnchBuildVersion;
  std::uint32_t cones_version = kNeighbourConesBuildVersion;
  std::uint32_t reserved = 0;
  std::uint64_t mesh_hash = 0;
  std::int32_t vertices = 0;
  std::int32_t triangles = 0;
  std::int32_t edges = 0;
  std::int32_t reserved2 = 0;
  std::uint64_t payload_bytes = 0;
  std::uint64_t payload_hash = 0;
};

std::uint64_t hashOf(const char* bytes, std::size_t size) {
  Hasher h;
  h.add(bytes, size);
  return h.value();
}

// Checks a loaded tree and cones against the mesh: counts, indices in range, every triangle in
// exactly one leaf. Fills leaf_of_triangle.
bool validHierarchy(MeshHierarchy& h, const TriMesh& mesh, std::string& why) {
  SnchTree& t = h.tree;
  const int nt = mesh.numTriangles();
  const int nv = mesh.numVertices();
  const auto n_nodes = static_cast<int>(t.nodes.size());
  if (n_nodes != 2 * nt - 1) {
    why = "holds " + std::to_string(n_nodes) + " nodes, expected " + std::to_string(2 * nt - 1);
    return false;
  }
  t.leaf_of_triangle.assign(static_cast<std::size_t>(nt), -1);
  for (int i = 0; i < n_nodes; ++i) {
    const SnchNode& n = t.nodes[static_cast<std::size_t>(i)];
    if (n.isLeaf()) {
      if (n.triangle < 0 || n.triangle >= nt || t.leaf_of_triangle[static_cast<std::size_t>(n.triangle)] >= 0) {
        why = "node " + std::to_string(i) + ": leaf triangle out of range or repeated";
        return false;
      }
      t.leaf_of_triangle[static_cast<std::size_t>(n.triangle)] = i;
    } else if (n.left <= i || n.left >= n_nodes || n.right <= i || n.right >= n_nodes) {
      why = "node " + std::to_string(i) + ": child index out of range";
      return false;
    }
  }
  const VertexGraph& g = t.vertex_graph;
  if (t.convex) {
    if (g.offset.size() != static_cast<std::size_t>(nv) + 1 || g.offset.front() != 0 ||
        g.offset.back() != static_cast<int>(g.neighbours.size()) || !std::is_sorted(g.offset.begin(), g.offset.end()) ||
        std::any_of(g.neighbours.begin(), g.neighbours.end(), [nv](int v) { return v < 0 || v >= nv; }) ||
        t.support_start_vertex < 0 || t.support_start_vertex >= nv ||
        std::any_of(t.support_table.start_vertex.begin(), t.support_table.start_vertex.end(),
                    [nv](int v) { return v < 0 || v >= nv; })) {
      why = "convex-link data out of range";
      return false;
    }
  }
  if (h.cones.vertex.size() != static_cast<std::size_t>(nv) ||
      h.cones.edge.size() != static_cast<std::size_t>(mesh.numEdges())) {
    why = "neighbour cones of another size";
    return false;
  }
  return true;
}

}  // namespace

std::uint64_t meshContentHash(const TriMesh& mesh) noexcept {
  Hasher h;
  const std::int64_t counts[2] = {mesh.numVertices(), mesh.numTriangles()};
  h.add(counts, sizeof(counts));
  for (int v = 0; v < mesh.numVertices(); ++v) h.add(mesh.vertex(v).data(), 3 * sizeof(double));
  for (int t = 0; t < mesh.numTriangles(); ++t) h.add(mesh.triangle(t).data(), 3 * sizeof(int));
  return h.value();
}

MeshHierarchy buildMeshHierarchy(const TriMesh& mesh) {
  return {buildSnchTree(mesh), computeNeighbourCones(mesh)};
}

void saveMeshHierarchy(const MeshHierarchy& hierarchy, const TriMesh& mesh, const std::filesystem::path& file) {
  const std::vector<char> body = payload(hierarchy);
  Header header;
  header.mesh_hash = meshContentHash(mesh);
  header.vertices = mesh.numVertices();
  header.triangles = mesh.numTriangles();
  header.edges = mesh.numEdges();
  header.payload_bytes = body.size();
  header.payload_hash = hashOf(body.data(), body.size());
  // Beside the final name, then renamed into place (atomic on one file system).
  static std::atomic<unsigned> counter{0};
  std::filesystem::path temp = file;
  temp += ".tmp" + std::to_string(::getpid()) + "." + std::to_string(counter.fetch_add(1));
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    out.write(kMagic, sizeof(kMagic));
    out.write(reinterpret_cast<const char*>(&header), sizeof(header));
    out.write(body.data(), static_cast<std::streamsize>(body.size()));
    out.close();
    if (!out) throw std::runtime_error(temp.string() + ": cannot write the hierarchy");
  }
  std::error_code ec;
  std::filesystem::rename(temp, file, ec);
  if (ec) {
    std::filesystem::remove(temp, ec);
    throw std::runtime_error(file.string() + ": cannot write the hierarchy (" + ec.message() + ")");
  }
}

std::optional<MeshHierarchy> loadMeshHierarchy(const TriMesh& mesh, const std::filesystem::path& file,
                                               std::string* why) {
  std::string reason;
  auto fail = [&](std::string text) -> std::optional<MeshHierarchy> {
    if (why != nullptr) *why = file.string() + ": " + std::move(text);
    return std::nullopt;
  };
  std::ifstream in(file, std::ios::binary | std::ios::ate);
  if (!in) return fail("no such file");
  const std::streamoff size = in.tellg();
  if (size < 0) return fail("cannot read");
  std::vector<char> bytes(static_cast<std::size_t>(size));
  in.seekg(0);
  if (!in.read(bytes.data(), size)) return fail("cannot read");
  if (bytes.size() < sizeof(kMagic) + sizeof(Header) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    return fail("not a hierarchy file");
  }
  Header header;
  std::memcpy(&header, bytes.data() + sizeof(kMagic), sizeof(Header));
  if (header.file_format != kFileFormat)
    return fail("file format " + std::to_string(header.file_format) + ", expected " + std::to_string(kFileFormat));
  if (header.snch_version != kSnchBuildVersion || header.cones_version != kNeighbourConesBuildVersion) {
    return fail("stale: built by version " + std::to_string(header.snch_version) + "/" +
                std::to_string(header.cones_version) + ", expected " + std::to_string(kSnchBuildVersion) + "/" +
                std::to_string(kNeighbourConesBuildVersion));
  }
  if (header.mesh_hash != meshContentHash(mesh) || header.vertices != mesh.numVertices() ||
      header.triangles != mesh.numTriangles() || header.edges != mesh.numEdges()) {
    return fail("stale: saved for another mesh (content hash or counts differ)");
  }
  const std::size_t offset = sizeof(kMagic) + sizeof(Header);
  if (bytes.size() - offset != header.payload_bytes) return fail("truncated or extended");
  const char* body = bytes.data() + offset;
  const std::size_t body_size = bytes.size() - offset;
  if (hashOf(body, body_size) != header.payload_hash) return fail("corrupt (checksum)");
  MeshHierarchy h;
  Reader r(body, body_size);
  std::uint64_t n_nodes = 0;
  if (!r.get(n_nodes) || n_nodes != static_cast<std::uint64_t>(2 * mesh.numTriangles() - 1))
    return fail("bad node count");
  h.tree.nodes.resize(static_cast<std::size_t>(n_nodes));
  for (SnchNode& n : h.tree.nodes) {
    if (!getNode(r, n)) return fail("truncated nodes");
  }
  std::uint8_t convex = 0;
  const auto limit = static_cast<std::uint64_t>(body_size);
  if (!r.get(convex) || convex > 1 || !r.getArray(h.tree.vertex_graph.offset, limit) ||
      !r.getArray(h.tree.vertex_graph.neighbours, limit) || !r.get(h.tree.support_start_vertex) ||
      !r.getVector3(h.tree.bracket.a_m) || !r.getVector3(h.tree.bracket.b_m) || !r.get(h.tree.bracket.outer_radius_m) ||
      !r.get(h.tree.bracket.inner_radius_m) || !r.get(h.tree.support_table.cells_per_edge) ||
      !r.getArray(h.tree.support_table.start_vertex, limit) || !r.getArray(h.cones.vertex, limit) ||
      !r.getArray(h.cones.edge, limit) || !r.atEnd()) {
    return fail("truncated or malformed");
  }
  h.tree.convex = convex != 0;
  if (!validHierarchy(h, mesh, reason)) return fail(reason);
  return h;
}

std::filesystem::path hierarchyCacheFile(const TriMesh& mesh, const std::filesystem::path& cache_dir) {
  std::ostringstream name;
  name << std::hex;
  name.width(16);
  name.fill('0');
  name << meshContentHash(mesh);
  return cache_dir / (name.str() + ".snch");
}

MeshHierarchy hierarchyFromCache(const TriMesh& mesh, const std::filesystem::path& cache_dir,
                                 HierarchyCacheOutcome* outcome) {
  const std::filesystem::path file = hierarchyCacheFile(mesh, cache_dir);
  const bool existed = std::filesystem::exists(file);
  if (existed) {
    if (std::optional<MeshHierarchy> h = loadMeshHierarchy(mesh, file)) {
      if (outcome != nullptr) *outcome = HierarchyCacheOutcome::kLoaded;
      return std::move(*h);
    }
  }
  MeshHierarchy h = buildMeshHierarchy(mesh);
  std::error_code ec;
  std::filesystem::create_directories(cache_dir, ec);
  if (ec) throw std::runtime_error(cache_dir.string() + ": cannot create the hierarchy cache (" + ec.message() + ")");
  saveMeshHierarchy(h, mesh, file);
  if (outcome != nullptr)
    *outcome = existed ? HierarchyCacheOutcome::kRebuiltStale : HierarchyCacheOutcome::kBuiltAndSaved;
  return h;
}

}  // namespace fullarm::haptics
