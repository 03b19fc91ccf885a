#pragma once
/// @file
/// Spatialized normal cone hierarchy (SNCH; Johnson & Cohen, I3D 2001) and the pair query
/// that reports every local minimum distance (LMD) between two meshes within a cutoff.
///
/// Definition of a local minimum used throughout the module (and by the brute-force oracle in
/// the tests): the closest points p (on triangle A of mesh 1) and q (on triangle B of mesh 2)
/// of a triangle pair, classified by feature (face / edge / vertex), with d = |q - p| <= L, such
/// that (1) no triangle incident to p's feature comes closer to q than d, and no triangle
/// incident to q's feature comes closer to p than d (within kLocalMinimumTolerance_m): then
/// (p, q) minimises the distance over the neighbourhood of both features, because the distance
/// between two triangles is convex; and (2) the minimum is seen from outside: u = (q - p)/d has
/// u . n_p >= 0 and -u . n_q >= 0 for the feature pseudo-normals n_p, n_q (this rejects the
/// "through the body" minima that every flat back face of a polyhedron would otherwise give).
/// Touching or intersecting triangles (d = 0) are minima with u = -n_q. Minima of the same
/// feature pair are merged.

#include <Eigen/Geometry>
#include <cstdint>
#include <utility>
#include <vector>

#include "fullarm/haptics/convex_distance.hpp"
#include "fullarm/haptics/geometry.hpp"
#include "fullarm/haptics/minima.hpp"
#include "fullarm/haptics/tri_mesh.hpp"

namespace fullarm::haptics {

/// Distance slack of the local-minimum test [m].
inline constexpr double kLocalMinimumTolerance_m = 1e-12;
/// Cosine slack of the outside (pseudo-normal) test.
inline constexpr double kOutsideCosineTolerance = 1e-9;
/// Angle added to every cone test so rounding never prunes an accepted minimum [rad].
inline constexpr double kConeSlack_rad = 1e-3;
/// Cone tests run only on node pairs proven at least this far apart [m]. The local-minimum
/// test accepts a direction u up to sqrt(2 kLocalMinimumTolerance_m / d) outside the exact
/// normal cone of its feature; above this gap that is below 4.5e-4 rad < kConeSlack_rad.
/// Closer pairs (touching, intersecting) are always descended.
inline constexpr double kConeTestMinGap_m = 1e-5;

/// One node: bounding sphere and axis-aligned box of its triangles, and bounding cone of the
/// normals that a local minimum on them can have (all in the mesh frame).
///
/// The sphere and the box share their centre (the centre of the vertex box). The box bounds
/// thin and sliver-shaped nodes far more tightly than the sphere: the query takes the larger of
/// the two distance lower bounds.
///
/// Layout: 128 bytes, aligned to a 64-byte cache line; the first line holds what every visit
/// reads (centre, radius, box, children), the second what only the nodes that pass the distance
/// bounds read (the cone and the leaf's triangle). Nodes are stored depth first (a node's left
/// child follows it).
struct alignas(64) SnchNode {
  Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();  ///< sphere and box centre [m]
  double radius_m = 0.0;
  /// Half extents of the axis-aligned box around the vertices, mesh frame [m].
  Eigen::Vector3d box_half_m = Eigen::Vector3d::Zero();
  int left = -1;  ///< child nodes (-1 for a leaf)
  int right = -1;
  Eigen::Vector3d cone_axis = Eigen::Vector3d::UnitZ();  ///< unit
  double cone_half_angle_rad = 0.0;                      ///< in [0, pi]; pi = every direction
  /// cos and sin of cone_half_angle_rad + kConeSlack_rad (cos = -1, sin = 0 when that reaches
  /// pi): the query's cone tests use them instead of trigonometric calls.
  double cone_cos = -1.0;
  double cone_sin = 0.0;
  int triangle = -1;  ///< the leaf's triangle
  /// The normals are bounded by the double cone +-cone_axis (half angle below pi/2), not by the
  /// cone: set on leaves of double-sided surfaces (each triangle also present with the opposite
  /// winding, as the DRC CAD exports are) and on every node above one.
  bool cone_two_sided = false;
  [[nodiscard]] bool isLeaf() const noexcept { return left < 0; }
};
static_assert(sizeof(SnchNode) == 128, "two cache lines per node");

/// The hierarchy of one mesh: a binary tree with one triangle per leaf, root at index 0.
/// Leaf cones bound the normals of the triangle and of every triangle in its vertices'
/// one-rings (so edge and vertex minima are covered); an inner cone bounds its children's.
/// A triangle with a vertex on a boundary or non-manifold edge (not exactly two triangles) gets
/// a full cone: at a boundary the minimum direction can lie in the plane of the sheet, outside
/// every one-ring normal. A triangle of a double-sided surface (its twin, the same vertices in
/// the opposite winding, is in the mesh) gets a cone or double cone around the exact normal
/// cones of its face, edges and vertices (the directions u with u . e <= 0 for every direction
/// e from the feature into an incident triangle), or a full cone when they do not fit in one.
struct SnchTree {
  std::vector<SnchNode> nodes;
  /// The mesh is the closed surface of a convex body: every edge has exactly two triangles and
  /// no vertex lies more than kConvexTolerance x (box diagonal) in front of any face plane (the
  /// link capsules are). querySnchPair then bounds each object triangle's minima by its
  /// distance to the link (kConvexBoundSlack_m). Meshes above kConvexCheckMaxWork (triangles x
  /// vertices) are not checked and count as not convex.
  bool convex = false;
  /// Leaf node of each triangle.
  std::vector<int> leaf_of_triangle;
  /// The mesh's vertex graph (convex meshes only; empty otherwise).
  VertexGraph vertex_graph;
  /// A vertex of a triangle, where the support climbs on the vertex graph start (convex meshes
  /// only). Not simply vertex 0: a vertex no triangle uses (a copy removed by welding, or one of
  /// a dropped degenerate triangle) has no neighbours, and a climb from it would never move.
  int support_start_vertex = 0;
  /// Capsules around a common segment that bracket the body (convex meshes only): the query
  /// bounds an object node's distance to the link by them before (or instead of) GJK.
  ConvexBracket bracket;
  /// Start vertices of the support climbs by direction (convex meshes only; mesh frame).
  SupportTable support_table;
};

/// Cells per cube-face edge of SnchTree::support_table (6 x 6 x 6 = 216 directions, about 15
/// degrees each: finer than the facets of the arm's 16-segment capsules).
inline constexpr int kSupportTableCells = 6;

/// Relative tolerance of the convexity check (of the mesh's bounding-box diagonal).
inline constexpr double kConvexTolerance = 1e-9;
/// Largest triangles x vertices product for which buildSnchTree checks convexity.
inline constexpr long kConvexCheckMaxWork = 50'000'000;
/// Slack of the convex-link bound [m]. When the link mesh is convex (SnchTree::convex), every
/// local minimum (p, q) with q on object triangle B has distance d = dist(B, link body): p is
/// the projection of q on the link body (condition (1) of the file comment at p is first-order
/// optimality over p's star, whose directions span the body's tangent cone at p), and q
/// minimises dist(., link body) over B (condition (1) at q, and that function is convex with
/// gradient u). Hence d <= the distance from B to any link triangle, and a link node whose
/// distance lower bound to B exceeds the smallest B-to-link-triangle distance seen so far plus
/// this slack cannot pair with B. The local-minimum test accepts up to kLocalMinimumTolerance_m,
/// which moves d by about (1 / sine of the smallest angle at p)^2 x 1e-12 m; the convexity
/// tolerance adds about 1e-9 x the link's size. 1e-6 m covers both by two orders of magnitude
/// and costs nothing measurable in pruning (node gaps are millimetres).
inline constexpr double kConvexBoundSlack_m = 1e-6;
/// GJK stops once its bounds on an object triangle's distance to a convex link are this close
/// [m] (the upper bound then starts the triangle's bound; the exact tests tighten it).
inline constexpr double kConvexHullTolerance_m = 2e-5;
/// Same for an object node's sphere against a convex link [m] (its lower bound prunes the node;
/// both bounds bound the direction of its minima). Used only for links whose SnchTree::bracket
/// is not valid; otherwise the bracket capsules bound the node.
inline constexpr double kConvexNodeTolerance_m = 1e-3;

/// Builds the hierarchy (top-down median split along the longest extent of the centroids).
[[nodiscard]] SnchTree buildSnchTree(const TriMesh& mesh);

/// Reusable traversal storage for querySnchPair (grows, then stays allocated).
struct SnchQueryScratch {
  std::vector<std::pair<int, int>> stack;
  /// One link node in the object frame: its centre, its cone axis, and the half extents of the
  /// object-frame box around its (link-frame) box [m].
  struct LinkNodeO {
    Eigen::Vector3d centre_m;
    Eigen::Vector3d axis;
    Eigen::Vector3d box_half_m;
  };
  /// Per link node, filled when the traversal first reaches the node in a query (most link
  /// nodes never are: the pair is pruned near the root).
  std::vector<LinkNodeO> link_node_O;
  /// Per link node, the query that filled link_node_O (entries below `query` are stale).
  std::vector<std::uint32_t> link_node_query;
  std::uint32_t query = 0;
  /// The link mesh's vertices in the object frame (filled once per query).
  std::vector<Eigen::Vector3d> link_vertex_O;
  /// Convex links: stamps of the link vertices and triangles already taken for the current
  /// object triangle, and the vertex search's frontier.
  std::vector<std::uint32_t> link_vertex_stamp;
  std::vector<std::uint32_t> link_triangle_stamp;
  std::uint32_t link_stamp = 0;
  std::vector<int> link_frontier;
  /// Convex links: each stamped vertex's height along the current object triangle's axis [m].
  std::vector<double> link_vertex_height;
};

/// Counters of the last querySnchPair call.
struct SnchQueryStats {
  long node_pairs_visited = 0;
  long pruned_by_distance = 0;  ///< distance lower bound (sphere or box) above the cutoff
  long pruned_by_cone = 0;      ///< any normal-cone test
  /// convex link: a candidate link triangle proven (along the GJK axis or by separating axes)
  /// farther from the object triangle than the triangle's bound
  long pruned_by_convex_bound = 0;
  /// convex link: GJK calls (object nodes and triangles against the whole link body)
  long convex_hull_tests = 0;
  long triangle_pairs_tested = 0;  ///< leaf pairs given to the exact test (evaluateTrianglePair)
  long coherence_kept = 0;         ///< coherent capsule query: front nodes kept without a test
  long coherence_rebuilds = 0;     ///< coherent capsule query: fronts rebuilt from the root
};

/// Closest points of link triangle `tri_link` and object triangle `tri_object`, computed in
/// the object frame (p and q both in the object frame). `X_OL` is the link pose in the object
/// frame.
/// @rt
[[nodiscard]] TriangleTriangleResult closestPointsInObjectFrame(const TriMesh& link_mesh, int tri_link,
                                                                const TriMesh& object_mesh, int tri_object,
                                                                const Eigen::Isometry3d& X_OL) noexcept;

/// The mesh feature (TriMesh vertex id, edge id, or the triangle itself) that `f`, a feature of
/// triangle `tri` in the triangle's local numbering, names.
/// @rt
[[nodiscard]] Feature meshFeature(const TriMesh& mesh, int tri, const LocalFeature& f) noexcept;

/// Tests one triangle pair: when its closest points form a local minimum (definition in the
/// file comment) at distance <= cutoff_m, fills `out` (triangles, features, p_L in the link
/// frame, p_O in the object frame, distance, u in the OBJECT frame; link/object left as they
/// are) and returns true.
/// @rt
bool evaluateTrianglePair(const TriMesh& link_mesh, int tri_link, const TriMesh& object_mesh, int tri_object,
                          const Eigen::Isometry3d& X_OL, double cutoff_m, LocalMinimum& out) noexcept;

/// Appends to `out` every local minimum between a link mesh and an object mesh within
/// `cutoff_m`, merged by feature pair. A convex link tree (SnchTree::convex) is queried as one
/// body against the object tree (GJK bounds; docs/haptics.md, "Convex links"), any other by the
/// two-tree traversal; both give the brute-force set. link/object fields of the appended minima are -1 (the
/// caller fills them); u_W is in the world frame.
/// @param X_WL pose of the link mesh frame; @param X_WO pose of the object mesh frame
void querySnchPair(const SnchTree& link_tree, const TriMesh& link_mesh, const Eigen::Isometry3d& X_WL,
                   const SnchTree& obj_tree, const TriMesh& obj_mesh, const Eigen::Isometry3d& X_WO, double cutoff_m,
                   SnchQueryScratch& scratch, std::vector<LocalMinimum>& out, SnchQueryStats* stats = nullptr);

/// A capsule: the points within radius_m of the segment [a_m, b_m] (a sphere when the two ends
/// coincide). The exact geometry of an arm link whose LinkGeometry is a capsule.
struct Capsule {
  Eigen::Vector3d a_m = Eigen::Vector3d::Zero();  ///< segment end (LinkGeometry::from_m) [m]
  Eigen::Vector3d b_m = Eigen::Vector3d::Zero();  ///< other end (LinkGeometry::to_m) [m]
  double radius_m = 0.0;
};

/// A capsule's part in LocalMinimum::feature_link: the cap around a_m ({kVertex, 0}), the cap
/// around b_m ({kVertex, 1}) or the cylinder between them ({kEdge, 0}), from the parameter s of
/// the segment point that the minimum's direction passes through (s <= 0, s >= 1, between).
/// @rt
[[nodiscard]] Feature capsuleFeature(double s) noexcept;

/// The closest pair of a segment [a_O, b_O] and one feature of a mesh (same frame), computed from
/// the feature alone: a vertex against the segment; an edge (taken from its smaller vertex id)
/// against the segment (closestPointsSegmentSegment); a face (the triangle f.index) by
/// closestPointsSegmentTriangle.
struct CapsuleFeaturePair {
  double s = 0.0;  ///< parameter of on_segment_m on the segment, in [0, 1]
  Eigen::Vector3d on_segment_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d q_m = Eigen::Vector3d::Zero();  ///< the feature's point
  double distance_sq = 0.0;                       ///< |q_m - on_segment_m|^2 [m^2]
  /// The feature whose relative interior holds q_m: the feature itself, an edge's end vertex, or
  /// the edge or vertex of a face's triangle.
  Feature holder;
};

/// @rt
[[nodiscard]] CapsuleFeaturePair capsuleFeatureClosest(const Eigen::Vector3d& a_O, const Eigen::Vector3d& b_O,
                                                       const TriMesh& mesh, const Feature& feature) noexcept;

/// Fills `out` with the minimum of a capsule against the object feature `feature_object`
/// held by triangle `tri_object`, computed from that feature alone (so every triangle that
/// finds it, and local descent, report the same points and distance): the closest pair of the
/// capsule's segment [a_O, b_O] (object frame) and the vertex, the edge (taken from its
/// smaller vertex id) or the face; with d_s their distance, distance_m = max(0, d_s -
/// radius_m), u = (q - s)/d_s (minus the feature's pseudo-normal when d_s = 0), p = s +
/// radius_m u: on the capsule's surface, beyond q when the capsule reaches into the surface
/// (0 < d_s < radius_m), within the capsule when the segment itself meets it (d_s = 0). u_W is left in the OBJECT
/// frame; tri_link is -1; link/object untouched.
/// @param X_LO pose of the object frame in the link frame (p_L = X_LO p)
/// @rt
void capsuleMinimumAtFeature(const Eigen::Vector3d& a_O, const Eigen::Vector3d& b_O, double radius_m,
                             const Eigen::Isometry3d& X_LO, const TriMesh& object_mesh, int tri_object,
                             const Feature& feature_object, LocalMinimum& out) noexcept;

/// Same with the feature's pair already computed: `pair` = capsuleFeatureClosest(a_O, b_O,
/// object_mesh, feature_object).
/// @rt
void capsuleMinimumFromPair(const CapsuleFeaturePair& pair, double radius_m, const Eigen::Isometry3d& X_LO,
                            const TriMesh& object_mesh, int tri_object, const Feature& feature_object,
                            LocalMinimum& out) noexcept;

/// Tests one capsule/triangle pair: the closest pair (s, q) of the capsule's segment and the
/// triangle is a local minimum of the capsule against the object mesh when d_s - radius <=
/// cutoff_m, the object side sees it from outside (-u . n(f_q) >= -kOutsideCosineTolerance) and
/// no triangle incident to q's feature f_q comes closer to s than d_s (within
/// kLocalMinimumTolerance_m): the distance to the segment is convex with gradient u, so that is
/// exactly q minimising the distance to the capsule over f_q's neighbourhood, and the capsule's
/// own side is exact (its point is the projection of q). Fills `out` like
/// capsuleMinimumAtFeature and returns true.
/// @param a_O, b_O the capsule's segment in the object frame [m]
/// @rt
bool evaluateCapsuleTriangle(const Eigen::Vector3d& a_O, const Eigen::Vector3d& b_O, double radius_m,
                             const Eigen::Isometry3d& X_LO, const TriMesh& object_mesh, int tri_object, double cutoff_m,
                             LocalMinimum& out) noexcept;

/// Appends to `out` every local minimum between a capsule (link frame) and an object mesh within
/// `cutoff_m` (docs/haptics.md, "Capsule links"), merged by feature pair: a traversal of the
/// object's tree against the capsule's segment with the segment's exact distances (sphere and
/// box bounds, the normal-cone direction and support tests), then evaluateCapsuleTriangle at
/// the leaves. The output equals evaluateCapsuleTriangle on every triangle (the brute force).
/// link/object of the appended minima are -1; u_W is in the world frame.
void querySnchCapsule(const Capsule& capsule, const Eigen::Isometry3d& X_WL, const SnchTree& obj_tree,
                      const TriMesh& obj_mesh, const Eigen::Isometry3d& X_WO, double cutoff_m,
                      SnchQueryScratch& scratch, std::vector<LocalMinimum>& out, SnchQueryStats* stats = nullptr);

/// What a capsule query proved about one object tree, kept for the next query of the same pair
/// (temporal coherence, querySnchCapsuleCoherent): the cut of the tree where the traversal
/// stopped (the front: nodes pruned by distance or by a cone, leaves tested), each with a lower
/// bound on the distance from the capsule's segment to its triangles at a reference pose of the
/// segment. Between two queries at 100 Hz the arm moves millimetres, so most front nodes are
/// still farther than the cutoff and need no test. Default-constructed: empty (the first query
/// builds it).
struct CapsuleFront {
  bool valid = false;
  Eigen::Vector3d a_ref_m = Eigen::Vector3d::Zero();  ///< segment ends at the reference pose, object frame
  Eigen::Vector3d b_ref_m = Eigen::Vector3d::Zero();
  double reach_m = 0.0;            ///< cutoff + radius the front was built for
  const SnchTree* tree = nullptr;  ///< the tree it was built on, and its size
  std::size_t tree_nodes = 0;
  std::vector<int> node;         ///< front nodes
  std::vector<double> bound_m;   ///< per node: distance lower bound at the reference pose [m]
  std::size_t rebuilt_size = 0;  ///< front size after the last rebuild from the root
  std::vector<int> next_node;    ///< scratch of the next front
  std::vector<double> next_bound_m;
};

/// A coherent query rebuilds its front from the root once either end of the capsule's segment
/// has moved this far from the reference pose (object frame) [m]: the bounds kept lose that much.
inline constexpr double kCoherenceRebuildDrift_m = 0.05;
/// ... or once the front has grown this many times beyond its size after the last rebuild (a
/// front only refines; it is never coarsened).
inline constexpr std::size_t kCoherenceFrontGrowth = 4;

/// querySnchCapsule started from `front` instead of the tree's root: every front node whose
/// bound, less the drift of the segment since the reference pose (the larger move of its two
/// ends), still exceeds cutoff + radius is kept without a test; every other node is traversed
/// as in a fresh query and replaced by the nodes where that traversal stops. The front is a cut
/// of the tree, each pruning test is a necessary condition for a minimum, and the merge puts
/// the minima in canonical order, so the appended minima are exactly querySnchCapsule's (a
/// test replays a recorded motion). The front is rebuilt from the root on the first query,
/// when the tree, cutoff or radius changed, after kCoherenceRebuildDrift_m of drift, or after
/// kCoherenceFrontGrowth times growth. Not @rt (the front grows).
void querySnchCapsuleCoherent(const Capsule& capsule, const Eigen::Isometry3d& X_WL, const SnchTree& obj_tree,
                              const TriMesh& obj_mesh, const Eigen::Isometry3d& X_WO, double cutoff_m,
                              SnchQueryScratch& scratch, CapsuleFront& front, std::vector<LocalMinimum>& out,
                              SnchQueryStats* stats = nullptr);

/// Sorts minima[begin, end) by feature pair and removes repeated feature pairs (keeps the
/// smaller distance, then the smaller triangle ids, so the result does not depend on the input
/// order); returns the new end. No allocation.
/// @rt
std::size_t mergeDuplicateMinima(std::vector<LocalMinimum>& minima, std::size_t begin) noexcept;

}  // namespace fullarm::haptics
