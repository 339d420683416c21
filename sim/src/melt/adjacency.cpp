#include "adjacency.h"

#include <algorithm>

namespace meltlab::sim {

namespace {
// Spare entries per vertex so a list can grow by a few merges before it has to move.
constexpr Index kSlack = 4;
}  // namespace

template <class Real>
void VertexTriangles::build(const TriMesh<Real>& m) {
  const std::size_t nv = m.vertex_slots(), nt = m.triangle_slots();
  size_.assign(nv, 0);
  for (std::size_t t = 0; t < nt; ++t)
    if (m.triangle_alive[t])
      for (Index v : m.triangle[t]) ++size_[static_cast<std::size_t>(v)];
  begin_.resize(nv);
  capacity_.resize(nv);
  std::size_t total = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    begin_[v] = total;
    capacity_[v] = size_[v] + kSlack;
    total += static_cast<std::size_t>(capacity_[v]);
  }
  pool_.assign(total, -1);
  std::fill(size_.begin(), size_.end(), 0);
  for (std::size_t t = 0; t < nt; ++t)  // ascending t: every list comes out sorted
    if (m.triangle_alive[t])
      for (Index v : m.triangle[t]) {
        const auto vs = static_cast<std::size_t>(v);
        pool_[begin_[vs] + static_cast<std::size_t>(size_[vs]++)] = static_cast<Index>(t);
      }
  abandoned_ = 0;
  built_ = true;
}

void VertexTriangles::assign(Index v, std::span<const Index> sorted) {
  const auto vs = static_cast<std::size_t>(v);
  const auto n = static_cast<Index>(sorted.size());
  if (n > capacity_[vs]) {
    abandoned_ += static_cast<std::size_t>(capacity_[vs]);
    begin_[vs] = pool_.size();
    capacity_[vs] = n + kSlack;
    pool_.resize(pool_.size() + static_cast<std::size_t>(capacity_[vs]), -1);
  }
  std::copy(sorted.begin(), sorted.end(), pool_.begin() + static_cast<std::ptrdiff_t>(begin_[vs]));
  size_[vs] = n;
  if (abandoned_ > pool_.size() / 2) compact();
}

void VertexTriangles::erase(Index v, Index t) {
  const auto vs = static_cast<std::size_t>(v);
  Index* first = pool_.data() + begin_[vs];
  Index* last = first + size_[vs];
  Index* it = std::lower_bound(first, last, t);
  if (it == last || *it != t) return;
  std::copy(it + 1, last, it);
  --size_[vs];
}

void VertexTriangles::grow(std::size_t vertex_count) {
  while (size_.size() < vertex_count) {
    begin_.push_back(pool_.size());
    size_.push_back(0);
    capacity_.push_back(kSlack);
    pool_.resize(pool_.size() + static_cast<std::size_t>(kSlack), -1);
  }
}

void VertexTriangles::compact() {
  std::vector<Index> pool;
  pool.reserve(pool_.size() - abandoned_);
  for (std::size_t v = 0; v < size_.size(); ++v) {
    const std::size_t b = pool.size();
    pool.insert(pool.end(), pool_.begin() + static_cast<std::ptrdiff_t>(begin_[v]),
                pool_.begin() + static_cast<std::ptrdiff_t>(begin_[v] + static_cast<std::size_t>(capacity_[v])));
    begin_[v] = b;
  }
  pool_ = std::move(pool);
  abandoned_ = 0;
}

template void VertexTriangles::build(const TriMesh<float>&);
template void VertexTriangles::build(const TriMesh<double>&);

}  // namespace meltlab::sim
