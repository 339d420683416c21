#pragma once
// The statistics of a triangle mesh that `meltlab simulate` writes after every cycle: the
// Euler counts of §2.3 and the quality measures of §2.4, from one pairing of the edges.
//
// A MeshStatistics keeps its buffers between calls, so a run that asks for a row every cycle
// allocates nothing after the first. The per-triangle and per-edge measures (square roots,
// divisions, arccosines) are evaluated in parallel into arrays (eight triangles or edges at a
// time on SIMD lanes, with the scalar operations in their order) and then summed in mesh order by
// one thread: every value is that of a serial evaluation bit for bit, whatever the number
// of threads (`mesh_quality` and `euler_counts(TriMesh)` are this class on a fresh object; its
// counts are tested against the general polygon-loop check, `check_topology`).

#include <meltlab/sim/mesh.h>
#include <meltlab/sim/quality.h>
#include <meltlab/sim/topology.h>

#include <cstdint>
#include <limits>
#include <vector>

namespace meltlab::sim {

struct MeshStats {
  EulerCounts topology;   ///< as euler_counts(m): degenerate triangles left out
  QualityReport quality;  ///< as mesh_quality(m): every live triangle
};

class MeshStatistics {
 public:
  /// The statistics of the live part of `m`. The reference stays valid until the next call.
  template <class Real>
  const MeshStats& compute(const TriMesh<Real>& m);

 private:
  struct TriangleTerms {
    double half_area = 0, six_volume = 0, twist_deg = 0, quality = 0;
  };
  /// Bounding box of the corners of the live triangles.
  struct Box {
    Vec3<double> lo = Vec3<double>::Constant(std::numeric_limits<double>::infinity());
    Vec3<double> hi = Vec3<double>::Constant(-std::numeric_limits<double>::infinity());
    void join(const Box& o) {
      lo = lo.cwiseMin(o.lo);
      hi = hi.cwiseMax(o.hi);
    }
  };
  template <class Real>
  void triangle_terms(const TriMesh<Real>& m, std::size_t begin, std::size_t end, Box& box);
  /// One use of an undirected edge (lo, hi), lo <= hi, filed under lo: `tri` is the using
  /// triangle, or ~tri for a degenerate one (left out of the Euler counts).
  struct EdgeUse {
    Index hi;
    Index tri;
  };
  struct EdgeTerms {
    double length = 0, dihedral_deg = 0;
  };
  /// An edge waiting for its terms: its first use, its vertices and, for an edge of two uses,
  /// the two triangles (else -1).
  struct PendingEdge {
    std::size_t use;
    Index lo, hi, ta, tb;
  };
  template <class Real>
  void edge_terms(const TriMesh<Real>& m, const PendingEdge* pending, std::size_t count);

  MeshStats stats_;
  std::vector<TriangleTerms> tri_;
  std::vector<Vec3<double>> unit_normal_;  ///< of each triangle slot, apart: the dihedral measures read them
  std::vector<std::size_t> start_;         ///< uses of edges filed under lo: use_[start_[lo] .. start_[lo + 1])
  std::vector<EdgeUse> use_;
  std::vector<EdgeTerms> edge_;  ///< at the first use of each edge
  std::vector<std::uint8_t> used_;
  std::vector<std::int64_t> comp_sum_;
  std::vector<Index> parent_;  ///< the union-find's, kept for its allocation
};

}  // namespace meltlab::sim
