#pragma once
/// @file
/// Saved hierarchies: an object mesh's SNCH tree and neighbour-rejection cones written to a file
/// and read back, keyed by the mesh's content hash and the versions of the two builds, so a
/// scene of million-triangle CAD meshes loads without rebuilding them. A saved hierarchy whose
/// key does not match the mesh (the mesh changed, or the build did) is stale: it is rejected and
/// rebuilt. A scene names its cache folder with `hierarchy_cache:` (docs/haptics.md, "Scene
/// files"); CollisionWorld::Options::hierarchy_cache_dir does the same in code.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "fullarm/haptics/neighbour_cones.hpp"
#include "fullarm/haptics/snch.hpp"
#include "fullarm/haptics/tri_mesh.hpp"

namespace fullarm::haptics {

/// Version of what buildSnchTree computes (node bounds, cones, split rule). Raised with every
/// change to the build; a saved tree of another version is stale.
inline constexpr std::uint32_t kSnchBuildVersion = 2;
/// Version of what computeNeighbourCones computes.
inline constexpr std::uint32_t kNeighbourConesBuildVersion = 1;

/// A 64-bit hash of a mesh's content: its vertex coordinates (their bit patterns) and its
/// triangles, in order. Equal meshes hash equal; any changed coordinate, index or order changes
/// it (up to the 2^-64 chance of a collision; it is a cache key, not a signature).
[[nodiscard]] std::uint64_t meshContentHash(const TriMesh& mesh) noexcept;

/// An object mesh's hierarchy: what CollisionObject holds besides the mesh.
struct MeshHierarchy {
  SnchTree tree;
  NeighbourCones cones;
};

/// Builds both (buildSnchTree, computeNeighbourCones).
[[nodiscard]] MeshHierarchy buildMeshHierarchy(const TriMesh& mesh);

/// Writes `hierarchy`, built from `mesh`, to `file` (binary: a header with the key, the tree, the
/// cones, a checksum). The file is written beside its final name and renamed into place, so a
/// reader never sees half of it.
/// @throws std::runtime_error naming the file when it cannot be written
void saveMeshHierarchy(const MeshHierarchy& hierarchy, const TriMesh& mesh, const std::filesystem::path& file);

/// Reads a hierarchy saved by saveMeshHierarchy for a mesh with `mesh`'s content and the current
/// build versions. Returns nothing, and says why in `why` when given, when the file is missing,
/// is not a hierarchy file, was saved for another mesh or another build version (stale), or is
/// truncated or corrupt (checksum, counts or indices out of range). Never throws for a bad file.
[[nodiscard]] std::optional<MeshHierarchy> loadMeshHierarchy(const TriMesh& mesh, const std::filesystem::path& file,
                                                             std::string* why = nullptr);

/// What hierarchyFromCache did.
enum class HierarchyCacheOutcome {
  kLoaded,         ///< a valid saved hierarchy was read
  kBuiltAndSaved,  ///< none was saved: built and saved
  kRebuiltStale,   ///< the saved one was stale or corrupt: rebuilt and saved over it
};

/// The hierarchy of `mesh` from `cache_dir`: the file `<hash>.snch` (the content hash in hex)
/// when it holds a valid one, else built and saved there (the folder is created).
/// @throws std::runtime_error naming the file when the folder or file cannot be written
[[nodiscard]] MeshHierarchy hierarchyFromCache(const TriMesh& mesh, const std::filesystem::path& cache_dir,
                                               HierarchyCacheOutcome* outcome = nullptr);

/// The cache file of `mesh` in `cache_dir`.
[[nodiscard]] std::filesystem::path hierarchyCacheFile(const TriMesh& mesh, const std::filesystem::path& cache_dir);

}  // namespace fullarm::haptics
