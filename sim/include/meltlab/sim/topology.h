#pragma once
// Validity of a mesh as the monograph defines it (§2.3): every edge shared by exactly two
// faces, every vertex on at least three edges and faces, and the Euler characteristic
//     chi = V - E + F - H - 2 (S - G)                                     (Eq. 2.3)
// which is 0 for a valid closed solid. V, E, F, H and S are counted; the genus G (tunnels)
// of a closed orientable 2-manifold is not countable independently of Euler's relation, so
// it is derived per component as G = S - (V - E + F - H) / 2 and must come out a
// non-negative integer: a mesh whose counts give a fractional or negative G has chi != 0.

#include <meltlab/sim/mesh.h>
#include <meltlab/sim/polygon_mesh.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::sim {

struct EulerCounts {
  std::int64_t V = 0, E = 0, F = 0, H = 0, S = 0, G = 0;
  std::int64_t chi = 0;     ///< Eq. 2.3 with the derived G (0 when the counts are consistent)
  bool genus_valid = true;  ///< false if (V - E + F - H) is odd or G < 0 in some component
};

/// One problem found by the manifold check, named by mesh indices.
struct TopologyProblem {
  enum class Kind {
    kBoundaryEdge,             ///< edge used by one face only (open mesh)
    kNonManifoldEdge,          ///< edge used by more than two faces
    kInconsistentOrientation,  ///< edge used twice in the same direction
    kNonManifoldVertex,        ///< vertex whose faces form more than one fan
    kLowValence,               ///< vertex on fewer than 3 faces
    kDegenerateFace,           ///< face with a repeated vertex
    kOrphanVertex,             ///< live vertex that no live face uses (TriMesh only)
    kDeadVertexReference,      ///< live face using a deleted vertex (TriMesh only)
  };
  Kind kind;
  Index a = -1, b = -1;          ///< the vertex (a) or edge (a, b)
  int count = 0;                 ///< faces on the edge / fans at the vertex / faces at the vertex
  std::string describe() const;  ///< e.g. "non-manifold edge (v12, v40) shared by 3 faces"
};

struct TopologyReport {
  EulerCounts counts;
  bool closed = true;    ///< no boundary edges
  bool manifold = true;  ///< every edge has 2 faces, every vertex one fan
  bool oriented = true;  ///< every edge used once in each direction
  std::int64_t boundary_edges = 0;
  std::int64_t nonmanifold_edges = 0;
  std::int64_t nonmanifold_vertices = 0;
  std::int64_t misoriented_edges = 0;
  std::int64_t low_valence_vertices = 0;
  std::int64_t orphan_vertices = 0;
  std::int64_t dead_vertex_references = 0;
  std::vector<TopologyProblem> problems;  ///< first few problems, for messages
  /// All properties the melt cycle relies on: closed, manifold, oriented, valence >= 3,
  /// Euler counts consistent.
  bool valid() const {
    return closed && manifold && oriented && low_valence_vertices == 0 && orphan_vertices == 0 &&
           dead_vertex_references == 0 && counts.genus_valid;
  }
};

/// Counts of Eq. 2.3 for a polygon mesh (faces may have holes). Vertices used by no face
/// are not counted. S counts connected components through shared vertices.
EulerCounts euler_counts(const PolygonMesh& m);

/// Counts of Eq. 2.3 for the live, non-degenerate triangles of a triangle mesh: the same
/// counts as check_topology(m).counts, without the vertex-fan and orphan checks (O(n); the
/// counts of MeshStatistics, mesh_stats.h, which computes the quality measures with them).
template <class Real>
EulerCounts euler_counts(const TriMesh<Real>& m);

/// Full check of a polygon mesh (faces may have holes; loops are walked as edges).
TopologyReport check_topology(const PolygonMesh& m, std::size_t max_problems = 8);

/// Full check of the live part of a triangle mesh. O(n log n).
template <class Real>
TopologyReport check_topology(const TriMesh<Real>& m, std::size_t max_problems = 8);

/// Connected components of the live triangles (through shared vertices): the component id
/// of every vertex slot (-1 for dead/unused) and the number of components.
template <class Real>
std::pair<std::vector<Index>, Index> vertex_components(const TriMesh<Real>& m);

}  // namespace meltlab::sim
